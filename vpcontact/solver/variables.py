# SPDX-License-Identifier: MIT
"""The unknowns SNES works on, when they are not the physical ones.

Two reasons to change variables, both at the nodes of Signorini contact parts:

* **local frames** (:mod:`vpcontact.model.frames`): at a node of a curved or inclined Γ3 the
  unknowns are ũ = Qᵀu, so that u_ν is one unknown and u_ν ≤ g a bound;
* **obstacles driven by a force**: an obstacle pressed by a given force F(t) = F(t) e (a fixed
  direction e) translates by an unknown d along e, solved with u in the same Newton iteration so
  that the contact force on it balances F(t). With the gaps of its nodes linear in d over a step,
  g_i(d) = g_i(d_p) + c_i δ, δ = d − d_p (d_p the step's predicted d; c_i = e · ν_i, see
  :class:`~vpcontact.model.signorini_part.DrivenSignoriniPart`), the condition
  u_ν,i ≤ g_i(d) becomes the bound w_i ≤ g_i(d_p) on w_i = u_ν,i − c_i δ.
  SNES works on x̃ = (w̃, δ̃): u = R w̃ + N δ,
  where R holds the frames and the column of N for obstacle j is c_ij ν_i at each of its nodes.
  (The unknown is the increment δ, not d itself: SNES VI decides which bounds are active with an
  absolute tolerance, which the round-off of w = u_ν − c d would exceed once d is large.)

In both cases u = P x̃ with P = [R  N] (n × (n + k), k driven obstacles, their unknowns last on the
last rank). Since the problem is the minimum of Π(u) − Σ_j F_j d_j (Π the incremental potential),
SNES solves Pᵀ F(P x̃) − (0, F_j) = 0 with Jacobian Pᵀ J P; the δ rows say
Σ_i σ_ν,i ν_i · e = F_j — the obstacle's equilibrium along e. The inverse map, for initial guesses, is
w̃ = Rᵀ(u − N δ), δ̃ = δ (R is orthogonal).
"""

from __future__ import annotations

from typing import Optional, Protocol, Sequence

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc


class DrivenUnknown(Protocol):
    """A scalar unknown besides the fields (the increment δ of a force-driven obstacle's
    displacement over its step's prediction).

    Attributes:
        increment: δ, physical units (set by the solver at every iterate).
    """

    increment: float

    def applied_force(self) -> float:
        """F_j(t) = F(t) · e at the current time."""

    def column(self) -> tuple[np.ndarray, np.ndarray]:
        """(owned unrolled u dofs, values) of the column of N (c_i ν_i at the nodes)."""

    def bounded_dofs(self) -> np.ndarray:
        """Owned entries of x̃ with the bounds of the obstacle's nodes (w̃'s normal slots)."""


