# SPDX-License-Identifier: MIT
"""A test that fails on one MPI rank only ends the 2-rank test run soon (after the conftest's
agreement timeout), with a non-zero exit and the failure's report, instead of leaving the other
rank waiting in its next collective call; a test that fails on every rank does not end the run:
the later tests still run, so one run reports every failure. Likewise a bug that raises on one
rank only in a command-line run ends the MPI job with its message and exit status 3."""

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

_SYMMETRIC = textwrap.dedent("""
    from mpi4py import MPI

    def test_fails_on_every_rank():
        total = MPI.COMM_WORLD.allreduce(1)
        assert total == 0, "deliberate failure on every rank"

    def test_runs_after_it():
        assert MPI.COMM_WORLD.allreduce(1) == MPI.COMM_WORLD.size
""")


def _run_two_ranks(tmp_path, tests: str) -> tuple[int, str, float]:
    mpirun = shutil.which("mpirun")
    assert mpirun is not None, "mpirun (Open MPI) is required; run scripts/setup.sh"
    shutil.copy(Path(__file__).resolve().parents[1] / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "test_two_ranks.py").write_text(tests)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_"))}
    env["OMPI_MCA_rmaps_base_oversubscribe"] = "1"
    env["VPCONTACT_TEST_AGREE_SECONDS"] = "5"
    root = ["--allow-run-as-root"] if os.geteuid() == 0 else []
    start = time.perf_counter()
    done = subprocess.run(
        [mpirun, *root, "-n", "2", sys.executable, "-m", "pytest", "-q", "--color=no",
         "-p", "no:cacheprovider", "--rootdir", str(tmp_path), str(tmp_path / "test_two_ranks.py")],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    return done.returncode, done.stdout + done.stderr, time.perf_counter() - start


def test_one_rank_failure_aborts_the_job_quickly(tmp_path):
    code, output, elapsed = _run_two_ranks(tmp_path, _TESTS)
    assert code != 0, output
    assert "test_fails_on_rank_1_only failed (call)" in output, output
    assert "deliberate failure" in output, output
    assert "aborting the MPI job" in output, output
    assert elapsed < 60, f"the job took {elapsed:.0f} s to end"


def test_a_failure_on_every_rank_lets_the_later_tests_run(tmp_path):
    code, output, _ = _run_two_ranks(tmp_path, _SYMMETRIC)
    assert code != 0, output
    assert output.count("test_fails_on_every_rank failed (call)") == 2, output
    assert "aborting" not in output, output
    assert output.count("1 failed, 1 passed") == 2, output


_PLANTED = textwrap.dedent("""
    import sys
    from mpi4py import MPI
    from vpcontact import cli
    from vpcontact.solver import QuasistaticProblem

    original = QuasistaticProblem.step

    def step(self, dt, tolerance=None):
        if self.step_index == 1 and MPI.COMM_WORLD.rank == 1:
            raise ZeroDivisionError("planted on rank 1")
        return original(self, dt, tolerance)

    QuasistaticProblem.step = step
    sys.exit(cli.main(["run", "signorini_2d", "--out", sys.argv[1], "--quiet"]))
""")


def test_a_bug_on_one_rank_of_a_run_ends_the_job_with_its_message(tmp_path):
    """The other rank would wait for ever in the outputs' collective calls (as a bug in the
    nodal friction's set-up on a process without contact nodes once did): the run aborts."""
    mpirun = shutil.which("mpirun")
    assert mpirun is not None, "mpirun (Open MPI) is required; run scripts/setup.sh"
    (tmp_path / "planted.py").write_text(_PLANTED)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_"))}
    env["OMPI_MCA_rmaps_base_oversubscribe"] = "1"
    root = ["--allow-run-as-root"] if os.geteuid() == 0 else []
    start = time.perf_counter()
    done = subprocess.run([mpirun, *root, "-n", "2", sys.executable, str(tmp_path / "planted.py"),
                           str(tmp_path / "out")], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=300)
    output = done.stdout + done.stderr
    assert done.returncode != 0, output
    assert "internal error on rank 1" in output and "ZeroDivisionError: planted on rank 1" in output, output
    assert "Traceback" not in output, output
    assert time.perf_counter() - start < 240, output
