# SPDX-License-Identifier: MIT
"""What every benchmark records: the machine and library versions, and the JSON result file."""

from __future__ import annotations

import json
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
