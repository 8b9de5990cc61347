# SPDX-License-Identifier: MIT
"""Exceptions raised by vpcontact.

Library code raises these (never ``assert``) so that callers, the CLI and the tests can tell a
bad input from a solver that did not converge.
"""

from __future__ import annotations


#: exit status of an unexpected exception: a bug in vpcontact, not a bad scene nor a failed step
INTERNAL_ERROR = 3


class VpcontactError(Exception):
    """Base class of all errors raised on purpose by vpcontact."""


class InputError(VpcontactError, ValueError):
    """A parameter, scene entry or mesh does not describe a valid problem.

    Attributes:
        key: the scene key the problem concerns (e.g. ``"contact.obstacle"``), set by the code
            that found it, so that a scene builder can locate it in the file without reading
            the message; None when no scene key applies.
        part: the contact part (its boundary part's name) a ``contact.…`` key belongs to, when
            the scene has several; None otherwise.
    """

    def __init__(self, message: str, key: str | None = None, part: str | None = None):
        super().__init__(message)
        self.key = key
        self.part = part


class SolverOptionError(InputError):
    """PETSc (or vpcontact) refused a solver option while a solver was set up.

    Attributes:
        option: the option's name (as given, without the leading "-") when the refusal names
            its value, else None.
        problems: each refused option's own message, when several are refused at once (e.g.
            options PETSc never read); empty otherwise.
    """

    def __init__(self, message: str, option: str | None = None,
                 problems: dict[str, str] | None = None):
        super().__init__(message, key="solver.petsc_options")
        self.option = option
        self.problems = dict(problems or {})


class ObstacleOutOfReach(InputError):
    """During the run a moving obstacle left the reach of the contact nodes' normal rays (its
    ``part`` names the contact part)."""


class ConvergenceError(VpcontactError, RuntimeError):
    """A nonlinear (SNES) or linear (KSP) solve of one time step did not converge.

    Attributes:
        reason: PETSc converged-reason name, e.g. ``"DIVERGED_MAX_IT"``.
        iterations: Newton iterations performed.
        time: time t_n of the step being solved.
        step: index n of the step being solved.
    """

    def __init__(self, reason: str, iterations: int, time: float, step: int, detail: str = ""):
        self.reason = reason
        self.iterations = iterations
        self.time = time
        self.step = step
        msg = (f"time step {step} (t = {time:.6g}) did not converge: {reason} after "
               f"{iterations} Newton iteration(s)")
        super().__init__(msg + (f"; {detail}" if detail else ""))


class NonFiniteStateError(VpcontactError, FloatingPointError):
    """The state after a step contains NaN or Inf (checked on every rank together)."""


class StepRejected(VpcontactError):
    """A converged step whose local time-error estimate exceeds the tolerance (rolled back).

    Attributes:
        ratio: estimate / tolerance (> 1).
        order: order of the scheme the estimate assumed (1 or 2).
        time: time t_n of the rejected step.
    """

    def __init__(self, ratio: float, order: int, time: float):
        self.ratio, self.order, self.time = ratio, order, time
        super().__init__(f"step to t = {time:.6g} rejected: local error estimate {ratio:.3g} "
                         "times the tolerance")


class StepTooSmall(VpcontactError):
    """Halving the step after failures took it below the floor of
    :func:`~vpcontact.solver.stepping.advance` (the run makes no progress in time there).

    Attributes:
        time: time t_{n−1} the steps started from.
        step: the step size that would have been tried next.
        last: the failure that asked for the cut.
    """

    def __init__(self, time: float, step: float, floor: float, last: Exception):
        self.time, self.step, self.last = time, step, last
        super().__init__(f"the step size fell to {step:.3g}, below {floor:.3g}, after repeated "
                         f"failures from t = {time:.6g} (the last: {last})")


class OutputError(VpcontactError, OSError):
    """An output could not be written (full disk, unwritable folder, a file in the way)."""


class Interrupted(VpcontactError):
    """The run was stopped by a signal (SIGINT or SIGTERM) at a clean point between steps.

    Attributes:
        signal: ``"SIGINT"`` or ``"SIGTERM"``.
    """

    def __init__(self, signal: str, time: float):
        self.signal = signal
        self.time = time
        super().__init__(f"interrupted by {signal} at t = {time:.6g}")

