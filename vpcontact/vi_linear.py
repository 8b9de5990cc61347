# SPDX-License-Identifier: MIT
"""Linear solves inside SNES VI with a factorization that outlives the active set.

PETSc's reduced-space VI (``vinewtonrsls``) solves, at each Newton iteration, J_II y_I = F_I on
the inactive set I. The reduced matrix is a new object every iteration and its size changes with
I, so a direct solver factorizes afresh every time: a viscoplastic contact step costs one full
factorization (about one elastic solve) per Newton iteration.

:class:`LaggedDirectSolve` replaces that linear solver (a PETSc python KSP). It keeps one matrix
of fixed size and sparsity,

    M = J with the rows and columns of the active set A replaced by the identity,

which after a symmetric permutation is diag(J_II, 1): its factors solve the reduced system
exactly. Each reduced solve first tries GMRES preconditioned by the factors of the last M (the
"lagged" factors, from an earlier iterate or active set); when that does not converge within
20 iterations (the tangent moved too much, e.g. many quadrature points switched between elastic
and plastic), M is rebuilt from the current Jacobian and active set, refactorized (numeric
only: the pattern never changes; Cholesky when M is symmetric, as the tangents here are) and
the system is solved directly. Near convergence, where the tangent barely changes, a Newton
iteration then costs a few substitutions instead of a factorization; the worst case costs a
bounded number of wasted substitutions more than PETSc's own approach.
"""

from __future__ import annotations

from typing import Callable, Optional

import numpy as np
from petsc4py import PETSc

_KSP_REASON = PETSc.KSP.ConvergedReason


class _LaggedFactors:
    """Python-PC context: y = (M⁻¹ E x)_I (embed x on I with zeros on A, solve with M, restrict)."""

    def __init__(self, owner: "LaggedDirectSolve"):
        self.owner = owner

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self.owner.substitute(x, y)


