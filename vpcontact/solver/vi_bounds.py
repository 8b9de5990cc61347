# SPDX-License-Identifier: MIT
"""The bounds of a variational inequality (rigid contact, SNES VI) in SNES's layout and units:
their embedding, the first guess's snapping onto them, the active set a solve ends with and the
feasibility of plain Newton's answer (:class:`VIBounds`)."""

from __future__ import annotations

from typing import Optional

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc


class VIBounds:
    """lower ≤ x ≤ upper on SNES's unknown x (physical bounds on u divided by ``scale``).

    Args:
        fields: the field layout (other fields than u are unbounded).
        variables: the change of variables u = P x̃, or None.
        scale: SNES's displacement scale.
        extent: the mesh's extent (the snapping distance is relative to it).
        comm: the mesh's communicator.
    """

    #: Entries of the initial guess this close to a bound (a length relative to the mesh's
    #: extent) start on it.
    SNAP = 1e-9

    def __init__(self, fields, variables, scale: float, extent: float, comm: MPI.Comm):
        self.fields, self.variables = fields, variables
        self.scale, self.extent, self.comm = scale, extent, comm
        self.pair: Optional[tuple[PETSc.Vec, PETSc.Vec]] = None
        self._last_active: Optional[np.ndarray] = None  # the last solve's active bounds

    def _embedded(self, vec_u: PETSc.Vec, fill: float) -> PETSc.Vec:
        """A bound on u as a vector of the SNES layout (other fields: ``fill``); ``vec_u`` is
        destroyed when a new vector is made."""
        vec = self.fields.embed(vec_u, fill)
        if vec.handle != vec_u.handle:
            vec_u.destroy()
        if self.variables is not None:
            full = self.variables.extend(vec, fill)
            if full.handle != vec.handle:
                vec.destroy()
            vec = full
        return vec

    def _scaled(self, lower: PETSc.Vec, upper: PETSc.Vec) -> tuple[PETSc.Vec, PETSc.Vec]:
        """The physical bounds on u as bounds on x."""
        lower, upper = (self._embedded(lower, PETSc.NINFINITY),
                        self._embedded(upper, PETSc.INFINITY))
        for vec in (lower, upper):
            finite = np.abs(vec.array) < PETSc.INFINITY
            vec.array[finite] /= self.scale
        return lower, upper

    def set(self, lower: PETSc.Vec, upper: PETSc.Vec) -> tuple[PETSc.Vec, PETSc.Vec]:
        """Take the physical bounds ``lower``, ``upper`` on u; return them on x."""
        self.pair = self._scaled(lower, upper)
        return self.pair

    def update(self, lower: PETSc.Vec, upper: PETSc.Vec) -> None:
        """New values (physical units) for the bounds (a moving obstacle); the vectors passed
        are destroyed."""
        for new, old in zip(self._scaled(lower, upper), self.pair):
            new.copy(old)
            new.destroy()

    def snap(self, x: PETSc.Vec) -> None:
        """Start SNES VI with the last step's active set: an entry that ended the last solve on
        a bound starts on that bound (which may have moved), and so does an entry within
        :data:`SNAP` × the mesh's extent of a bound. SNES VI takes a bound as active only
        within 1e-8 in x's units (about 1e-20 of the extent), which a contact node predicted
        by extrapolation misses when its bound moves (an obstacle with a motion, or driven by
        a force); an obstacle driven by a force whose nodes are all inactive has no
        equilibrium (a singular Jacobian). Entries whose residual pulls them off the bound
        are released by the VI itself."""
        array = x.getArray()
        near = self.SNAP * self.extent / self.scale  # in x's units
        for side, bound in zip((-1, 1), self.pair):
            values = bound.getArray(readonly=True)
            finite = np.abs(values) < PETSc.INFINITY
            snap = finite & (np.abs(array - values) <= near)
            if self._last_active is not None:
                snap |= finite & (self._last_active == side)
            array[snap] = values[snap]

    def record_active(self, x: PETSc.Vec) -> None:
        """Which entries of x ended the solve on their lower (−1) or upper (+1) bound."""
        array = x.getArray(readonly=True)
        active = np.zeros(len(array), dtype=np.int8)
        for side, bound in zip((-1, 1), self.pair):
            values = bound.getArray(readonly=True)
            finite = np.abs(values) < PETSc.INFINITY
            active[finite & (np.abs(array - values) <= 1e-8)] = side
        self._last_active = active

    def feasible(self, x: PETSc.Vec) -> bool:
        """x within the bounds (to 1e-6 in units of x, i.e. round-off in physical units;
        collective)."""
        lower, upper = self.pair
        ok = bool(np.all(x.array <= upper.array + 1e-6) and np.all(x.array >= lower.array - 1e-6))
        return self.comm.allreduce(ok, op=MPI.LAND)
