# SPDX-License-Identifier: MIT
"""Contact on boundaries of any orientation, Dirichlet parts and reactions.

* A Signorini (and a normal-compliance) problem and the same problem rotated by an angle that is
  not a multiple of 90° give the same contact force, active set and (rotated back) displacements
  to solver tolerance, in 2-D and 3-D: the local frames at the contact nodes are exact.
* Local frames forced on an axis-aligned Γ3 (identity blocks, SNES on Rᵀu) give the fast path's
  answer: one code path tested against the other.
* Rollers and a prescribed displacement: uniaxial compression of a block has the closed-form
  reaction E δ W / H; reactions, contact force and loads balance; missing supports are refused
  with the free rigid motion named.
"""

import math

import numpy as np
import pytest
import ufl
from dolfinx import mesh as dmesh
from mpi4py import MPI

from vpcontact.errors import InputError
from vpcontact.model import Elastic, Elasticity, NormalCompliance, Signorini
from vpcontact.solver import Dirichlet, Loads, QuasistaticProblem, StepControl, advance, tag_facets

COMM = MPI.COMM_WORLD


def rotation(dim: int, angle: float) -> np.ndarray:
    """Rotation by ``angle`` (about the axis (1, 2, 2)/3 in 3-D)."""
    c, s = math.cos(angle), math.sin(angle)
    if dim == 2:
        return np.array([[c, -s], [s, c]])
    a = np.array([1.0, 2.0, 2.0]) / 3.0
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + s * K + (1 - c) * K @ K


def block_on_floor(dim: int, Q: np.ndarray, contact: str, rotate=None, petsc_options=None,
                   formulation=None):
    """A block clamped on top, pulled down by its weight onto a floor 0.01 below its bottom; the
    whole problem (mesh, load, floor) turned by Q. Returns the problem after the load is on."""
    if dim == 2:
        msh = dmesh.create_rectangle(COMM, [np.zeros(2), np.array([1.0, 0.5])], [12, 6])
    else:
        msh = dmesh.create_box(COMM, [np.zeros(3), np.array([1.0, 0.5, 0.5])], [6, 3, 3])
    up = dim - 1  # the block's vertical axis (before turning)
    x = msh.geometry.x
    x[:, :dim] = x[:, :dim] @ Q.T

    def reference(p):
        return Q.T @ p[:dim]

    tags = tag_facets(msh, {1: lambda p: np.isclose(reference(p)[up], 0.5),
                            2: lambda p: np.isclose(reference(p)[up], 0.0)})
    law = Elastic(Elasticity("plane_stress" if dim == 2 else "3d", 1e3, 0.3))
    weight = Q @ (-200.0 * np.eye(dim)[up])
    loads = Loads(body_force=lambda X, t: ufl.as_vector([float(w) * t for w in weight]))
    normal = Q @ np.eye(dim)[up]  # the floor's normal, towards the body
    if contact == "signorini":
        condition = Signorini(2, obstacle=lambda p: normal @ p[:dim] + 0.01, max_distance=1.0)
    else:
        condition = NormalCompliance(2, mu=1e-4, alpha=1.0, gap=0.01)
    problem = QuasistaticProblem(msh, tags, law, clamped_tag=1, loads=loads, contact=condition,
                                 rotate_contact=rotate, petsc_options=petsc_options,
                                 formulation=formulation)
    for _ in advance(problem, 1.0, StepControl(0.5)):
        pass
    return problem


def state(problem, Q):
    """(contact force, active nodes, displacements in the block's own frame sorted by node)."""
    dim = Q.shape[0]
    reactions, contact = problem.support_forces()
    u = problem.u.x.array.reshape(-1, dim) @ Q
    X = problem.V.tabulate_dof_coordinates()[:, :dim] @ Q
    owned = problem.V.dofmap.index_map.size_local
    u, X = u[:owned], X[:owned]
    order = np.lexsort(tuple(X[:, i].round(8) for i in range(dim)))
    points = COMM.allgather(X[order])
    values = COMM.allgather(u[order])
    X, u = np.concatenate(points), np.concatenate(values)
    order = np.lexsort(tuple(X[:, i].round(8) for i in range(dim)))
    active = problem.contact_monitor.report().active if problem.contact_monitor else None
    return contact @ Q, active, u[order]


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("contact", ["signorini", "normal_compliance"])
def test_rotated_problem_gives_the_same_answer(dim, contact):
    angle = math.radians(30.0 if dim == 2 else 40.0)
    f0, a0, u0 = state(block_on_floor(dim, np.eye(dim), contact), np.eye(dim))
    Q = rotation(dim, angle)
    f1, a1, u1 = state(block_on_floor(dim, Q, contact), Q)
    up = dim - 1
    assert f0[up] > 1.0, f"the block must press on the floor (force {f0})"
    assert a0 == a1
    if a0 is not None:
        assert a0 > 0
    assert np.allclose(f1, f0, rtol=1e-8, atol=1e-8 * abs(f0[up])), (f0, f1)
    scale = np.abs(u0).max()
    assert np.abs(u1 - u0).max() <= 1e-8 * scale, np.abs(u1 - u0).max() / scale


