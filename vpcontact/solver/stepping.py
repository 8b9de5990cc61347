# SPDX-License-Identifier: MIT
"""Time-step control: reject a step that does not converge, halve k, retry, then grow k back.

The nominal step k is what the user asked for and is never exceeded. A step whose SNES diverges
(or whose state turns non-finite) is rolled back by :meth:`QuasistaticProblem.step`; the
controller then halves k, at most ``max_cuts`` times in a row, and after each step that Newton
solved easily (at most ``easy_iterations`` iterations) doubles it again up to the nominal k.
Steps never overshoot the final time. Every cut is recorded, so a run can report them.

With a ``tolerance`` the step size also follows a local time-error estimate (Milne's device,
:mod:`vpcontact.solver.error_estimate`): a converged step whose estimate exceeds ``tolerance`` · max|u|
is rejected, and every step proposes the next k = k · clip(0.9 (1/ratio)^(1/(p+1)), 0.2, 2)
(p the scheme's order), still capped by the nominal k. Where the solution has a kink (contact
onset or release) the estimate grows and the steps shrink there, landing steps near the event.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Iterator, Optional

from vpcontact.errors import (ConvergenceError, InputError, NonFiniteStateError, StepRejected,
                              StepTooSmall)
from vpcontact.solver.problem import QuasistaticProblem, StepReport


@dataclass(frozen=True)
class Cut:
    """A rejected step: its start time, the k tried and why it failed."""

    time: float
    dt: float
    reason: str


@dataclass
class StepControl:
    """Step-size policy.

    Args:
        dt: nominal (and largest) step k.
        max_cuts: consecutive halvings allowed before the run stops with the last error;
            0 disables adaptivity (any failure stops the run).
        easy_iterations: a step converged in at most this many Newton iterations lets k double.
        tolerance: relative local time-error tolerance (None: no error control, k changes only
            on solver failures); rejections by the estimate count against ``max_cuts`` too. The
            estimate is as accurate as the Newton solves: with the default SNES tolerances
            (relative 1e-10) tolerances down to about 1e-7 work; below, round-off in the first
            tiny steps can reject every step.
    """

    dt: float
    max_cuts: int = 12
    easy_iterations: int = 5
    tolerance: Optional[float] = None
    cuts: list = field(default_factory=list)
    next_dt: Optional[float] = None  # the step proposed after the last accepted one
    resume: bool = False  # a restart: the next call continues with next_dt

    def __post_init__(self):
        if not self.dt > 0:
            raise InputError(f"time step must be > 0, got {self.dt}")
        if self.max_cuts < 0:
            raise InputError(f"max_cuts must be >= 0, got {self.max_cuts}")
        if self.tolerance is not None and not 0 < self.tolerance < 1:
            raise InputError(f"tolerance must be in (0, 1), got {self.tolerance}")


#: A step the time-error estimate would cut below this fraction of the nominal k is taken at
#: this size without the estimate (once): at a kink in time the estimate does not fall with
#: k, and a sweep's cylinder pressed into a block at rest (tolerance 0.1) was rejected down
#: to k ~ 1e-9 and failed.
ESTIMATE_FLOOR_FRACTION = 1e-6

#: Steps below this fraction of the nominal k are not tried: the run stops with
#: :class:`~vpcontact.errors.StepTooSmall` (12 halvings in a row, the default, reach 2.4e−4).
MIN_STEP_FRACTION = 1e-8


def advance(problem: QuasistaticProblem, t_final: float, control: StepControl) -> Iterator[StepReport]:
    """Step ``problem`` from its current time to ``t_final``, yielding each accepted step.

    Raises:
        ConvergenceError, NonFiniteStateError or StepRejected: the step still failed after
            ``max_cuts`` consecutive cuts; the problem holds the last accepted state.
        StepTooSmall: a cut would take the step below MIN_STEP_FRACTION of ``control.dt``.
    """
    if not t_final > float(problem.time.value):
        raise InputError(f"final time {t_final} must exceed the current time {float(problem.time.value)}")
    # With error control a later call continues with the step proposed last; without, each call
    # starts from the nominal k (a cut then costs only the steps up to the next call's end).
    continued = control.tolerance is not None or control.resume
    dt = (control.next_dt if continued else None) or control.dt
    control.resume = False
    if control.tolerance is not None and problem.step_index == 0:
        # no history, no estimate: a first step of √tolerance · k has a small error, and
        # the controller grows k from there (by at most 2 per step)
        dt = min(dt, math.sqrt(control.tolerance) * control.dt)
    cuts_in_a_row = 0
    # Relative slack so that round-off in the accumulated time never leaves a sliver step.
    slack = 1e-9 * control.dt
    # The smallest step tried: cuts that alternate with accepted steps (the count of cuts in a
    # row starts again after each) could otherwise take k down to round-off, where t + k == t
    floor = max(MIN_STEP_FRACTION * control.dt, 1e-12 * abs(t_final))
    waive = False  # the next step is taken without the error estimate
    while True:
        t = float(problem.time.value)
        remaining = t_final - t
        if remaining <= slack:
            return
        k = remaining if remaining <= dt + slack else dt
        try:
            report = problem.step(k, None if waive else control.tolerance)
            waive = False
        except StepRejected as rejected:
            control.cuts.append(Cut(t, k, "ERROR_ESTIMATE"))
            cuts_in_a_row += 1
            if cuts_in_a_row > control.max_cuts:
                raise
            dt = k * _factor(rejected.ratio, rejected.order)
            if dt < ESTIMATE_FLOOR_FRACTION * control.dt:
                # An estimate that does not fall with k (a kink in time: contact onset from
                # rest, where the extrapolated history has no velocity to go on): the next
                # step, of this size, is taken without it
                dt, waive = ESTIMATE_FLOOR_FRACTION * control.dt, True
            continue
        except (ConvergenceError, NonFiniteStateError) as error:
            reason = getattr(error, "reason", "NONFINITE_STATE")
            control.cuts.append(Cut(t, k, reason))
            cuts_in_a_row += 1
            if cuts_in_a_row > control.max_cuts:
                raise
            dt = k / 2
            if dt < floor:
                raise StepTooSmall(t, dt, floor, error) from error
            continue
        cuts_in_a_row = 0
        grow = 2.0 if report.newton_iterations <= control.easy_iterations else 1.0
        if report.error_ratio is not None:
            grow = min(grow, _factor(report.error_ratio, report.order))
        if k < dt and remaining <= dt + slack:  # shortened to land on t_final: keep the proposal
            k = dt
        dt = control.next_dt = min(control.dt, grow * k)
        yield report


def _factor(ratio: float, order: int) -> float:
    """Step-size factor from an error ratio: 0.9 ratio^(-1/(p+1)), within [0.2, 2]."""
    if ratio <= 0.0:
        return 2.0
    return min(2.0, max(0.2, 0.9 * ratio ** (-1.0 / (order + 1))))
