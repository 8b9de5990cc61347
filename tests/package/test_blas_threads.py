# SPDX-License-Identifier: MIT
"""One BLAS thread per process (vpcontact/__init__.py): OpenBLAS's threads busy-wait behind
every vector operation of PETSc once vectors pass a few thousand entries, which stalls Krylov
iterations whenever the cores are shared (MPI ranks, other jobs)."""

import ctypes.util
import subprocess
import sys

import pytest

from tests.support.mpi_launch import clean_environment

pytestmark = pytest.mark.serial

_PROBE = ("import numpy, ctypes, vpcontact; "
          "print(ctypes.CDLL('libopenblas.so.0').openblas_get_num_threads())")


def _threads(env_value):
    env = clean_environment()
    env.pop("OPENBLAS_NUM_THREADS", None)
    if env_value is not None:
        env["OPENBLAS_NUM_THREADS"] = env_value
    done = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True,
                          env=env, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    return int(done.stdout.split()[-1])


def test_one_blas_thread_even_when_numpy_loaded_openblas_first():
    """numpy is imported first (it loads OpenBLAS with a thread per core); importing vpcontact
    still leaves one thread. scripts/setup.sh installs OpenBLAS, so the library is there."""
    assert ctypes.util.find_library("openblas") is not None, "OpenBLAS missing: run scripts/setup.sh"
    assert _threads(None) == 1


def test_the_user_s_thread_count_is_kept():
    assert _threads("2") == 2
