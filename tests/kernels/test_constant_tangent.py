# SPDX-License-Identifier: MIT
"""A law affine in ε_n has a tangent that depends on the step size only: the update writes it
at its first call for each step size (and scheme) and skips it afterwards, with bit-for-bit the
results of writing it at every call."""

import numpy as np
import pytest

from vpcontact.paper import bar1d
from vpcontact.paper import signorini as paper


class _Recording:
    """A law that records, per update, whether it was asked for the tangent."""

    def __init__(self, law):
        self._law, self.written = law, []

    def __getattr__(self, name):
        return getattr(self._law, name)

    def update(self, *args):
        self.written.append(args[-1] is not None)
        self._law.update(*args)


def _explicit_perzyna(monkeypatch):  # tangent E whatever the step
    return paper.signorini_2d(3, scheme="explicit", sigma_y=1e-2), (1e-6, 1e-6, 5e-7, 5e-7)


def _implicit_linear(monkeypatch, time_scheme="euler"):
    # tangent (E + k b)/(1 - k a); the §4.2.1 data (E = b = 10, a = -1) make it E for every k,
    # so b = 0 here, where it changes with the step
    monkeypatch.setattr(bar1d, "G_B", 0.0)
    problem = bar1d.build_problem(8, scheme="implicit", time_scheme=time_scheme)
    return problem, (0.05, 0.05, 0.025, 0.025)


def _bdf2_linear(monkeypatch):  # BDF2 scales the step of its implicit update by its own factor
    return _implicit_linear(monkeypatch, time_scheme="bdf2")


def _run(monkeypatch, build, always_write: bool):
    problem, steps = build(monkeypatch)
    assert problem.law.linear_in_strain
    if always_write:  # the behaviour before tangents were skipped: written at every update
        monkeypatch.setattr(problem, "_tangent_out", lambda key: problem.state.tangent_view())
    law = _Recording(problem.law)
    monkeypatch.setattr(problem, "law", law)
    tangents = []  # what the Jacobian reads after each step (Newton may not need it at all)
    for k in steps:
        problem.step(k)
        tangents.append(problem.state.tangent.x.array.copy())
    return problem.u.x.array.copy(), problem.state.stress.x.array.copy(), tangents, law.written


@pytest.mark.parametrize("build, writes", [(_explicit_perzyna, 2), (_implicit_linear, 2),
                                           (_bdf2_linear, None)])
def test_affine_law_writes_its_tangent_once_per_step_size(monkeypatch, build, writes):
    u, sigma, tangents, written = _run(monkeypatch, build, always_write=False)
    u_ref, sigma_ref, tangents_ref, written_ref = _run(monkeypatch, build, always_write=True)
    assert all(written_ref) and len(written) == len(written_ref) > 4
    if writes is not None:
        assert sum(written) == writes, written
    else:  # one write per distinct (step, BDF2 factor): fewer than the updates
        assert 2 <= sum(written) < len(written), written
    assert np.array_equal(u, u_ref) and np.array_equal(sigma, sigma_ref)
    assert all(np.array_equal(t, t_ref) for t, t_ref in zip(tangents, tangents_ref))
