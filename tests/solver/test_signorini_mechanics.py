# SPDX-License-Identifier: MIT
"""Signorini solutions checked against mechanics and against independent solves.

* Global force balance at every step: applied loads + clamp reaction + contact force = 0.
* Elastic limit (σ_Y = ∞) without active contact = a plain dolfinx linear-elastic solve.
* Elastic limit with active contact = a separate SNES VI solve of the same elastic problem,
  written here from scratch (clamp as equal bounds, no Dirichlet machinery shared).
"""

import numpy as np
import pytest
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.paper import signorini as paper
from vpcontact.solver import StepControl, advance


def _owned(V):
    """Unrolled indices of owned dofs and their coordinates (one row per dof)."""
    bs = V.dofmap.index_map_bs
    n_owned = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:n_owned]
    return bs, n_owned, x


def _component_sums(problem, where):
    """Σ over owned dofs selected by ``where(x)`` of the residual R = (σ, ε(v)) - (f, v), per component."""
    V = problem.V
    bs, n_owned, x = _owned(V)
    R = fem_petsc.assemble_vector(fem.form(problem.equilibrium))
    R.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    r = R.array[: n_owned * bs].reshape(n_owned, bs)
    R.destroy()
    local = r[where(x)].sum(axis=0)
    return V.mesh.comm.allreduce(local, op=MPI.SUM)


def _balance_errors(problem, applied, clamp_where, contact_where):
    """|applied + clamp + contact| / |applied| with reactions read off the residual."""
    clamp = _component_sums(problem, clamp_where)
    contact = _component_sums(problem, lambda x: contact_where(x) & ~clamp_where(x))
    return np.linalg.norm(applied + clamp + contact) / np.linalg.norm(applied), contact


def test_force_balance_3d_every_step():
    problem = paper.signorini_3d(9, 3, 3)
    for step in advance(problem, 1.0, StepControl(0.25)):
        # The end-face traction (0, 0, -10 t) over the unit face x1 = 3.
        applied = np.array([0.0, 0.0, -10.0 * step.time])
        err, contact = _balance_errors(problem, applied, lambda x: np.isclose(x[:, 0], 0.0),
                                       lambda x: np.isclose(x[:, 2], 0.0))
        assert err <= 1e-8, f"t = {step.time}: force balance off by {err:.2e}"
        # The contact force read off the residual is the one the contact monitor reports.
        normal_force = problem.contact_monitor.report().normal_force
        assert contact[2] == pytest.approx(-normal_force, rel=1e-10)
        assert contact[2] > 0.0, "the foundation pushes the beam up"


@pytest.mark.slow
def test_force_balance_2d_with_contact_on_the_curved_obstacle():
    # Past the paper's T the square reaches the ellipse (from t ≈ 1.3 s); run to 1.45 s.
    problem = paper.signorini_2d(6)
    touched, first = False, 0
    for step in advance(problem, 1.45, StepControl(0.05)):
        applied = np.array([0.0, -10.0 * step.time])  # f_0 = (0, -10 t) over the unit square
        err, contact = _balance_errors(problem, applied, lambda x: np.isclose(x[:, 1], 1.0),
                                       lambda x: np.isclose(x[:, 1], 0.0))
        assert err <= 1e-8, f"t = {step.time}: force balance off by {err:.2e}"
        rep = problem.contact_monitor.report()
        assert rep.max_penetration <= 1e-10
        # no tensile contact pressure, to the force-balance tolerance relative to the load
        # (at inactive nodes the "pressure" is the residual's round-off, which scales with it)
        assert rep.max_pressure <= 1e-8 * max(abs(rep.min_pressure), np.linalg.norm(applied))
        if rep.active > 0 and not touched:
            first = rep.active
        touched |= rep.active > 0
    assert touched, "the square must reach the obstacle by t = 1.45 s"
    assert first == 1, f"grazing contact starts at one node (the corner x1 = 1), not {first}"
    assert rep.active >= 2, "contact spreads from the corner x1 = 1"


def _plane_stress(u, E, nu):
    eps = ufl.sym(ufl.grad(u))
    return E * nu / (1 - nu**2) * ufl.tr(eps) * ufl.Identity(2) + E / (1 + nu) * eps


