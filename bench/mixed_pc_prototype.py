# SPDX-License-Identifier: MIT
"""Prototype: block preconditioners for the Taylor–Hood (P2–P1) displacement–pressure system.

Measures how PETSc solvers cope with the linearised (Newton) system of a mixed u–p formulation of
nearly incompressible / isochoric-plastic 3-D bodies, before anything is built into vpcontact.

Problem: the beam (0,3)×(0,1)×(0,1), tetrahedra from ``create_box`` with 3n×n×n cells, clamped at
x = 0; u ∈ P2 (vector), p ∈ P1 (mean stress). E = 1e8, ν = 0.3 (G = E/2(1+ν), K = E/3(1−2ν)).
The matrix is the symmetric saddle point (β = 1)

    [ A  Bᵀ ] [du]      A(du, v) = ∫ 2 G_eff dev ε(du) : ε(v) dx
    [ B −C  ] [dp],     B(du, q) = ∫ div du q dx,     C(dp, q) = ∫ (1/K) dp q dx

with a cellwise G_eff (``--form dev``, as briefed). ``--form lame`` (recommended) is Herrmann's
variant: A = ∫ 2 G_eff ε(du) : ε(v), C = 1/(K − 2G_eff/3), p̂ = p − (2/3) G_eff div u; its Schur
complement is spectrally equivalent to the weighted mass matrix (the dev form's has outliers up to
1e4–1e8 that grow with n). By default the system is scaled symmetrically to unit diagonal
(``--scaling diag``). The Schur preconditioner handed to PETSc is −Sp (S is negative definite).
Cases (``--case``):

* ``plastic_x2``   G_eff = 1e3 for x < 2 (the collapsed shear stiffness of the consistent
                   tangent, contrast ≈ 4e4), G elsewhere; ν = 0.3.
* ``plastic_all``  G_eff = 1e3 everywhere; ν = 0.3.
* ``elastic_nu05`` G_eff = G = E/3, ν = 0.5, 1/K = 0 (C = 0).

Each case also runs with ``_id`` appended: the z-displacement dofs on the face z = 0 with
x > 1.5 replaced by identity rows and columns (``MatZeroRowsColumns``, diagonal 1), as in the
full-size matrix M of vpcontact's SNES-VI linear solver.

Solvers (``--solvers``): PCFIELDSPLIT Schur variants (GAMG on the displacement block with the
six rigid-body modes of the P2 dof coordinates as near null space; the Schur complement
preconditioned by the pressure mass matrix weighted cellwise by 1/(2 G_eff) + 1/K, or by
PETSc's ``selfp``), plain GAMG on the monolithic matrix, and MUMPS LU.

For each size n (``--sizes``), case and solver: outer Krylov iterations to rtol 1e-8 in the
unpreconditioned residual norm, setup and solve wall times (max over ranks), the true relative
residual, the error against the MUMPS solution (when MUMPS ran), the growth of the resident
memory during setup and, for MUMPS, its own memory report (INFOG(22), MB summed over ranks).

    .venv/bin/python bench/mixed_pc_prototype.py [--sizes 2 4 6 8] [--case plastic_x2 ...]
        [--solvers fs_full_mass_jacobi mumps ...] [--out bench/results/mixed_pc_prototype.json]
    mpirun -n 2 --allow-run-as-root .venv/bin/python bench/mixed_pc_prototype.py ...

writes (or, with ``--append``, merges into) bench/results/mixed_pc_prototype.json.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

import ufl
from dolfinx import fem, mesh as dmesh
from dolfinx.fem.petsc import assemble_matrix, assemble_matrix_block, assemble_vector_block

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchlib import key_value, machine, mesh_size, nonnegative_int, output_file  # noqa: E402

E = 1e8
G_PLASTIC = 1e3
RTOL = 1e-8

# --------------------------------------------------------------------------------------------
# Solver configurations: PETSc options relative to the outer KSP's prefix, plus the Schur
# preconditioning matrix (``schur_user``: the weighted pressure mass matrix via
# PCFieldSplitSetSchurPre(USER)).
# --------------------------------------------------------------------------------------------
GAMG_U = {
    "fieldsplit_u_ksp_type": "preonly",
    "fieldsplit_u_pc_type": "gamg",
    "fieldsplit_u_pc_gamg_threshold": "0.02",
    "fieldsplit_u_pc_gamg_square_graph": "1",
    "fieldsplit_u_pc_gamg_coarse_eq_limit": "1000",
    "fieldsplit_u_mg_levels_ksp_type": "chebyshev",
    "fieldsplit_u_mg_levels_pc_type": "jacobi",
    "fieldsplit_u_mg_levels_ksp_max_it": "2",
}
P_JACOBI = {"fieldsplit_p_ksp_type": "preonly", "fieldsplit_p_pc_type": "jacobi"}
# The Schur KSP's operator is PETSc's MatSchurComplement S (each application solves with A);
# iterating on the mass matrix Sp alone needs PCKSP (its inner KSP works on the Pmat, Sp).
P_CHEB = {"fieldsplit_p_ksp_type": "preonly", "fieldsplit_p_pc_type": "ksp",
          "fieldsplit_p_ksp_ksp_type": "chebyshev", "fieldsplit_p_ksp_ksp_max_it": "3",
          "fieldsplit_p_ksp_ksp_norm_type": "none",
          "fieldsplit_p_ksp_ksp_chebyshev_eigenvalues": "0.5,2.5",
          "fieldsplit_p_ksp_pc_type": "jacobi"}


def fieldsplit(fact: str, pre: str = "user", outer: str = "fgmres", u=None, p=None,
               sp_positive: bool = False) -> dict:
    opts = {"ksp_type": outer, "ksp_gmres_restart": "200", "ksp_rtol": str(RTOL),
            "ksp_max_it": "500", "ksp_norm_type": "unpreconditioned",
            "pc_type": "fieldsplit", "pc_fieldsplit_type": "schur",
            "pc_fieldsplit_schur_fact_type": fact}
    if outer == "gmres":
        opts["ksp_pc_side"] = "right"
    if pre != "user":
        opts["pc_fieldsplit_schur_precondition"] = pre
    if fact == "diag":
        opts["pc_fieldsplit_schur_scale"] = "1.0"  # −Sp already has S's sign (PETSc's default: −1)
    opts.update(GAMG_U if u is None else u)
    opts.update(P_JACOBI if p is None else p)
    if sp_positive:  # wrong sign for lower/upper/full (diag: PETSc's scale −1 flips it back)
        opts.pop("pc_fieldsplit_schur_scale", None)
    return {"options": opts, "schur_user": pre == "user", "sp_positive": sp_positive}


def _with(base: dict, **changes) -> dict:
    out = dict(base)
    out.update({k: str(v) for k, v in changes.items()})
    return out


SOLVERS = {
    # Schur factorisations, one GAMG V-cycle on A, Jacobi on the weighted pressure mass matrix
    "fs_full_mass_jacobi": fieldsplit("full"),
    "fs_lower_mass_jacobi": fieldsplit("lower"),
    "fs_upper_mass_jacobi": fieldsplit("upper"),
    "fs_diag_mass_jacobi": fieldsplit("diag"),
    "fs_lower_mass_jacobi_possign": fieldsplit("lower", sp_positive=True),
    "fs_lower_mass_cheb_possign": fieldsplit("lower", p=P_CHEB, sp_positive=True),
    "fs_diag_mass_cheb_possign": fieldsplit("diag", p=P_CHEB, sp_positive=True),
    "fs_lower_mass_jacobi_gmres": fieldsplit("lower", outer="gmres"),
    # Schur preconditioner applied by GAMG / ICC / Chebyshev-Jacobi on the mass matrix
    "fs_lower_mass_gamg": fieldsplit("lower", p={"fieldsplit_p_ksp_type": "preonly",
                                                  "fieldsplit_p_pc_type": "gamg"}),
    "fs_lower_mass_icc": fieldsplit("lower", p={"fieldsplit_p_ksp_type": "preonly",
                                                 "fieldsplit_p_pc_type": "bjacobi",
                                                 "fieldsplit_p_sub_pc_type": "icc"}),
    # P1 tetrahedra: spectrum of diag(M)^-1 M (any positive cellwise weight) lies in [0.5, 2.5]
    "fs_lower_mass_cheb": fieldsplit("lower", p=P_CHEB),
    "fs_full_mass_cheb": fieldsplit("full", p=P_CHEB),
    "fs_diag_mass_cheb": fieldsplit("diag", p=P_CHEB),
    # CG on the true Schur complement S (inner A-solves by the u-block's V-cycle), Sp-Jacobi
    "fs_lower_schurcg": fieldsplit("lower", p={"fieldsplit_p_ksp_type": "cg",
                                                "fieldsplit_p_ksp_rtol": "1e-2",
                                                "fieldsplit_p_pc_type": "jacobi"}),
    "fs_lower_schurgmres": fieldsplit("lower", p={"fieldsplit_p_ksp_type": "gmres",
                                                   "fieldsplit_p_ksp_rtol": "1e-2",
                                                   "fieldsplit_p_pc_type": "jacobi"}),
    # CG on the mass matrix Sp alone (PCKSP), to 1e-3
    "fs_lower_mass_cg": fieldsplit("lower", p={"fieldsplit_p_ksp_type": "preonly",
                                                "fieldsplit_p_pc_type": "ksp",
                                                "fieldsplit_p_ksp_ksp_type": "cg",
                                                "fieldsplit_p_ksp_ksp_rtol": "1e-3",
                                                "fieldsplit_p_ksp_pc_type": "jacobi"}),
    "fs_lower_mass_cheb_sq0": fieldsplit("lower", p=P_CHEB,
                                         u=_with(GAMG_U, fieldsplit_u_pc_gamg_square_graph=0)),
    "fs_lower_mass_cheb_cg1e-1": fieldsplit("lower", p=P_CHEB,
                                            u=_with(GAMG_U, fieldsplit_u_ksp_type="cg",
                                                    fieldsplit_u_ksp_rtol=1e-1)),
    "fs_lower_mass_cheb_cg1e-2": fieldsplit("lower", p=P_CHEB,
                                            u=_with(GAMG_U, fieldsplit_u_ksp_type="cg",
                                                    fieldsplit_u_ksp_rtol=1e-2)),
    "fs_lower_mass_cheb_2v": fieldsplit("lower", p=P_CHEB,
                                        u=_with(GAMG_U, fieldsplit_u_ksp_type="richardson",
                                                fieldsplit_u_ksp_max_it=2,
                                                fieldsplit_u_ksp_norm_type="none")),
    "fs_lower_mass_cheb_sm4": fieldsplit("lower", p=P_CHEB,
                                         u=_with(GAMG_U, fieldsplit_u_mg_levels_ksp_max_it=4)),
    # PETSc's selfp = C + B diag(A)^-1 Bᵀ instead of the mass matrix
    "fs_lower_selfp_jacobi": fieldsplit("lower", pre="selfp"),
    "fs_lower_selfp_gamg": fieldsplit("lower", pre="selfp",
                                      p={"fieldsplit_p_ksp_type": "preonly",
                                         "fieldsplit_p_pc_type": "gamg"}),
    # the displacement block solved more accurately (inner CG + GAMG)
    "fs_lower_mass_jacobi_cg1e-2": fieldsplit("lower", u=_with(GAMG_U, fieldsplit_u_ksp_type="cg",
                                                               fieldsplit_u_ksp_rtol=1e-2)),
    # GAMG variants on the displacement block
    "fs_lower_mass_jacobi_thr0": fieldsplit("lower", u=_with(GAMG_U, fieldsplit_u_pc_gamg_threshold=0.0)),
    "fs_lower_mass_jacobi_thr05": fieldsplit("lower", u=_with(GAMG_U, fieldsplit_u_pc_gamg_threshold=0.05)),
    "fs_lower_mass_jacobi_sq0": fieldsplit("lower", u=_with(GAMG_U, fieldsplit_u_pc_gamg_square_graph=0)),
    "fs_lower_mass_jacobi_sm1": fieldsplit("lower", u=_with(GAMG_U, fieldsplit_u_mg_levels_ksp_max_it=1)),
    "fs_lower_mass_jacobi_sm4": fieldsplit("lower", u=_with(GAMG_U, fieldsplit_u_mg_levels_ksp_max_it=4)),
    "fs_lower_mass_jacobi_sor": fieldsplit("lower", u=_with(GAMG_U, fieldsplit_u_mg_levels_ksp_type="richardson",
                                                            fieldsplit_u_mg_levels_pc_type="sor")),
    "fs_full_mass_jacobi_sor": fieldsplit("full", u=_with(GAMG_U, fieldsplit_u_mg_levels_ksp_type="richardson",
                                                          fieldsplit_u_mg_levels_pc_type="sor")),
    "fs_lower_mass_jacobi_nonull": fieldsplit("lower"),   # near null space left out (see run_one)
    "fs_lower_mass_jacobi_hypre": fieldsplit("lower", u={"fieldsplit_u_ksp_type": "preonly",
                                                         "fieldsplit_u_pc_type": "hypre",
                                                         "fieldsplit_u_pc_hypre_type": "boomeramg",
                                                         "fieldsplit_u_pc_hypre_boomeramg_strong_threshold": "0.5"}),
    # monolithic
    "gamg_monolithic": {"options": {"ksp_type": "gmres", "ksp_gmres_restart": "200",
                                    "ksp_pc_side": "right", "ksp_norm_type": "unpreconditioned",
                                    "ksp_rtol": str(RTOL), "ksp_max_it": "500", "pc_type": "gamg",
                                    "pc_gamg_threshold": "0.02"}, "schur_user": False},
    "mumps": {"options": {"ksp_type": "preonly", "pc_type": "lu",
                          "pc_factor_mat_solver_type": "mumps", "mat_mumps_icntl_14": "80"},
              "schur_user": False},
}


# --------------------------------------------------------------------------------------------
def rss_mb() -> float:
    """Resident memory of this process, MB."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 / 2**20


