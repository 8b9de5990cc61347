# SPDX-License-Identifier: MIT
"""Where a python preconditioner of :mod:`vpcontact.solver.pc` finds its context.

PETSc creates the python PC contexts itself (``pc_type python`` with ``pc_python_type``), deep
inside a field split that the step solver only configures; as Firedrake's ``PCBase`` classes
call ``get_appctx(pc)``, each finds what it needs (the coarse space, the rigid-body modes, the
frames, the Schur complement's parts) with :func:`get_appctx` from the PC itself: the context
registered (:func:`attach`) under the longest options prefix that the PC's own prefix starts with
(the step solver's, e.g. ``vpcontact_step_0_``; the split's sub-PC is
``vpcontact_step_0_fieldsplit_u_`` or, inside SNES VI, ``vpcontact_step_0_lagged_fieldsplit_u_``).
Prefixes are rank-independent, so every process finds the same context.
"""

from __future__ import annotations

import weakref

from petsc4py import PETSc

from vpcontact.errors import SolverOptionError

_CONTEXTS: "weakref.WeakValueDictionary[str, object]" = weakref.WeakValueDictionary()


def attach(prefix: str, context) -> None:
    """Make ``context`` the application context of every PC under options ``prefix`` (kept
    while the caller holds ``context``)."""
    _CONTEXTS[prefix] = context


def lookup(prefix: str):
    """The context registered under the longest key ``prefix`` starts with.

    Raises:
        SolverOptionError: none is (a python PC of this package used outside the mixed
            formulation's step solver).
    """
    matches = [key for key in _CONTEXTS.keys() if prefix.startswith(key)]
    if not matches:
        raise SolverOptionError(f"no P1 coarse space registered for the options prefix "
                                f"{prefix!r} (pc_type python with vpcontact's p-multigrid "
                                "needs the mixed formulation's step solver)")
    return _CONTEXTS[max(matches, key=len)]


def get_appctx(pc: PETSc.PC):
    """The application context of ``pc`` (:func:`lookup` by its options prefix)."""
    return lookup(pc.getOptionsPrefix() or "")
