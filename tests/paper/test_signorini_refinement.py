# SPDX-License-Identifier: MIT
"""Observed convergence orders of the Signorini tests on shortened runs, against fine references.

The paper proves O(h + k). Errors are nodal displacements at the vertices of the coarse meshes
(the unit-square and box meshes are nested under halving, so those vertices are fine-mesh
vertices too); rates are log–log least-squares slopes.
"""

import numpy as np
import pytest

from vpcontact.paper import signorini as paper
from vpcontact.solver import StepControl, advance

pytestmark = pytest.mark.serial  # compares dof arrays of separate meshes gathered on one rank


def _solve(problem, t_final, k, max_cuts=0):
    """Run to t_final with steps k (max_cuts = 0: uniform k, any divergence fails the test)."""
    list(advance(problem, t_final, StepControl(k, max_cuts=max_cuts)))
    x = problem.V.tabulate_dof_coordinates()
    bs = problem.V.dofmap.index_map_bs
    return x, problem.u.x.array.reshape(-1, bs).copy()


def _rms_error(coarse, reference):
    (x, u), (xr, ur) = coarse, reference
    index = {tuple(np.round(p, 9)): j for j, p in enumerate(xr)}
    rows = np.array([index[tuple(np.round(p, 9))] for p in x])
    return float(np.sqrt(np.mean((u - ur[rows]) ** 2)))


def _slope(steps, errors):
    return np.polyfit(np.log(steps), np.log(errors), 1)[0]


def test_time_refinement_3d_with_active_contact():
    # Fixed 9×3×3 mesh, T = 0.2 s: yielding starts within the first step and the beam presses
    # on the foundation throughout. Backward Euler in time: order 1.
    t_final, ks, k_ref = 0.2, [0.05, 0.025, 0.0125], 0.003125
    reference = _solve(paper.signorini_3d(9, 3, 3), t_final, k_ref)
    errors = []
    for k in ks:
        problem = paper.signorini_3d(9, 3, 3)
        errors.append(_rms_error(_solve(problem, t_final, k), reference))
        assert problem.contact_monitor.report().active > 0
    rate = _slope(ks, errors)
    assert rate >= 0.9, f"time rate {rate:.2f}, errors {errors}"


@pytest.mark.slow
def test_mesh_and_time_refinement_2d():
    # h = 1/n and k = 0.4 h refined together up to T = 0.6 s, past the plastic limit load
    # (t ≈ 0.38 s) where the square flows. Reference: n = 32, k = 0.0125. At the limit load
    # Newton may need a halved step (stepping.py); k is the nominal, largest step.
    t_final = 0.6
    reference = _solve(paper.signorini_2d(32), t_final, 0.0125, max_cuts=6)
    ns = [4, 8, 16]
    errors = [_rms_error(_solve(paper.signorini_2d(n), t_final, 0.4 / n, max_cuts=6), reference)
              for n in ns]
    rate = _slope([1.0 / n for n in ns], errors)
    assert rate >= 0.9, f"h = k rate {rate:.2f}, errors {errors}"
