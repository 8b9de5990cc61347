# SPDX-License-Identifier: MIT
"""The step solver's PETSc options, SNES converged-reason names and its wall-time split."""

from __future__ import annotations

import re

import numpy as np

from petsc4py import PETSc

from vpcontact.errors import SolverOptionError

_REASONS = {v: k for k, v in vars(PETSc.SNES.ConvergedReason).items() if not k.startswith("_")}

DEFAULT_OPTIONS = {
    "snes_type": "newtonls",
    "snes_linesearch_type": "basic",
    "snes_rtol": 1e-10,
    "snes_atol": 1e-11,
    "snes_stol": 1e-11,  # a relative Newton step this small is at round-off (E ~ 1e8)
    # Round-off stops (snes_stol) also require ||F|| <= this * max(||F_0||, ||load||): a tiny
    # step alone may just be a stalled line search.
    "vpcontact_stall_rtol": 1e-6,
    # Also converged when ||F|| <= this * ||load||: the residual is then a force imbalance this
    # small relative to the applied loads (0 disables the test).
    "vpcontact_force_rtol": 0.0,
    "snes_max_it": 50,
    # Stop as diverged once this many Newton iterations in a row have left ||F|| above 10 times
    # its best in the step (the initial residual included): the step is then cut at once
    # instead of after snes_max_it (0: never). See vpcontact.solver.convergence.
    "vpcontact_stagnation_its": 12,
    "ksp_type": "preonly",
    "pc_type": "lu",
    # Linear solves of SNES VI (vpcontact.solver.vi_linear): "lagged_lu" (GMRES preconditioned by kept
    # factors of a full-size matrix, refactorized when they stop fitting), "lagged_gamg" (the
    # same with an algebraic multigrid cycle: for large 3-D meshes), or "petsc" (the ksp_/pc_
    # options on the reduced matrix, refactorized every iteration: PETSc's own behaviour).
    # Options of the inner solver go under "lagged_" (e.g. lagged_pc_gamg_threshold).
    "vpcontact_vi_linear": "lagged_lu",
    "vpcontact_vi_lag_below": 1e-2,
    # A line search to try a failed step once more with (at most RESCUE_ITERATIONS Newton
    # iterations) before it is cut; empty: none. Friction on a Signorini part asks for "l2".
    "vpcontact_rescue_linesearch": "",
}
if PETSc.Sys.hasExternalPackage("mumps"):
    DEFAULT_OPTIONS["pc_factor_mat_solver_type"] = "mumps"


_SNES_REASON = PETSc.SNES.ConvergedReason


def reason_name(reason: int) -> str:
    """Name of a SNES converged reason, e.g. ``DIVERGED_MAX_IT``."""
    return _REASONS.get(reason, f"UNKNOWN({reason})")


def _forget(prefix: str, keys) -> None:
    """Remove options this module put into PETSc's database once a solver has read them (the
    database holds at most 512 entries per process, and solvers are created many times)."""
    opts = PETSc.Options()
    for key in keys:
        if opts.hasName(prefix + key):
            opts.delValue(prefix + key)


#: options whose value PETSc takes but vpcontact cannot run with, and why
_UNSUPPORTED = {
    "snes_mf": "vpcontact assembles its Jacobians (and SNES VI needs them): no matrix-free SNES",
    "snes_mf_operator": "vpcontact assembles its Jacobians: no matrix-free operator",
}


#: options that take a PETSc viewer, or nothing to switch them on
_VIEWER_SUFFIXES = ("_view", "_monitor", "_converged_reason")


def viewer_flags(options: dict) -> dict:
    """``options`` with a boolean given to a viewer option (``snes_converged_reason = true``,
    natural in TOML) made PETSc's bare flag ("" on; off dropped): PETSc read "true" as a
    viewer's name and failed in the middle of a solve."""
    result = {}
    for key, value in options.items():
        word = str(value).strip().lower()
        if str(key).endswith(_VIEWER_SUFFIXES) and word in ("true", "1", "yes", "false", "0", "no"):
            if word in ("true", "1", "yes"):
                result[key] = ""
            continue
        result[key] = value
    return result


def check_values(options: dict) -> None:
    """Refuse, before any solver reads them, option values that PETSc would only refuse in the
    middle of a solve or not at all (a negative iteration count, a tolerance that is negative,
    NaN or infinite) and options vpcontact cannot run with; SolverOptionError naming the
    option. (Values that are not numbers, e.g. PETSc's ``default``, are left to PETSc.)"""
    for key, value in options.items():
        name = str(key).lstrip("-")
        if name in _UNSUPPORTED and str(value).strip().lower() not in ("0", "false", "no"):
            raise SolverOptionError(f"{name}: {_UNSUPPORTED[name]}", name)
        counted = name.endswith(("max_it", "max_funcs"))
        if not (counted or name.endswith(("rtol", "atol", "stol"))):
            continue
        try:
            number = float(str(value))
        except ValueError:
            continue
        if counted and not (np.isfinite(number) and number >= 0 and number == int(number)):
            raise SolverOptionError(f"{name} = {value!r}: must be a whole number >= 0", name)
        if not counted and not (np.isfinite(number) and number >= 0):
            raise SolverOptionError(f"{name} = {value!r}: must be a finite number >= 0", name)


def rejected_option(err: Exception, options: dict) -> SolverOptionError:
    """The error for PETSc options that PETSc (or vpcontact) refused while a solver was set up,
    in one line: PETSc's own reason (the last line of its error stack), and the option(s) whose
    value it names, else every option given."""
    lines = [line.split("] ", 1)[-1].strip() for line in str(err).splitlines() if line.strip()]
    reason = lines[-1] if lines else type(err).__name__
    named = [key for key, value in options.items()
             if re.search(rf"(?<![\w.-]){re.escape(str(value))}(?![\w.-])", reason)]
    given = ", ".join(f"{key} = {options[key]!r}" for key in (named or options))
    return SolverOptionError(
        f"invalid solver option(s) ({given or 'the defaults'}): {reason}. See the PETSc manual "
        "pages of SNESSetFromOptions, KSPSetFromOptions and PCSetFromOptions for the valid names "
        "and values", named[0] if len(named) == 1 else None)


def time_split(timings: dict) -> dict:
    """The parts of a solver's :attr:`timings` [s]: kernels, residual and Jacobian assembly,
    linear solves (KSPSolve), and the rest of the SNES solves (VI/active-set work: reduced
    matrices and index sets; line searches and vector work)."""
    rest = timings["snes"] - timings["kernel"] - timings["residual"] - timings["jacobian"]
    return {"kernel": timings["kernel"], "residual_assembly": timings["residual"],
            "jacobian_assembly": timings["jacobian"], "linear_solve": timings["linear_solve"],
            "vi_and_other_snes": rest - timings["linear_solve"]}
