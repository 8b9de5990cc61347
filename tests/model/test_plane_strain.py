# SPDX-License-Identifier: MIT
"""Plane strain (ε33 = 0, σ33 free) on 2-D meshes: a 3-D law restricted to the plane."""


import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh as dmesh
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI

from vpcontact.model import Elastic, Elasticity, Perzyna, PlaneStrain
from vpcontact.errors import InputError
from vpcontact.output import CellStress, von_mises
from vpcontact.solver import Loads, QuasistaticProblem, tag_facets

E, NU = 1e5, 0.3
CLAMP, END = 1, 2


def _cantilever(law, formulation=None):
    mesh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.zeros(2), np.array([4.0, 1.0])], [16, 4])
    tags = tag_facets(mesh, {CLAMP: lambda x: np.isclose(x[0], 0.0),
                             END: lambda x: np.isclose(x[0], 4.0)})
    loads = Loads(tractions={END: lambda x, t: ufl.as_vector([0.2 * t, -t])})
    return QuasistaticProblem(mesh, tags, law, clamped_tag=CLAMP, loads=loads,
                              formulation=formulation), tags


def _global_max(a):
    return MPI.COMM_WORLD.allreduce(float(np.abs(a).max(initial=0.0)), op=MPI.MAX)


def test_elastic_plane_strain_equals_a_dolfinx_solve_with_lame_constants():
    problem, tags = _cantilever(PlaneStrain(Elastic(Elasticity("3d", E, NU))))
    problem.step(1.0)
    mesh, V = problem.mesh, problem.V
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = ufl.sym(ufl.grad(u))
    sigma = lam * ufl.tr(eps) * ufl.Identity(2) + 2 * mu * eps
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    L = ufl.dot(ufl.as_vector([0.2, -1.0]), v) * ds(END)
    bc = fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(V, 1, tags.find(CLAMP)), V)
    ref = fem_petsc.LinearProblem(ufl.inner(sigma, ufl.sym(ufl.grad(v))) * ufl.dx, L, bcs=[bc],
                                  petsc_options={"ksp_type": "preonly", "pc_type": "lu"}).solve()
    err = _global_max(problem.u.x.array - ref.x.array) / _global_max(ref.x.array)
    assert err <= 1e-9, f"relative difference {err:.2e}"
    # σ33 = ν (σ11 + σ22) in elastic plane strain
    s = problem.state.view(problem.state.stress)
    s33 = problem.law.out_of_plane_stress()
    assert np.allclose(s33, NU * (s[:, 0] + s[:, 1]), rtol=1e-10, atol=1e-10 * _global_max(s))


@pytest.mark.parametrize("formulation", ["displacement", "mixed"])
def test_perzyna_plane_strain_limits_and_flow(formulation):
    elastic, _ = _cantilever(PlaneStrain(Elastic(Elasticity("3d", E, NU))), formulation)
    rigid, _ = _cantilever(PlaneStrain(Perzyna(Elasticity("3d_standard", E, NU), 1e12, 200.0)),
                           formulation)
    soft, _ = _cantilever(PlaneStrain(Perzyna(Elasticity("3d_standard", E, NU), 0.5, 200.0)),
                          formulation)
    for p in (elastic, rigid, soft):
        for _ in range(4):
            p.step(0.25)
    # separate meshes may be partitioned differently: compare partition-free measures
    scale = _global_max(elastic.u.x.array)
    for measure in (_global_max, lambda a: MPI.COMM_WORLD.allreduce(float(a.min()), op=MPI.MIN)):
        assert abs(measure(rigid.u.x.array) - measure(elastic.u.x.array)) <= 1e-9 * scale
    assert _global_max(soft.u.x.array) > 1.5 * scale, "a low yield stress must let the beam flow"
    s33 = soft.law.out_of_plane_stress()
    assert np.isfinite(s33).all() and _global_max(s33) > 0


def test_von_mises_output_uses_the_out_of_plane_stress():
    problem, _ = _cantilever(PlaneStrain(Elastic(Elasticity("3d", E, NU))))
    problem.step(1.0)
    cells = CellStress(problem.state, problem.law.out_of_plane_stress)
    cells.update()
    plane_stress_formula = CellStress(problem.state)
    plane_stress_formula.update()
    n = problem.mesh.topology.index_map(2).size_local
    assert not np.allclose(cells.von_mises.x.array[:n], plane_stress_formula.von_mises.x.array[:n])
    # uniaxial check of the formula: σ = diag(1, 0, 1) has von Mises norm 1
    assert von_mises(np.array([[1.0, 0.0, 0.0]]), 2, np.array([1.0]))[0] == pytest.approx(1.0)


def test_plane_strain_needs_a_3d_law():
    with pytest.raises(InputError, match="plane strain needs a 3-D law"):
        PlaneStrain(Elastic(Elasticity("plane_stress", E, NU)))
