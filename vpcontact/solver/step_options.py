# SPDX-License-Identifier: MIT
"""The step solver's own options (``vpcontact_*`` under its prefix, :class:`StepOptions`) and
the check of the user's options against what the solvers read (:class:`SolverTypes`; the
bookkeeping of reads is :mod:`.option_reads`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.solver.line_search import LINE_SEARCHES
from vpcontact.solver.option_reads import (OptionReads, decided_at_setup, judged_after_solves,
                                           unread_error)
from vpcontact.solver.snes_options import DEFAULT_OPTIONS


@dataclass
class StepOptions:
    """vpcontact's own options of a step solver (see
    :data:`~vpcontact.solver.snes_options.DEFAULT_OPTIONS`)."""

    stall_rtol: float
    stagnation_its: int
    force_rtol: float
    lag_below: float
    vi_linear: str
    rescue_line_search: str


def read_step_options(prefix: str, options: dict, check: Callable[[dict], None]) -> StepOptions:
    """Put ``options`` into PETSc's database under ``prefix`` (the SNES, KSP and PC read theirs
    when they are set from the options; the caller takes them out again) and read vpcontact's
    own; ``check(options)``: the preconditioners' own check.

    Raises:
        ValueError: an option with an invalid value, naming it.
    """
    opts = PETSc.Options()
    opts.prefixPush(prefix)
    try:
        for key, value in options.items():
            opts[key] = value
        read = StepOptions(
            stall_rtol=float(opts.getReal(prefix + "vpcontact_stall_rtol")),
            stagnation_its=int(opts.getReal(prefix + "vpcontact_stagnation_its")),
            force_rtol=float(opts.getReal(prefix + "vpcontact_force_rtol")),
            lag_below=float(opts.getReal(prefix + "vpcontact_vi_lag_below")),
            vi_linear=opts.getString(prefix + "vpcontact_vi_linear"),
            rescue_line_search=opts.getString(prefix + "vpcontact_rescue_linesearch", ""))
    finally:
        opts.prefixPop()
    _check(read)
    check(options)
    return read


def _check(read: StepOptions) -> None:
    """Refuse invalid values of vpcontact's own options."""
    if read.rescue_line_search not in ("",) + LINE_SEARCHES:
        raise ValueError("vpcontact_rescue_linesearch must be one of basic, bt, l2, cp, "
                         f"nleqerr or empty (none), got {read.rescue_line_search!r}")
    if read.vi_linear not in ("lagged_lu", "lagged_gamg", "petsc"):
        raise ValueError("vpcontact_vi_linear must be lagged_lu, lagged_gamg or petsc, got "
                         f"{read.vi_linear!r}")
    if not 0.0 <= read.force_rtol < 1.0:
        raise ValueError(f"vpcontact_force_rtol must be in [0, 1), got {read.force_rtol}")
    if not 0.0 < read.stall_rtol < 1.0:
        raise ValueError(f"vpcontact_stall_rtol must be in (0, 1), got {read.stall_rtol}")
    if read.stagnation_its < 0:
        raise ValueError("vpcontact_stagnation_its must be >= 0 (0: off), got "
                         f"{read.stagnation_its}")


class SolverTypes:
    """The step's solvers as set up, and which of the user's options they must have read.

    Args:
        snes: the step's SNES, set up.
        linear_given: ``[solver] linear`` as the user gave it.
    """

    def __init__(self, snes: PETSc.SNES, linear_given: str):
        ksp = snes.getKSP()
        #: the step's solver types as set up, e.g. ``SNES newtonls, KSP preonly, PC lu``
        self.solvers = (f"SNES {snes.getType()}, KSP {ksp.getType()}, "
                        f"PC {ksp.getPC().getType()}")
        # ksp_/pc_ options are judged at set-up only where the user chose the direct solver:
        # under "auto" they may be meant for the iterative one, which larger meshes get (a
        # warning after the solves then says the direct solver did not read them)
        self.direct = (ksp.getType() == "preonly"
                       and ksp.getPC().getType() in ("lu", "cholesky"))
        self.direct_chosen = self.direct and linear_given == "direct"

    def refuse_unread(self, reads: OptionReads, comm: MPI.Comm) -> None:
        """Refuse the user's options that nothing read at set-up, among those every reader of
        has run by then (:func:`~.option_reads.decided_at_setup`; collective).

        Raises:
            SolverOptionError: naming them.
        """
        unread = reads.unread(comm, lambda key: decided_at_setup(key, self.direct_chosen))
        if unread:
            own = [key for key in DEFAULT_OPTIONS if key.startswith("vpcontact_")]
            raise unread_error(unread, self.solvers, own)

    def unread_after_solves(self, reads: OptionReads, comm: MPI.Comm) -> list[str]:
        """The user's options that no solve read and that the run's solves would have read if
        PETSc knew them (:func:`~.option_reads.judged_after_solves`); empty before any solve
        ran with the options in PETSc's database. Collective."""
        if not comm.allreduce(reads.solves, op=MPI.MAX):
            return []
        return reads.unread(comm, lambda key: not decided_at_setup(key, self.direct_chosen)
                            and judged_after_solves(key, self.direct))
