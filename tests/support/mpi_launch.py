# SPDX-License-Identifier: MIT
"""MPI helpers for the tests: launching child processes (mpirun, the command line) and
writing a file that every rank then reads."""

import os
from pathlib import Path

from mpi4py import MPI


def clean_environment() -> dict:
    """The environment for a child mpirun or command. The test process itself is an MPI
    singleton; its Open MPI/PMIx variables must not leak into the child."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_"))}
    for key in ("OMPI_ALLOW_RUN_AS_ROOT", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM"):
        if key in os.environ:
            env[key] = os.environ[key]
    env["OMPI_MCA_rmaps_base_oversubscribe"] = "1"
    return env


def write_shared(path: Path, text: str) -> Path:
    """Write ``text`` on rank 0; every rank returns once the file exists.

    The first barrier keeps rank 0 from overwriting a file that another rank is still reading
    (tests read a scene, change it and write it back under the same name).
    """
    MPI.COMM_WORLD.barrier()
    if MPI.COMM_WORLD.rank == 0:
        path.write_text(text)
    MPI.COMM_WORLD.barrier()
    return path
