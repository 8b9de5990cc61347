# SPDX-License-Identifier: MIT
"""Benchmark: cost of one viscoplastic Signorini step (paper §4.1.2, 3-D) against an elastic solve.

Targets (issue "[2 of 5]"): on average at most 4 Newton iterations per step when warm-started from
the previous step, and one step at most 3x one plain dolfinx linear-elastic solve (assembly +
solve, same mesh). Three baselines are recorded: the same MUMPS LU the step's solver is built
on, MUMPS Cholesky (the elastic matrix is SPD; the strictest), and dolfinx's default PETSc LU.
Each step size of --dt runs the whole interval; iterations of rejected (cut) attempts count.
Records the per-step split: kernel (strain evaluation + C++ stress update), residual assembly,
Jacobian assembly, and the rest of the SNES solve (linear solves and VI active-set work), and the
factorizations per step of the VI's lagged direct solver (vpcontact.solver.vi_linear).

    .venv/bin/python bench/signorini_step.py [--n 8] [--dt 0.05 0.02 0.01] [--t-final 1.0] [-o key=value ...]

(-o passes PETSc options to the step's SNES, e.g. -o snes_linesearch_type=basic).

writes bench/results/signorini_step.json (and prints it).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import dolfinx
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI

if not __package__:  # run as a file (python bench/x.py): import bench, tests from the repo root
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from vpcontact.cli import configure_logging
from bench.benchlib import (check_steps, key_value, machine, mesh_size, output_file,
                            positive_float, save)
from vpcontact.paper import signorini as paper
from vpcontact.solver import DEFAULT_OPTIONS, time_split
from vpcontact.solver import StepControl, advance


def elastic_solve_time(V, options: dict, repeats: int = 3) -> float:
    """Seconds per plain dolfinx LinearProblem solve (assemble A and b, solve) on V's mesh."""
    mesh = V.mesh
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    E, nu = paper.YOUNG, paper.POISSON
    eps = ufl.sym(ufl.grad(u))
    sigma = E * nu / ((1 + nu) * (1 - 2 * nu)) * ufl.tr(eps) * ufl.Identity(3) + E / (1 + nu) * eps
    facets = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[0], 3.0))
    tags = dolfinx.mesh.meshtags(mesh, 2, facets, np.full(len(facets), 1, dtype=np.int32))
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    L = ufl.dot(ufl.as_vector([0.0, 0.0, -10.0]), v) * ds(1)
    clamp = fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], 0.0))
    bc = fem.dirichletbc(np.zeros(3), clamp, V)
    problem = fem_petsc.LinearProblem(ufl.inner(sigma, ufl.sym(ufl.grad(v))) * ufl.dx, L, bcs=[bc],
                                      petsc_options=options)
    problem.solve()  # JIT and symbolic set-up outside the timing
    mesh.comm.barrier()
    start = time.perf_counter()
    for _ in range(repeats):
        problem.solve()
    return (time.perf_counter() - start) / repeats


def _run(args, dt: float, options: dict, baselines: dict) -> dict:
    """Run the paper's 3-D test with step dt; per-step cost, split and solver counters."""
    problem = paper.signorini_3d(3 * args.n, args.n, args.n, petsc_options=options)
    problem.solver.timings.update({k: 0.0 for k in problem.solver.timings})
    start = time.perf_counter()
    control = StepControl(dt)
    reports = list(advance(problem, args.t_final, control))
    wall = time.perf_counter() - start
    steps = len(reports)
    total_its = problem.solver.total_iterations  # with the iterations of rejected attempts
    t = problem.solver.timings
    split = {k: v / steps for k, v in time_split(t).items()}
    split["other"] = (wall - t["snes"]) / steps
    step_time = wall / steps
    lagged = problem.solver.lagged_lu
    run = {
        "dt": dt, "steps": steps, "cuts": len(control.cuts),
        "newton_iterations": [r.newton_iterations for r in reports],
        "newton_iterations_per_step": total_its / steps,
        "factorizations_per_step": (None if lagged is None
                                    else lagged.counters()["factorizations"] / steps),
        "vi_linear_solves": None if lagged is None else lagged.counters(),
        "seconds_per_step": step_time, "seconds_per_step_split": split,
        **{f"step_over_elastic_solve{key}": step_time / t for key, t in baselines.items()},
        "targets": {"newton_iterations_per_step <= 4": bool(total_its / steps <= 4),
                    **{f"step_over_elastic_solve{key} <= 3": bool(step_time / t <= 3)
                       for key, t in baselines.items()}},
    }
    problem.solver.destroy()
    return run


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=mesh_size(18, 3), default=8,
                        help="cells across the beam (mesh 3n × n × n)")
    parser.add_argument("--dt", type=positive_float, nargs="+", default=[0.05, 0.02, 0.01],
                        help="time steps to run (each over the whole interval)")
    parser.add_argument("--t-final", type=positive_float, default=1.0)
    parser.add_argument("-o", dest="options", type=key_value, action="append", default=[],
                        metavar="KEY=VALUE", help="PETSc option for the step's SNES")
    parser.add_argument("--out", type=output_file,
                        default=str(Path(__file__).parent / "results" / "signorini_step.json"))
    args = parser.parse_args(argv)
    check_steps(parser, "--dt/--t-final", args.t_final / min(args.dt))
    comm = MPI.COMM_WORLD

    options = dict(o.split("=", 1) for o in args.options)
    problem = paper.signorini_3d(3 * args.n, args.n, args.n, petsc_options=options)
    V = problem.V
    problem.solver.destroy()
    dofs = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    linear = {k: v for k, v in {**DEFAULT_OPTIONS, **options}.items() if k.startswith(("ksp_", "pc_"))}
    elastic = elastic_solve_time(V, linear)
    elastic_default = elastic_solve_time(V, {"ksp_type": "preonly", "pc_type": "lu"})
    # the strictest baseline: the elastic matrix is SPD, so MUMPS Cholesky
    elastic_cholesky = elastic_solve_time(V, {**linear, "pc_type": "cholesky"})

    baselines = {"": elastic, "_dolfinx_default_lu": elastic_default,
                 "_mumps_cholesky": elastic_cholesky}
    runs = [_run(args, dt, options, baselines) for dt in args.dt]
    result = {
        "benchmark": "signorini_step",
        "machine": machine(comm),
        "problem": {"case": "paper 4.1.2 (3-D Signorini, implicit Perzyna)",
                    "mesh": [3 * args.n, args.n, args.n], "dofs": dofs,
                    "t_final": args.t_final, "petsc_options": options, "linear_solver": linear},
        "seconds_per_elastic_solve": elastic,
        "seconds_per_elastic_solve_dolfinx_default_lu": elastic_default,
        "seconds_per_elastic_solve_mumps_cholesky": elastic_cholesky,
        "runs": runs,
    }
    save(result, args.out, comm)
    return 0


if __name__ == "__main__":
    configure_logging()  # JIT messages off the terminal
    sys.exit(main())
