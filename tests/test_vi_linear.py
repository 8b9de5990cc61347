# SPDX-License-Identifier: MIT
"""The VI's reduced systems solved with lagged full-size factors (vpcontact.vi_linear) give
PETSc's own reduced direct solves' answer with fewer factorizations."""

import numpy as np
from mpi4py import MPI

from vpcontact import paper_signorini as paper
from vpcontact.problem import QuasistaticProblem


def _run(lagged: bool, steps: int = 6, dt: float = 0.02) -> tuple[QuasistaticProblem, list]:
    problem = paper.signorini_3d(9, 3, 3, petsc_options={"vpcontact_vi_lagged_lu": int(lagged)})
    reports = [problem.step(dt) for _ in range(steps)]
    return problem, reports


def _global(problem, values):
    comm = problem.mesh.comm
    owned = problem.V.dofmap.index_map.size_local * problem.V.dofmap.index_map_bs
    local = values[:owned]
    return (comm.allreduce(float(np.max(local)), op=MPI.MAX),
            comm.allreduce(float(np.min(local)), op=MPI.MIN),
            np.sqrt(comm.allreduce(float(local @ local), op=MPI.SUM)))


def test_lagged_factors_reproduce_petsc_reduced_solves_with_fewer_factorizations():
    reference, ref_reports = _run(lagged=False)
    problem, reports = _run(lagged=True)
    assert reference.solver.lagged_lu is None
    counters = problem.solver.lagged_lu.counters()

    # Same solution (both converge to the solver tolerance), same Newton effort.
    got, want = _global(problem, problem.u.x.array), _global(reference, reference.u.x.array)
    scale = max(abs(w) for w in want)
    assert np.allclose(got, want, rtol=0, atol=1e-8 * scale), (got, want)
    its = sum(r.newton_iterations for r in reports)
    ref_its = sum(r.newton_iterations for r in ref_reports)
    assert abs(its - ref_its) <= len(reports), (its, ref_its)

    # Effort: lagged solves happen, and fewer factorizations than Newton iterations.
    assert counters["lagged_solves"] >= 1, counters
    assert counters["factorizations"] < its, (counters, its)
    assert counters["lagged_failures"] <= counters["lagged_solves"], counters
