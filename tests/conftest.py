# SPDX-License-Identifier: MIT
"""Shared fixtures: a temporary folder that is the same on every MPI rank, and the shared scene
files under tests/scenes/ (``scene_text``, ``scene_path``; see tests/support/scenes.py).

On more than one rank, a test that fails on some ranks only can leave the others waiting in a
collective call of the test. So after each test the ranks meet, on a communicator of their own
(whose collectives cannot match the tests'), in a non-blocking barrier that every rank polls for
:data:`AGREE_SECONDS`. When all ranks get there, the run goes on: a failure every rank saw is
reported by each, and the later tests still run, so one CI run shows every failure. When a rank
waits longer, another is stuck in the failed test: the waiting rank aborts the whole MPI job,
with a non-zero exit and the failure's report, instead of letting the run hang until its time
limit.
"""

import logging
import os
import sys
import time
from pathlib import Path

import pytest
from mpi4py import MPI

logging.getLogger().setLevel(logging.WARNING)  # the form compiler logs its builds at INFO

#: How long a rank that finished a test waits for the others (the slowest test's imbalance
#: between ranks is far below this).
AGREE_SECONDS = float(os.environ.get("VPCONTACT_TEST_AGREE_SECONDS", "60"))

_AGREE = MPI.COMM_WORLD.Dup() if MPI.COMM_WORLD.size > 1 else None
_failed: set = set()  # the tests that failed on this rank (until the ranks met after it)


@pytest.fixture
def shared_tmp_path(tmp_path) -> Path:
    """rank 0's tmp_path, broadcast so that all ranks read and write the same folder."""
    return Path(MPI.COMM_WORLD.bcast(str(tmp_path), root=0))


@pytest.fixture
def scene_text():
    """``scene_text(name, **values)``: the text of ``tests/scenes/<name>.toml`` with its
    ``${key}`` placeholders filled (:func:`tests.support.scenes.scene_text`)."""
    from tests.support.scenes import scene_text  # (here: test_mpi_abort runs a copy of this file)
    return scene_text


@pytest.fixture
def scene_path():
    """``scene_path(name)``: the file ``tests/scenes/<name>.toml``."""
    from tests.support.scenes import scene_path
    return scene_path


def pytest_runtest_logreport(report):
    if _AGREE is None or not report.failed:
        return
    comm = MPI.COMM_WORLD
    text = (f"\n[rank {comm.rank} of {comm.size}] {report.nodeid} failed ({report.when}):\n"
            f"{report.longreprtext}\n")
    _failed.add(report.nodeid)
    sys.stderr.write(text)
    sys.stderr.flush()


def pytest_runtest_logfinish(nodeid, location):
    if _AGREE is None:
        return
    mine = nodeid in _failed
    request = _AGREE.Ibarrier()
    deadline = time.monotonic() + AGREE_SECONDS
    while not request.Test():
        if time.monotonic() > deadline:
            comm = MPI.COMM_WORLD
            sys.stderr.write(
                f"\n[rank {comm.rank}] {nodeid}: the other ranks did not finish it within "
                f"{AGREE_SECONDS:g} s (stuck after a failure on some rank"
                f"{' — this one' if mine else ''}): aborting the MPI job\n")
            sys.stderr.flush()
            comm.Abort(1)
        time.sleep(0.001)
    _failed.discard(nodeid)
