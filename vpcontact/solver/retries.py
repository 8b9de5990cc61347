# SPDX-License-Identifier: MIT
"""What a step does when its first SNES run does not converge: strategy objects built from the
nodal terms' own protocol (:class:`~vpcontact.model.nodal_terms.NodalTerm`: ``first_try``,
``has_fallback()``/``fallback(x)``, ``second_try``/``freeze(stick)``/``thaw()``, ``holding``)
and the parts' rescue line search; the step solver runs :class:`StepRetries` and knows none of
them.

* :class:`OtherGuess`: where a term has another guess (friction on a compliant part: sticking,
  :class:`~vpcontact.model.friction.StickingGuess`), a limited first try from the extrapolated
  guess, finished where it is in Newton's fast phase (:data:`FINISHING_RATIO`), then the other
  guess (stopped where it makes no progress, :data:`NO_PROGRESS_ITERATIONS`);
* :class:`Predictor`: where a term has a predictor (Coulomb friction on a Signorini part), a
  limited second try stopped where it crawls (:data:`CRAWL_ITERATIONS`), then the predictor's
  stages from the other guess;
* :class:`Rescue`: the step once more with the rescue line search before it is cut.

Each runs SNES through its ``runner`` (the step solver: ``snes``, ``x``, ``test`` — the
:class:`~vpcontact.solver.convergence.ConvergenceTest` —, ``run()``, ``predict()``,
``invalidate()``, ``read_multipliers(x)`` and ``usual_line_search``); the sequence of SNES runs
and their settings is the step solver's as it was before these strategies were taken out of it.
"""

from __future__ import annotations

import contextlib
from typing import Optional, Sequence

import numpy as np
from petsc4py import PETSc

from vpcontact.solver.line_search import set_line_search

#: Newton iterations of a failed step's second try with the rescue line search
#: (:class:`Rescue`): a quick attempt before the step is cut (where it converged, it
#: took 7; in a scene whose dragging steps fail either way, 50 more per failed step cost 1 184
#: iterations in the run against 680)
RESCUE_ITERATIONS = 15
#: Newton iterations of each stage of a nodal term's predictor (:class:`Predictor`)
PREDICTOR_ITERATIONS = 20
#: The try before a predictor (:class:`OtherGuess`) gives up once this many
#: Newton iterations in a row have not halved its best ||F||: a crawl the predictor cuts short.
#: On the dragged block's hard step (its slip zone spreading over the face) 19 / 21 / 22 / 27
#: Newton iterations on 64×16 / 128×32 / 256×64 / 512×128 cells became 13 / 15 / 16 / 21; the
#: squeezed block's first step 19 → 15 and the rigid-and-compliant scene 109 → 106 in its run;
#: every other step and the viscoplastic scratch benchmark took what they took (2: the dragged
#: block's first dragging step, which converges in 6–7, went to the predictor: 10–12). Not
#: while a term is still bringing nodes back into their cones (``holding``: friction's
#: unloading nodes, :meth:`~vpcontact.model.nodal_friction.NodalFriction._unloading`): on
#: 512×128 cells the hard step converges at the 12th iteration, and stopped at the 11th, it
#: took 31 through the predictor
CRAWL_ITERATIONS = 3
#: A first try (:class:`OtherGuess`) whose budget runs out while its last
#: iteration cut ||F|| by at least this factor is in Newton's fast phase: it goes on, for at
#: most FINISHING_ITERATIONS more, from where it is (and toward the same target), instead of
#: starting again from the other guess. The paper's 3-D beam on a compliant foundation with
#: Tresca friction and the mixed formulation (6×2×2 cells, k = 0.02): the first try fell 0.117 →
#: 9.1e-4 in its 5 iterations (ratios 0.47, 0.16, 0.18 at the end), the sticking guess then
#: started at 1.15 and crawled for 50, and the run took 24 steps for 10 (17 cut, 24.5 s).
FINISHING_RATIO, FINISHING_ITERATIONS = 0.25, 5
#: The other guess's try (a compliant part's sticking guess) stops when after this many Newton
#: iterations its best ||F|| is still above its own first one and above the first try's last
#: one, and the step goes on from the first try's last iterate instead. On the beam above (P2
#: displacements or the mixed formulation) the sticking guess put the contact nodes back where
#: the last step left them, 10–100 times the extrapolation's ||F||, and from there Newton
#: wandered between 1.4 and 3 for 50 iterations where the first try was converging, slowly
#: (||F|| × 0.7–0.9 per iteration).
NO_PROGRESS_ITERATIONS = 5


