# SPDX-License-Identifier: MIT
"""The paper's 1-D normal-compliance test (§4.2.1): data, exact solution and error measurement.

A bar Ω = (0, 1) is clamped at x = 0 and pushed by f_0 = 10 towards a deformable foundation at
x = 1, initially at distance g = 0.25. The law is σ̇ = E ε̇ + G(σ, ε), E = 10, G = -σ + 10ε,
with σ_0 = 10 - 10x and u_0 = 0; the foundation follows σ(1) = -(1/μ)(u(1) - g)_+ with μ = 100.
The bar touches the foundation at t = ln 2; the exact solution is (21) before and (22) after.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, List, Optional

import numpy as np
import ufl
from dolfinx import fem, mesh as dmesh
from mpi4py import MPI

from vpcontact.model.constitutive import Elasticity, LinearRate
from vpcontact.model.normal_compliance import NormalCompliance
from vpcontact.output.fields import CellStress
from vpcontact.solver.loads import Loads, tag_facets
from vpcontact.solver.problem import QuasistaticProblem

T_FINAL = 10.0
GAP = 0.25
YOUNG = 10.0
MU = 100.0
BODY_FORCE = 10.0
G_A, G_B = -1.0, 10.0  # G(σ, ε) = aσ + bε
CONTACT_ONSET = math.log(2.0)
CLAMP, CONTACT = 1, 3


def exact_coefficients(t: float, mu: float = MU):
    """(A, B, C) with u(x, t) = A x + B x², σ(x, t) = C - 10 x (eqs. (21)-(22))."""
    e = math.exp(-t)
    if t <= CONTACT_ONSET:
        return 1.0 - e, -(1.0 - e) / 2.0, 10.0
    q = (2.0 * e + 3.0 + 40.0 * mu) / (10.0 * mu + 1.0)
    return q / 4.0 - e, (e - 1.0) / 2.0, 5.0 * q / 2.0


def exact_displacement(x, t: float, mu: float = MU):
    """u(x, t) of (21)-(22)."""
    a, b, _ = exact_coefficients(t, mu)
    return a * np.asarray(x) + b * np.asarray(x) ** 2


def exact_stress(x, t: float, mu: float = MU):
    """σ(x, t) of (21)-(22)."""
    _, _, c = exact_coefficients(t, mu)
    return c - 10.0 * np.asarray(x)


@dataclass
class Bar1DResult:
    """Errors and histories of one run with mesh size h and time step k."""

    h: float
    k: float
    times: np.ndarray
    nodes: np.ndarray                 # node coordinates, sorted
    displacements: np.ndarray         # (steps + 1, nodes), including t = 0
    err_vq: float                     # max_n ‖u - u_h‖_V + ‖σ - σ_h‖_Q
    err_nodal: float                  # max_n max_i |u(x_i, t_n) - u_h(x_i, t_n)|
    newton_iterations: List[int] = field(default_factory=list)


def build_problem(n_cells: int, comm=MPI.COMM_WORLD, scheme: str = "explicit",
                  petsc_options: Optional[dict] = None,
                  time_scheme: str = "euler") -> QuasistaticProblem:
    """The §4.2.1 problem on a uniform mesh of ``n_cells`` P1 elements (P0 stress);
    ``time_scheme="bdf2"`` (with ``scheme="implicit"``) integrates the law to second order."""
    mesh = dmesh.create_unit_interval(comm, n_cells)
    tags = tag_facets(mesh, {CLAMP: lambda x: np.isclose(x[0], 0.0),
                             CONTACT: lambda x: np.isclose(x[0], 1.0)})
    law = LinearRate(Elasticity("1d", YOUNG), a=G_A, b=G_B, scheme=scheme)
    loads = Loads(body_force=lambda x, t: ufl.as_vector([BODY_FORCE]))
    problem = QuasistaticProblem(mesh, tags, law, clamped_tag=CLAMP, loads=loads,
                                 contact=NormalCompliance(CONTACT, mu=MU, alpha=1.0, gap=GAP),
                                 petsc_options=petsc_options, time_scheme=time_scheme)
    # σ_0^h: the P0 projection of 10 - 10x is its value at the cell midpoint (the quadrature point).
    problem.set_initial_stress(lambda x: (10.0 - 10.0 * x[0])[:, None])
    return problem


class _ErrorForms:
    """‖ε(u) - ε(u_h)‖_L2² and ‖σ - σ_h‖_L2² with the exact solution in Constants."""

    def __init__(self, problem: QuasistaticProblem):
        mesh = problem.mesh
        self.a, self.b, self.c = (fem.Constant(mesh, 0.0) for _ in range(3))
        x = ufl.SpatialCoordinate(mesh)[0]
        # σ_h is piecewise constant: its DG0 copy lets the error be integrated exactly.
        self.cells = CellStress(problem.state)
        dx = ufl.dx(metadata={"quadrature_degree": 4})
        eps_h = problem.u[0].dx(0)
        self.strain_err = fem.form((self.a + 2 * self.b * x - eps_h) ** 2 * dx)
        self.stress_err = fem.form((self.c - 10.0 * x - self.cells.stress[0, 0]) ** 2 * dx)
        self.comm = mesh.comm

    def __call__(self, t: float) -> float:
        self.a.value, self.b.value, self.c.value = exact_coefficients(t)
        self.cells.update()
        ee = self.comm.allreduce(fem.assemble_scalar(self.strain_err), op=MPI.SUM)
        es = self.comm.allreduce(fem.assemble_scalar(self.stress_err), op=MPI.SUM)
        return math.sqrt(ee) + math.sqrt(es)


class NodalError:
    """max_i |u_h(x_i, t) - u(x_i, t)| over the nodes x_i of ``problem``'s mesh (all ranks)."""

    def __init__(self, problem: QuasistaticProblem):
        # owned displacement dofs through the scalar collapsed subspace (bs = 1 in 1-D)
        V0, parent = problem.V.sub(0).collapse()
        owned = V0.dofmap.index_map.size_local
        self.x = V0.tabulate_dof_coordinates()[:owned, 0]
        self._parent = np.asarray(parent[:owned])
        self._u = problem.u
        self._comm = problem.mesh.comm

    def values(self) -> np.ndarray:
        """u_h at the owned nodes."""
        return self._u.x.array[self._parent].copy()

    def __call__(self, t: float) -> float:
        local = np.max(np.abs(self.values() - exact_displacement(self.x, t)), initial=0.0)
        return self._comm.allreduce(float(local), op=MPI.MAX)