def material(case: str):
    nu = 0.5 if case.startswith("elastic_nu05") else 0.3
    G = E / (2 * (1 + nu))
    inv_K = 0.0 if nu == 0.5 else 3 * (1 - 2 * nu) / E
    return G, inv_K


class System:
    """The assembled block system for one mesh size and case."""

    def __init__(self, comm, n: int, case: str, scaling: str = "diag", form: str = "dev"):
        t0 = time.perf_counter()
        self.comm, self.n, self.case = comm, n, case
        constrained = case.endswith("_id")
        base = case[:-3] if constrained else case
        G, inv_K = material(base)
        msh = dmesh.create_box(comm, [np.zeros(3), np.array([3.0, 1.0, 1.0])], [3 * n, n, n],
                               dmesh.CellType.tetrahedron)
        cell = msh.ufl_cell()
        V = fem.FunctionSpace(msh, ufl.VectorElement("Lagrange", cell, 2))
        Q = fem.FunctionSpace(msh, ufl.FiniteElement("Lagrange", cell, 1))
        D = fem.FunctionSpace(msh, ("DG", 0))
        g_eff = fem.Function(D)
        if base == "plastic_x2":
            g_eff.interpolate(lambda x: np.where(x[0] < 2.0, G_PLASTIC, G))
        elif base == "plastic_all":
            g_eff.x.array[:] = G_PLASTIC
        elif base == "elastic_nu05":
            g_eff.x.array[:] = G
        else:
            raise ValueError(f"unknown case {case}")
        ik = fem.Constant(msh, PETSc.ScalarType(inv_K))

        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        p, q = ufl.TrialFunction(Q), ufl.TestFunction(Q)
        eps = ufl.sym(ufl.grad(u))
        if form == "dev":
            # as briefed: p = mean stress, A = 2 G_eff dev ε : ε, C = 1/K
            A_u = 2 * g_eff * (eps - ufl.tr(eps) / 3 * ufl.Identity(3))
            inv_c = ik
        elif form == "lame":
            # Herrmann: p̂ = p − (2/3) G_eff div u, A = 2 G_eff ε : ε, C = 1/λ_eff,
            # λ_eff = K − (2/3) G_eff (> 0 whenever ν_eff > 0); mean stress = p̂ + (2/3) G_eff div u
            A_u = 2 * g_eff * eps
            inv_c = ik / (1 - ik * 2 * g_eff / 3)  # 1/(K − 2G/3), 0 when 1/K = 0
        elif form == "dev_pmat":
            # the dev system, preconditioned through a Pmat whose displacement block is
            # Herrmann's 2 G_eff ε : ε (= dev block + (2/3) G_eff div du div v)
            A_u = 2 * g_eff * (eps - ufl.tr(eps) / 3 * ufl.Identity(3))
            inv_c = ik
        else:
            raise ValueError(form)
        self.P = None
        if form == "dev_pmat":
            a_pc = fem.form([[ufl.inner(2 * g_eff * eps, ufl.sym(ufl.grad(v))) * ufl.dx,
                              p * ufl.div(v) * ufl.dx],
                             [ufl.div(u) * q * ufl.dx, -inv_c * p * q * ufl.dx]])
        a = fem.form([[ufl.inner(A_u, ufl.sym(ufl.grad(v))) * ufl.dx, p * ufl.div(v) * ufl.dx],
                      [ufl.div(u) * q * ufl.dx, -inv_c * p * q * ufl.dx]])
        # Schur preconditioner: S = −C − B A⁻¹ Bᵀ ≈ −M[1/(2 G_eff) + 1/K]  (negative definite);
        # we give PETSc the positive matrix (PCs like GAMG/ICC want SPD), the sign is GMRES's.
        sp_form = fem.form((1 / (2 * g_eff) + inv_c) * p * q * ufl.dx)
        x = ufl.SpatialCoordinate(msh)
        f = fem.Constant(msh, PETSc.ScalarType((0.0, 0.0, -1e4)))
        L = fem.form([ufl.inner(f, v) * ufl.dx, 1e-4 * x[0] * q * ufl.dx])

        fdim = msh.topology.dim - 1
        clamp = dmesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[0], 0.0))
        zero = fem.Function(V)
        bc = fem.dirichletbc(zero, fem.locate_dofs_topological(V, fdim, clamp))

        self.K = assemble_matrix_block(a, bcs=[bc])
        self.K.assemble()
        if form == "dev_pmat":
            self.P = assemble_matrix_block(a_pc, bcs=[bc])
            self.P.assemble()
        self.Sp = assemble_matrix(sp_form)
        self.Sp.assemble()
        self.b = assemble_vector_block(L, a, bcs=[bc])

        # field index sets in the block matrix (dolfinx: per rank, owned u then owned p)
        imu, imq = V.dofmap.index_map, Q.dofmap.index_map
        bs = V.dofmap.index_map_bs
        nu_loc, np_loc = imu.size_local * bs, imq.size_local
        off_u = imu.local_range[0] * bs + imq.local_range[0]
        off_p = off_u + nu_loc
        self.is_u = PETSc.IS().createStride(nu_loc, off_u, 1, comm=PETSc.COMM_SELF)
        self.is_u.setBlockSize(bs)
        self.is_p = PETSc.IS().createStride(np_loc, off_p, 1, comm=PETSc.COMM_SELF)

        # rigid-body modes of the P2 dof coordinates, orthonormalised (u-block layout)
        X = V.tabulate_dof_coordinates()[:imu.size_local]
        o, z = np.ones(len(X)), np.zeros(len(X))
        fields = [np.column_stack(c) for c in
                  ((o, z, z), (z, o, z), (z, z, o), (-X[:, 1], X[:, 0], z),
                   (z, -X[:, 2], X[:, 1]), (X[:, 2], z, -X[:, 0]))]
        vecs = []
        for fld in fields:
            vec = PETSc.Vec().createMPI((nu_loc, PETSc.DECIDE), bsize=bs, comm=comm)
            vec.array[:] = fld.ravel()
            for prev in vecs:
                vec.axpy(-vec.dot(prev), prev)
            vec.normalize()
            vecs.append(vec)
        self.nullspace = PETSc.NullSpace().create(vectors=vecs, comm=comm)

        # identity rows/columns: z-dofs on z = 0, x > 1.5 (as the VI solver's M)
        self.n_constrained = 0
        if constrained:
            sel = np.flatnonzero(np.isclose(X[:, 2], 0.0) & (X[:, 0] > 1.5))
            rows = (off_u + sel * bs + 2).astype(PETSc.IntType)
            self.K.zeroRowsColumns(rows, diag=1.0)
            if self.P is not None:
                self.P.zeroRowsColumns(rows, diag=1.0)
            self.b.setValues(rows, np.zeros(len(rows)))
            self.b.assemble()
            self.n_constrained = comm.allreduce(len(rows))

        # symmetric diagonal scaling D K D, D = diag(|diag A|^-1/2, diag(Sp)^-1/2): unit diagonal
        # in A and in the Schur preconditioner, B = O(1); the residual norm then weighs the u and
        # p equations (and soft and stiff regions) alike. The near null space becomes D_u^-1 r.
        self.scaling = scaling
        self.nu_loc = nu_loc
        self.d = self.K.createVecRight()
        self.d.set(1.0)
        if scaling == "diag":
            dk = self.K.getDiagonal()
            dsp = self.Sp.getDiagonal()
            self.d.array[:nu_loc] = 1.0 / np.sqrt(np.abs(dk.array[:nu_loc]))
            self.d.array[nu_loc:] = 1.0 / np.sqrt(dsp.array)
            dp = dsp.copy()
            dp.array[:] = self.d.array[nu_loc:]
            self.K.diagonalScale(self.d, self.d)
            if self.P is not None:
                self.P.diagonalScale(self.d, self.d)
            self.Sp.diagonalScale(dp, dp)
            self.b.pointwiseMult(self.b, self.d)
            for vec in vecs:
                vec.array[:] /= self.d.array[:nu_loc]
            for i, vec in enumerate(vecs):
                for prev in vecs[:i]:
                    vec.axpy(-vec.dot(prev), prev)
                vec.normalize()
            self.nullspace.destroy()
            self.nullspace = PETSc.NullSpace().create(vectors=vecs, comm=comm)
            for obj in (dk, dsp, dp):
                obj.destroy()

        # S = −C − B A⁻¹ Bᵀ is negative definite: PETSc's lower/upper/full factorisations use the
        # user matrix as is, so the Schur preconditioner must be −Sp (Jacobi, Chebyshev–Jacobi and
        # CG–Jacobi do not mind the sign). The positive Sp is kept for the wrong-sign comparison.
        self.Sp_neg = self.Sp.copy()
        self.Sp_neg.scale(-1.0)

        self.dofs_u = imu.size_global * bs
        self.dofs_p = imq.size_global
        self.assembly_time = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)
        self.reference = None  # MUMPS solution, when computed

    def destroy(self):
        if self.P is not None:
            self.P.destroy()
        for obj in (self.K, self.Sp, self.Sp_neg, self.b, self.d, self.is_u, self.is_p, self.nullspace):
            obj.destroy()
        if self.reference is not None:
            self.reference.destroy()


