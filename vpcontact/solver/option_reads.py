# SPDX-License-Identifier: MIT
"""Which of the user's PETSc options were ever read: a misspelt option (``snes_linesearh_type``)
is otherwise silently ignored, and the run uses PETSc's default instead.

PETSc marks an entry of its options database as used when a solver queries it
(``PetscOptionsUsed``, which petsc4py 3.18 does not bind: called here through ctypes). The step
solver puts its options into the database only while a solver reads them and removes them after
(:func:`~vpcontact.solver.snes_options._forget`, :func:`~vpcontact.solver.vi_linear.
options_in_database`), so the flags are collected (:class:`OptionReads`) before every removal.

An option can be judged only once everything that could read it has run. Two moments:

* **at set-up** (refused, before anything is written): ``vpcontact_*`` (vpcontact reads all of
  its own there), ``snes_*`` (SNESSetFromOptions, with its line search and type-specific
  options), and, where the scene chose the direct linear solver (``linear = "direct"``: KSP
  ``preonly``, PC ``lu``/``cholesky``), ``ksp_*`` and ``pc_*``. Names with :data:`SOLVE_TIME_WORDS` (viewers, converged reasons,
  Jacobian tests, monitors) wait for a solve.
* **after the run's solves** (a warning), when at least one solve ran with the options in the
  database: the names above that wait for a solve, ``ksp_*``/``pc_*`` otherwise (``auto``
  may give a small mesh the direct solver and a large one the iterative one), ``mat_*`` with the direct one (MUMPS reads ``mat_mumps_*`` at factorization), and
  names of no prefix PETSc knows here (``snse_rtol``).

Never judged: options of sub-solvers that are set up only in some runs or read under their own
prefix — :data:`NOT_JUDGED` (``lagged_*``, the VI's linear solver, built only where contact
becomes active; ``fieldsplit_*``, ``mg_*``, ``pmg_*``, ``sub_*`` of the iterative solvers), and
``mat_*`` with the iterative solvers.
"""

from __future__ import annotations

import ctypes
import difflib
import logging
from functools import lru_cache
from typing import Iterable, Optional

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.errors import SolverOptionError

log = logging.getLogger(__name__)

#: words of option names PETSc reads only while solving (at the end of SNESSolve or KSPSolve,
#: in the Jacobian's evaluation), never at SNESSetFromOptions/KSPSetFromOptions
SOLVE_TIME_WORDS = ("view", "reason", "test", "compare", "monitor", "compute", "draw", "plot",
                    "log", "dump")
#: first words of options read by sub-solvers that only some runs set up
NOT_JUDGED = ("lagged", "fieldsplit", "mg", "pmg", "sub")


@lru_cache(maxsize=1)
def _options_used():
    """``PetscOptionsUsed(options, name, &used)`` of the PETSc library petsc4py is linked to
    (found through petsc4py's own extension module); None if it cannot be found."""
    try:
        function = ctypes.CDLL(PETSc.__file__).PetscOptionsUsed
    except (OSError, AttributeError) as err:  # pragma: no cover (a PETSc without the symbol)
        log.warning("cannot check which PETSc options were read (%s)", err)
        return None
    function.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.POINTER(ctypes.c_int)]
    function.restype = ctypes.c_int
    return function


def read_by_petsc(name: str) -> Optional[bool]:
    """Whether the entry ``name`` (full name, prefix included, no leading "-") of PETSc's
    global options database has been queried since it was set; None if that cannot be asked."""
    function = _options_used()
    if function is None:
        return None
    used = ctypes.c_int(0)
    if function(None, name.encode(), ctypes.byref(used)) != 0:
        return None
    return bool(used.value)


def decided_at_setup(key: str, direct: bool) -> bool:
    """Whether every reader of ``key`` has run once the step's SNES, KSP and PC have read their
    options (``direct``: the scene chose a factorization under ``preonly``)."""
    if key.startswith("vpcontact_"):
        return True
    if any(word in key for word in SOLVE_TIME_WORDS):
        return False
    return key.startswith("snes_") or (direct and key.startswith(("ksp_", "pc_")))


def judged_after_solves(key: str, direct: bool) -> bool:
    """Whether every reader of ``key`` has run once a solve ran with the options in PETSc's
    database (see the module's docstring)."""
    first = key.split("_", 1)[0]
    if first in NOT_JUDGED:
        return False
    return direct or first != "mat"


class OptionReads:
    """The user's option names (without prefix) that PETSc read at least once, under any of a
    step solver's prefixes (its own and its unconstrained twin's, ``<prefix>free_``).

    Args:
        keys: the options to follow (the user's; ``vpcontact_*`` included: vpcontact reads its
            own through the same database).
    """

    def __init__(self, keys: Iterable[str]):
        self.keys = tuple(sorted(set(keys)))
        self.read: set[str] = set()
        self.solves = 0  # solves run with the options in the database
        self.available = _options_used() is not None

    def note(self, prefix: str) -> None:
        """Record which followed options under ``prefix`` PETSc has read (call before they are
        removed from the database)."""
        if not self.available:
            return
        for key in self.keys:  # (not Options.hasName: asking marks the entry used)
            if key not in self.read and read_by_petsc(prefix + key):
                self.read.add(key)

    def unread(self, comm: MPI.Comm, judged) -> list[str]:
        """The followed options for which ``judged(key)`` holds that no process saw read
        (collective: every process gets the same list)."""
        if not self.available:
            return []
        flags = np.array([key in self.read for key in self.keys], dtype=np.int32)
        comm.Allreduce(MPI.IN_PLACE, flags, op=MPI.MAX)
        return [key for key, flag in zip(self.keys, flags) if not flag and judged(key)]



def unread_error(keys: list[str], solvers: str, own: Iterable[str]) -> SolverOptionError:
    """The refusal of options nothing read when the step's solvers were set up (``solvers``:
    their types, for the message; ``own``: vpcontact's option names)."""
    own = sorted(own)
    problems = {}
    for key in keys:
        if key.startswith("vpcontact_"):
            close = difflib.get_close_matches(key, own, n=1)
            hint = f'did you mean "{close[0]}"? ' if close else ""
            problems[key] = (f"not an option of vpcontact ({hint}its options: "
                             f"{', '.join(own)})")
        else:
            problems[key] = (f"PETSc never read this option when the step's solver was set up "
                             f"({solvers}): a misspelt name, or one these solvers do not take "
                             "(see the PETSc manual pages of SNESSetFromOptions, "
                             "KSPSetFromOptions and PCSetFromOptions)")
    message = "; ".join(f"{key}: {text}" for key, text in problems.items())
    return SolverOptionError(message, keys[0], problems)
