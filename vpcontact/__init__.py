# SPDX-License-Identifier: MIT
"""vpcontact: quasistatic frictionless contact of rate-type elastic-viscoplastic bodies.

The subpackages follow a run's data flow:

* :mod:`vpcontact.scene`: a TOML scene file, read, validated and built into a model;
* :mod:`vpcontact.model`: laws σ̇ = E ε(u̇) + G(σ, ε(u)), quadrature state, contact conditions
  and obstacles (UFL terms, with :mod:`vpcontact.kernels` doing the constitutive work in C++);
* :mod:`vpcontact.solver`: the discrete problem, one SNES solve per step (VI mode for Signorini),
  step control;
* :mod:`vpcontact.output`: the time loop with its XDMF, CSV and PNG outputs and ``summary.json``;
* :mod:`vpcontact.studies`: convergence and cost studies; :mod:`vpcontact.paper`: the paper's
  examples with their exact solutions; :mod:`vpcontact.cli`: the command line.
"""
import os

# dolfinx partitions meshes with PT-Scotch, whose threads make the partition (and so the
# round-off and Krylov iteration counts of a parallel run) change from run to run. One Scotch
# thread per rank gives the same partition every time; a value already in the environment is kept.
os.environ.setdefault("SCOTCH_PTHREAD_NUMBER", "1")


def _one_blas_thread() -> None:
    """One OpenBLAS thread per process unless OPENBLAS_NUM_THREADS says otherwise.

    vpcontact runs one MPI rank per core. PETSc's vector operations call BLAS, and OpenBLAS
    threads every level-1 call on vectors of more than a few thousand entries; its threads
    busy-wait, so on a machine whose cores are all busy (two ranks on two cores, or any other
    job) they stall every Krylov iteration: measured, a 19 690-unknown 3-D step went from
    seconds to minutes. The environment variable only helps if it is set before the library
    loads, and numpy loads it before a script imports vpcontact, so the thread count is also
    set through OpenBLAS's own call."""
    if "OPENBLAS_NUM_THREADS" in os.environ:
        return
    os.environ["OPENBLAS_NUM_THREADS"] = "1"  # for processes started from here
    import ctypes

    for name in ("libopenblas.so.0", "libopenblasp.so.0"):
        try:
            ctypes.CDLL(name).openblas_set_num_threads(1)
        except (OSError, AttributeError):
            continue


_one_blas_thread()


def _two_sided_by_allreduce() -> None:
    """PETSc's rendezvous for off-process entries (``-build_twosided``, run by every parallel
    matrix assembly and sub-matrix extraction) by an allreduce, unless the user chose.

    The one Debian's PETSc 3.18 takes by default, with a nonblocking barrier, cost about 1 ms
    per call under Open MPI on 2 ranks: in the linearized window of the paper's 3-D test at
    44 508 unknowns a 2-rank step took 1.42 s, 0.62 s of the run's 10.5 s in 582 such calls,
    and 1.17 s with the allreduce (0.14 s). The allreduce moves one integer per rank, which
    is cheap up to hundreds of ranks (newer PETSc makes it the default up to 1 024). PETSc
    reads the option once, at its first rendezvous: it is put in the environment for a PETSc
    not yet started and in its options database otherwise."""
    import sys

    if "build_twosided" in os.environ.get("PETSC_OPTIONS", ""):
        return
    petsc = sys.modules.get("petsc4py.PETSc")
    if petsc is None:
        os.environ["PETSC_OPTIONS"] = (os.environ.get("PETSC_OPTIONS", "")
                                       + " -build_twosided allreduce").strip()
    elif not petsc.Options().hasName("build_twosided"):
        petsc.Options()["build_twosided"] = "allreduce"


_two_sided_by_allreduce()

__version__ = "0.1.0"