@pytest.mark.parametrize("contact", ["signorini", "normal_compliance"])
def test_rotated_mixed_problem_gives_the_same_answer(contact):
    """Taylor–Hood (P2 frames at vertices and edge nodes, the pressure left unrotated)."""
    f0, a0, u0 = state(block_on_floor(3, np.eye(3), contact, formulation="mixed"), np.eye(3))
    Q = rotation(3, math.radians(40.0))
    f1, a1, u1 = state(block_on_floor(3, Q, contact, formulation="mixed"), Q)
    assert f0[2] > 1.0, f"the block must press on the floor (force {f0})"
    assert a0 == a1
    assert np.allclose(f1, f0, rtol=1e-8, atol=1e-8 * abs(f0[2])), (f0, f1)
    scale = np.abs(u0).max()
    assert np.abs(u1 - u0).max() <= 1e-8 * scale, np.abs(u1 - u0).max() / scale


@pytest.mark.parametrize("dim", [2, 3])
def test_forced_frames_match_the_fast_path(dim):
    fast = block_on_floor(dim, np.eye(dim), "signorini")
    framed = block_on_floor(dim, np.eye(dim), "signorini", rotate=True)
    assert not fast.contact_dofs.rotated and framed.contact_dofs.rotated
    f0, a0, u0 = state(fast, np.eye(dim))
    f1, a1, u1 = state(framed, np.eye(dim))
    assert a0 == a1 > 0
    assert np.allclose(f0, f1, rtol=1e-10)
    assert np.abs(u1 - u0).max() <= 1e-10 * np.abs(u0).max()


def compressed_block(parts, nu=0.3):
    """[0, 2] × [0, 1] (plane stress, E = 100) with the given Dirichlet parts; tags: 1 bottom,
    2 left (x = 0), 3 top, 4 right."""
    msh = dmesh.create_rectangle(COMM, [np.zeros(2), np.array([2.0, 1.0])], [8, 4])
    tags = tag_facets(msh, {1: lambda p: np.isclose(p[1], 0.0), 2: lambda p: np.isclose(p[0], 0.0),
                            3: lambda p: np.isclose(p[1], 1.0), 4: lambda p: np.isclose(p[0], 2.0)})
    law = Elastic(Elasticity("plane_stress", 100.0, nu))
    return QuasistaticProblem(msh, tags, law, dirichlet=parts)


def test_rollers_and_prescribed_displacement_give_the_uniaxial_reaction():
    delta = 0.01
    parts = [Dirichlet.symmetry(1, 2, axis=1, name="bottom"),
             Dirichlet.symmetry(2, 2, axis=0, name="left"),
             Dirichlet(3, (None, lambda x, t: -delta * t * np.ones(x.shape[1])), name="top")]
    problem = compressed_block(parts)
    for _ in advance(problem, 1.0, StepControl(0.5)):
        pass
    reactions, contact = problem.support_forces()
    expected = 100.0 * delta / 1.0 * 2.0  # E ε W: uniaxial stress in the rollers' block
    assert reactions[2, 1] == pytest.approx(-expected, rel=1e-10)
    assert reactions[0, 1] == pytest.approx(expected, rel=1e-10)
    assert np.abs(reactions[:, 0]).max() <= 1e-10 * expected  # frictionless rollers
    u = problem.u.x.array.reshape(-1, 2)
    x = problem.V.tabulate_dof_coordinates()
    assert np.allclose(u[:, 1], -delta * x[:, 1], atol=1e-12)
    assert np.allclose(u[:, 0], 0.3 * delta * x[:, 0], atol=1e-12)  # Poisson's expansion
    assert problem.driving_displacement() == pytest.approx(-delta)  # signed: pushed down


@pytest.mark.parametrize("parts, free", [
    ([Dirichlet(3, (None, -0.01), name="top")], "translation along x"),
    ([Dirichlet.symmetry(1, 2, axis=1, name="bottom")], "translation along x"),
    ([Dirichlet.symmetry(2, 2, axis=0, name="left"), Dirichlet.symmetry(4, 2, axis=0)],
     "translation along y"),
])
def test_parts_that_leave_a_rigid_motion_free_are_refused(parts, free):
    with pytest.raises(InputError, match=f"do not hold the body: the rigid motion.*{free}"):
        compressed_block(parts)


def test_reactions_contact_force_and_loads_balance():
    problem = block_on_floor(2, rotation(2, 0.3), "signorini")
    reactions, contact = problem.support_forces()
    load = rotation(2, 0.3) @ np.array([0.0, -200.0 * 0.5])  # weight of the 1 × 0.5 block
    assert np.allclose(reactions.sum(axis=0) + contact + load, 0.0, atol=1e-9 * 100.0)
    assert np.linalg.norm(contact) > 1.0


def test_lagged_multigrid_solves_in_the_frames():
    """The VI's lagged GAMG solver (near-null space turned with the frames) gives the answer of
    the default lagged LU on a turned problem."""
    Q = rotation(2, math.radians(30.0))
    reference = state(block_on_floor(2, Q, "signorini"), Q)
    msh_problem = block_on_floor(2, Q, "signorini", petsc_options={
        "vpcontact_vi_linear": "lagged_gamg"})
    assert msh_problem.solver.lagged_lu.__class__.__name__ == "LaggedMultigrid"
    f, a, u = state(msh_problem, Q)
    assert a == reference[1]
    assert np.allclose(f, reference[0], rtol=1e-7)
    assert np.abs(u - reference[2]).max() <= 1e-7 * np.abs(reference[2]).max()
