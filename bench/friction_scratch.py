# SPDX-License-Identifier: MIT
"""Benchmark: what friction costs on a viscoplastic body — the scratch scene with and without it.

Target (issue "Friction"): a frictional step costs at most 1.5× the frictionless step of the same
problem. bench/friction_step.py measures it on an elastic block, where the frictionless problem
is linear once pressed (0–2 Newton iterations per step) and any semi-smooth friction iteration
is extra. Here the body is the bundled ``scratch`` scene's Perzyna block (plane strain, mixed
formulation), whose frictionless steps need Newton iterations of their own: the tip pressed in
(t ≤ 0.25) and dragged along (to t = 1), with Coulomb friction 𝔣 = 0.2 and without. Recorded:
wall time of the run, Newton iterations (accepted steps and in all), rejected steps, per
phase (press, drag) seconds per step, and the ratios.

    .venv/bin/python bench/friction_scratch.py [--cells 80 20] [--k 0.025]

writes bench/results/friction_scratch.json (and prints it).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

from mpi4py import MPI

if not __package__:  # run as a file (python bench/x.py): import bench, tests from the repo root
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from bench.benchlib import (check_cells, machine, output_file, positive_float,  # noqa: E402
                            positive_int, save)

from vpcontact import scene as scenes  # noqa: E402
from vpcontact.scene import build  # noqa: E402
from vpcontact.solver import StepControl, advance  # noqa: E402

PRESS = 0.25  # the end of the indentation (the scene's motion)


def run(cells, k: float, friction: bool) -> dict:
    scene = scenes.load_bundled("scratch", cells, k)
    if not friction:
        contact = dataclasses.replace(scene.contacts[0], friction=None)
        scene = dataclasses.replace(scene, contacts=(contact,))
    problem = build(scene).problem
    phases = {"press": [0.0, []], "drag": [0.0, []]}
    start = time.perf_counter()
    for step in advance(problem, scene.time.T, StepControl(k)):
        now = time.perf_counter()
        phase = phases["press" if step.time <= PRESS + 1e-12 else "drag"]
        phase[0] += now - start
        phase[1].append(step.newton_iterations)
        start = now
    out = {name: {"steps": len(its), "seconds_per_step": wall / len(its),
                  "newton_iterations_per_step": sum(its) / len(its)}
           for name, (wall, its) in phases.items()}
    out.update({"seconds": sum(w for w, _ in phases.values()),
                "newton_iterations_total": problem.solver.total_iterations,
                "dofs": problem.solver.unknowns, "formulation": problem.formulation})
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=positive_int, nargs=2, default=[80, 20])
    parser.add_argument("--k", type=positive_float, default=0.025)
    parser.add_argument("--out", type=output_file,
                        default=str(Path(__file__).parent / "results" / "friction_scratch.json"))
    args = parser.parse_args(argv)
    check_cells(parser, "--cells", 2 * args.cells[0] * args.cells[1])
    if args.k > PRESS:  # (each phase needs a step of its own)
        parser.error(f"--k must lie in (0, {PRESS}] (the press phase needs a step), got {args.k}")
    comm = MPI.COMM_WORLD
    run((8, 2), 0.25, True)  # warm-up: JIT of the forms
    run((8, 2), 0.25, False)
    frictionless = run(tuple(args.cells), args.k, False)
    coulomb = run(tuple(args.cells), args.k, True)
    result = {"benchmark": "friction_scratch", "machine": machine(comm), "cells": args.cells,
              "k": args.k, "frictionless": frictionless, "coulomb": coulomb,
              "cost_ratio": {"run": coulomb["seconds"] / frictionless["seconds"],
                             **{phase: coulomb[phase]["seconds_per_step"]
                                / frictionless[phase]["seconds_per_step"]
                                for phase in ("press", "drag")}},
              "target_cost_ratio": 1.5}
    save(result, args.out, comm)
    return 0


if __name__ == "__main__":
    sys.exit(main())
