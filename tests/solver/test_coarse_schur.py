# SPDX-License-Identifier: MIT
"""The stars' Schur complement with the cycle's coarse term (``pmg_schur_coarse``): the mixed
coarse matrix K_c stacked as MatNest numbers it, Ŝ₂⁻¹ = (Ŝ − (BP) A_c⁻¹ (BP)ᵀ)⁻¹ against
dense numpy, and the flowing beam's answers with it (serially and on 2 ranks)."""

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.errors import SolverOptionError
from vpcontact.solver.pc import coarse_schur
from tests.support import flowing_beam

COMM = MPI.COMM_WORLD


def _distributed(dense: np.ndarray, rows: int, cols: int) -> PETSc.Mat:
    """``dense`` (the same on every process) as an AIJ matrix of local sizes rows × cols."""
    matrix = PETSc.Mat().createAIJ(((rows, None), (cols, None)), comm=COMM)
    matrix.setPreallocationNNZ(dense.shape[1])
    start, end = matrix.getOwnershipRange()
    columns = np.arange(dense.shape[1], dtype=PETSc.IntType)
    for i in range(start, end):
        matrix.setValues([i], columns, dense[i])
    matrix.assemble()
    return matrix


def _gathered(vec: PETSc.Vec) -> np.ndarray:
    return np.concatenate(COMM.allgather(vec.getArray(readonly=True).copy()))


def _system(seed=3):
    """A_c (SPD, 4 + 3 rows per process), Ŝ (negative definite, 3 + 2) and (BP)ᵀ, dense."""
    rng = np.random.default_rng(seed)
    n_c, n_p = 7 * COMM.size, 5 * COMM.size
    X = rng.standard_normal((n_c, n_c))
    Ac = X @ X.T + n_c * np.eye(n_c)
    Y = rng.standard_normal((n_p, n_p))
    S = -(Y @ Y.T + n_p * np.eye(n_p))
    BPt = rng.standard_normal((n_c, n_p))
    return Ac, S, BPt


def test_the_coarse_matrix_is_stacked_as_matnest_numbers_it():
    Ac, S, BPt = _system()
    blocks = [[_distributed(Ac, 7, 7), _distributed(BPt, 7, 5)],
              [_distributed(BPt.T.copy(), 5, 7), _distributed(S, 5, 5)]]
    stacked, is_p = coarse_schur._stack(blocks)
    nest = PETSc.Mat().createNest(blocks, comm=COMM)
    nest_is_p = nest.getNestISs()[0][1]
    assert np.array_equal(is_p.getIndices(), nest_is_p.getIndices())
    x = nest.createVecRight()
    x.setArray(np.arange(x.getLocalSize()) + 1.0 + 100 * COMM.rank)
    y, z = nest.createVecLeft(), stacked.createVecLeft()
    nest.mult(x, y)
    stacked.mult(x, z)
    assert np.allclose(_gathered(y), _gathered(z), rtol=1e-14, atol=0)


def test_the_pressure_solve_is_the_inverse_of_shat_with_the_coarse_term():
    """CoarseSchur.update with an identity interpolation (A_c given, Bᵀ its coupling): solve
    gives (Ŝ − (BP) A_c⁻¹ (BP)ᵀ)⁻¹ r."""
    Ac, S, BPt = _system(seed=5)
    identity = _distributed(np.eye(Ac.shape[0]), 7, 7)
    coarse = coarse_schur.CoarseSchur(COMM)
    coarse.update(_distributed(BPt, 7, 5), identity, _distributed(Ac, 7, 7),
                  _distributed(S, 5, 5))
    r = PETSc.Vec().createMPI((5, None), comm=COMM)
    r.setArray(np.sin(np.arange(5) + 5.0 * COMM.rank))
    y = r.duplicate()
    coarse.solve(r, y)
    S2 = S - BPt.T @ np.linalg.solve(Ac, BPt)
    assert np.allclose(_gathered(y), np.linalg.solve(S2, _gathered(r)), rtol=1e-10, atol=0)
    coarse.destroy()


def _run(coarse: str):
    options = {f"{split}fieldsplit_u_pmg_{key}": value for split in ("", "lagged_")
               for key, value in (("smooth_stars", "true"), ("schur_coarse", coarse))}
    return flowing_beam.run(options=options)


def test_with_the_coarse_term_the_answers_stay():
    """The flowing beam (SNES VI) with the Schur block K_c's: its pressure split applies the
    coarse term, the cycle's coarse level is factorized, and the steps converge to the answers
    of the stars' Ŝ alone (serially and on 2 ranks)."""
    problem, steps = _run("true")
    pc = problem.solver.lagged_lu.inner.getPC()
    block, pressure = pc.getFieldSplitSubKSP()
    assert pressure.getPC().getType() == "python"
    assert isinstance(pressure.getPC().getPythonContext(), coarse_schur.CoarseSchurPC)
    assert block.getPC().getPythonContext().coarse.getPC().getType() == "cholesky"  # symmetric
    assert problem.solver._block.star_schur.coarse.matrix is not None
    reference, reference_steps = _run("false")
    assert reference.solver._block.star_schur.coarse is None
    u, u_ref = problem.u.x.array, reference.u.x.array
    assert np.abs(u - u_ref).max() < 1e-6 * np.abs(u_ref).max()
    assert [s.time for s in steps] == [s.time for s in reference_steps]


@pytest.mark.serial
def test_a_bad_coarse_term_option_is_refused():
    from vpcontact.paper import signorini as paper

    with pytest.raises(SolverOptionError, match="pmg_schur_coarse must be auto, true or false, "
                       "got 'lu'") as err:
        paper.signorini_3d(6, 2, 2, petsc_options={"fieldsplit_u_pmg_schur_coarse": "lu"},
                           sigma_y=paper.SIGMA_Y, mu_star=paper.MU_STAR, formulation="mixed",
                           degree=2, linear="iterative")
    assert err.value.option == "fieldsplit_u_pmg_schur_coarse"


@pytest.mark.serial
def test_the_coarse_term_without_the_stars_is_refused():
    """On a block below the stars' threshold, pmg_schur_coarse alone names what it needs."""
    from vpcontact.paper import signorini as paper

    options = {"fieldsplit_u_pmg_schur_coarse": "true",
               "lagged_fieldsplit_u_pmg_schur_coarse": "true"}
    with pytest.raises(SolverOptionError, match="pmg_schur_coarse needs the vertex-star "
                       "smoothing") as err:
        paper.signorini_3d(6, 2, 2, petsc_options=options, sigma_y=paper.SIGMA_Y,
                           mu_star=paper.MU_STAR, formulation="mixed", degree=2,
                           linear="iterative")
    assert err.value.option == "fieldsplit_u_pmg_schur_coarse"
