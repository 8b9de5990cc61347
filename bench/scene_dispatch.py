# SPDX-License-Identifier: MIT
"""Benchmark: a scene costs only what it calls for.

Targets (issue "[3 of 5]"):

* an elastic, contact-free scene costs at most 1.15x a plain dolfinx ``LinearProblem`` over the
  same mesh and steps (a user's loop: update t, ``problem.solve()``);
* a Signorini scene whose obstacle is never reached costs at most 1.2x the same scene without
  contact.

The scene is the bundled ``elastic_2d`` cantilever on a finer mesh (``--cells``), run for
``--steps`` steps; each variant is timed after a warm-up run (JIT, symbolic set-up).

    .venv/bin/python bench/scene_dispatch.py [--cells 256 64] [--steps 10]

writes bench/results/scene_dispatch.json (and prints it).
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI

if not __package__:  # run as a file (python bench/x.py): import bench, tests from the repo root
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from vpcontact.cli import configure_logging
from bench.benchlib import check_cells, machine, output_file, positive_count, positive_int, save
from vpcontact import scene as scenes
from vpcontact.scene import build
from vpcontact.solver import DEFAULT_OPTIONS


def scene_text(cells, steps: int, obstacle: bool) -> str:
    text = scenes.bundled()["elastic_2d"].read_text()
    text = re.sub(r"(?m)^cells = .*$", f"cells = [{cells[0]}, {cells[1]}]", text)
    text = re.sub(r"(?m)^k = .*$", f"k = {1.0 / steps!r}", text)
    text = re.sub(r"(?m)^xdmf = .*$", "", text)
    if obstacle:  # a floor 10 m below the beam: never reached
        text = text.replace("[boundary.end]", '[boundary.floor]\nkind = "contact"\n'
                            'plane = { axis = "y", value = 0.0 }\n\n[boundary.end]')
        text += '\n[contact]\ntype = "signorini"\nboundary = "floor"\ngap = 10.0\n'
    return text


def time_scene(text: str, steps: int, folder: Path, name: str) -> tuple[float, dict]:
    path = folder / f"{name}.toml"
    if MPI.COMM_WORLD.rank == 0:
        path.write_text(text)
    MPI.COMM_WORLD.barrier()
    scene = scenes.load(path)
    build(scene).problem.step(scene.time.k)  # warm-up: JIT and symbolic factorization
    model = build(scene)
    MPI.COMM_WORLD.barrier()
    start = time.perf_counter()  # the time steps only, as for the LinearProblem loop
    for _ in range(steps):
        model.problem.step(scene.time.k)
    wall = time.perf_counter() - start
    s = model.problem.solver
    return wall, {"jacobian_assemblies": s.jacobian_assemblies, "vi_solves": s.vi_solves,
                  "newton_iterations": s.total_iterations}


def time_linear_problem(scene, steps: int) -> float:
    """The same cantilever as a user would write it in dolfinx: one LinearProblem, solve per step."""
    model = build(scene)  # for the mesh only
    mesh = model.problem.mesh
    V = fem.VectorFunctionSpace(mesh, ("Lagrange", 1))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    E, nu = scene.material.E, scene.material.nu
    eps = ufl.sym(ufl.grad(u))
    # plane stress
    sigma = E * nu / (1 - nu ** 2) * ufl.tr(eps) * ufl.Identity(2) + E / (1 + nu) * eps
    t = fem.Constant(mesh, 0.0)
    tags = model.facet_tags
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    end = model.part_tags["end"]
    L = ufl.dot(ufl.as_vector([0.0, -t]), v) * ds(end)
    clamp = fem.locate_dofs_topological(V, 1, tags.find(model.part_tags["clamp"]))
    bc = fem.dirichletbc(np.zeros(2), clamp, V)
    options = {k: val for k, val in DEFAULT_OPTIONS.items() if k.startswith(("ksp_", "pc_"))}
    problem = fem_petsc.LinearProblem(ufl.inner(sigma, ufl.sym(ufl.grad(v))) * ufl.dx, L,
                                      bcs=[bc], petsc_options=options)
    t.value = 1.0
    problem.solve()  # warm-up
    mesh.comm.barrier()
    start = time.perf_counter()
    for n in range(1, steps + 1):
        t.value = n / steps
        problem.solve()
    return time.perf_counter() - start


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=positive_int, nargs=2, default=[256, 64])
    parser.add_argument("--steps", type=positive_count, default=10)
    parser.add_argument("--out", type=output_file,
                        default=str(Path(__file__).parent / "results" / "scene_dispatch.json"))
    args = parser.parse_args(argv)
    check_cells(parser, "--cells", 2 * args.cells[0] * args.cells[1])
    comm = MPI.COMM_WORLD
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(comm.bcast(tmp, root=0))
        free, free_info = time_scene(scene_text(args.cells, args.steps, False), args.steps, folder, "free")
        far, far_info = time_scene(scene_text(args.cells, args.steps, True), args.steps, folder, "far")
        plain = time_linear_problem(scenes.load(folder / "free.toml"), args.steps)
    dofs = 2 * (args.cells[0] + 1) * (args.cells[1] + 1)
    result = {
        "benchmark": "scene_dispatch",
        "machine": machine(comm),
        "problem": {"scene": "elastic_2d", "cells": args.cells, "dofs": dofs, "steps": args.steps},
        "seconds": {"elastic_scene": free, "dolfinx_linear_problem": plain,
                    "signorini_scene_unreached": far},
        "solver_counts": {"elastic_scene": free_info, "signorini_scene_unreached": far_info},
        "elastic_scene_over_linear_problem": free / plain,
        "unreached_signorini_over_no_contact": far / free,
        "targets": {"elastic_scene_over_linear_problem <= 1.15": bool(free / plain <= 1.15),
                    "unreached_signorini_over_no_contact <= 1.2": bool(far / free <= 1.2)},
    }
    save(result, args.out, comm)
    return 0


if __name__ == "__main__":
    configure_logging()  # JIT messages off the terminal
    sys.exit(main())