def longest_first_try(terms) -> int:
    """The longest ``first_try`` among nodal terms (None or absent: the term has no other
    guess); 0 when none has one."""
    tries = [getattr(term, "first_try", None) for term in terms]
    return max([n for n in tries if n is not None] or [0])


@contextlib.contextmanager
def snes_settings(runner, max_its: Optional[int] = None, line_search: str = "",
                  crawl_its: int = 0, no_progress: tuple = (0, np.inf)):
    """The runner's SNES with at most ``max_its`` Newton iterations (None: as set; fewer if SNES
    allows fewer), the line search ``line_search`` (empty: the usual one, left alone), the
    crawl stop after ``crawl_its`` iterations and the no-progress stop ``no_progress`` (see
    :meth:`~vpcontact.solver.convergence.ConvergenceTest.stops`) inside the block; all
    restored after it."""
    snes = runner.snes
    if line_search:
        set_line_search(snes, line_search)
    max_it = snes.getTolerances()[3]
    if max_its is not None:
        snes.setTolerances(max_it=min(max_its, max_it))
    try:
        with runner.test.stops(crawl_its, no_progress):
            yield
    finally:
        if max_its is not None:
            snes.setTolerances(max_it=max_it)
        if line_search:
            set_line_search(snes, runner.usual_line_search)


def run_limited(runner, max_its: int, crawl_its: int = 0) -> tuple[int, int]:
    """The runner's SNES with at most ``max_its`` Newton iterations (fewer if SNES allows
    fewer); with ``crawl_its``, stopped (diverged) once that many in a row have not halved the
    best ||F|| (:data:`CRAWL_ITERATIONS`): (converged reason, iterations)."""
    with snes_settings(runner, max_its, crawl_its=crawl_its):
        return runner.run()


class Predictor:
    """SNES from the fallback guess in ``runner.x`` once the terms' predictor has moved it
    (Coulomb friction on a Signorini part, :meth:`~vpcontact.model.nodal_friction.
    NodalFriction.freeze`): first every pressed node sticks, then the thresholds are fixed at
    that iterate's (Tresca's law, whose Newton iteration spreads a slip zone in a few
    iterations; kept only where it converged), then the step is solved with the terms' own law
    from there, with the rescue line search if there is one (a block pressed by a rigid plane
    with friction onto a compliant floor with friction and dragged: no step cut and 109 Newton
    iterations in the run, against 308 and a cut step with ``cp``). The first two stages have
    :data:`PREDICTOR_ITERATIONS` each. (Iterations of all count.)"""

    def __init__(self, runner, rescue_line_search: str):
        self.runner = runner
        self.line_search = rescue_line_search

    def run(self, terms) -> tuple[int, int]:
        runner = self.runner
        try:
            for term in terms:
                term.freeze(stick=True)
            _, its = run_limited(runner, PREDICTOR_ITERATIONS)
            runner.read_multipliers(runner.x)
            for term in terms:
                term.freeze(stick=False)
            stuck = runner.x.copy()
            reason, more = run_limited(runner, PREDICTOR_ITERATIONS)
            its += more
            if reason <= 0:
                stuck.copy(runner.x)
            stuck.destroy()
        finally:
            for term in terms:
                term.thaw()
        runner.invalidate()
        with snes_settings(runner, line_search=self.line_search):
            reason, more = runner.run()
        return reason, its + more


