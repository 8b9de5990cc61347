# SPDX-License-Identifier: MIT
"""What a Signorini part with friction reports node by node (contact.csv's ``pressure`` and
friction columns, the XDMF contact fields) is consistent with its law at every node (issue 45),
with the mixed P2–P1 formulation in 2-D and 3-D, and with P1:

* a node whose clearance is open carries no pressure, exactly;
* a slipping node carries |t| = 𝔣 p (to 1e-8), a sticking one |t| ≤ 𝔣 p;
* the nodal pressures times the nodes' areas add up to the part's normal force, and the nodal
  friction forces to its tangential force.

A rigid cylinder (2-D) or sphere (3-D) is pressed into an elastic block, then dragged along it
(𝔣 = 0.3): the contact zone has open nodes next to it, sticking and slipping ones. The mixed
formulation's pressure column was the P1 interpolant of vertex pressures: here open nodes
reported up to 34 % (2-D) and 100 % (3-D) of the peak pressure, |t|/p ranged over 0.07–0.44
and 0.002–0.61 at slipping nodes, up to 0.34 and 0.45 at sticking ones; P1's open nodes
carried round-off, 6e−15 of the peak (vpcontact.model.contact_monitor).
"""

import numpy as np
import pytest
from mpi4py import MPI
from dolfinx import mesh as dmesh

from vpcontact.model import Elastic, Elasticity, PlaneStrain, Signorini
from vpcontact.model.friction import Friction
from vpcontact.solver import Dirichlet, QuasistaticProblem, StepControl, advance, tag_facets

COEFFICIENT = 0.3


def _indented(dim: int, **discretization):
    """An elastic block whose top (z or y = 0) a rigid ball of radius 1 presses and drags."""
    comm = MPI.COMM_WORLD
    if dim == 2:
        msh = dmesh.create_rectangle(comm, [np.array([-1.0, -0.5]), np.array([1.0, 0.0])],
                                     [24, 6])
        law = PlaneStrain(Elastic(Elasticity("3d_standard", 1e3, 0.3)))
        depth = 0.01
    else:
        msh = dmesh.create_box(comm, [np.array([-0.5, -0.5, -0.25]), np.zeros(3)], [8, 8, 2])
        law = Elastic(Elasticity("3d_standard", 1e3, 0.3))
        depth = 0.03
    up = dim - 1
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[up], -0.5 if dim == 2 else -0.25),
                            2: lambda x: np.isclose(x[up], 0.0)})
    centre = np.zeros((3, 1))
    centre[up] = 1.0

    def motion(t):
        d = np.zeros(dim)
        d[0] = 0.05 * max(t - 0.5, 0.0)
        d[up] = -depth * min(t / 0.5, 1.0)
        return d

    ball = Signorini(2, obstacle=lambda x: np.linalg.norm(x - centre, axis=0) - 1.0,
                     max_distance=2.0, translation=motion,
                     friction=Friction("coulomb", coefficient=COEFFICIENT))
    return QuasistaticProblem(msh, tags, law, dirichlet=[Dirichlet.clamped(1, dim, "bottom")],
                              contact=ball, **discretization)


def _check(problem) -> np.ndarray:
    """Assert the nodal consistency at the current state; (open, slipping, sticking pressed)
    node counts over the ranks."""
    comm = MPI.COMM_WORLD
    part = problem.contacts[0]
    cd = part.nodes
    p = -part.pressure()
    t = part.nodal_values("traction")
    slipping = part.nodal_values("slipping") > 0.5
    clearance = cd.gap - cd.normal_displacement(problem.u)
    open_ = clearance > 1e-8
    assert np.all(p[open_] == 0.0), (cd.points[open_][p[open_] != 0], p[open_][p[open_] != 0])
    assert np.all(p >= 0.0)
    assert np.allclose(t[slipping], COEFFICIENT * p[slipping], rtol=1e-8, atol=0.0), \
        t[slipping] / p[slipping]
    assert np.all(t[~slipping] <= COEFFICIENT * p[~slipping] * (1 + 1e-8)), \
        (t / np.where(p > 0, p, 1))[~slipping].max()
    # the nodal forces add up to the part's forces
    _, _, split = problem.support_forces(per_part=True, split=True)
    normal, tangential = split[0]
    nodal_normal = comm.allreduce(float(np.sum(p * part.areas)), op=MPI.SUM)
    friction = part.friction
    local = np.einsum("nkt,nt->k", friction.frame_tangents, friction.last["force"])
    nodal_tangential = np.linalg.norm(comm.allreduce(local, op=MPI.SUM))
    assert nodal_normal == pytest.approx(normal, rel=1e-8), (nodal_normal, normal)
    assert nodal_tangential == pytest.approx(tangential, rel=1e-7, abs=1e-10 * normal), \
        (nodal_tangential, tangential)
    sticking = ~slipping & (p > 0)
    return np.array([comm.allreduce(int(a.sum()), op=MPI.SUM)
                     for a in (open_ & (cd.gap < 0.5), slipping, sticking)])


@pytest.mark.parametrize("dim, discretization", [
    (2, {"formulation": "mixed"}), (2, {}),
    pytest.param(3, {"formulation": "mixed"}, marks=pytest.mark.slow)],
    ids=["2d-mixed", "2d-P1", "3d-mixed"])
def test_each_node_reports_a_pressure_and_traction_its_law_allows(dim, discretization):
    problem = _indented(dim, **discretization)
    assert problem.formulation == discretization.get("formulation", "displacement")
    counts = np.zeros(3, dtype=int)
    for _ in advance(problem, 1.0, StepControl(0.1)):
        counts += _check(problem)
    # every kind of node was checked: open ones beside the contact, slipping and sticking ones
    assert np.all(counts > 5), counts
