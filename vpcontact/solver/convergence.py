# SPDX-License-Identifier: MIT
"""The step's convergence test (:class:`ConvergenceTest`): PETSc's default test, applied to VI
solvers too (their own test ignores ``snes_stol``), with vpcontact's round-off, stagnation,
crawl and no-progress stops.

Converged when ||F|| <= atol, or ||F|| <= rtol ||F_0||, or when the step is round-off relative
to the solution (||dx|| <= stol ||x||) while ||F|| <= stall_rtol max(||F_0||, ||load||, ||f||):
with E ~ 1e8 and accumulated strains ~ 1e-2 the residual cannot drop below ~ eps E |ε| however
small the step's load increment (and so ||F_0||) is. f is the residual at the step's initial
guess without Dirichlet conditions (its Dirichlet rows are the support reactions): in a run
driven by prescribed displacements, with no load, it is what sets the round-off floor (a held
step in stiff units, E = 1e9, stalled there).

Diverged (``stagnated``) when ``vpcontact_stagnation_its`` iterations in a row have left ||F||
above :data:`STAGNATION_FACTOR` times its best value so far (||F_0|| included): a step that
overshoots the onset of plastic flow (the paper's 3-D beam at k = 0.02 on 18×6×6 cells and
finer) wanders 17–300 times above ||F_0|| for its 50 iterations and never comes back, before the
step is cut and its halves converge in 8 and 2; stopping it after 12 saves three quarters of the
wasted factorizations. Slow steps that do converge stay near their best meanwhile (a plane-strain
Perzyna cantilever, mixed: ||F|| within 10 % of ||F_0|| for 20 iterations, then converged at the
41st) and are left alone.

In a try that may stop where it crawls (:meth:`ConvergenceTest.stops`), ``crawl_its`` iterations
in a row that have not halved the best ||F|| stop it too, unless a nodal term is ``holding`` at
the last Jacobian (see :data:`~vpcontact.solver.retries.CRAWL_ITERATIONS`); and a try given a
no-progress stop ends once, after so many iterations, its best ||F|| is still above its own
first one and above the level it must get below
(:data:`~vpcontact.solver.retries.NO_PROGRESS_ITERATIONS`).

Where the step's solves are aimed (a Jacobian fixed within the step, the block preconditioner),
the next Krylov solve's tolerance is set here from ||F|| and the target
(:func:`vpcontact.solver.linear.step_rtol`).

The round-off stop also applies when ||F|| comes out the same to the last bit three times in a
row: the iterate no longer moves. SNES VI's step, projected back onto the bounds, can leave it
where it is while the step's own norm is not small: the scratch demo's pressing reached 3.14e-11
(rtol × ||F_0|| = 2.56e-11) and repeated it for 47 iterations before the step was cut (twice in
the run, 100 of its 320 iterations).
"""

from __future__ import annotations

import contextlib
from typing import Optional, Sequence

import numpy as np
from petsc4py import PETSc

from vpcontact.solver import linear as linear_solvers

_SNES_REASON = PETSc.SNES.ConvergedReason

#: A Newton iteration "stagnates" while ||F|| stays above this many times its best value in the
#: step (see the module docstring).
STAGNATION_FACTOR = 10.0