class OtherGuess:
    """SNES from the guess; where a nodal term has another guess (friction on a compliant part:
    sticking, see :class:`~vpcontact.model.friction.StickingGuess`), the first try stops after
    the longest ``first_try`` of the terms that have one this step (friction on a compliant
    part: 5, :data:`~vpcontact.model.friction.FIRST_TRY`, or 8 at the onset of contact; on a
    Signorini part 0: its extrapolated guess is kept only where it already solves the step)
    and, unconverged, SNES starts again from the other guess. Where a term has a predictor
    (Coulomb friction on a Signorini part: ``second_try`` = 15), that second try is limited too
    (and stops where it crawls, :data:`CRAWL_ITERATIONS`) and, unconverged, the step starts
    once more from the other guess with the :class:`Predictor` (not if ``predict`` is False).
    (Iterations of all count.)"""

    def __init__(self, runner, terms: Sequence, predictor: Predictor):
        self.runner = runner
        self.terms = terms
        self.predictor = predictor

    def run(self, predict: bool = True) -> tuple[int, int]:
        runner = self.runner
        having = [term.has_fallback() for term in self.terms]  # (collective: no short cut)
        if not any(having):
            return runner.run()
        first_try = longest_first_try([t for t, has in zip(self.terms, having) if has])
        guess = runner.x.copy()
        reason, first = run_limited(runner, first_try)
        if reason <= 0 and first_try > 0 and runner.test.last_ratio <= FINISHING_RATIO:
            reason, more = self._finish()
            first += more
        if reason > 0:
            guess.destroy()
            return reason, first
        predictors = [t for t, has in zip(self.terms, having)
                      if predict and has and getattr(t, "second_try", None) is not None]
        tried, tried_norm = runner.x.copy(), runner.test.last_fnorm  # the first try's last iterate
        try:
            self._fall_back(guess)
            if not predictors:
                reason, more = self._from_other_guess(tried, tried_norm)
                return reason, first + more
            reason, more = run_limited(runner, max(t.second_try for t in predictors),
                                       crawl_its=CRAWL_ITERATIONS)
            if reason > 0:
                return reason, first + more
            self._fall_back(guess)
            reason, last = self.predictor.run(predictors)
        finally:
            guess.destroy()
            tried.destroy()
        return reason, first + more + last

    def _from_other_guess(self, tried: PETSc.Vec, tried_norm: float) -> tuple[int, int]:
        """SNES from the other guess (in ``runner.x``) with the no-progress stop; where it makes
        none, on from the first try's last iterate ``tried`` (its ||F||: ``tried_norm``)."""
        runner = self.runner
        with snes_settings(runner, no_progress=(NO_PROGRESS_ITERATIONS, tried_norm)):
            reason, more = runner.run()
        if reason <= 0 and runner.test.best >= min(runner.test.start, tried_norm):
            # no progress from the other guess: on from the first try's iterate
            tried.copy(runner.x)
            runner.invalidate()
            reason, last = runner.run()
            more += last
        return reason, more

    def _finish(self) -> tuple[int, int]:
        """A try that ran out of iterations in Newton's fast phase goes on from its last iterate
        (in ``runner.x``) toward the same target (its ||F_0||), :data:`FINISHING_ITERATIONS`
        more."""
        test = self.runner.test
        test.fnorm0_kept = test.fnorm0
        try:
            return run_limited(self.runner, FINISHING_ITERATIONS)
        finally:
            test.fnorm0_kept = None

    def _fall_back(self, guess: PETSc.Vec) -> None:
        """``runner.x`` ← the terms' fallback guesses from ``guess`` (from the last try's
        iterate where a term takes something from it: friction on a compliant part at the
        onset)."""
        x = self.runner.x
        guess.copy(x)
        for term in self.terms:
            term.fallback(x)
        self.runner.invalidate()


class Rescue:
    """The step once more from its initial guess with the rescue line search
    (``vpcontact_rescue_linesearch``), before the caller cuts the step; the usual one is
    restored after it. (A block clamped at one end and squeezed by a frictionless rigid plane
    onto a rigid floor with Coulomb friction: the critical-point search stalled at every step
    size, ``l2`` converges in 7 iterations; ``l2`` alone cut the steps of other dragged blocks,
    README.)"""

    def __init__(self, runner, line_search: str, other_guess: OtherGuess):
        self.runner = runner
        self.line_search = line_search
        self.other_guess = other_guess

    def run(self, guess: PETSc.Vec) -> tuple[int, int]:
        guess.copy(self.runner.x)
        self.runner.predict()
        with snes_settings(self.runner, RESCUE_ITERATIONS, self.line_search):
            return self.other_guess.run(predict=False)  # (a quick try: no predictor)


class StepRetries:
    """The SNES runs of one step: :class:`OtherGuess` (with its :class:`Predictor`) and, where
    the parts ask for a rescue line search and the step failed without stagnating,
    :class:`Rescue` from the step's initial guess.

    Args:
        runner: the step solver.
        terms: the nodal terms.
        rescue_line_search: ``vpcontact_rescue_linesearch`` (empty: no rescue).
    """

    def __init__(self, runner, terms: Sequence, rescue_line_search: str):
        self.runner = runner
        self.other_guess = OtherGuess(runner, terms, Predictor(runner, rescue_line_search))
        self.rescue = (Rescue(runner, rescue_line_search, self.other_guess)
                       if rescue_line_search else None)

    def run(self) -> tuple[int, int]:
        """SNES from ``runner.x`` with the retries: (converged reason, iterations of all)."""
        start_guess = self.runner.x.copy() if self.rescue is not None else None
        try:
            reason, its = self.other_guess.run()
            if reason <= 0 and start_guess is not None and not self.runner.test.stagnated:
                reason, more = self.rescue.run(start_guess)
                its += more
        finally:
            if start_guess is not None:
                start_guess.destroy()
        return reason, its