def run(r: float, t_final: float = T_FINAL, scheme: str = "explicit",
        on_step: Optional[Callable[[QuasistaticProblem], None]] = None) -> Bar1DResult:
    """Solve with h = k = r up to ``t_final`` and measure the errors of the paper's Fig. 7."""
    n_cells = int(round(1.0 / r))
    n_steps = int(round(t_final / r))
    if not (math.isclose(n_cells * r, 1.0) and math.isclose(n_steps * r, t_final)):
        raise ValueError(f"r = {r} must divide both 1 and T = {t_final}")
    problem = build_problem(n_cells, scheme=scheme)
    errors = _ErrorForms(problem)
    nodal = NodalError(problem)
    x_nodes = nodal.x
    comm = problem.mesh.comm
    times = [0.0]
    history = [nodal.values()]
    err_vq = errors(0.0)
    err_nodal = 0.0
    for _ in range(n_steps):
        report = problem.step(r)
        if on_step is not None:
            on_step(problem)
        t = report.time
        times.append(t)
        history.append(nodal.values())
        err_vq = max(err_vq, errors(t))
        err_nodal = max(err_nodal, nodal(t))

    # Gather node histories on every rank (the 1-D meshes are tiny), sorted by x.
    all_x = np.concatenate(comm.allgather(x_nodes))
    all_u = np.concatenate(comm.allgather(np.array(history).T), axis=0)
    order = np.argsort(all_x)
    result = Bar1DResult(h=1.0 / n_cells, k=r, times=np.array(times), nodes=all_x[order],
                         displacements=all_u[order].T, err_vq=err_vq, err_nodal=err_nodal,
                         newton_iterations=[rep.newton_iterations for rep in problem.reports])
    problem.solver.destroy()
    return result
