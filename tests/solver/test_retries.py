# SPDX-License-Identifier: MIT
"""The retries of a step that does not converge (vpcontact.solver.retries) run SNES in the
sequence the step solver ran it before they were taken out of it: checked here on a scripted
runner (no finite elements), run by run, with each run's iteration limit, line search, crawl
and no-progress stops."""

from __future__ import annotations

from types import SimpleNamespace

from petsc4py import PETSc

from vpcontact.solver.convergence import ConvergenceTest
from vpcontact.solver.retries import StepRetries

FAILED = PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT
CONVERGED = PETSc.SNES.ConvergedReason.CONVERGED_FNORM_RELATIVE


class _Snes:
    """What the retries ask of SNES: its iteration limit and (through the options) its line
    search."""

    def __init__(self, line_search: str):
        self.max_it, self.line_search = 50, line_search

    def getTolerances(self):
        return 1e-10, 1e-11, 1e-11, self.max_it

    def setTolerances(self, max_it):
        self.max_it = max_it

    def getOptionsPrefix(self):
        return "retries_test_"

    def getKSP(self):
        return SimpleNamespace(reset=lambda: None)

    def setFromOptions(self):
        self.line_search = PETSc.Options().getString("retries_test_snes_linesearch_type",
                                                     self.line_search)


class _Runner:
    """Runs that return scripted outcomes (reason, its, and what the test saw: best, start,
    last_ratio) and record how each was set up."""

    def __init__(self, outcomes, line_search="cp"):
        self.snes = _Snes(line_search)
        self.usual_line_search = line_search
        self.x = PETSc.Vec().createSeq(2, comm=PETSc.COMM_SELF)
        self.test = ConvergenceTest([], 1e-6, 12, 0.0)
        self.outcomes, self.log = list(outcomes), []

    def run(self):
        reason, its, seen = self.outcomes.pop(0)
        test = self.test
        self.log.append((self.snes.max_it, self.snes.line_search, test.crawl_its,
                         test.no_progress_its, test.fnorm0_kept is not None))
        test.best, test.start, test.last_ratio = seen.get("best", 1.0), 1.0, seen.get("ratio", 1.0)
        test.last_fnorm, test.stagnated = seen.get("fnorm", 1.0), False
        return reason, its

    def predict(self):
        self.log.append("predict")

    def invalidate(self):
        pass

    def read_multipliers(self, x):
        self.log.append("multipliers")


class _Term:
    """A nodal term with another guess and (``second_try``) a predictor."""

    def __init__(self, first_try, second_try=None):
        self.first_try, self.second_try, self.holding = first_try, second_try, False
        self.calls = []

    def has_fallback(self):
        return True

    def fallback(self, x):
        self.calls.append("fallback")

    def freeze(self, stick):
        self.calls.append(f"freeze {stick}")

    def thaw(self):
        self.calls.append("thaw")


def test_coulomb_on_a_signorini_part_tries_the_predictor_then_the_rescue():
    term = _Term(first_try=0, second_try=15)
    runner = _Runner([(FAILED, 0, {}), (FAILED, 15, {}), (FAILED, 20, {}), (FAILED, 20, {}),
                      (FAILED, 50, {}), (FAILED, 0, {}), (FAILED, 5, {"best": 2.0}),
                      (CONVERGED, 7, {})])
    reason, its = StepRetries(runner, [term], "l2").run()
    assert (reason, its) == (CONVERGED, 15 + 20 + 20 + 50 + 5 + 7)
    # (max_it, line search, crawl stop, no-progress stop, a finishing try)
    assert runner.log == [
        (0, "cp", 0, 0, False),  # the extrapolated guess: first_try 0
        (15, "cp", 3, 0, False),  # the other guess: second_try, stopped where it crawls
        (20, "cp", 0, 0, False),  # the predictor: every pressed node sticks
        "multipliers",
        (20, "cp", 0, 0, False),  # ... Tresca with the thresholds of that iterate
        (50, "l2", 0, 0, False),  # ... the term's own law, with the rescue line search
        "predict",  # the rescue: from the step's initial guess, no predictor
        (0, "l2", 0, 0, False),
        (15, "l2", 0, 5, False),  # the other guess, stopped where it makes no progress
        (15, "l2", 0, 0, False)]  # ... so on from the first try's iterate
    assert runner.snes.max_it == 50 and runner.snes.line_search == "cp"  # (restored)
    assert term.calls == ["fallback", "fallback", "freeze True", "freeze False", "thaw",
                          "fallback"]


def test_a_first_try_in_newton_s_fast_phase_goes_on_toward_the_same_target():
    term = _Term(first_try=5)
    runner = _Runner([(FAILED, 5, {"ratio": 0.2}), (CONVERGED, 2, {})], line_search="l2")
    assert StepRetries(runner, [term], "").run() == (CONVERGED, 7)
    assert runner.log == [(5, "l2", 0, 0, False), (5, "l2", 0, 0, True)]
    assert runner.test.fnorm0_kept is None and term.calls == []


def test_without_another_guess_snes_runs_once():
    term = _Term(first_try=None)
    term.has_fallback = lambda: False
    runner = _Runner([(FAILED, 50, {})])
    assert StepRetries(runner, [term], "").run() == (FAILED, 50)
    assert runner.log == [(50, "cp", 0, 0, False)]
