# SPDX-License-Identifier: MIT
"""Time-step control: reject a step that does not converge, halve k, retry, then grow k back.

The nominal step k is what the user asked for and is never exceeded. A step whose SNES diverges
(or whose state turns non-finite) is rolled back by :meth:`QuasistaticProblem.step`; the
controller then halves k, at most ``max_cuts`` times in a row, and after each step that Newton
solved easily (at most ``easy_iterations`` iterations) doubles it again up to the nominal k.
Steps never overshoot the final time. Every cut is recorded, so a run can report them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterator

from vpcontact.errors import ConvergenceError, InputError, NonFiniteStateError
from vpcontact.problem import QuasistaticProblem, StepReport


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
    """

    dt: float
    max_cuts: int = 12
    easy_iterations: int = 5
    cuts: list = field(default_factory=list)

    def __post_init__(self):
        if not self.dt > 0:
            raise InputError(f"time step must be > 0, got {self.dt}")
        if self.max_cuts < 0:
            raise InputError(f"max_cuts must be >= 0, got {self.max_cuts}")


def advance(problem: QuasistaticProblem, t_final: float, control: StepControl) -> Iterator[StepReport]:
    """Step ``problem`` from its current time to ``t_final``, yielding each accepted step.

    Raises:
        ConvergenceError or NonFiniteStateError: the step still failed after ``max_cuts``
            consecutive halvings; the problem holds the last accepted state.
    """
    if not t_final > float(problem.time.value):
        raise InputError(f"final time {t_final} must exceed the current time {float(problem.time.value)}")
    dt = control.dt
    cuts_in_a_row = 0
    # Relative slack so that round-off in the accumulated time never leaves a sliver step.
    slack = 1e-9 * control.dt
    while True:
        t = float(problem.time.value)
        remaining = t_final - t
        if remaining <= slack:
            return
        k = remaining if remaining <= dt + slack else dt
        try:
            report = problem.step(k)
        except (ConvergenceError, NonFiniteStateError) as error:
            reason = getattr(error, "reason", "NONFINITE_STATE")
            control.cuts.append(Cut(t, k, reason))
            cuts_in_a_row += 1
            if cuts_in_a_row > control.max_cuts:
                raise
            dt = k / 2
            continue
        cuts_in_a_row = 0
        if report.newton_iterations <= control.easy_iterations:
            dt = min(control.dt, 2 * k)
        else:
            dt = k
        yield report
