# SPDX-License-Identifier: MIT
"""What every benchmark records: the machine and library versions, and the JSON result file; and
the checks of their command lines (argparse ``type=`` functions and a few checks across options),
so that a bad value ends in one line naming the option, exit status 2, before any work."""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
from pathlib import Path

import dolfinx
from petsc4py import PETSc


def blas() -> str:
    """The BLAS library the process loaded (Debian picks it through alternatives)."""
    try:
        maps = Path("/proc/self/maps").read_text()
    except OSError:
        return "unknown"
    names = sorted({line.split()[-1] for line in maps.splitlines() if "blas" in line.lower()})
    return ", ".join(names) or "unknown"


def machine(comm) -> dict:
    """Platform, Python, dolfinx, PETSc, BLAS and the number of MPI ranks."""
    return {"platform": platform.platform(), "processor": platform.processor(),
            "python": sys.version.split()[0], "dolfinx": dolfinx.__version__,
            "petsc": ".".join(map(str, PETSc.Sys.getVersion())), "blas": blas(),
            "mpi_ranks": comm.size}


def save(result: dict, out: str | Path, comm) -> None:
    """Write ``result`` as JSON (rank 0) and print it."""
    if comm.rank == 0:
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(result, indent=2) + "\n")
        print(json.dumps(result, indent=2))


#: dolfinx numbers a process's cells with 32-bit integers: a mesh of more cells cannot be made.
MAX_CELLS = 2**31 - 1
#: The most time steps (or repetitions) a run may ask for: more is a typo, not a benchmark (a
#: million steps of the smallest problem here take hours).
MAX_STEPS = 10**6


def int_range(low: int, high: int | None = None):
    """An argparse ``type=``: an integer in [low, high] (no upper bound when high is None)."""
    def check(text: str) -> int:
        value = int(text)  # (a ValueError: argparse's "invalid int value")
        if value < low or (high is not None and value > high):
            bound = f">= {low}" if high is None else f"in [{low}, {high}]"
            raise argparse.ArgumentTypeError(f"must be an integer {bound}, got {text!r}")
        return value
    check.__name__ = "int"
    return check


positive_int = int_range(1)
nonnegative_int = int_range(0)
positive_count = int_range(1, MAX_STEPS)  # steps, repetitions


def mesh_size(cells_per_n: int, dim: int):
    """An argparse ``type=``: the n of a mesh of ``cells_per_n`` · n^dim cells (e.g. 18 n³ for
    the 3n×n×n beam in tetrahedra), from 1 to the largest n whose mesh dolfinx can number."""
    return int_range(1, math.floor((MAX_CELLS / cells_per_n) ** (1.0 / dim) + 1e-9))


def finite_float(text: str) -> float:
    """An argparse ``type=``: a finite number."""
    value = float(text)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """An argparse ``type=``: a finite number > 0."""
    value = float(text)
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text!r}")
    return value


def positive_or_inf(text: str) -> float:
    """An argparse ``type=``: a number > 0, infinity allowed (a yield stress: inf, elastic)."""
    value = float(text)
    if not value > 0:  # (NaN too)
        raise argparse.ArgumentTypeError(f"must be a number > 0 (or inf), got {text!r}")
    return value


def relative_tolerance(text: str) -> float:
    """An argparse ``type=``: a relative tolerance, in (0, 1)."""
    value = float(text)
    if not 0 < value < 1:  # (NaN too)
        raise argparse.ArgumentTypeError(f"must lie in (0, 1), got {text!r}")
    return value


def key_value(text: str) -> str:
    """An argparse ``type=``: a ``KEY=VALUE`` option (returned as given)."""
    if "=" not in text or not text.split("=", 1)[0]:
        raise argparse.ArgumentTypeError(f"takes KEY=VALUE, got {text!r}")
    return text


def output_file(text: str) -> str:
    """An argparse ``type=``: a file to write: not an existing folder, nor under an existing
    file (missing folders are made by :func:`save`)."""
    path = Path(text)
    if text == "" or path.is_dir():
        raise argparse.ArgumentTypeError(f"must name a file, not a folder, got {text!r}")
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise argparse.ArgumentTypeError(f"{str(parent)!r} in {text!r} is a file, "
                                                 "not a folder")
            break
    return text


def check_cells(parser: argparse.ArgumentParser, option: str, cells: int) -> None:
    """Refuse a mesh of more cells than dolfinx can number (``option``: what asked for it)."""
    if cells > MAX_CELLS:
        parser.error(f"{option}: a mesh of {cells} cells, more than dolfinx can number "
                     f"({MAX_CELLS})")


def check_steps(parser: argparse.ArgumentParser, option: str, steps: float) -> None:
    """Refuse a run of more than :data:`MAX_STEPS` time steps (``option``: what asked for it)."""
    if not steps <= MAX_STEPS:
        parser.error(f"{option}: {steps:.3g} time steps, more than {MAX_STEPS} (a typo?)")
