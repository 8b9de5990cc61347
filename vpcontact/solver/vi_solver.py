# SPDX-License-Identifier: MIT
"""SNES VI's linear solver: the reduced systems solved with a kept full-size preconditioner
(:mod:`vpcontact.solver.vi_linear`), set up on the step's SNES (:func:`use_lagged_solver`), and
when to try lagged factors (:class:`LagPolicy`)."""

from __future__ import annotations

from typing import Callable, Optional

from petsc4py import PETSc

from vpcontact.solver import linear as linear_solvers
from vpcontact.solver.vi_linear import LaggedDirectSolve, LaggedMultigrid


class LagPolicy:
    """When to try lagged factors (measured on the paper's 3-D test, k = 0.01-0.02): with a
    Jacobian fixed within the step (``fixed``); at a step's first iteration (the last step's
    factors usually still fit); and once Newton is in its final phase, ||F|| <=
    ``vpcontact_vi_lag_below`` ||F_0||. In between, quadrature points still switch between the
    elastic and the plastic branch: allowing the lag there too (lag_below = 1) halves the
    factorizations but doubles the substitutions, a net loss of 30-45 %.

    Args:
        snes: the step's SNES.
        test: its :class:`~vpcontact.solver.convergence.ConvergenceTest` (``fnorm0``).
        lag_below: ``vpcontact_vi_lag_below``.
        fixed: whether the Jacobian is fixed within the step (asked at every call: the step
            solver's flags may change after set-up).
    """

    def __init__(self, snes: PETSc.SNES, test, lag_below: float, fixed: Callable[[], bool]):
        self.snes, self.test, self.lag_below, self.fixed = snes, test, lag_below, fixed

    def __call__(self) -> bool:
        return (self.fixed() or self.snes.getIterationNumber() == 0
                or self.snes.getFunctionNorm() <= self.lag_below * self.test.fnorm0)


def use_lagged_solver(snes: PETSc.SNES, A: PETSc.Mat, prefix: str, options: dict,
                      vi_linear: str, modes: Callable[[], PETSc.NullSpace], block,
                      lag_allowed: Callable[[], bool], aimed: bool, bounds
                      ) -> LaggedDirectSolve | LaggedMultigrid:
    """Give ``snes`` (SNES VI) the lagged solver ``vi_linear`` (``lagged_lu`` or
    ``lagged_gamg``) on its Jacobian ``A``, with the ``lagged_`` ``options`` under
    ``prefix`` + ``lagged_``; ``modes()``: the rigid-body modes (multigrid); ``block``: the
    mixed formulation's preconditioner context, or None; ``aimed``: the step's solves are aimed
    (a Jacobian fixed within the step and the block preconditioner), within ``bounds``."""
    inner = {k[len("lagged_"):]: v for k, v in options.items() if k.startswith("lagged_")}
    solver: LaggedDirectSolve | LaggedMultigrid
    if vi_linear == "lagged_lu":
        solver = LaggedDirectSolve(snes, A, prefix + "lagged_", inner)
        solver.lag_allowed = lag_allowed
    else:
        solver = LaggedMultigrid(snes, A, prefix + "lagged_", modes(), inner)
        if block is not None:  # a saddle point: GMRES, and the fields on M
            solver.allow_cg = False
            solver.configure = block.configure
            block.solver = solver  # its rebuilds: the block's policy
    ksp = snes.getKSP()
    ksp.setType("python")
    ksp.setPythonContext(solver)
    ksp.getPC().setType("none")  # the context solves; PETSc must not factorize J_II
    # Direct (lagged factors): GMRES to 1e-9 costs a few substitutions. The block
    # preconditioner of the mixed formulation: an inexact Newton step (rtol
    # ITERATIVE_RTOL) keeps Newton's iteration count (see vpcontact.solver.linear).
    rtol = linear_solvers.ITERATIVE_RTOL if block is not None else 1e-9
    ksp.setTolerances(rtol=rtol, atol=0.0)
    # With a Jacobian fixed within the step, each solve aims at what the step needs
    # (linear_solvers.step_rtol, set by the convergence test); one that stops short of it but
    # within ITERATIVE_RTOL is still a usable Newton direction.
    if aimed:
        solver.accept_rtol = linear_solvers.ITERATIVE_RTOL
        solver.bounds = bounds
        solver.probe_rtol = linear_solvers.STEP_FIRST_RTOL
    return solver


def expire_if(solver: Optional[LaggedDirectSolve | LaggedMultigrid], multigrid_only: bool = False
              ) -> None:
    """Expire ``solver``'s kept preconditioner (if any; ``multigrid_only``: only a lagged
    multigrid's hierarchy)."""
    if solver is None or (multigrid_only and not isinstance(solver, LaggedMultigrid)):
        return
    solver.expire()
