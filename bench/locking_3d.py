# SPDX-License-Identifier: MIT
"""Volumetric locking on the paper's 3-D test, and how the formulations converge.

The bundled ``signorini_3d`` (§4.1.2, all its data: E = 1e8, ν = 0.3, σ_Y = √10 with the
paper's set, μ* = 200, k = 0.02) run to t = T on the beam refined as 3n × n × n cells (six
tetrahedra each), with the displacement formulation at P1 and P2 and the mixed one (Taylor–Hood
P2–P1). Recorded per run: u at a few points of the free end and the middle of the top face,
the contact force, the unknowns, Newton iterations and the wall time. Differences between
successive meshes show each formulation's convergence; P1 locks (it barely moves under
refinement, far from the converged value).

    .venv/bin/python bench/locking_3d.py [--sizes 2 3 4 6 8] [--formulations mixed p1 p2]
        [--T 0.3] [--out bench/results/locking_3d.json]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from dolfinx import geometry
from mpi4py import MPI

if not __package__:  # run as a file (python bench/x.py): import bench, tests from the repo root
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from bench.benchlib import check_steps, machine, mesh_size, output_file, positive_float, save
from vpcontact import scene as scenes
from vpcontact.solver import StepControl, advance

POINTS = {"end_top": (3.0, 0.5, 1.0), "end_bottom": (3.0, 0.5, 0.0), "mid_top": (1.5, 0.5, 1.0)}
FORMULATIONS = {"p1": ("displacement", 1), "p2": ("displacement", 2), "mixed": ("mixed", 2)}


def value_at(u, point) -> list:
    """u at a point (collective: the rank that owns a cell around it evaluates)."""
    mesh = u.function_space.mesh
    tree = geometry.BoundingBoxTree(mesh, mesh.topology.dim)
    pts = np.array([point], dtype=np.float64)
    cells = geometry.compute_colliding_cells(mesh, geometry.compute_collisions(tree, pts), pts)
    local = u.eval(pts, cells.links(0)[:1]).tolist() if len(cells.links(0)) else None
    return next(v for v in mesh.comm.allgather(local) if v is not None)


def run(n: int, formulation: str, T: float) -> dict:
    scene = scenes.load(scenes.bundled()["signorini_3d"])
    kind, degree = FORMULATIONS[formulation]
    scene = dataclasses.replace(
        scene, mesh=dataclasses.replace(scene.mesh, cells=(3 * n, n, n)),
        time=dataclasses.replace(scene.time, T=T), formulation=kind, degree=degree)
    start = time.perf_counter()
    problem = scenes.build(scene).problem
    newton = 0
    for report in advance(problem, T, StepControl(scene.time.k)):
        newton += report.newton_iterations
    wall = problem.mesh.comm.allreduce(time.perf_counter() - start, op=MPI.MAX)
    _, contact = problem.support_forces()
    return {"n": n, "cells": [3 * n, n, n], "formulation": formulation,
            "unknowns": problem.solver.unknowns,
            "u": {name: value_at(problem.u, p) for name, p in POINTS.items()},
            "contact_force_z": float(contact[2]), "newton_iterations": newton,
            "wall_time_s": wall}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=mesh_size(18, 3), nargs="+", default=[2, 3, 4, 6, 8])
    parser.add_argument("--formulations", nargs="+", default=["mixed", "p2", "p1"],
                        choices=tuple(FORMULATIONS))
    parser.add_argument("--T", type=positive_float, default=0.3)
    parser.add_argument("--out", type=output_file,
                        default=str(Path(__file__).parent / "results" / "locking_3d.json"))
    args = parser.parse_args(argv)
    check_steps(parser, "--T", args.T / 0.02)  # (the scene's k)
    comm = MPI.COMM_WORLD
    runs = []
    for formulation in args.formulations:
        for n in args.sizes:
            runs.append(run(n, formulation, args.T))
            if comm.rank == 0:
                r = runs[-1]
                print(f"{formulation:6s} n={n:2d} unknowns={r['unknowns']:7d} "
                      f"u3(end top)={r['u']['end_top'][2]:.4e} "
                      f"u1(end top)={r['u']['end_top'][0]:.4e} {r['wall_time_s']:.1f} s", flush=True)
    save({"benchmark": "locking_3d", "machine": machine(comm), "T": args.T, "runs": runs},
         args.out, comm)


if __name__ == "__main__":
    main()
