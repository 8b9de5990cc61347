# SPDX-License-Identifier: MIT
"""Benchmark (a diagnosis): which part of the mixed formulation's field split loses iterations on
a flowing viscoplastic contact step.

The paper's 3-D test (3n×n×n cells, Taylor–Hood, its data, iterative solver) is run to ``--t0``
with k = 0.02, then one step of k = 0.01 begins. The second reduced system SNES VI solves in that
step is captured and solved again by GMRES (rtol 1e-4 and 1e-8, as the VI's lagged solver does)
with each part of the field split swapped for its exact counterpart:

* ``as_used``: vpcontact's solver: one p-multigrid cycle on the displacement block A and, below
  15 000 displacement unknowns (``p_multigrid.STARS_FROM``), three Chebyshev–Jacobi sweeps
  on the weighted pressure mass S_p
  (each point's shear compliance, capped at 10 times that of its pressure nodes' patch mean
  stiffness), from 15 000 on (with the vertex stars) six on the stars' Schur complement Ŝ;
* ``mass``: the stars' cycle with S_p (as used before Ŝ); ``star_schur_lu``: with Ŝ factorized;
  ``coarse_schur``: with Ŝ and the cycle's coarse term, the coarse level factorized
  (``pmg_schur_coarse``, :mod:`vpcontact.solver.coarse_schur`);
* ``cell_weights``: as used, but S_p weighted by each point's own compliance 1/(2G_eff) + 1/K,
  uncapped (vpcontact's solver before the cap);
* ``exact_A``: A factorized (MUMPS), S_p;
* ``formed_schur``: one p-multigrid cycle on A, and the Schur complement C − B Ã⁻¹ Bᵀ of that
  cycle Ã formed column by column and factorized (far too dear to use: a diagnosis);
* ``exact_both``: A factorized and the Schur complement of A formed and factorized;
* ``coarse_lu``, ``four_sweeps``: the p-multigrid cycle with its P1 level factorized, or with
  four Chebyshev–Jacobi sweeps instead of two; ``coarse_lu_stars``: the stars' cycle (and Ŝ)
  with its P1 level factorized;
* ``stars``, ``chebyshev``: the cycle's P2 level smoothed over the vertex stars, or by two
  Chebyshev–Jacobi sweeps, whatever the size (``as_used`` chooses by it);
  ``stars_formed_schur``: the stars' cycle with its Schur complement formed and factorized.

    .venv/bin/python bench/field_split_parts.py [--n 4 8] [--scheme linearized] [--t0 0.06]
        [--sigma-y inf]   # an elastic body, for comparison

writes bench/results/field_split_parts_<scheme>_t<t0>.json (``--out``). Serial only.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchlib import (check_steps, machine, mesh_size, output_file, positive_float,  # noqa: E402
                      positive_or_inf, save)

from vpcontact.paper import signorini as paper  # noqa: E402
from vpcontact.solver import StepControl, advance  # noqa: E402
from vpcontact.solver.pc import factory as pc_factory  # noqa: E402
from vpcontact.solver import vi_linear  # noqa: E402
from vpcontact.solver.pc import fieldsplit, star_schur  # noqa: E402

#: the exact counterparts: (A by MUMPS, Schur complement formed, other options) per variant
VARIANTS = {"as_used": (False, False, {}), "cell_weights": (False, False, {}),
            "exact_A": (True, False, {}),
            "formed_schur": (False, True, {}), "exact_both": (True, True, {}),
            # the cycle's own parts: its P1 level solved exactly, or four smoothing sweeps
            "coarse_lu": (False, False, {"fieldsplit_u_pmg_coarse_pc_type": "lu",
                                         "fieldsplit_u_pmg_coarse_pc_factor_mat_solver_type":
                                         "mumps", "fieldsplit_u_pmg_smooth_stars": "false"}),
            "four_sweeps": (False, False, {"fieldsplit_u_pmg_smooth_ksp_max_it": 4,
                                           "fieldsplit_u_pmg_smooth_stars": "false"}),
            # the P2 level's smoothing chosen (as_used: by the block's size)
            "stars": (False, False, {"fieldsplit_u_pmg_smooth_stars": "true"}),
            "chebyshev": (False, False, {"fieldsplit_u_pmg_smooth_stars": "false"}),
            "stars_formed_schur": (False, True, {"fieldsplit_u_pmg_smooth_stars": "true"}),
            # the Schur block: the weighted mass S_p with the stars (as used before the stars'
            # Schur complement), or the stars' Schur complement factorized
            "mass": (False, False, {"fieldsplit_u_pmg_smooth_stars": "true"}),
            "star_schur_lu": (False, False, {"fieldsplit_u_pmg_smooth_stars": "true",
                                             "fieldsplit_p_pc_type": "lu"}),
            # the stars' Schur complement with the cycle's coarse term, the coarse level and
            # the mixed coarse matrix factorized (vpcontact.solver.coarse_schur)
            "coarse_schur": (False, False, {"fieldsplit_u_pmg_smooth_stars": "true"})}
#: the stars' cycle (and its Ŝ) with its P1 level factorized
VARIANTS["coarse_lu_stars"] = (False, False, {**VARIANTS["coarse_lu"][2],
                                              "fieldsplit_u_pmg_smooth_stars": "true"})
#: variants whose Schur block is the stars' Ŝ (``as_used`` too where the solver has one)
STAR_SCHUR = ("star_schur_lu", "coarse_schur", "coarse_lu_stars")


def _inner(solver, block, matrix, exact_a: bool, formed: bool, extra: dict,
           name: str) -> PETSc.KSP:
    """The field split of vpcontact's lagged VI solver on ``matrix``, with the swaps."""
    prefix = solver.prefix + f"parts_{name}_"
    coarse = name == "coarse_schur"
    star = not formed and (name in STAR_SCHUR
                           or (name == "as_used" and block.star_schur is not None))
    options = pc_factory.lagged_options(True)
    if coarse:
        options = fieldsplit.coarse_schur_options(options)
    elif star:
        options = fieldsplit.star_schur_options(options)
    options.update(extra)
    if exact_a:
        options.update({"fieldsplit_u_pc_type": "lu",
                        "fieldsplit_u_pc_factor_mat_solver_type": "mumps"})
    if formed:
        options.update({"fieldsplit_p_ksp_type": "preonly", "fieldsplit_p_pc_type": "lu"})
    ksp = PETSc.KSP().create(MPI.COMM_WORLD)
    ksp.setOptionsPrefix(prefix)
    ksp.setType("preonly")
    ksp.setOperators(matrix)
    with vi_linear.options_in_database(prefix, options):
        ksp.setFromOptions()
        pc = ksp.getPC()
        pc.setFieldSplitIS(("u", block.is_u), ("p", block.is_p))
        block.coarse_space.schur = None
        if formed:
            pc.setFieldSplitSchurPreType(PETSc.PC.SchurPreType.FULL)
        elif star:
            schur = block.star_schur
            if schur is None or coarse != (schur.coarse is not None):
                schur = _SCRATCH[prefix] = star_schur.StarSchur(block.is_u, block.is_p,
                                                                 coarse=coarse)
            schur.parents[prefix] = pc
            block.coarse_space.schur = schur
            pc.setFieldSplitSchurPreType(PETSc.PC.SchurPreType.USER, schur.matrix)
        else:
            pc.setFieldSplitSchurPreType(PETSc.PC.SchurPreType.USER, _mass(block, name))
        ksp.setUp()
        for sub in pc.getFieldSplitSubKSP():  # (with the options: as the lagged solver does)
            sub.setUp()
    block.coarse_space.schur = block.star_schur  # (the production solver's again)
    return ksp


