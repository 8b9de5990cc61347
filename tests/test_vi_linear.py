# SPDX-License-Identifier: MIT
"""The VI's reduced systems solved with lagged full-size factors (vpcontact.vi_linear) give
PETSc's own reduced direct solves' answer with fewer factorizations."""

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import paper_signorini as paper
from vpcontact.problem import QuasistaticProblem


def _run(linear: str, steps: int = 6, dt: float = 0.02) -> tuple[QuasistaticProblem, list]:
    problem = paper.signorini_3d(9, 3, 3, petsc_options={"vpcontact_vi_linear": linear})
    reports = [problem.step(dt) for _ in range(steps)]
    return problem, reports


def _global(problem, values):
    comm = problem.mesh.comm
    owned = problem.V.dofmap.index_map.size_local * problem.V.dofmap.index_map_bs
    local = values[:owned]
    return (comm.allreduce(float(np.max(local)), op=MPI.MAX),
            comm.allreduce(float(np.min(local)), op=MPI.MIN),
            np.sqrt(comm.allreduce(float(local @ local), op=MPI.SUM)))


def _compare_with_petsc(linear: str, atol: float):
    """Run with ``linear`` and with PETSc's reduced direct solves: the same solution (both to the
    solver tolerance, ``atol`` relative to the largest value) and the same Newton effort (within
    one iteration per step); returns the problem and its total Newton iterations."""
    reference, ref_reports = _run("petsc")
    problem, reports = _run(linear)
    assert reference.solver.lagged_lu is None
    got, want = _global(problem, problem.u.x.array), _global(reference, reference.u.x.array)
    scale = max(abs(w) for w in want)
    assert np.allclose(got, want, rtol=0, atol=atol * scale), (got, want)
    its = sum(r.newton_iterations for r in reports)
    ref_its = sum(r.newton_iterations for r in ref_reports)
    assert abs(its - ref_its) <= len(reports), (its, ref_its)
    return problem, its


def test_lagged_factors_reproduce_petsc_reduced_solves_with_fewer_factorizations():
    problem, its = _compare_with_petsc("lagged_lu", atol=1e-8)
    counters = problem.solver.lagged_lu.counters()
    # Effort: lagged solves happen, and fewer factorizations than Newton iterations.
    assert counters["lagged_solves"] >= 1, counters
    assert counters["factorizations"] < its, (counters, its)
    assert counters["lagged_failures"] <= counters["lagged_solves"], counters


def test_lagged_multigrid_gives_the_same_solution():
    """GAMG on the full-size matrix inside the VI (PETSc's GAMG refuses the reduced matrices)."""
    problem, its = _compare_with_petsc("lagged_gamg", atol=1e-7)
    counters = problem.solver.lagged_lu.counters()
    assert 1 <= counters["multigrid_setups"] <= its, counters
    assert counters["krylov_iterations"] >= its, counters


def test_unknown_vi_linear_solver_is_refused():
    with pytest.raises(ValueError, match="vpcontact_vi_linear must be"):
        _run("cholesky", steps=0)
