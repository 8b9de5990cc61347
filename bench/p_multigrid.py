# SPDX-License-Identifier: MIT
"""Benchmark: the displacement block's preconditioner in the mixed formulation's field split —
one GAMG V-cycle on P2 against vpcontact's two-level p-multigrid (P2 smoothing, a P1 Galerkin
coarse problem under GAMG; :mod:`vpcontact.solver.pc.p_multigrid`): ``p_multigrid`` smooths over
the vertex stars, ``p_multigrid_chebyshev`` with two Chebyshev–Jacobi sweeps (as before the
stars).

Problem (single linear solves): the beam (0,3)×(0,1)×(0,1)
on 3n×n×n tetrahedra, clamped at x = 0, Taylor–Hood P2–P1, E = 1e8, ν = 0.3, the tangent of the
paper's 3-D test once it flows: G_eff = 10³ on x < 2 (the collapsed shear stiffness), G beyond.
``--form dev``: vpcontact's unknowns (p the mean stress, A = 2G_eff dev ε : ε); ``herrmann``:
p̂ = p − (2/3) G_eff div u, A = 2G_eff ε : ε. The rest of the field split is vpcontact's
(lower Schur factorization, the weighted pressure mass matrix under three Chebyshev–Jacobi
sweeps, FGMRES to rtol 1e−8 in the unpreconditioned residual).

For each size: outer iterations, set-up and solve times (max over ranks), the true relative
residual.

    .venv/bin/python bench/p_multigrid.py [--sizes 2 4 6 8 12] [--forms dev herrmann]
    mpirun -n 2 .venv/bin/python bench/p_multigrid.py --sizes 16

writes bench/results/p_multigrid.json (``--out``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from dolfinx.fem.petsc import assemble_matrix, assemble_matrix_block, assemble_vector_block
from mpi4py import MPI
from petsc4py import PETSc

if not __package__:  # run as a file (python bench/x.py): import bench, tests from the repo root
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import vpcontact  # noqa: F401  (one BLAS thread per process)
from vpcontact.solver.near_nullspace import rigid_body_modes
from vpcontact.solver.pc import fieldsplit, p_multigrid

from bench.benchlib import machine, mesh_size, output_file, save  # noqa: E402

E, NU, G_PLASTIC, RTOL = 1e8, 0.3, 1e3, 1e-8
GAMG_U = {"fieldsplit_u_pc_type": "gamg", "fieldsplit_u_pc_gamg_threshold": 0.02,
          "fieldsplit_u_pc_gamg_square_graph": 1, "fieldsplit_u_pc_gamg_coarse_eq_limit": 1000,
          "fieldsplit_u_mg_levels_ksp_type": "chebyshev",
          "fieldsplit_u_mg_levels_pc_type": "jacobi", "fieldsplit_u_mg_levels_ksp_max_it": 2}


def system(comm, n: int, form: str):
    """The block matrix, right-hand side, Schur preconditioner, field index sets and P2 space."""
    msh = dmesh.create_box(comm, [np.zeros(3), np.array([3.0, 1.0, 1.0])], [3 * n, n, n],
                           dmesh.CellType.tetrahedron)
    V = fem.FunctionSpace(msh, ufl.VectorElement("Lagrange", msh.ufl_cell(), 2))
    Q = fem.FunctionSpace(msh, ("Lagrange", 1))
    g = fem.Function(fem.FunctionSpace(msh, ("DG", 0)))
    G = E / (2 * (1 + NU))
    g.interpolate(lambda x: np.where(x[0] < 2.0, G_PLASTIC, G))
    inv_k = fem.Constant(msh, 3 * (1 - 2 * NU) / E)
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    p, q = ufl.TrialFunction(Q), ufl.TestFunction(Q)
    eps = ufl.sym(ufl.grad(u))
    if form == "dev":
        stress, inv_c = 2 * g * ufl.dev(eps), inv_k
    else:
        stress, inv_c = 2 * g * eps, inv_k / (1 - inv_k * 2 * g / 3)
    a = fem.form([[ufl.inner(stress, ufl.sym(ufl.grad(v))) * ufl.dx, p * ufl.div(v) * ufl.dx],
                  [ufl.div(u) * q * ufl.dx, -inv_c * p * q * ufl.dx]])
    sp = fem.form(-(1 / (2 * g) + inv_c) * p * q * ufl.dx)
    x = ufl.SpatialCoordinate(msh)
    f = fem.Constant(msh, PETSc.ScalarType((0.0, 0.0, -1e4)))
    L = fem.form([ufl.inner(f, v) * ufl.dx, 1e-4 * x[0] * q * ufl.dx])
    clamp = dmesh.locate_entities_boundary(msh, 2, lambda x: np.isclose(x[0], 0.0))
    bc = fem.dirichletbc(fem.Function(V), fem.locate_dofs_topological(V, 2, clamp))
    K = assemble_matrix_block(a, bcs=[bc])
    K.assemble()
    S = assemble_matrix(sp)
    S.assemble()
    b = assemble_vector_block(L, a, bcs=[bc])
    n_u = V.dofmap.index_map.size_local * 3
    n_p = Q.dofmap.index_map.size_local
    start = comm.scan(n_u + n_p) - (n_u + n_p)
    is_u = PETSc.IS().createStride(n_u, start, 1, comm=comm)
    is_p = PETSc.IS().createStride(n_p, start + n_u, 1, comm=comm)
    dofs = V.dofmap.index_map.size_global * 3 + Q.dofmap.index_map.size_global
    return K, b, S, is_u, is_p, V, dofs


def solve(comm, K, b, S, is_u, is_p, V, variant: str) -> dict:
    prefix = f"pmg_bench_{variant}_"
    options = {k: v for k, v in fieldsplit.MIXED_OPTIONS.items()}
    options.update({"ksp_rtol": RTOL})
    space = None
    if variant == "gamg":
        options = {k: v for k, v in options.items() if not k.startswith("fieldsplit_u_pc_")}
        options.update(GAMG_U)
    else:
        space = p_multigrid.CoarseSpace(V)
        p_multigrid.register(prefix, space)
        if variant == "p_multigrid_chebyshev":  # the P2 level smoothed as before the stars
            options["fieldsplit_u_pmg_smooth_stars"] = "false"
    opts = PETSc.Options()
    for key, value in options.items():
        opts[prefix + key] = value
    modes = rigid_body_modes(V)
    is_u.compose("nearnullspace", modes)
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(K)
    pc = ksp.getPC()
    pc.setType("fieldsplit")
    pc.setFieldSplitIS(("u", is_u), ("p", is_p))
    ksp.setFromOptions()
    pc.setFieldSplitSchurPreType(PETSc.PC.SchurPreType.USER, S)
    x = K.createVecRight()
    comm.Barrier()
    t0 = time.perf_counter()
    ksp.setUp()
    for sub in pc.getFieldSplitSubKSP():
        sub.setUp()
    t1 = time.perf_counter()
    ksp.solve(b, x)
    t2 = time.perf_counter()
    r = b.duplicate()
    K.mult(x, r)
    r.aypx(-1.0, b)
    record = {"variant": variant, "iterations": ksp.getIterationNumber(),
              "reason": int(ksp.getConvergedReason()),
              "setup_s": comm.allreduce(t1 - t0, op=MPI.MAX),
              "solve_s": comm.allreduce(t2 - t1, op=MPI.MAX),
              "relative_residual": r.norm() / b.norm()}
    for key in options:
        opts.delValue(prefix + key)
    for obj in (ksp, x, r, modes):
        obj.destroy()
    if space is not None:
        space.destroy()
    return record


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=mesh_size(18, 3), nargs="*", default=[2, 4, 6, 8, 12])
    parser.add_argument("--forms", nargs="*", default=["dev", "herrmann"],
                        choices=["dev", "herrmann"])
    parser.add_argument("--variants", nargs="*", default=["gamg", "p_multigrid"],
                        choices=["gamg", "p_multigrid", "p_multigrid_chebyshev"])
    parser.add_argument("--out", type=output_file,
                        default=str(Path(__file__).parent / "results" / "p_multigrid.json"))
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD
    records = []
    for n in args.sizes:
        for form in args.forms:
            K, b, S, is_u, is_p, V, dofs = system(comm, n, form)
            for variant in args.variants:
                record = {"n": n, "dofs": dofs, "form": form,
                          **solve(comm, K, b, S, is_u, is_p, V, variant)}
                records.append(record)
                if comm.rank == 0:
                    print(record, flush=True)
            for obj in (K, b, S, is_u, is_p):
                obj.destroy()
    save({"benchmark": "p_multigrid", "machine": machine(comm), "records": records}, args.out, comm)
    return 0


if __name__ == "__main__":
    sys.exit(main())
