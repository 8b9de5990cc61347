# SPDX-License-Identifier: MIT
"""Shared fixtures: a temporary folder that is the same on every MPI rank."""

import logging
from pathlib import Path

import pytest
from mpi4py import MPI

logging.getLogger().setLevel(logging.WARNING)  # the form compiler logs its builds at INFO


@pytest.fixture
def shared_tmp_path(tmp_path) -> Path:
    """rank 0's tmp_path, broadcast so that all ranks read and write the same folder."""
    return Path(MPI.COMM_WORLD.bcast(str(tmp_path), root=0))
