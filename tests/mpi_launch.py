# SPDX-License-Identifier: MIT
"""Launching child processes (mpirun, the command line) from the tests."""

import os


def clean_environment() -> dict:
    """The environment for a child mpirun or command. The test process itself is an MPI
    singleton; its Open MPI/PMIx variables must not leak into the child."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_"))}
    for key in ("OMPI_ALLOW_RUN_AS_ROOT", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM"):
        if key in os.environ:
            env[key] = os.environ[key]
    env["OMPI_MCA_rmaps_base_oversubscribe"] = "1"
    return env
