# SPDX-License-Identifier: MIT
"""The step-cost benchmark's exponent fits (bench/step_cost.py) recover known power laws: over
all sizes, between consecutive sizes, and over the largest sizes only."""

import numpy as np
import pytest

from bench import step_cost


def records(dofs, seconds):
    return [{"dofs": d, "seconds_per_step": s, "seconds_per_step_split": {"kernel": s / 10}}
            for d, s in zip(dofs, seconds)]


def test_fits_recover_a_power_law():
    dofs = [1e3, 3e3, 1e4, 3e4, 1e5]
    rs = records(dofs, [2e-6 * d ** 1.3 for d in dofs])
    assert step_cost.exponent(rs) == pytest.approx(1.3, abs=1e-12)
    assert step_cost.exponent(rs, "kernel") == pytest.approx(1.3, abs=1e-12)
    assert step_cost.local_exponents(rs) == pytest.approx([1.3] * 4, abs=1e-12)
    assert step_cost.largest_fit(rs) == pytest.approx(1.3, abs=1e-12)


def test_largest_fit_sees_only_the_largest_sizes():
    """Cost growing as dofs^1.5 up to 1e4 dofs and linearly beyond (a cache transition): the
    large-size fit is 1, the whole-range fit lies between; the order of the records is free."""
    dofs = [1e2, 1e3, 1e4, 2e4, 4e4, 8e4]
    cost = [d ** 1.5 if d <= 1e4 else 1e6 * d / 1e4 for d in dofs]
    rs = records(dofs, cost)[::-1]
    assert step_cost.largest_fit(rs) == pytest.approx(1.0, abs=1e-12)
    assert 1.0 < step_cost.exponent(rs) < 1.5
    assert step_cost.local_exponents(rs)[:2] == pytest.approx([1.5, 1.5], abs=1e-12)


@pytest.mark.parametrize("count", [1, 4])
def test_largest_fit_needs_more_sizes_than_it_fits(count):
    rs = records(np.geomspace(1e3, 1e5, count), np.geomspace(1.0, 100.0, count))
    assert step_cost.largest_fit(rs) is None