def _forget_split(block, prefix: str) -> None:
    """Drop a variant's field split from the solver's stars' Schur complement, and destroy the
    one built for the variant where the solver has none (or one of the other kind)."""
    if block.star_schur is not None:
        block.star_schur.parents.pop(prefix, None)
    scratch = _SCRATCH.pop(prefix, None)
    if scratch is not None:
        scratch.destroy()


#: the stars' Schur complements built for variants where the solver has none, by prefix
_SCRATCH: dict = {}


def _mass(block, name: str) -> PETSc.Mat:
    """S_p as used (capped), or (``cell_weights``) weighted by each point's own compliance."""
    if name != "cell_weights":
        block.assemble_mass()
        return block.matrix
    fields = block.fields
    q, dp = ufl.TestFunction(fields.Q), ufl.TrialFunction(fields.Q)
    weight = 1.0 / fields.shear_stiffness() + fields.inverse_bulk
    form = fem.form(-(fields.beta ** 2 * block.scale) * weight * dp * q * fields.measure)
    matrix = fem_petsc.assemble_matrix(form)
    matrix.assemble()
    return matrix


def measure(n: int, scheme: str, t0: float, sigma_y: float, variants) -> dict:
    problem = paper.signorini_3d(3 * n, n, n, petsc_options={}, sigma_y=sigma_y,
                                 mu_star=paper.MU_STAR, scheme=scheme, formulation="mixed",
                                 degree=2, linear="iterative")
    list(advance(problem, t0, StepControl(0.02)))
    solver = problem.solver
    block = solver._block
    record = {"n": n, "unknowns": solver.unknowns}
    solves = {"count": 0}
    original = vi_linear.LaggedMultigrid.solve

    def capture(lagged, ksp, b, x):
        original(lagged, ksp, b, x)
        solves["count"] += 1
        if solves["count"] != 2:
            return
        reduced, _ = ksp.getOperators()
        record["reduced_size"] = reduced.getSize()[0]
        record["production_iterations"] = lagged.krylov.getIterationNumber()
        kept = lagged.inner
        for name in variants:
            start = time.perf_counter()
            lagged.inner = _inner(solver, block, lagged.matrix, *VARIANTS[name], name)
            setup = time.perf_counter() - start
            y = x.duplicate()
            row = {"setup_seconds": setup}
            for rtol in (1e-4, 1e-8):
                y.set(0.0)
                start = time.perf_counter()
                converged = lagged._krylov(reduced, b, y, rtol, 0.0, 600)
                row[f"iterations_rtol_{rtol:g}"] = lagged.krylov.getIterationNumber()
                row[f"converged_rtol_{rtol:g}"] = bool(converged)
                row[f"seconds_rtol_{rtol:g}"] = time.perf_counter() - start
            record[name] = row
            _forget_split(block, solver.prefix + f"parts_{name}_")
            lagged.inner.destroy()
            y.destroy()
        lagged.inner = kept

    vi_linear.LaggedMultigrid.solve = capture
    try:
        problem.step(0.01)
    finally:
        vi_linear.LaggedMultigrid.solve = original
    return record


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=mesh_size(18, 3), nargs="+", default=[4, 8])
    parser.add_argument("--scheme", default="linearized", choices=["implicit", "linearized"])
    parser.add_argument("--t0", type=positive_float, default=0.06)
    parser.add_argument("--sigma-y", type=positive_or_inf, default=paper.SIGMA_Y)
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--out", type=output_file)
    args = parser.parse_args(argv)
    check_steps(parser, "--t0", args.t0 / 0.02)
    comm = MPI.COMM_WORLD
    if comm.size != 1:
        raise SystemExit("field_split_parts.py runs serially")
    records = [measure(n, args.scheme, args.t0, args.sigma_y, args.variants) for n in args.n]
    body = "elastic" if math.isinf(args.sigma_y) else "flowing"
    out = args.out or str(Path(__file__).parent / "results"
                          / f"field_split_parts_{args.scheme}_{body}_t{args.t0:g}.json")
    save({"benchmark": "field_split_parts", "machine": machine(comm), "scheme": args.scheme,
          "t0": args.t0, "sigma_y": None if math.isinf(args.sigma_y) else args.sigma_y,
          "records": records}, out, comm)
    return 0


if __name__ == "__main__":
    sys.exit(main())
