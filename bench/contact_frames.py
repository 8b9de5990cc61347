# SPDX-License-Identifier: MIT
"""Benchmark: what Signorini in local frames costs (issue 18: ≤ 1.2× the axis-aligned path on the
same problem, with the same Newton iterations).

The problem: a viscoplastic block (Perzyna, plane stress in 2-D) clamped on its top and pulled by
its weight onto a rigid floor; contact spreads over its bottom while it flows. Three runs on the
same mesh and steps:

* ``aligned``: the floor is y = const: the fast path (bounds on u_y, no change of variables);
* ``aligned_frames``: the same, with local frames forced (identity blocks): the change of
  variables' own cost (Rᵀ F, Rᵀ J R by MatPtAP, R x̃);
* ``rotated``: mesh, load and floor turned by 30° (2-D) or 40° about (1, 2, 2)/3 (3-D): frames
  with full rotation blocks at every contact node.

Timed: the time loop only (JIT and set-up excluded), best of ``--repeat`` runs; also Newton
iterations per step and the solver's wall-time split.

    .venv/bin/python bench/contact_frames.py [--n2d 96] [--n3d 12] [--steps 8] [--repeat 2]

writes bench/results/contact_frames.json (and prints it).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
import ufl
from dolfinx import mesh as dmesh
from mpi4py import MPI

if not __package__:  # run as a file (python bench/x.py): import bench, tests from the repo root
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from vpcontact.cli import configure_logging
from bench.benchlib import machine, mesh_size, output_file, positive_count, save
from vpcontact.model import Elasticity, Perzyna, Signorini
from vpcontact.solver import Loads, QuasistaticProblem, StepControl, advance, tag_facets, time_split

COMM = MPI.COMM_WORLD


def rotation(dim: int, degrees: float) -> np.ndarray:
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    if dim == 2:
        return np.array([[c, -s], [s, c]])
    a = np.array([1.0, 2.0, 2.0]) / 3.0
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + s * K + (1 - c) * K @ K


def problem(dim: int, n: int, Q: np.ndarray, rotate):
    if dim == 2:
        msh = dmesh.create_rectangle(COMM, [np.zeros(2), np.array([2.0, 1.0])], [2 * n, n])
    else:
        msh = dmesh.create_box(COMM, [np.zeros(3), np.array([2.0, 1.0, 1.0])], [2 * n, n, n])
    up = dim - 1
    msh.geometry.x[:, :dim] = msh.geometry.x[:, :dim] @ Q.T
    tags = tag_facets(msh, {1: lambda p: np.isclose((Q.T @ p[:dim])[up], 1.0),
                            2: lambda p: np.isclose((Q.T @ p[:dim])[up], 0.0)})
    law = Perzyna(Elasticity("plane_stress" if dim == 2 else "3d_standard", 1e4, 0.3),
                  sigma_y=20.0, mu_star=500.0)
    weight = Q @ (-40.0 * np.eye(dim)[up])
    loads = Loads(body_force=lambda X, t: ufl.as_vector([float(w) * t for w in weight]))
    normal = Q @ np.eye(dim)[up]
    floor = Signorini(2, obstacle=lambda p: normal @ p[:dim] + 2e-3, max_distance=1.0)
    return QuasistaticProblem(msh, tags, law, clamped_tag=1, loads=loads, contact=floor,
                              rotate_contact=rotate)


def measure(dim: int, n: int, degrees: float, rotate, steps: int, repeat: int) -> dict:
    best = None
    for _ in range(repeat):
        p = problem(dim, n, rotation(dim, degrees), rotate)
        start = time.perf_counter()
        for _ in advance(p, 1.0, StepControl(1.0 / steps)):
            pass
        wall = COMM.allreduce(time.perf_counter() - start, op=MPI.MAX)
        result = {
            "wall_s": wall,
            "newton_iterations": [r.newton_iterations for r in p.reports],
            "active_contact_nodes": p.contact_monitor.report().active,
            "frames": bool(p.contact_dofs.rotated),
            "dofs": p.V.dofmap.index_map.size_global * p.V.dofmap.index_map_bs,
            "split_s": time_split(p.solver.timings),
        }
        p.solver.destroy()
        if best is None or wall < best["wall_s"]:
            best = result
    return best


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n2d", type=mesh_size(4, 2), default=96, help="2-D mesh: 2n × n cells")
    parser.add_argument("--n3d", type=mesh_size(12, 3), default=12, help="3-D mesh: 2n × n × n cells")
    parser.add_argument("--steps", type=positive_count, default=8)
    parser.add_argument("--repeat", type=positive_count, default=2)
    parser.add_argument("--out", type=output_file,
                        default=str(Path(__file__).parent / "results/contact_frames.json"))
    args = parser.parse_args(argv)
    result = {"machine": machine(COMM), "steps": args.steps, "cases": {}}
    for dim, n, degrees in ((2, args.n2d, 30.0), (3, args.n3d, 40.0)):
        problem(dim, 2, np.eye(dim), None)  # JIT outside the timings
        runs = {"aligned": measure(dim, n, 0.0, None, args.steps, args.repeat),
                "aligned_frames": measure(dim, n, 0.0, True, args.steps, args.repeat),
                "rotated": measure(dim, n, degrees, None, args.steps, args.repeat)}
        base = runs["aligned"]
        summary = {
            "rotated_over_aligned": runs["rotated"]["wall_s"] / base["wall_s"],
            "frames_over_aligned": runs["aligned_frames"]["wall_s"] / base["wall_s"],
            "same_newton_iterations": (runs["rotated"]["newton_iterations"]
                                       == base["newton_iterations"]),
            "target": "rotated_over_aligned <= 1.2 with the same Newton iterations",
        }
        summary["met"] = summary["rotated_over_aligned"] <= 1.2 and summary["same_newton_iterations"]
        result["cases"][f"{dim}d"] = {**runs, **summary}
    save(result, args.out, COMM)
    return 0


if __name__ == "__main__":
    configure_logging()  # JIT messages off the terminal
    sys.exit(main())
