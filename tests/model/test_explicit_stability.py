# SPDX-License-Identifier: MIT
"""The explicit scheme beyond its stability limit k < 2/L is refused (or warned about), and
below it the explicit and implicit schemes agree as k -> 0."""

import math
import warnings

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact.paper import signorini as paper
from vpcontact.model import Elasticity, LinearRate, Perzyna
from vpcontact.errors import InputError


def test_limits_from_the_data():
    # plane stress: λ_max(E) = E/(1-ν) (the hydrostatic mode); 3-D: E/(1-2ν)
    ps = Perzyna(Elasticity("plane_stress", 1e8, 0.3), math.sqrt(10), 200.0, scheme="explicit")
    assert ps.explicit_step_limit() == pytest.approx(2 * 200.0 * (1 - 0.3) / 1e8)
    solid = Perzyna(Elasticity("3d", 1e8, 0.3), math.sqrt(10), 200.0, scheme="explicit")
    assert solid.explicit_step_limit() == pytest.approx(2 * 200.0 * (1 - 2 * 0.3) / 1e8)
    assert Perzyna(Elasticity("3d", 1e8, 0.3), 1.0, 200.0).explicit_step_limit() == math.inf
    assert LinearRate(Elasticity("1d", 10.0), -1.0, 10.0).explicit_step_limit() == 2.0


def test_explicit_step_beyond_the_limit_is_refused():
    problem = paper.signorini_2d(4, scheme="explicit")
    with pytest.raises(InputError, match=r"exceeds the stability limit 2\.8e-06"):
        problem.step(1e-3)
    assert problem.step_index == 0


def test_warn_mode_runs_and_warns_once():
    problem = paper.signorini_2d(4, scheme="explicit")
    problem.unstable_steps = "warn"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        problem.step(1e-3)
        problem.step(1e-3)
    assert sum("stability limit" in str(w.message) for w in caught) == 1


def _displacement(scheme: str, sigma_y: float, k: float, t_final: float = 4e-5) -> np.ndarray:
    """(min u_1, max u_1, min u_2) over the mesh: independent of how ranks share it."""
    problem = paper.signorini_2d(3, scheme=scheme, sigma_y=sigma_y)
    for _ in range(round(t_final / k)):
        problem.step(k)
    u = problem.u.x.array.reshape(-1, 2)
    comm = MPI.COMM_WORLD
    return np.array([comm.allreduce(float(u[:, 0].min()), op=MPI.MIN),
                     comm.allreduce(float(u[:, 0].max()), op=MPI.MAX),
                     comm.allreduce(float(u[:, 1].min()), op=MPI.MIN)])


def test_explicit_below_the_limit_converges_to_implicit():
    # σ_Y tiny: the square flows (u ≈ 12x the elastic one by t = 4e-5 s); below the limit
    # (2.8e-6 s) the explicit and implicit schemes differ by O(k).
    elastic = np.abs(_displacement("implicit", 1e8, 2e-6)).max()
    gaps = []
    for k in (2e-6, 1e-6, 5e-7):
        implicit = _displacement("implicit", 1e-6, k)
        assert np.abs(implicit).max() > 5 * elastic, "the body must flow"
        gaps.append(np.abs(_displacement("explicit", 1e-6, k) - implicit).max()
                    / np.abs(implicit).max())
    rate = np.polyfit(np.log([2e-6, 1e-6, 5e-7]), np.log(gaps), 1)[0]
    assert rate >= 0.8, f"explicit - implicit = {gaps} at k = 2e-6, 1e-6, 5e-7 (rate {rate:.2f})"
