# SPDX-License-Identifier: MIT
"""The one place that chooses the iterative solver's preconditioner (:func:`configure`).

The step solver asks for "the iterative solver's options and the context of its preconditioner"
and names none of them: GAMG with the rigid-body modes for the displacement formulation; for the
mixed formulation the field split of :mod:`.fieldsplit`, whose displacement block is smoothed
over the vertex stars (:mod:`.star_smoother`, with their Schur complement :mod:`.star_schur`)
from :data:`~.p_multigrid.STARS_FROM` rows on, and whose Schur block takes the cycle's coarse
term only when asked (:mod:`.coarse_schur`, experimental).
"""

from __future__ import annotations

from typing import Callable, Optional

from petsc4py import PETSc

from vpcontact.errors import SolverOptionError
from vpcontact.solver import linear
import vpcontact.solver.pc.fieldsplit as fieldsplit
import vpcontact.solver.pc.p_multigrid as p_multigrid


def iterative_options(mixed: bool) -> dict:
    """KSP/PC options of the iterative solver (without prefix)."""
    return dict(fieldsplit.MIXED_OPTIONS if mixed else linear.DISPLACEMENT_OPTIONS)


def lagged_options(mixed: bool) -> dict:
    """Options of the VI's inner preconditioner on M (``lagged_`` + these): the same PC."""
    options = iterative_options(mixed)
    return {k: v for k, v in options.items() if not k.startswith("ksp_")}


def check_options(options: dict) -> None:
    """Refuse a preconditioner option that is read only inside a solve (the p-multigrid's
    ``pmg_smooth_stars``, ``pmg_schur_coarse``) and has an invalid value.

    Raises:
        ValueError: naming the option and the valid values.
    """
    p_multigrid.check_options(options)


def _both_splits(options: dict, option: str, decide: Callable[[str, str], bool]) -> bool:
    """Whether ``decide(key, value)`` holds for the ``pmg_`` ``option`` of both of the mixed
    formulation's field splits (Newton's and SNES VI's lagged one; an invalid value counts as
    no: it is refused when the options are read)."""
    try:
        return all(decide(key, options.get(key, "auto"))
                   for key in (f"fieldsplit_u_pmg_{option}", f"lagged_fieldsplit_u_pmg_{option}"))
    except ValueError:
        return False


def _uses_stars(options: dict, rows: int) -> bool:
    """Whether both field splits smooth a displacement block of ``rows`` rows over the stars."""
    return _both_splits(options, "smooth_stars",
                        lambda key, value: p_multigrid.uses_stars(key, value, rows))


def _uses_coarse_schur(options: dict) -> bool:
    """Whether both field splits' Schur blocks take the cycle's coarse term (with the stars)."""
    return _both_splits(options, "schur_coarse", p_multigrid.uses_coarse_schur)


def configure(fields, modes: PETSc.NullSpace, scale: float, prefix: str,
              rotation: Optional[PETSc.Mat], user_options: dict,
              defaults: dict) -> tuple[dict, Optional[fieldsplit.BlockPreconditioner]]:
    """The iterative solver's preconditioner: ``defaults`` with its options (Newton's and, under
    ``lagged_``, SNES VI's inner one), and the application context of a mixed formulation's
    field split (None for the displacement formulation: GAMG, the caller gives the matrix the
    near null space ``modes``).

    Args:
        fields: the field layout (a pressure field: the mixed formulation).
        modes: the rigid-body modes in the layout of the SNES vector.
        scale: SNES's displacement scale.
        prefix: the step solver's options prefix (the python PCs find their context by it).
        rotation: the local frames' rotation R of the unknowns, or None.
        user_options: the user's options (``pmg_smooth_stars``, ``pmg_schur_coarse`` decide
            the Schur block's set-up here).
        defaults: the step's default options.

    Raises:
        SolverOptionError: the coarse Schur term asked for without the vertex stars.
    """
    mixed = len(fields.functions) > 1
    defaults = {**defaults, **iterative_options(mixed),
                **{"lagged_" + k: v for k, v in lagged_options(mixed).items()}}
    defaults["vpcontact_vi_linear"] = "lagged_gamg"
    if not mixed:
        return defaults, None
    rows = fields.field_indices()["displacement"].getSize()
    stars = _uses_stars(user_options, rows)
    coarse = _uses_coarse_schur(user_options)
    if coarse and not stars:
        raise SolverOptionError(
            "pmg_schur_coarse needs the vertex-star smoothing (and is experimental: off by "
            "default, slower on every mesh measured): give "
            "pmg_smooth_stars = true to both field splits (fieldsplit_u_ and "
            f"lagged_fieldsplit_u_), or leave it to auto with at least "
            f"{p_multigrid.STARS_FROM} displacement unknowns (here {rows})",
            "fieldsplit_u_pmg_schur_coarse")
    if coarse:  # the stars' Schur complement with the cycle's coarse term
        defaults = fieldsplit.coarse_schur_options(defaults)
    elif stars:  # the Schur complement from the stars' factors
        defaults = fieldsplit.star_schur_options(defaults)
    block = fieldsplit.BlockPreconditioner(fields, modes, scale, prefix=prefix, rotation=rotation,
                                           stars=stars, coarse=coarse)
    return defaults, block
