# SPDX-License-Identifier: MIT
"""Benchmark: cost of a viscoplastic Signorini step against the number of unknowns, memory per
unknown, and the speed-up of 2 MPI ranks.

Targets (issue "[5 of 5]"): the step cost's fitted exponent in the dof count (3-D ≤ 1.15 with an
iterative solver); peak memory per dof recorded; ``mpirun -n 2`` speed-up on the 3-D test ≥ 1.6.
Recorded per dimension: the fit over all sizes, the exponents between consecutive sizes and the
fit over the four largest (when there are more than four).

Each mesh size runs in a fresh process (so its peak resident memory is its own): the paper's
2-D test (§4.1.1, n×n) in its viscoplastic flow regime, t ∈ [0.4, 0.5] s, and the 3-D test
(§4.1.2, 3n×n×n) in contact, t ∈ [0.3, 0.4] s, both with k = 0.01 s after an untimed run-in from
t = 0 with k = 0.02 s. Per step: wall time and its split (kernel, residual assembly, Jacobian
assembly, linear solves, VI and other SNES work), Newton iterations, factorizations.

    .venv/bin/python bench/step_cost.py [--sizes2d 16 32 64 128] [--sizes3d 4 6 8 12 16] [--ranks 2]
        [--mpi-size 8] [--mu-star MU] [--sigma-y SY] [--window3d T0 T1] [-o KEY=VALUE ...]
        [--scheme implicit|linearized|explicit] [--out FILE]

``--mu-star``/``--sigma-y`` change the paper's μ* = 200 and σ_Y = √10 (a larger μ* lowers the
stiffness contrast k E/μ* of the plastic tangent, which decides whether multigrid works);
``-o`` passes PETSc options, e.g. ``-o vpcontact_vi_linear=lagged_gamg -o lagged_pc_type=ml``.

writes bench/results/step_cost.json (and prints it). ``--single DIM N`` runs one size in this
process (what the driver launches, serially or under mpirun) and prints its JSON record.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import time
from typing import Optional
from pathlib import Path

import numpy as np
from mpi4py import MPI

if not __package__:  # run as a file (python bench/x.py): import bench, tests from the repo root
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from vpcontact.cli import configure_logging
from bench.benchlib import (check_cells, check_steps, key_value, machine, mesh_size,
                            output_file, positive_float, positive_int, positive_or_inf, save)

WINDOWS = {2: (0.4, 0.5), 3: (0.3, 0.4)}  # timed interval per dimension [s]
RUN_IN_STEP, STEP = 0.02, 0.01
LARGEST_FIT = 4  # sizes in the large-size fit


def single(dim: int, n: int, options: dict, sigma_y: Optional[float] = None,
           mu_star: Optional[float] = None, formulation: str = "displacement",
           linear: str = "auto", window: Optional[tuple] = None,
           scheme: str = "implicit") -> dict:
    """Run one size in this process; the record of its timed window (``sigma_y``: the paper's
    √10 by default; ``inf`` makes the body elastic; ``window``: (t0, t1) instead of the
    dimension's default)."""
    from vpcontact.paper import signorini as paper
    from vpcontact.solver import time_split
    from vpcontact.solver import StepControl, advance

    sigma_y = paper.SIGMA_Y if sigma_y is None else sigma_y
    mu_star = paper.MU_STAR if mu_star is None else mu_star

    comm = MPI.COMM_WORLD
    data = {"petsc_options": options, "sigma_y": sigma_y, "mu_star": mu_star, "scheme": scheme}
    if dim == 2:
        problem = paper.signorini_2d(n, **data)
    else:
        problem = paper.signorini_3d(3 * n, n, n, **data, formulation=formulation,
                                     degree=2 if formulation == "mixed" else 1, linear=linear)
    t0, t1 = window or WINDOWS[dim]
    list(advance(problem, t0, StepControl(RUN_IN_STEP)))
    solver = problem.solver
    solver.timings.update({k: 0.0 for k in solver.timings})
    its0 = solver.total_iterations
    lagged = solver.lagged_lu
    counters0 = lagged.counters() if lagged is not None else {}
    comm.barrier()
    start = time.perf_counter()
    steps = len(list(advance(problem, t1, StepControl(STEP))))
    comm.barrier()
    wall = time.perf_counter() - start
    t = {k: comm.allreduce(v, op=MPI.MAX) / steps for k, v in solver.timings.items()}
    rss = comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024, op=MPI.SUM)
    counters = {k: (v - counters0[k]) / steps  # the lagged VI solver's, per step
                for k, v in (lagged.counters() if lagged is not None else {}).items()
                if not isinstance(v, str)}
    dofs = solver.unknowns
    return {"dim": dim, "n": n, "window": [t0, t1], "formulation": formulation,
            "scheme": scheme, "linear": solver.linear, "sigma_y": _json_float(sigma_y),
            "mu_star": mu_star, "dofs": dofs, "ranks": comm.size, "steps": steps,
            "seconds_per_step": wall / steps,
            "seconds_per_step_split": time_split(t),
            "newton_iterations_per_step": (solver.total_iterations - its0) / steps,
            "factorizations_per_step": counters.get("factorizations"),
            "vi_linear_counters_per_step": counters,
            "peak_memory_bytes": rss, "peak_memory_bytes_per_dof": rss / dofs}


