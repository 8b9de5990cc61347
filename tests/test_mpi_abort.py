# SPDX-License-Identifier: MIT
"""A test that fails on one MPI rank only ends the 2-rank test run at once, with a non-zero exit
and the failure's report, instead of leaving the other rank waiting in its next collective call."""

import os
import shutil
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

pytestmark = [pytest.mark.serial, pytest.mark.mpi]

_TESTS = textwrap.dedent("""
    from mpi4py import MPI

    def test_fails_on_rank_1_only():
        assert MPI.COMM_WORLD.rank == 0, "deliberate failure on rank 1"
        MPI.COMM_WORLD.barrier()  # rank 0 waits here for rank 1, which never comes

    def test_needs_every_rank():
        MPI.COMM_WORLD.bcast(1, root=0)
""")


def test_one_rank_failure_aborts_the_job_quickly(tmp_path):
    mpirun = shutil.which("mpirun")
    assert mpirun is not None, "mpirun (Open MPI) is required; run scripts/setup.sh"
    shutil.copy(Path(__file__).with_name("conftest.py"), tmp_path / "conftest.py")
    (tmp_path / "test_one_rank.py").write_text(_TESTS)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_"))}
    env["OMPI_MCA_rmaps_base_oversubscribe"] = "1"
    root = ["--allow-run-as-root"] if os.geteuid() == 0 else []
    start = time.perf_counter()
    done = subprocess.run(
        [mpirun, *root, "-n", "2", sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
         "--rootdir", str(tmp_path), str(tmp_path / "test_one_rank.py")],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    elapsed = time.perf_counter() - start
    output = done.stdout + done.stderr
    assert done.returncode != 0, output
    assert "test_fails_on_rank_1_only failed (call)" in output, output
    assert "deliberate failure" in output, output
    assert elapsed < 120, f"the job took {elapsed:.0f} s to end"
