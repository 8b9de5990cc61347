# SPDX-License-Identifier: MIT
"""The line-search policy of a step: one function decides it (:func:`line_search_for`), one
switches it while a retry runs (:func:`set_line_search`).

The policy, from the law and the contact parts (each part says what it needs in its
``snes_defaults``, with the measurements in its docstring):

* a law not linear in ε (viscoplastic: stiff elastic against soft viscous branches): ``l2``,
  full Newton steps overshoot where points unload;
* a law linear in ε with a state-dependent tangent (the linearized scheme): ``bt``, which breaks
  SNES VI's cycling between two active sets (the paper's 3-D test on 18×6×6 cells: three steps
  cut after 50 iterations each with full steps, 2–6 iterations per step with ``bt``);
* otherwise PETSc's full steps (``basic``, :data:`~vpcontact.solver.snes_options.
  DEFAULT_OPTIONS`);
* then each part's own needs, in order (friction's line search; the VI solver of a rigid part);
  where parts disagree and one asks for ``cp``, ``cp`` (a block pressed by a rigid plane with
  friction onto a compliant floor with friction: 1 145 Newton iterations with ``l2``, 680 with
  ``cp``, in 29 / 22 steps).

A part may also ask for a rescue line search (``vpcontact_rescue_linesearch``), with which a
failed step is tried once more before it is cut (:class:`~vpcontact.solver.retries.Rescue`).
"""

from __future__ import annotations

from typing import Iterable

from petsc4py import PETSc

#: The line searches SNES knows, and the empty rescue line search (none)
LINE_SEARCHES = ("basic", "bt", "l2", "cp", "nleqerr")


def line_search_for(law, parts: Iterable) -> dict:
    """The SNES defaults (line search, and what the contact ``parts`` ask for with it: the VI
    solver, the rescue line search) of a step with constitutive ``law``, under the user's own
    options (module docstring)."""
    defaults = {}
    if not law.linear_in_strain:
        defaults["snes_linesearch_type"] = "l2"
    elif not law.constant_tangent:  # the linearized scheme: a tangent fixed within each step
        defaults["snes_linesearch_type"] = "bt"
    searches = []
    for part in parts:  # (a part's needs come first: friction's line search)
        wants = part.snes_defaults(law.linear_in_strain)
        searches.append(wants.get("snes_linesearch_type"))
        defaults.update(wants)
    if "cp" in searches:  # parts that disagree: the critical-point search
        defaults["snes_linesearch_type"] = "cp"
    return defaults


def set_line_search(snes: PETSc.SNES, kind: str) -> None:
    """Switch ``snes``'s line search (through PETSc's options: petsc4py 3.18 has no handle on
    it); every other setting keeps its value."""
    opts = PETSc.Options()
    key = snes.getOptionsPrefix() + "snes_linesearch_type"
    opts[key] = kind
    try:
        # (SNESSetFromOptions gives the KSP the full-size Jacobian again; SNES VI left it the
        # reduced one of its last iteration: reset it, as SNES VI does when the set changes)
        snes.getKSP().reset()
        snes.setFromOptions()
    finally:
        opts.delValue(key)