def _json_float(x: Optional[float]):
    """x for a strict JSON file (infinity as the string "inf")."""
    return x if x is None or np.isfinite(x) else str(x)


def launch(dim: int, n: int, ranks: int, passed_on: list) -> dict:
    """Run ``--single dim n`` in a fresh process (under mpirun when ranks > 1), with the
    driver's data and PETSc options (``passed_on``: their command-line arguments)."""
    cmd = [sys.executable, __file__, "--single", str(dim), str(n), *passed_on]
    if ranks > 1:
        mpirun = shutil.which("mpirun")
        if mpirun is None:
            raise SystemExit("mpirun (Open MPI) is needed for --ranks > 1")
        root = ["--allow-run-as-root"] if os.geteuid() == 0 else []
        cmd = [mpirun, *root, "-n", str(ranks), *cmd]
    # this process is an MPI singleton: its Open MPI/PMIx variables must not reach the child
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_"))}
    env.update({k: os.environ[k] for k in ("OMPI_ALLOW_RUN_AS_ROOT",
                                           "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM") if k in os.environ})
    env["OMPI_MCA_rmaps_base_oversubscribe"] = "1"
    done = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{done.stdout[-1000:]}{done.stderr[-2000:]}")
    record = [line for line in done.stdout.splitlines() if line.startswith("RECORD ")][-1]
    return json.loads(record[len("RECORD "):])


def exponent(records: list, part: Optional[str] = None) -> float:
    """Fitted p in seconds per step ~ dofs^p (of one part of the split when ``part`` is given)."""
    dofs = np.array([r["dofs"] for r in records], dtype=float)
    cost = np.array([r["seconds_per_step"] if part is None else r["seconds_per_step_split"][part]
                     for r in records])
    return float(np.polyfit(np.log(dofs), np.log(cost), 1)[0])


def local_exponents(records: list) -> list:
    """Exponents between consecutive sizes (where the growth changes: e.g. when the matrices
    leave the caches)."""
    rs = sorted(records, key=lambda r: r["dofs"])
    return [float(np.log(b["seconds_per_step"] / a["seconds_per_step"])
                  / np.log(b["dofs"] / a["dofs"])) for a, b in zip(rs, rs[1:])]


def largest_fit(records: list, count: int = LARGEST_FIT):
    """Fitted exponent over the ``count`` largest sizes (the asymptotic regime, where the
    matrices no longer fit the caches); None with fewer sizes than that."""
    rs = sorted(records, key=lambda r: r["dofs"])[-count:]
    return exponent(rs) if len(rs) == count and len(records) > count else None