def test_elastic_limit_without_contact_equals_plain_dolfinx_solve():
    problem = paper.signorini_2d(8, sigma_y=float("inf"))
    list(advance(problem, 0.5, StepControl(0.25)))
    assert problem.contact_monitor.report().active == 0

    V = problem.V
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = ufl.inner(_plane_stress(u, paper.YOUNG, paper.POISSON), ufl.sym(ufl.grad(v))) * ufl.dx
    L = ufl.dot(ufl.as_vector([0.0, -10.0 * 0.5]), v) * ufl.dx
    mesh = V.mesh
    top = fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[1], 1.0))
    bc = fem.dirichletbc(np.zeros(2), top, V)
    reference = fem_petsc.LinearProblem(a, L, bcs=[bc], petsc_options={"ksp_type": "preonly",
                                                                      "pc_type": "lu"}).solve()
    diff = mesh.comm.allreduce(float(np.abs(problem.u.x.array - reference.x.array).max()), op=MPI.MAX)
    size = mesh.comm.allreduce(float(np.abs(reference.x.array).max()), op=MPI.MAX)
    assert size > 0
    assert diff <= 1e-9 * size, f"elastic limit differs from dolfinx by {diff / size:.2e} (relative)"


def _elasticity_3d(u, E, nu):
    eps = ufl.sym(ufl.grad(u))
    return E * nu / ((1 + nu) * (1 - 2 * nu)) * ufl.tr(eps) * ufl.Identity(3) + E / (1 + nu) * eps


def test_elastic_limit_with_contact_equals_separate_vi_solve():
    t = 0.5
    problem = paper.signorini_3d(9, 3, 3, sigma_y=float("inf"))
    list(advance(problem, t, StepControl(0.25)))
    assert problem.contact_monitor.report().active > 0

    # The same elastic problem with E scaled to 1 (so u is scaled by E: a linear problem),
    # solved as one bound-constrained system K u = f: clamp as lower = upper = 0,
    # contact as u3 >= 0 on x3 = 0.
    V = problem.V
    mesh = V.mesh
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    facets = mesh.topology.dim - 1
    end = dmesh.locate_entities_boundary(mesh, facets, lambda x: np.isclose(x[0], 3.0))
    tags = dmesh.meshtags(mesh, facets, end, np.full(len(end), 7, dtype=np.int32))
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    K = fem_petsc.assemble_matrix(fem.form(ufl.inner(_elasticity_3d(u, 1.0, paper.POISSON),
                                                     ufl.sym(ufl.grad(v))) * ufl.dx))
    K.assemble()
    f = fem_petsc.assemble_vector(fem.form(ufl.dot(ufl.as_vector([0.0, 0.0, -10.0 * t]), v) * ds(7)))
    f.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)

    bs, n_owned, x = _owned(V)
    lower = f.duplicate()
    upper = f.duplicate()
    lo = np.full((n_owned, bs), PETSc.NINFINITY)
    hi = np.full((n_owned, bs), PETSc.INFINITY)
    lo[np.isclose(x[:, 2], 0.0), 2] = 0.0
    clamp = np.isclose(x[:, 0], 0.0)
    lo[clamp] = 0.0
    hi[clamp] = 0.0
    lower.array[:] = lo.ravel()
    upper.array[:] = hi.ravel()

    snes = PETSc.SNES().create(mesh.comm)
    prefix = "test_reference_vi_"
    snes.setOptionsPrefix(prefix)
    options = PETSc.Options()
    for key, value in {"snes_type": "vinewtonrsls", "snes_linesearch_type": "basic",
                       "snes_rtol": 1e-12, "snes_atol": 1e-14, "snes_max_it": 50,
                       "ksp_type": "preonly", "pc_type": "lu"}.items():
        options[prefix + key] = value
    if PETSc.Sys.hasExternalPackage("mumps"):
        options[prefix + "pc_factor_mat_solver_type"] = "mumps"
    r = f.duplicate()

    def residual(snes, xv, F):
        K.mult(xv, F)
        F.axpy(-1.0, f)

    snes.setFunction(residual, r)
    snes.setJacobian(lambda snes, xv, A, P: None, K)
    snes.setFromOptions()
    snes.setVariableBounds(lower, upper)
    sol = f.duplicate()
    sol.set(0.0)
    snes.solve(None, sol)
    assert snes.getConvergedReason() > 0, (snes.getConvergedReason(), snes.getKSP().getConvergedReason())

    ours = problem.u.x.array[: n_owned * bs]
    ref = sol.array / paper.YOUNG
    diff = mesh.comm.allreduce(float(np.abs(ours - ref).max()), op=MPI.MAX)
    size = mesh.comm.allreduce(float(np.abs(ref).max()), op=MPI.MAX)
    assert diff <= 1e-7 * size, f"elastic contact limit differs from the VI solve by {diff / size:.2e}"
    for obj in (snes, K, f, r, lower, upper, sol):
        obj.destroy()
