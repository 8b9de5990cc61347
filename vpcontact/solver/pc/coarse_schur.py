# SPDX-License-Identifier: MIT
"""EXPERIMENTAL: the stars' Schur complement with the cycle's coarse term, solved exactly.

Off by default (``pmg_schur_coarse = true`` under both field splits' displacement prefixes turns
it on): on the paper's 3-D test up to 143 128 unknowns its two factorizations cost more time than
the Krylov iterations they save. Kept as a research preconditioner; not part of any default path.

The field split's preconditioner is block-triangular: the p-multigrid cycle Ã on the displacement
block and an approximation of the Schur complement on the pressure block. What the outer Krylov
method sees is how well that approximation matches the cycle's own Schur complement
C − B Ã⁻¹ Bᵀ, not the exact one: with A factorized and S_p, or with the cycle's P1 level
factorized and the stars' Ŝ, it takes more iterations than the cycle as used (the window's last
system at 44 508 unknowns: 22 as used, 35 with the coarse level factorized). The cycle's coarse
correction P A_c⁻¹ Pᵀ contributes B P A_c⁻¹ (B P)ᵀ to its Schur complement, which Ŝ (the vertex
stars' local Schur complements, :mod:`~vpcontact.solver.pc.star_schur`) lacks. With the coarse
level solved exactly, the sum

    Ŝ₂ = Ŝ − (B P) A_c⁻¹ (B P)ᵀ

is the pressure block's Schur complement of the mixed coarse matrix

    K_c = [ A_c      (B P)ᵀ ]        (A_c = Pᵀ A P: P1 displacements on the vertices,
          [ B P      Ŝ      ]         pressure unknowns as they are)

so Ŝ₂⁻¹ r is the pressure part of K_c⁻¹ (0, r): one sparse factorization (MUMPS) of about
four unknowns per vertex, beside the cycle's coarse factorization of three (:func:`factorize`;
in place of GAMG's V-cycle when the coarse term is on).
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from petsc4py import PETSc

import vpcontact.solver.pc.context as context


def factorize(ksp: PETSc.KSP, matrix: PETSc.Mat) -> None:
    """Set ``ksp`` up to solve with ``matrix`` by MUMPS: Cholesky (LDLᵀ) where ``matrix`` is
    symmetric (to round-off), LU where it is not (friction, say). Cholesky halves the
    factorization: on the paper's 3-D test at 44 508 unknowns the window's step took 4.25 s with
    LU for both factorizations, 3.49 s with Cholesky."""
    scale = matrix.norm(PETSc.NormType.INFINITY)
    kind = "cholesky" if matrix.isSymmetric(1e-12 * scale) else "lu"
    ksp.setType("preonly")
    pc = ksp.getPC()
    if pc.getType() != kind:
        pc.setType(kind)
    pc.setFactorSolverType("mumps")
    ksp.setOperators(matrix)
    ksp.setUp()


class CoarseSchur:
    """K_c (module docstring) factorized, and Ŝ₂⁻¹ applied with it."""

    def __init__(self, comm: PETSc.Comm):
        self.ksp = PETSc.KSP().create(comm)
        self.matrix: Optional[PETSc.Mat] = None
        self._is_p: Optional[PETSc.IS] = None
        self._rhs = self._sol = None

    def update(self, coupling: PETSc.Mat, P: PETSc.Mat, coarse: PETSc.Mat,
               schur: PETSc.Mat) -> None:
        """Assemble and factorize K_c.

        Args:
            coupling: the displacement rows' block on the pressure columns of the matrix split
                (Bᵀ, in the displacement split's numbering).
            P: the cycle's interpolation (its rows at fixed unknowns zero).
            coarse: the cycle's coarse matrix A_c = Pᵀ A P.
            schur: Ŝ.
        """
        coupling_c = P.transposeMatMult(coupling)  # (B P)ᵀ
        coupling_r = coupling_c.transpose(PETSc.Mat())  # (without one: in place)
        matrix, is_p = _stack([[coarse, coupling_c], [coupling_r, schur]])
        for obj in (coupling_c, coupling_r, self.matrix, self._is_p):
            if obj is not None:
                obj.destroy()
        self.matrix, self._is_p = matrix, is_p
        factorize(self.ksp, self.matrix)
        if self._rhs is None or self._rhs.getSizes() != self.matrix.getSizes()[0]:
            for vec in (self._rhs, self._sol):
                if vec is not None:
                    vec.destroy()
            self._sol, self._rhs = self.matrix.createVecs()

    def solve(self, r: PETSc.Vec, y: PETSc.Vec) -> None:
        """y = Ŝ₂⁻¹ r: the pressure part of K_c⁻¹ (0, r)."""
        self._rhs.set(0.0)
        part = self._rhs.getSubVector(self._is_p)
        r.copy(part)
        self._rhs.restoreSubVector(self._is_p, part)
        self.ksp.solve(self._rhs, self._sol)
        part = self._sol.getSubVector(self._is_p)
        part.copy(y)
        self._sol.restoreSubVector(self._is_p, part)

    def destroy(self) -> None:
        for obj in (self.matrix, self.ksp, self._rhs, self._sol, self._is_p):
            if obj is not None:
                obj.destroy()


def _stack(blocks: list) -> tuple[PETSc.Mat, PETSc.IS]:
    """The 2×2 block matrix ``blocks`` as one AIJ matrix, each process's rows those of its
    rows of the first block row, then of the second (MatNest's numbering); and the index set of
    the second block's rows in it."""
    (a, b), (c, d) = blocks
    comm = a.getComm()
    mpi = comm.tompi4py()
    n0, n1 = a.getLocalSize()[0], d.getLocalSize()[0]
    starts0 = np.concatenate([[0], np.cumsum(mpi.allgather(n0))])
    starts1 = np.concatenate([[0], np.cumsum(mpi.allgather(n1))])
    starts = starts0 + starts1  # where each process's rows begin in the stack

    def renumber(columns: np.ndarray, field_starts: np.ndarray, shift: np.ndarray) -> np.ndarray:
        owner = np.searchsorted(field_starts, columns, side="right") - 1
        return columns - field_starts[owner] + starts[owner] + shift[owner]

    zero = np.zeros_like(starts0)
    sizes0 = np.diff(starts0)
    indptr, indices, values = [np.zeros(1, dtype=PETSc.IntType)], [], []
    for (left, right) in ((a, b), (c, d)):
        rows_l, cols_l, vals_l = left.getValuesCSR()
        rows_r, cols_r, vals_r = right.getValuesCSR()
        cols_l = renumber(cols_l, starts0, zero)
        cols_r = renumber(cols_r, starts1, np.append(sizes0, 0))
        counts = np.diff(rows_l) + np.diff(rows_r)
        row_of_l = np.repeat(np.arange(len(rows_l) - 1), np.diff(rows_l))
        row_of_r = np.repeat(np.arange(len(rows_r) - 1), np.diff(rows_r))
        order = np.argsort(np.concatenate([row_of_l, row_of_r]), kind="stable")
        indices.append(np.concatenate([cols_l, cols_r])[order])
        values.append(np.concatenate([vals_l, vals_r])[order])
        indptr.append(indptr[-1][-1] + np.cumsum(counts))
    size = (n0 + n1, starts[-1])
    matrix = PETSc.Mat().createAIJ((size, size), comm=comm,
                                   csr=(np.concatenate(indptr).astype(PETSc.IntType),
                                        np.concatenate(indices).astype(PETSc.IntType),
                                        np.concatenate(values)))
    matrix.assemble()
    second = PETSc.IS().createStride(n1, starts[mpi.rank] + n0, 1, comm=comm)
    return matrix, second


class CoarseSchurPC:
    """EXPERIMENTAL. The PETSc python PC context of the pressure split (``pc_python_type``
    ``vpcontact.solver.pc.coarse_schur.CoarseSchurPC``): applies the :class:`CoarseSchur` of
    the stars' Schur complement registered with the step solver's coarse space (found on the
    PC, :func:`~vpcontact.solver.pc.context.get_appctx`), factorized when the displacement
    split's cycle set up."""

    def __init__(self):
        self.coarse: Optional[CoarseSchur] = None

    def setUp(self, pc: PETSc.PC) -> None:
        schur = context.get_appctx(pc).schur
        if schur is None or schur.coarse is None:
            raise RuntimeError("CoarseSchurPC: the stars' Schur complement has no coarse term "
                               "(pmg_coarse_schur needs the vertex-star smoothing)")
        self.coarse = schur.coarse

    def apply(self, pc: PETSc.PC, r: PETSc.Vec, y: PETSc.Vec) -> None:
        self.coarse.solve(r, y)