class ConvergenceTest:
    """The test of the module docstring, as SNES's convergence test (``setConvergenceTest``),
    and what it saw of the last run (``fnorm0``, ``best``, ``start``, ``last_fnorm``,
    ``last_ratio``, ``stagnated``), which the retries read.

    Args:
        terms: the nodal terms (their ``holding`` delays the crawl stop).
        stall_rtol, stagnation_its, force_rtol: ``vpcontact_stall_rtol``,
            ``vpcontact_stagnation_its`` and ``vpcontact_force_rtol``.
    """

    def __init__(self, terms: Sequence, stall_rtol: float, stagnation_its: int,
                 force_rtol: float):
        self.terms = terms
        self.stall_rtol, self.stagnation_its, self.force_rtol = (stall_rtol, stagnation_its,
                                                                 force_rtol)
        self.force_scale = 0.0  # ||load|| of the step
        self.round_off_scale = 0.0  # max(||load||, ||f||) of the step
        self.aimed = False  # Krylov tolerances set per Newton iteration
        self.fnorm0 = 0.0
        self.fnorm0_kept: Optional[float] = None  # ||F_0|| of a try that goes on (retries)
        self.last_ratio = 1.0  # ||F|| of the last iteration against the one before
        self.best, self.above, self.stagnated = 0.0, 0, False
        self.crawl_its = 0
        self.no_progress_its = 0
        self.no_progress_level = np.inf  # ... and the ||F|| a try must get below
        self.start = 0.0  # ||F|| at the solve's first iterate
        self.last_fnorm = 0.0
        self._halved_at, self._halved_best, self._repeats = 0, 0.0, 0

    @contextlib.contextmanager
    def stops(self, crawl_its: int = 0, no_progress: tuple = (0, np.inf)):
        """The crawl stop after ``crawl_its`` iterations and the no-progress stop
        ``no_progress`` (after so many iterations, the level to get below; 0: none) inside the
        block; none after it."""
        self.crawl_its = crawl_its
        self.no_progress_its, self.no_progress_level = no_progress
        try:
            yield
        finally:
            self.crawl_its = self.no_progress_its = 0
            self.no_progress_level = np.inf

    def _observe(self, it: int, fnorm: float) -> None:
        """Record iteration ``it``'s ||F||."""
        if it == 0:
            self.fnorm0 = fnorm if self.fnorm0_kept is None else self.fnorm0_kept
            self.last_ratio, self.start = 1.0, fnorm
            self.best, self.above, self.stagnated = fnorm, 0, False
            self._halved_at, self._halved_best = 0, fnorm
            self._repeats = 0
        else:
            self.above = self.above + 1 if fnorm > STAGNATION_FACTOR * self.best else 0
            if fnorm <= 0.5 * self._halved_best:
                self._halved_at, self._halved_best = it, fnorm
            self.best = min(self.best, fnorm)
            self._repeats = self._repeats + 1 if fnorm == self.last_fnorm else 0
            self.last_ratio = fnorm / self.last_fnorm if self.last_fnorm > 0 else 1.0
        self.last_fnorm = fnorm

    def __call__(self, snes: PETSc.SNES, it: int, norms) -> int:
        xnorm, ynorm, fnorm = norms
        rtol, atol, stol, _ = snes.getTolerances()
        if not np.isfinite(fnorm):
            return _SNES_REASON.DIVERGED_FNORM_NAN
        self._observe(it, fnorm)
        if fnorm <= atol or fnorm <= self.force_rtol * self.force_scale:
            return _SNES_REASON.CONVERGED_FNORM_ABS
        if self.aimed:
            target = max(atol, self.force_rtol * self.force_scale, rtol * self.fnorm0)
            snes.getKSP().setTolerances(rtol=linear_solvers.step_rtol(it, fnorm, target),
                                        atol=0.0)
        if it == 0:
            return _SNES_REASON.ITERATING
        if fnorm <= rtol * self.fnorm0:
            return _SNES_REASON.CONVERGED_FNORM_RELATIVE
        at_round_off = fnorm <= self.stall_rtol * max(self.fnorm0, self.round_off_scale)
        if at_round_off and (ynorm <= stol * xnorm or self._repeats >= 2):
            # (or the same ||F||, to the last bit, three times: the iterate no longer moves —
            # SNES VI projecting each step back onto the bounds)
            return _SNES_REASON.CONVERGED_SNORM_RELATIVE
        return self._stopped(it)

    def _stopped(self, it: int) -> int:
        """DIVERGED_DTOL where a crawl, no-progress or stagnation stop ends the try at
        iteration ``it``; else ITERATING."""
        if (self.crawl_its and it - self._halved_at >= self.crawl_its
                and not any(term.holding for term in self.terms)):
            return _SNES_REASON.DIVERGED_DTOL
        if (self.no_progress_its and it >= self.no_progress_its
                and self.best >= min(self.start, self.no_progress_level)):
            return _SNES_REASON.DIVERGED_DTOL
        if self.stagnation_its and self.above >= self.stagnation_its:
            self.stagnated = True
            return _SNES_REASON.DIVERGED_DTOL
        return _SNES_REASON.ITERATING

    def stagnation_message(self) -> str:
        """The reason name of a stagnated solve."""
        return (f"stagnated ({self.stagnation_its} iterations with a residual above "
                f"{STAGNATION_FACTOR:g} × its best, {self.best:.3g})")