class LaggedDirectSolve:
    """PETSc python-KSP context for the reduced systems of SNES VI (see the module docstring).

    Args:
        snes: the VI solver (its inactive set defines the reduced vectors).
        jacobian: the full Jacobian matrix SNES assembles into.
        options_prefix: prefix of the inner direct solver (``<prefix>pc_factor_...`` etc.).
        lagged_iterations: GMRES iterations allowed with lagged factors before refactorizing
            (a substitution costs ~1/20 of a factorization on the paper's 3-D test; 20 gave
            the fewest factorizations + substitutions/20 per step of 6, 10, 15, 20 and 30).

    Attributes:
        lag_allowed: called before each solve; False skips the lagged attempt (the owner knows
            when the tangent is likely to have moved far, e.g. early in a Newton solve).
    """

    def __init__(self, snes: PETSc.SNES, jacobian: PETSc.Mat, options_prefix: str,
                 lagged_iterations: int = 20):
        self.snes = snes
        self.jacobian = jacobian
        comm = jacobian.getComm()
        self.matrix: Optional[PETSc.Mat] = None  # M, with J's pattern (copied at first use)
        self.direct = PETSc.KSP().create(comm)
        self.direct.setOptionsPrefix(options_prefix)
        self.direct.setType("preonly")
        pc = self.direct.getPC()
        pc.setType("lu")
        if PETSc.Sys.hasExternalPackage("mumps"):
            pc.setFactorSolverType("mumps")
        self.direct.setFromOptions()
        self.krylov = PETSc.KSP().create(comm)  # GMRES on J_II with the lagged factors
        self.krylov.setType("gmres")
        self.krylov.setGMRESRestart(lagged_iterations)
        self.krylov.setPCSide(PETSc.PC.Side.RIGHT)  # converges on the true residual
        kpc = self.krylov.getPC()
        kpc.setType("python")
        kpc.setPythonContext(_LaggedFactors(self))
        self.lagged_iterations = int(lagged_iterations)
        self._full_rhs = jacobian.createVecRight()
        self._full_sol = jacobian.createVecRight()
        self._inactive = np.zeros(0, dtype=np.int32)  # local positions of the current I
        self._krylov_size = None
        self.lag_allowed: Callable[[], bool] = lambda: True
        self.factorization = "lu"
        self._factored = False
        self._skip_lagged = False  # the last lagged attempt failed: refactorize straight away
        self.factorizations = 0  # numeric factorizations of M
        self.substitutions = 0  # forward/backward solves with its factors
        self.lagged_solves = 0  # reduced systems solved with lagged factors
        self.lagged_failures = 0  # lagged attempts abandoned for a refactorization

    def counters(self) -> dict:
        """Factorizations, substitutions, and lagged solves (successful and abandoned)."""
        return {"factorization": self.factorization, "factorizations": self.factorizations, "substitutions": self.substitutions,
                "lagged_solves": self.lagged_solves, "lagged_failures": self.lagged_failures}

    def expire(self) -> None:
        """Refactorize at the next solve (the Jacobian changed in a way GMRES should not chase)."""
        self._factored = False

    # --- PETSc python-KSP interface ------------------------------------------------------------
    def solve(self, ksp: PETSc.KSP, b: PETSc.Vec, x: PETSc.Vec) -> None:
        rtol, atol, _, _ = ksp.getTolerances()
        reduced, _ = ksp.getOperators()
        rstart = self.jacobian.getOwnershipRange()[0]
        self._inactive = (self.snes.getVIInactiveSet().getIndices() - rstart).astype(np.int32)
        if self._factored and not self._skip_lagged and self.lag_allowed():
            if self._krylov_size != reduced.getSizes():
                self.krylov.reset()  # PETSc refuses operators of another size after use
                self._krylov_size = reduced.getSizes()
            self.krylov.setOperators(reduced)
            self.krylov.setTolerances(rtol=rtol, atol=atol, max_it=self.lagged_iterations)
            self.krylov.solve(b, x)
            if self.krylov.getConvergedReason() > 0:
                self.lagged_solves += 1
                ksp.setIterationNumber(self.krylov.getIterationNumber())
                ksp.setConvergedReason(_KSP_REASON.CONVERGED_RTOL)
                return
            self.lagged_failures += 1
            self._skip_lagged = True
        else:
            self._skip_lagged = False
        self._factorize(rstart)
        self.substitute(b, x)
        ksp.setIterationNumber(1)
        ksp.setConvergedReason(_KSP_REASON.CONVERGED_ITS)

    def substitute(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y = (M⁻¹ E x)_I with E the embedding of I into the full space (zeros on A)."""
        rhs = self._full_rhs
        rhs.set(0.0)
        rhs.array[self._inactive] = x.array_r
        self.direct.solve(rhs, self._full_sol)
        y.array[:] = self._full_sol.array_r[self._inactive]
        self.substitutions += 1

    def _factorize(self, rstart: int) -> None:
        if self.matrix is None:
            self.matrix = self.jacobian.duplicate(copy=True)
            self.matrix.setOption(PETSc.Mat.Option.KEEP_NONZERO_PATTERN, True)
        else:
            self.jacobian.copy(self.matrix, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        owned = self.jacobian.getLocalSize()[0]
        active = np.setdiff1d(np.arange(owned, dtype=np.int32), self._inactive) + rstart
        self.matrix.zeroRowsColumns(active.astype(PETSc.IntType), diag=1.0)
        self._choose_factorization()
        self.direct.setOperators(self.matrix)
        self.direct.setUp()  # numeric factorization; the symbolic one is reused after the first
        self.factorizations += 1
        self._factored = True

    def _choose_factorization(self) -> None:
        """Cholesky (LDLᵀ) when M is symmetric to round-off, else LU: the consistent tangents of
        the energy-norm projection and of the linear laws are symmetric, and LDLᵀ halves the
        factorization. Checked at every factorization (a user law need not be symmetric)."""
        scale = self.matrix.norm(PETSc.NormType.INFINITY)
        kind = "cholesky" if self.matrix.isSymmetric(1e-12 * scale) else "lu"
        pc = self.direct.getPC()
        if pc.getType() != kind:
            solver = pc.getFactorSolverType()
            pc.reset()
            pc.setType(kind)
            pc.setFactorSolverType(solver)
            self.factorization = kind

    def destroy(self, ksp: Optional[PETSc.KSP] = None) -> None:
        for obj in (self.direct, self.krylov, self.matrix, self._full_rhs, self._full_sol):
            if obj is not None:
                obj.destroy()
