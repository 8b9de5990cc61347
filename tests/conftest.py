# SPDX-License-Identifier: MIT
"""Shared fixtures: a temporary folder that is the same on every MPI rank.

On more than one rank, a test that fails on some ranks only leaves the others waiting in the next
collective call. So a failure on any rank prints its report and aborts the whole MPI job at once,
with a non-zero exit, instead of letting the run hang until its time limit.
"""

import logging
import sys
from pathlib import Path

import pytest
from mpi4py import MPI

logging.getLogger().setLevel(logging.WARNING)  # the form compiler logs its builds at INFO


@pytest.fixture
def shared_tmp_path(tmp_path) -> Path:
    """rank 0's tmp_path, broadcast so that all ranks read and write the same folder."""
    return Path(MPI.COMM_WORLD.bcast(str(tmp_path), root=0))


def pytest_runtest_logreport(report):
    comm = MPI.COMM_WORLD
    if comm.size == 1 or not report.failed:
        return
    sys.stderr.write(f"\n[rank {comm.rank} of {comm.size}] {report.nodeid} failed "
                     f"({report.when}):\n{report.longreprtext}\n"
                     f"[rank {comm.rank}] aborting the MPI job\n")
    sys.stderr.flush()
    comm.Abort(1)
