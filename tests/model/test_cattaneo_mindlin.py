# SPDX-License-Identifier: MIT
"""Partial slip (Cattaneo–Mindlin): a rigid cylinder pressed into an incompressible block, then
pulled sideways by less than the friction limit (issue "Friction", §3).

For a body and an indenter that are elastically similar in Dundurs' sense (β = 0: here a rigid
indenter on an incompressible body, ν = 1/2), the normal and tangential problems uncouple: the
pressure stays Hertz's, p(x) = p0 √(1 − x²/a²), p0 = 2P/(πa), and under a tangential force Q <
𝔣P applied after the normal one the contact sticks in a central zone |x| < c and slips outside
it, with (2-D, plane strain)

    c/a = √(1 − Q/(𝔣P)),
    q(x) = 𝔣 p0 [√(1 − x²/a²) − (c/a) √(1 − x²/c²)]   (the second term for |x| < c only).

The block is [−4, 4] × [−4, 0] (a half-plane as far as a contact of half-width a ≈ 0.06 can
tell), Taylor–Hood displacement and pressure (the mixed formulation: ν = 1/2 needs it), refined
towards the contact to facets of h = 1/512 there (a/h ≈ 30). Its bottom is pushed up by 0.004
against the cylinder (R = 2), then moved sideways by 0.0012, which transmits Q ≈ 0.6 𝔣P.

Asserted: the stick zone's half-width is a √(1 − Q/(𝔣P)) to within one facet, and the
tangential traction (the nodal friction forces over the nodes' areas) is q(x) to 5 % in L2 over
the contact. Measured: c/a = 0.6281 against 0.6291 (a twentieth of a facet) and 4.8 % (9.8 %
with facets twice as large: first order, as the traction's kink at |x| = c allows). The stick
stiffness is not what limits it: 1e3 G/h gives the same numbers as the default 1e2 G/h.
"""

from __future__ import annotations

import numpy as np
import pytest
from mpi4py import MPI
from dolfinx import mesh as dmesh

from vpcontact.model import Elastic, Elasticity, PlaneStrain, Signorini
from vpcontact.model.friction import Friction
from vpcontact.solver import Dirichlet, QuasistaticProblem, StepControl, advance, tag_facets

RADIUS, SIZE, COEFFICIENT = 2.0, 4.0, 0.3


def _graded_block(comm, levels: int, radius: float):
    """[−SIZE, SIZE] × [−SIZE, 0] in 16 × 8 cells, refined ``levels`` times near the origin:
    refinement k splits the cells within radius · 2^(levels − 1 − k) of it."""
    msh = dmesh.create_rectangle(comm, [np.array([-SIZE, -SIZE]), np.array([SIZE, 0.0])], [16, 8])
    for k in range(levels):
        r = radius * 2.0 ** (levels - 1 - k)
        msh.topology.create_entities(1)
        edges = dmesh.locate_entities(msh, 1, lambda x: np.hypot(x[0], x[1]) < r)
        msh = dmesh.refine(msh, edges, redistribute=False)
    return msh


def _half_width(x: np.ndarray, inside: np.ndarray) -> float:
    """Half the width of the zone ``inside`` (sorted nodes x), each end midway between the last
    node inside and the first outside."""
    xi = x[inside]
    right = 0.5 * (xi.max() + x[x > xi.max()].min())
    left = 0.5 * (xi.min() + x[x < xi.min()].max())
    return 0.5 * (right - left)


@pytest.mark.slow
def test_the_stick_zone_and_the_traction_are_cattaneo_mindlins():
    comm = MPI.COMM_WORLD
    msh = _graded_block(comm, 8, 0.1)
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[1], -SIZE), 2: lambda x: np.isclose(x[1], 0.0)})
    cylinder = Signorini(2, obstacle=lambda x: np.hypot(x[0], x[1] - RADIUS) - RADIUS,
                         max_distance=1.0, friction=Friction("coulomb", coefficient=COEFFICIENT))
    bottom = Dirichlet(1, (lambda x, t: np.full(x.shape[1], 0.0012 * max(t - 1.0, 0.0)),
                           lambda x, t: np.full(x.shape[1], 0.004 * min(t, 1.0))), "bottom")
    problem = QuasistaticProblem(msh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", 1.0, 0.5))),
                                 dirichlet=[bottom], contact=cylinder, formulation="mixed")
    for step in advance(problem, 2.0, StepControl(0.25)):
        assert step.newton_iterations <= 10, step
    _, force = problem.support_forces()
    P, Q = -force[1], abs(force[0])
    assert 0.5 < Q / (COEFFICIENT * P) < 0.7  # partial slip, well inside the limit

    part = problem.contacts[0]
    state, last = part.friction.last, part.last_friction

    def gathered(a):
        return np.concatenate(comm.allgather(np.asarray(a)))
    x = gathered(part.nodes.points[:, 0])
    lam, slips = gathered(state["lam"]), gathered(state["slips"])
    traction = np.abs(gathered(last["traction"][:, 0]))
    order = np.argsort(x)
    x, lam, slips, traction = x[order], lam[order], slips[order], traction[order]
    touching = lam > 0
    a = _half_width(x, touching)
    c = _half_width(x, touching & ~slips)
    facet = 2 * np.diff(x[touching]).max()  # P2: two node spacings
    assert a / facet > 25  # the contact is resolved

    expected_c = a * np.sqrt(1.0 - Q / (COEFFICIENT * P))
    assert abs(c - expected_c) <= facet, (c, expected_c, facet)

    inside = np.abs(x) < a
    xi = x[inside]
    p0 = 2.0 * P / (np.pi * a)
    q = COEFFICIENT * p0 * (np.sqrt(1.0 - (xi / a) ** 2)
                            - expected_c / a * np.sqrt(np.maximum(1.0 - (xi / expected_c) ** 2, 0.0)))
    error = np.sqrt(np.trapz((traction[inside] - q) ** 2, xi) / np.trapz(q ** 2, xi))
    assert error < 0.05, error
