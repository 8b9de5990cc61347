# SPDX-License-Identifier: MIT
"""Benchmark (a diagnosis): every Krylov solve of the linearized window, one by one.

The paper's 3-D test (3n×n×n cells, Taylor–Hood, its data, linearized scheme, iterative solver)
is run to t = 0.05 s with k = 0.01 s, then the window's three steps to t = 0.08 s (the window of
``bench/step_cost.py --scheme linearized --window3d 0.05 0.08``). For each solve SNES VI asks of
the block-preconditioned lagged solver it records the Newton iteration, the relative tolerance
asked, the FGMRES iterations, the reduction reached, the decades per iteration and whether the
probe ended it (:class:`vpcontact.solver.vi_linear.LaggedMultigrid`).

``--first-rtol R --first-unprobed`` changes the step's first solve (default: 1e-2, probed like
the others): aimed tighter and not probed, its direction is the exact Newton direction up to R,
as the direct solver's is.

    .venv/bin/python bench/solve_trace.py --n 8 [--first-rtol 1e-4 --first-unprobed] [--out F]
    mpirun -n 2 .venv/bin/python bench/solve_trace.py --n 24 ...

writes bench/results/solve_trace_n<n>.json (``--out``) and prints it.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from mpi4py import MPI

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchlib import machine, mesh_size, output_file, relative_tolerance, save  # noqa: E402

from vpcontact.paper import signorini as paper  # noqa: E402
from vpcontact.solver import StepControl, advance  # noqa: E402
from vpcontact.solver import linear as linear_solvers  # noqa: E402
from vpcontact.solver import vi_linear  # noqa: E402


def traced(first_rtol: float | None, first_unprobed: bool, log: list) -> None:
    """Wrap the lagged solver's Krylov solve (and the first solve's tolerance) to fill ``log``."""
    krylov = vi_linear.LaggedMultigrid._probed_krylov
    aimed = linear_solvers.step_rtol

    def step_rtol(iteration, fnorm, target):
        if iteration == 0 and first_rtol is not None:
            return first_rtol
        return aimed(iteration, fnorm, target)

    def probed(self, reduced, b, x, rtol, atol):
        newton = self.snes.getIterationNumber()
        stops, rhs = self.probe_stops, b.norm()
        saved = self.probe_rtol
        if newton == 0 and first_unprobed:
            self.probe_rtol = None
        try:
            converged, its = krylov(self, reduced, b, x, rtol, atol)
        finally:
            self.probe_rtol = saved
        reached = self.krylov.getResidualNorm() / rhs if rhs > 0 else 0.0
        decades = -math.log10(reached) if reached > 0 else math.nan
        log.append({"newton": newton, "rtol": rtol, "iterations": its, "reached": reached,
                    "decades": decades, "iterations_per_decade": its / decades,
                    "probe_stop": self.probe_stops > stops})
        return converged, its

    linear_solvers.step_rtol = step_rtol
    vi_linear.LaggedMultigrid._probed_krylov = probed


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--n", type=mesh_size(18, 3), default=8, help="3n×n×n cells (default 8)")
    parser.add_argument("--first-rtol", type=relative_tolerance,
                        help="the step's first solve's tolerance, in (0, 1)")
    parser.add_argument("--first-unprobed", action="store_true",
                        help="no probe in the step's first solve")
    parser.add_argument("--out", type=output_file,
                        help="JSON file (default bench/results/solve_trace_n<n>.json)")
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD
    log: list = []
    traced(args.first_rtol, args.first_unprobed, log)
    n = args.n
    problem = paper.signorini_3d(3 * n, n, n, petsc_options={}, sigma_y=paper.SIGMA_Y,
                                 mu_star=paper.MU_STAR, scheme="linearized",
                                 formulation="mixed", degree=2, linear="iterative")
    list(advance(problem, 0.05, StepControl(0.01)))
    steps = []
    for k in range(3):
        log.clear()
        newton = problem.solver.total_iterations
        start = time.perf_counter()
        list(advance(problem, 0.05 + 0.01 * (k + 1), StepControl(0.01)))
        steps.append({"t": round(0.05 + 0.01 * (k + 1), 10),
                      "seconds": time.perf_counter() - start,
                      "newton_iterations": problem.solver.total_iterations - newton,
                      "krylov_iterations": sum(s["iterations"] for s in log),
                      "solves": list(log)})
    unknowns = problem.u.vector.getSize() + problem.p.vector.getSize()
    save({"benchmark": "solve_trace", "machine": machine(comm), "n": n, "unknowns": unknowns,
          "first_rtol": args.first_rtol or linear_solvers.STEP_FIRST_RTOL,
          "first_unprobed": args.first_unprobed, "steps": steps},
         args.out or Path(__file__).parent / "results" / f"solve_trace_n{n}.json", comm)
    return 0


if __name__ == "__main__":
    from vpcontact.cli import run_script
    run_script(main)