class ChangeOfVariables:
    """u = P x̃ (see the module docstring).

    Args:
        layout: the field layout (:mod:`vpcontact.model.fields`): the physical vectors.
        rotation: R (square, laid out like the layout's vectors), or None (the identity).
        driven: the scalar unknowns appended to x̃.
        scale: SNES's displacement scale (x̃'s δ entries are δ / scale).
    """

    def __init__(self, layout, rotation: Optional[PETSc.Mat], driven: Sequence[DrivenUnknown],
                 scale: float):
        self.layout = layout
        self.rotation = rotation
        self.driven = list(driven)
        self.scale = scale
        probe = layout.create_vector()
        self._start, self._end = probe.getOwnershipRange()
        probe.destroy()
        self.comm = layout.u.function_space.mesh.comm
        self._owner = self.comm.size - 1  # the rank owning the driven unknowns
        self.k = len(self.driven) if self.comm.rank == self._owner else 0
        self.matrix = rotation if not self.driven else self._assemble()
        self._n_local = self._end - self._start
        self._xu: Optional[PETSc.Vec] = None  # scratch vector, physical layout

    @property
    def square(self) -> bool:
        """P is R alone (no driven unknown)."""
        return not self.driven

    def _assemble(self) -> PETSc.Mat:
        """P = [R  N] as an MPI AIJ matrix."""
        n_local = self._end - self._start
        columns_global = self.comm.allreduce(n_local) + len(self.driven)
        col_start = self._start  # x̃'s field entries keep the layout's numbering
        d_global = [columns_global - len(self.driven) + j for j in range(len(self.driven))]
        rows: list = [[] for _ in range(n_local)]
        if self.rotation is not None:
            indptr, indices, values = self.rotation.getValuesCSR()
            for r in range(n_local):
                rows[r] = list(zip(indices[indptr[r]:indptr[r + 1]],
                                   values[indptr[r]:indptr[r + 1]]))
        else:
            for r in range(n_local):
                rows[r] = [(col_start + r, 1.0)]
        for j, unknown in enumerate(self.driven):
            dofs, values = unknown.column()
            for dof, value in zip(dofs, values):
                rows[dof].append((d_global[j], value))
        indptr = np.zeros(n_local + 1, dtype=np.int32)
        np.cumsum([len(r) for r in rows], out=indptr[1:])
        cols = np.array([c for r in rows for c, _ in r], dtype=np.int32)
        vals = np.array([v for r in rows for _, v in r], dtype=np.float64)
        P = PETSc.Mat().createAIJ(((n_local, None), (n_local + self.k, None)), comm=self.comm)
        P.setPreallocationCSR((indptr, cols, vals))
        P.assemble()
        return P

    # -- vectors -----------------------------------------------------------------------------
    def create_vector(self) -> PETSc.Vec:
        """A vector laid out like x̃."""
        return self.matrix.createVecRight()

    def to_physical(self, x: PETSc.Vec, xp: PETSc.Vec) -> None:
        """xp ← P x (and the driven unknowns read off x: δ = scale · δ̃, on every rank)."""
        self.matrix.mult(x, xp)
        if self.driven:
            tail = x.getArray(readonly=True)[x.getLocalSize() - self.k:] if self.k else None
            values = self.comm.bcast(None if tail is None else tail.tolist(), root=self._owner)
            for unknown, value in zip(self.driven, values):
                unknown.increment = value * self.scale

    def to_snes(self, xp: PETSc.Vec, x: PETSc.Vec) -> None:
        """x ← the x̃ with P x̃ = xp (xp in SNES units), the driven unknowns at their current
        increments."""
        if self.square:
            self.rotation.multTranspose(xp, x)
            return
        if self._xu is None:
            self._xu = xp.duplicate()
        self._xu.array[:] = xp.getArray(readonly=True)
        for unknown in self.driven:
            dofs, values = unknown.column()
            self._xu.array[dofs] -= values * (unknown.increment / self.scale)
        array = x.getArray()
        if self.rotation is None:
            array[:self._n_local] = self._xu.getArray(readonly=True)
        else:
            rotated = self._xu.duplicate()
            self.rotation.multTranspose(self._xu, rotated)
            array[:self._n_local] = rotated.getArray(readonly=True)
            rotated.destroy()
        if self.k:
            array[self._n_local:] = [u.increment / self.scale for u in self.driven]

    def refresh(self) -> None:
        """The driven unknowns' columns of P from their current linearization (the pattern,
        one entry per node dof, stays)."""
        if self.square:
            return
        n_global = self.comm.allreduce(self._n_local)
        for j, unknown in enumerate(self.driven):
            dofs, values = unknown.column()
            for dof, value in zip(dofs, values):
                self.matrix.setValue(self._start + int(dof), n_global + j, float(value))
        self.matrix.assemble()

    def extend(self, vec: PETSc.Vec, fill: float) -> PETSc.Vec:
        """``vec`` (layout of the fields) as a vector of x̃, ``fill`` at the driven unknowns;
        ``vec`` itself without driven unknowns."""
        if self.square:
            return vec
        out = self.create_vector()
        array = out.getArray()
        array[:self._n_local] = vec.getArray(readonly=True)
        array[self._n_local:] = fill
        return out

    def residual(self, b_phys: PETSc.Vec, b: PETSc.Vec) -> None:
        """b ← Pᵀ b_phys − (0, F_j)."""
        self.matrix.multTranspose(b_phys, b)
        if self.k:
            array = b.getArray()
            array[self._n_local:] -= [u.applied_force() for u in self.driven]

    def stabilize(self, A: PETSc.Mat, x: PETSc.Vec, b: PETSc.Vec, bounds) -> None:
        """Where no node of a driven obstacle is on its bound with the residual pressing it
        there (SNES VI's active set at the iterate x, residual b), the Jacobian is singular:
        with u fixed the obstacle moves freely (w̃ = −RᵀN δ, δ). Then its diagonal entry
        J̃_δδ = Nᵀ J N (the stiffness of its nodes moved together) is doubled, so that the Newton
        step moves the obstacle by about F / (Nᵀ J N) into contact instead of to infinity. The
        residual is unchanged: the solution is exact, and once a node is active the Jacobian
        is exact again (collective)."""
        if self.square or bounds is None:
            return
        lower, upper = (v.getArray(readonly=True) for v in bounds)
        xs, fs = x.getArray(readonly=True), b.getArray(readonly=True)
        free = []
        for unknown in self.driven:
            dofs = unknown.bounded_dofs()
            active = ((xs[dofs] >= upper[dofs] - 1e-8) & (fs[dofs] < 0)) | (
                (xs[dofs] <= lower[dofs] + 1e-8) & (fs[dofs] > 0))
            free.append(not self.comm.allreduce(bool(active.any()), op=MPI.LOR))
        if not any(free):
            return
        if self.k:
            start = A.getOwnershipRange()[1] - self.k
            rows = [start + j for j, loose in enumerate(free) if loose]
            values = [A.getValue(row, row) for row in rows]
            for row, value in zip(rows, values):
                A.setValue(row, row, value, addv=PETSc.InsertMode.ADD_VALUES)
        A.assemble()

    def jacobian(self, A_phys: PETSc.Mat, A: Optional[PETSc.Mat] = None) -> PETSc.Mat:
        """Pᵀ A_phys P (into ``A`` when given)."""
        if A is None:
            return A_phys.PtAP(self.matrix)
        return A_phys.PtAP(self.matrix, result=A)

    def destroy(self) -> None:
        if self.driven:
            self.matrix.destroy()
        if self._xu is not None:
            self._xu.destroy()
