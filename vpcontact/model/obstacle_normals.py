# SPDX-License-Identifier: MIT
"""Contact forces along the obstacle's normal (``normals = "obstacle"``): what ploughing needs.

The paper's Signorini condition bounds the displacement along the body's outward normal ν,
u_ν ≤ g, with g the distance to the obstacle along ν; its force acts along −ν. That is the exact
linearisation of non-penetration where the obstacle's surface faces the body squarely. Where it
is inclined — the flank of an indenter's tip, the front of a groove a slider pushes — the gap
along the ray also depends on the node's tangential motion: g(u) = g(x + u_τ) − u_ν to first order
in u, and the force conjugate to that gap is λ (−ν + s), s the obstacle normal's tangential part
over its normal part. That is the force along the obstacle's normal m (unit, pointing into the
body), λ m/(−m·ν), whose component along −ν is the VI's multiplier λ as before.

So the bound stays SNES VI's bound ũ_ν ≤ g (unchanged: the same active set, the same
frictionless Signorini solver), and the tangential unknowns of each node in contact gain the
nodal force λ_i s_i (λ_i read as in :mod:`vpcontact.model.nodal_terms`), with Jacobian rows
−s_i ∂λ_i/∂x̃ (the normal unknown's row, already in the pattern: the matrix is no longer
symmetric). s_i is evaluated once per step where the node's ray meets the obstacle at the step's
time, m = ∇φ/|∇φ| by central differences of the level set φ (any shape, any expression); the
tangential motion within the step does not move it (small deformations). A node whose ray grazes
the obstacle (−m·ν below :data:`MIN_COSINE`) gets s with that cosine: a force at most about ten
times tangential to its normal part.

With friction (:mod:`vpcontact.model.nodal_friction`) the friction force still acts in the
body's tangent plane with threshold 𝔣 λ_i: Coulomb's law on the inclined surface is matched to
first order in the slope (the normal force there is λ_i/(−m·ν) = λ_i (1 + O(|s|²)).
"""

from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from vpcontact.model.nodal_terms import NodalTerm

#: Smallest −m·ν used: a ray that meets the obstacle more obliquely is treated as meeting it at
#: this cosine (|s| ≤ about 10).
MIN_COSINE = 0.1


def obstacle_normals(phi, points: np.ndarray, step: float) -> np.ndarray:
    """Unit normals ∇φ/|∇φ| (N, 3) of the level set φ at ``points`` (N, 3), by central
    differences with ``step``; zero rows where the gradient vanishes or is not finite."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    grad = np.zeros_like(points)
    for k in range(3):
        e = np.zeros(3)
        e[k] = step
        ahead = np.asarray(phi((points + e).T), dtype=np.float64)
        behind = np.asarray(phi((points - e).T), dtype=np.float64)
        grad[:, k] = np.broadcast_to((ahead - behind) / (2.0 * step), len(points))
    size = np.linalg.norm(grad, axis=1)
    good = np.isfinite(size) & (size > 0)
    return np.where(good[:, None], grad / np.where(good, size, 1.0)[:, None], 0.0)


class ObstacleNormalForce(NodalTerm):
    """The tangential part λ_i s_i of the contact force along the obstacle's normal, at the
    nodes of one Signorini part (see the module docstring).

    Args:
        part: the :class:`~vpcontact.model.signorini_part.SignoriniPart` (framed nodes).
    """

    def __init__(self, part):
        super().__init__(part)
        self.tilt = np.zeros(self.tangential.shape)  # s_i in the frame's tangential slots
        points = part.nodes.points
        extent = float(np.ptp(points, axis=0).max()) if len(points) else 1.0
        self._step = 1e-7 * max(extent, float(np.abs(points).max(initial=0.0)), 1e-300)
        self.refresh(0.0)

    def refresh(self, time: float) -> None:
        """s at the nodes, where their rays meet the obstacle at ``time`` (after the gaps)."""
        cd, law = self.part.nodes, self.part.law
        if len(cd.points) == 0:
            return
        dim = cd.normals.shape[1]
        nu = np.zeros((len(cd.points), 3))
        nu[:, :dim] = cd.normals
        gaps = self.part.bound_gaps()
        reach = gaps < law.max_distance
        hits = cd.points + np.where(reach, gaps, 0.0)[:, None] * nu
        m = obstacle_normals(law.obstacle_at(time), hits, self._step)[:, :dim]
        cosine = np.maximum(-np.einsum("nk,nk->n", m, cd.normals), MIN_COSINE)
        tilt = np.einsum("nkt,nk->nt", self.frame_tangents, m) / cosine[:, None]
        self.tilt = np.where(reach[:, None], tilt, 0.0)

    def forces(self, lam: np.ndarray) -> np.ndarray:
        """The nodal tangential forces λ_i s_i (frame components) for normal forces λ."""
        return np.where(self.free, lam[:, None] * self.tilt, 0.0)

    def prescribed_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """(local u dofs, values): λ_i s_i at the tangential dofs a Dirichlet part prescribes
        (λ of the last residual: the solution's after a step), which the solver's rows there
        leave to the support (:meth:`NodalTerm.at_prescribed_rows`)."""
        return self.at_prescribed_rows(self._lam[:, None] * self.tilt)

    # -- hooks of the step solver --------------------------------------------------------------
    def residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """b ← b − λ s on the tangential rows (λ read off b first)."""
        xs, values = x.getArray(readonly=True), b.getArray()
        values[self.tangential] -= self.forces(self.read_multipliers(xs, values))

    def jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """A ← A − s ∂λ/∂x̃ = A + s_a s_i (normal row) on the tangential rows of the nodes with
        λ > 0 (λ of the last residual, at the same iterate). Collective (assembles A)."""
        start = A.getOwnershipRange()[0]
        entries = []  # (rows are read before any is changed: A stays assembled until then)
        for i in np.flatnonzero(self._lam > 0):
            cols, values = self.normal_row(A, i)
            for a in np.flatnonzero(self.free[i] & (self.tilt[i] != 0)):
                entries.append((int(start + self.tangential[i][a]), cols,
                                self.signs[i] * self.tilt[i][a] * values))
        for row, cols, values in entries:
            A.setValues(row, cols, values, addv=PETSc.InsertMode.ADD_VALUES)
        A.assemble()
