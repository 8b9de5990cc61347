# SPDX-License-Identifier: MIT
"""Benchmark: what friction costs per step.

Target (issue "Friction"): a frictional step costs at most 1.5× the frictionless step of the same
problem. The problem is the test's block (tests/model/test_friction.py) on a finer mesh: an elastic
block (plane strain, E = 1000, ν = 0.3) [0, 1] × [0, 0.25] pressed onto a normal-compliance
foundation (μ = 1e-3) by its top (u_2 = −0.002 over t ≤ 0.5), then dragged (u_1 = 0.02 (t − 0.5));
with Coulomb friction (𝔣 = 0.3) and without, k = 0.05; with ``--floor rigid`` the foundation is
rigid instead (Signorini: SNES VI, nodal friction). Timed separately: the press (t ≤ 0.5,
where frictional nodes switch between stick and slip) and the drag (t ∈ [0.5, 1]; without
friction the block then translates rigidly, which the linear predictor gets exactly) — wall time
and Newton iterations per step.

    .venv/bin/python bench/friction_step.py [--cells 256 64] [--floor compliant|rigid]

writes bench/results/friction_step.json (friction_step_rigid.json for a rigid floor).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

if not __package__:  # run as a file (python bench/x.py): import bench, tests from the repo root
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from bench.benchlib import check_cells, machine, output_file, positive_int, save  # noqa: E402

from vpcontact.model import Elastic, Elasticity, NormalCompliance, PlaneStrain, Signorini  # noqa: E402
from vpcontact.model.friction import Friction  # noqa: E402
from vpcontact.solver import Dirichlet, QuasistaticProblem, StepControl, advance, tag_facets  # noqa: E402


def run(cells, friction, floor: str = "compliant") -> dict:
    comm = MPI.COMM_WORLD
    msh = dmesh.create_rectangle(comm, [np.zeros(2), np.array([1.0, 0.25])], list(cells))
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[1], 0.25),
                            2: lambda x: np.isclose(x[1], 0.0)})

    def ux(x, t):
        return np.full(x.shape[1], 0.02 * max(t - 0.5, 0.0))

    def uy(x, t):
        return np.full(x.shape[1], -0.002 * min(t / 0.5, 1.0))

    problem = QuasistaticProblem(
        msh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", 1e3, 0.3))),
        dirichlet=[Dirichlet(1, (ux, uy), "top")],
        contact=(NormalCompliance(2, mu=1e-3, friction=friction) if floor == "compliant" else
                 Signorini(2, obstacle=lambda x: x[1], max_distance=1.0, friction=friction)))
    phases = {}
    for name, t_end in (("press", 0.5), ("drag", 1.0)):
        comm.barrier()
        start = time.perf_counter()
        its = [step.newton_iterations for step in advance(problem, t_end, StepControl(0.05))]
        comm.barrier()
        wall = time.perf_counter() - start
        phases[name] = {"steps": len(its), "seconds_per_step": wall / len(its),
                        "newton_iterations_per_step": float(np.mean(its)),
                        "newton_iterations": its}
    _, force = problem.support_forces()
    return {**phases, "dofs": problem.solver.unknowns, "final_contact_force": force.tolist()}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=positive_int, nargs=2, default=[256, 64])
    parser.add_argument("--floor", default="compliant", choices=["compliant", "rigid"])
    parser.add_argument("--out", type=output_file)
    args = parser.parse_args(argv)
    check_cells(parser, "--cells", 2 * args.cells[0] * args.cells[1])
    comm = MPI.COMM_WORLD
    run((8, 2), None, args.floor)  # warm-up: JIT of the forms
    run((8, 2), Friction("coulomb", coefficient=0.3), args.floor)
    frictionless = run(args.cells, None, args.floor)
    coulomb = run(args.cells, Friction("coulomb", coefficient=0.3), args.floor)
    name = "friction_step.json" if args.floor == "compliant" else f"friction_step_{args.floor}.json"
    out = args.out or str(Path(__file__).parent / "results" / name)
    result = {"benchmark": "friction_step", "machine": machine(comm), "cells": args.cells,
              "floor": args.floor,
              "frictionless": frictionless, "coulomb": coulomb,
              "cost_ratio": {phase: coulomb[phase]["seconds_per_step"]
                             / frictionless[phase]["seconds_per_step"]
                             for phase in ("press", "drag")},
              "target_cost_ratio": 1.5}
    save(result, out, comm)
    return 0


if __name__ == "__main__":
    sys.exit(main())