def marginal_memory(records: list):
    """Extra peak memory per extra dof between the two largest sizes (the fixed cost of the
    interpreter and libraries, ~100 MB, dominates the per-dof figure of small meshes)."""
    if len(records) < 2:
        return None
    a, b = sorted(records, key=lambda r: r["dofs"])[-2:]
    return (b["peak_memory_bytes"] - a["peak_memory_bytes"]) / (b["dofs"] - a["dofs"])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes2d", type=mesh_size(2, 2), nargs="*", default=[16, 32, 64, 128])
    parser.add_argument("--sizes3d", type=mesh_size(18, 3), nargs="*", default=[4, 6, 8, 12, 16])
    parser.add_argument("--ranks", type=positive_int, default=2,
                        help="ranks of the speed-up run (3-D; 1: no speed-up run)")
    parser.add_argument("-o", dest="options", type=key_value, action="append", default=[],
                        metavar="KEY=VALUE", help="PETSc option for the step's SNES")
    parser.add_argument("--sigma-y", type=positive_or_inf, default=None,
                        help="yield stress (default: the paper's √10; inf: an elastic body)")
    parser.add_argument("--mu-star", type=positive_float, default=None,
                        help="viscosity μ* (default: the paper's 200; larger: softer contrast)")
    parser.add_argument("--mpi-size", type=mesh_size(18, 3), default=8,
                        help="n of the speed-up run (3n×n×n)")
    parser.add_argument("--formulation", choices=["displacement", "mixed"], default="displacement",
                        help="3-D: the paper's P1 (default) or Taylor–Hood P2–P1")
    parser.add_argument("--linear", choices=["auto", "direct", "iterative"], default="auto",
                        help="linear solver (vpcontact.linear_solvers)")
    parser.add_argument("--window3d", nargs=2, type=positive_float, default=list(WINDOWS[3]),
                        metavar=("T0", "T1"), help="the 3-D test's timed interval [s] (the run-in "
                        "from t = 0 to T0 is untimed; default 0.3 0.4, the beam flowing)")
    parser.add_argument("--scheme", choices=["implicit", "linearized", "explicit"],
                        default="implicit", help="the law's time scheme (default: implicit Euler; "
                        "linearized: one linear problem per step)")
    parser.add_argument("--single", nargs=2, type=positive_int, metavar=("DIM", "N"),
                        help=argparse.SUPPRESS)
    parser.add_argument("--out", type=output_file,
                        default=str(Path(__file__).parent / "results" / "step_cost.json"))
    args = parser.parse_args(argv)
    t0, t1 = args.window3d
    if not t0 < t1:
        parser.error(f"--window3d: T0 must be < T1, got {t0:g} {t1:g}")
    check_steps(parser, "--window3d", t0 / RUN_IN_STEP + (t1 - t0) / STEP)
    if args.single:
        dim, n = args.single
        if dim not in (2, 3):
            parser.error(f"--single: DIM must be 2 or 3, got {dim}")
        check_cells(parser, "--single", 2 * n**2 if dim == 2 else 18 * n**3)
    if args.ranks > 18 * args.mpi_size**3:  # (a process without cells cannot take part)
        parser.error(f"--ranks {args.ranks}: more processes than the cells of --mpi-size "
                     f"{args.mpi_size} ({18 * args.mpi_size**3})")
    if args.single:
        record = single(*args.single, dict(o.split("=", 1) for o in args.options), args.sigma_y,
                        args.mu_star, args.formulation, args.linear,
                        tuple(args.window3d) if args.single[0] == 3 else None, args.scheme)
        if MPI.COMM_WORLD.rank == 0:
            print("RECORD " + json.dumps(record), flush=True)
        return 0

    result = {"benchmark": "step_cost", "machine": machine(MPI.COMM_WORLD),
              "step": STEP, "windows": {**{str(d): w for d, w in WINDOWS.items()},
                                        "3": list(args.window3d)},
              "petsc_options": args.options, "sigma_y": _json_float(args.sigma_y),
              "mu_star": args.mu_star}
    passed_on = [arg for o in args.options for arg in ("-o", o)]
    for flag, value in (("--sigma-y", args.sigma_y), ("--mu-star", args.mu_star)):
        if value is not None:
            passed_on += [flag, repr(value)]
    passed_on += ["--formulation", args.formulation, "--linear", args.linear, "--scheme", args.scheme,
                  "--window3d", *map(repr, args.window3d)]
    result.update({"formulation": args.formulation, "linear": args.linear, "scheme": args.scheme})
    for dim, sizes in ((2, args.sizes2d), (3, args.sizes3d)):
        records = [launch(dim, n, 1, passed_on) for n in sizes]
        result[f"{dim}d"] = {"records": records,
                             "exponent": exponent(records) if len(records) > 1 else None,
                             "split_exponents": ({part: exponent(records, part)
                                                  for part in records[0]["seconds_per_step_split"]}
                                                 if len(records) > 1 else None),
                             "local_exponents": local_exponents(records),
                             f"exponent_largest_{LARGEST_FIT}": largest_fit(records),
                             "marginal_memory_bytes_per_dof": marginal_memory(records)}
    if args.ranks > 1:
        serial = launch(3, args.mpi_size, 1, passed_on)
        parallel = launch(3, args.mpi_size, args.ranks, passed_on)
        speedup = serial["seconds_per_step"] / parallel["seconds_per_step"]
        result["mpi"] = {"serial": serial, "parallel": parallel, "speedup": speedup,
                         "target speedup >= 1.6": bool(speedup >= 1.6)}
    save(result, args.out, MPI.COMM_WORLD)
    return 0


if __name__ == "__main__":
    configure_logging()  # JIT messages off the terminal
    sys.exit(main())
