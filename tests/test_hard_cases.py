# SPDX-License-Identifier: MIT
"""Hard cases stay numerically stable and correct (issue "[4 of 5]", started here).

Stiff viscosity: the paper's 2-D data have E/μ* = 5·10⁵ s⁻¹, so k E/μ* ranges over 10³–10⁶ for
practical steps. The implicit scheme must stay bounded for all of them (rejected steps are halved)
and converge to the small-k answer as k → 0.
"""

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import paper_signorini as paper
from vpcontact.stepping import StepControl, advance

T = 0.5  # the square flows from t ≈ 0.38 s: past its limit load


def _run(k: float, t_final: float = T):
    problem = paper.signorini_2d(4)
    control = StepControl(k)
    steps = list(advance(problem, t_final, control))
    u = problem.u.x.array
    comm = MPI.COMM_WORLD
    assert comm.allreduce(bool(np.isfinite(u).all()), op=MPI.LAND)
    assert steps[-1].time == pytest.approx(t_final)
    return comm.allreduce(float(np.abs(u).max(initial=0.0)), op=MPI.MAX), problem


@pytest.mark.slow
@pytest.mark.serial  # compares nodal fields of separate runs (same partition only serially)
def test_stiff_viscosity_bounded_and_converging_as_k_goes_to_zero():
    ks = [T / 2 ** j for j in range(10)]          # k E/μ* from 2.5e5 down to 488
    peaks, fields = [], []
    for k in ks:
        peak, problem = _run(k)
        peaks.append(peak)
        fields.append(problem.u.x.array.copy())   # same mesh and partition: comparable
    # bounded: no step size produces more than the largest-step answer (+1 %)
    assert max(peaks) <= 1.01 * peaks[0], peaks
    ref = fields[-1]
    scale = MPI.COMM_WORLD.allreduce(float(np.abs(ref).max(initial=0.0)), op=MPI.MAX)
    errors = [MPI.COMM_WORLD.allreduce(float(np.abs(f - ref).max(initial=0.0)), op=MPI.MAX) / scale
              for f in fields[5:8]]                 # k E/μ* = 7.8e3, 3.9e3, 2.0e3
    rate = np.polyfit(np.log(ks[5:8]), np.log(errors), 1)[0]
    assert 0.8 <= rate <= 1.5, f"errors {errors} at k = {ks[5:8]}: rate {rate:.2f}"


@pytest.mark.slow
def test_a_single_huge_step_is_halved_until_it_converges():
    # k E/μ* = 10⁶: one step over the whole flow; halving must carry it to t = 2 s.
    peak, problem = _run(2.0, t_final=2.0)
    assert peak > 0 and problem.step_index > 1, "the step must have been split"