def run_one(sys_: System, name: str, extra: dict | None = None) -> dict:
    comm = sys_.comm
    cfg = dict(SOLVERS[name])
    cfg["options"] = {**cfg["options"], **(extra or {})}
    prefix = "mpc_"
    opts = PETSc.Options()
    for k, v in cfg["options"].items():
        opts[prefix + k] = v

    mem0 = rss_mb()
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(sys_.K, sys_.P if sys_.P is not None else sys_.K)
    ksp.setOptionsPrefix(prefix)
    pc = ksp.getPC()
    if cfg["options"]["pc_type"] == "fieldsplit":
        pc.setType("fieldsplit")
        pc.setFieldSplitIS(("u", sys_.is_u), ("p", sys_.is_p))
        if not name.endswith("_nonull"):
            # PCFieldSplit attaches the IS's composed "nearnullspace" to its A00 submatrix
            sys_.is_u.compose("nearnullspace", sys_.nullspace)
        else:
            sys_.is_u.compose("nearnullspace", None)
    ksp.setFromOptions()
    if cfg["schur_user"]:
        sp = sys_.Sp if cfg.get("sp_positive") else sys_.Sp_neg
        pc.setFieldSplitSchurPreType(PETSc.PC.SchurPreType.USER, sp)

    x = sys_.K.createVecRight()
    comm.Barrier()
    t0 = time.perf_counter()
    ok = True
    info = {}
    try:
        ksp.setUp()
        if cfg["options"]["pc_type"] == "fieldsplit":
            subs = pc.getFieldSplitSubKSP()
            for s in subs:
                s.setUp()
            Au = subs[0].getOperators()[1]
            info["u_block_bs"] = Au.getBlockSize()
            info["u_block_nearnullspace"] = Au.getNearNullSpace().handle != 0
            if cfg["options"].get("fieldsplit_u_pc_type") == "gamg":
                info["gamg_levels"] = subs[0].getPC().getMGLevels()
    except PETSc.Error as err:
        ok = False
        info["error"] = str(err)
    comm.Barrier()
    t_setup = time.perf_counter() - t0
    mem1 = rss_mb()
    t_solve = float("nan")
    its, reason = -1, 0
    if ok:
        comm.Barrier()
        t0 = time.perf_counter()
        try:
            ksp.solve(sys_.b, x)
        except PETSc.Error as err:
            info["error"] = str(err)
            ok = False
        comm.Barrier()
        t_solve = time.perf_counter() - t0
        its, reason = ksp.getIterationNumber(), int(ksp.getConvergedReason())
    r = sys_.b.duplicate()
    sys_.K.mult(x, r)
    r.aypx(-1.0, sys_.b)
    rel_res = r.norm() / sys_.b.norm()
    if name == "mumps" and ok:
        F = pc.getFactorMatrix()
        info["mumps_infog22_MB_total"] = F.getMumpsInfog(22)
        info["mumps_infog21_MB_max"] = F.getMumpsInfog(21)
        info["mumps_nnz_factors"] = F.getMumpsInfog(29) if F.getMumpsInfog(29) > 0 else None
        sys_.reference = x.copy()
    elif sys_.reference is not None:
        # errors in the original (unscaled) unknowns, u and p separately
        xo, ro = x.copy(), sys_.reference.copy()
        xo.pointwiseMult(xo, sys_.d)
        ro.pointwiseMult(ro, sys_.d)
        m = sys_.nu_loc
        for part, sl in (("u", slice(0, m)), ("p", slice(m, None))):
            num = comm.allreduce(float(np.sum((xo.array[sl] - ro.array[sl]) ** 2)))
            den = comm.allreduce(float(np.sum(ro.array[sl] ** 2)))
            info[f"rel_error_{part}_vs_mumps"] = np.sqrt(num / den)
        info["rel_error_vs_mumps"] = max(info["rel_error_u_vs_mumps"], info["rel_error_p_vs_mumps"])
        xo.destroy()
        ro.destroy()
    res = {"n": sys_.n, "case": sys_.case, "solver": name, "ranks": comm.size,
           "dofs": sys_.dofs_u + sys_.dofs_p, "dofs_u": sys_.dofs_u, "dofs_p": sys_.dofs_p,
           "identity_rows": sys_.n_constrained,
           "iterations": its, "converged_reason": reason, "converged": ok and reason > 0,
           "setup_s": comm.allreduce(t_setup, op=MPI.MAX),
           "solve_s": comm.allreduce(t_solve, op=MPI.MAX),
           "assembly_s": sys_.assembly_time,
           "rel_true_residual": rel_res,
           "setup_rss_growth_MB": comm.allreduce(mem1 - mem0, op=MPI.SUM),
           "rss_MB": comm.allreduce(mem1, op=MPI.SUM), **info}
    res["total_s"] = res["setup_s"] + res["solve_s"]
    ksp.destroy()
    x.destroy()
    r.destroy()
    for k in cfg["options"]:
        opts.delValue(prefix + k)
    return res


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=mesh_size(18, 3), nargs="+", default=[2, 4, 6, 8])
    ap.add_argument("--case", nargs="+", default=["plastic_x2"], metavar="CASE",
                    choices=[c + i for c in ("plastic_x2", "plastic_all", "elastic_nu05")
                             for i in ("", "_id")],
                    help="plastic_x2 | plastic_all | elastic_nu05, each optionally with _id")
    ap.add_argument("--solvers", nargs="+", default=["mumps", "fs_full_mass_jacobi",
                                                      "fs_lower_mass_jacobi", "gamg_monolithic"],
                    choices=list(SOLVERS))
    ap.add_argument("--mumps-max-n", type=nonnegative_int, default=12, help="skip MUMPS above this n")
    ap.add_argument("--monolithic-max-n", type=nonnegative_int, default=6,
                    help="skip monolithic GAMG above")
    ap.add_argument("--out", type=output_file, default=str(Path(__file__).resolve().parent
                                                            / "results" / "mixed_pc_prototype.json"))
    ap.add_argument("--append", action="store_true",
                    help="merge into the existing JSON (replace rows with the same key)")
    ap.add_argument("--tag", default="", help="label stored with every row")
    ap.add_argument("--scaling", choices=["diag", "none"], default="diag",
                    help="symmetric diagonal scaling of the system (see System)")
    ap.add_argument("--form", choices=["dev", "lame", "dev_pmat"], default="dev",
                    help="dev: A = 2G dev ε:ε, p = mean stress (as briefed); lame: A = 2G ε:ε, "
                         "p̂ = p − (2/3)G div u, C = 1/(K − 2G/3)")
    ap.add_argument("--set", type=key_value, nargs="*", default=[], metavar="KEY=VALUE",
                    help="extra PETSc options (relative to the outer KSP) for every solver")
    args = ap.parse_args(argv)
    if args.append and Path(args.out).exists():  # (read at the end, after all the runs)
        try:
            old = json.loads(Path(args.out).read_text())
        except (OSError, ValueError) as err:
            ap.error(f"--append: cannot read {args.out} as JSON ({err})")
        if not isinstance(old, dict) or not isinstance(old.get("runs", []), list):
            ap.error(f"--append: {args.out} is not a results file of this script (no list 'runs')")
    comm = MPI.COMM_WORLD

    extra = dict(kv.split("=", 1) for kv in args.set)
    rows = []
    for case in args.case:
        for n in args.sizes:
            s = System(comm, n, case, args.scaling, args.form)
            for name in args.solvers:
                if name == "mumps" and n > args.mumps_max_n:
                    continue
                if name == "gamg_monolithic" and n > args.monolithic_max_n:
                    continue
                row = run_one(s, name, extra)
                row["tag"] = args.tag
                row["scaling"] = args.scaling
                row["form"] = args.form
                if extra:
                    row["extra_options"] = extra
                rows.append(row)
                if comm.rank == 0:
                    print(f"{case:16s} n={n:2d} dofs={row['dofs']:8d} {name:30s} "
                          f"its={row['iterations']:4d} reason={row['converged_reason']:3d} "
                          f"setup={row['setup_s']:7.2f}s solve={row['solve_s']:7.2f}s "
                          f"res={row['rel_true_residual']:.1e} "
                          f"err={row.get('rel_error_vs_mumps', float('nan')):.1e} "
                          f"dMem={row['setup_rss_growth_MB']:.0f}MB", flush=True)
            s.destroy()

    if comm.rank == 0:
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        old = []
        if args.append and out.exists():
            old = json.loads(out.read_text()).get("runs", [])
        key = lambda r: (r["case"], r["n"], r["solver"], r["ranks"], r["form"], r["scaling"],  # noqa: E731
                         r.get("tag", ""))  # noqa: E731
        merged = {key(r): r for r in old}
        merged.update({key(r): r for r in rows})
        result = {"description": __doc__.split("\n")[0],
                  "machine": machine(comm), "rtol": RTOL,
                  "formulation": "symmetric saddle point, beta = 1: [A B^T; B -C], "
                                 "Schur pre = +M[1/(2G_eff)+1/K] (positive)",
                  "solvers": {k: v["options"] for k, v in SOLVERS.items()},
                  "runs": sorted(merged.values(), key=lambda r: (r["form"], r["case"], r["solver"],
                                                                   r["ranks"], r["n"]))}
        out.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
