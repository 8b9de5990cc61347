# SPDX-License-Identifier: MIT
"""Which linear solver a step gets: ``[solver] linear = "auto" | "direct" | "iterative"``.

Pure Python (the scene reader validates the key without the finite-element stack); the solvers
themselves are set up by :mod:`vpcontact.solver.linear`.
"""

from __future__ import annotations

#: Choices of ``[solver] linear``.
LINEAR_SOLVERS = ("auto", "direct", "iterative")

#: Unknowns from which ``auto`` picks the iterative solver (measured on this machine: see the
#: README's "Linear solvers").
ITERATIVE_FROM = 100_000


def choose(linear: str, unknowns: int) -> str:
    """``"direct"`` or ``"iterative"`` for ``[solver] linear`` and the problem's size."""
    if linear not in LINEAR_SOLVERS:
        raise ValueError(f"linear solver must be one of {LINEAR_SOLVERS}, got {linear!r}")
    if linear == "auto":
        return "iterative" if unknowns >= ITERATIVE_FROM else "direct"
    return linear
