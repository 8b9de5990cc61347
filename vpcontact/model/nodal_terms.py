# SPDX-License-Identifier: MIT
"""What the nodal terms of a Signorini part share: its nodes' unknowns in SNES's vector and the
normal force λ_i that the variational inequality's multiplier gives each node.

A Signorini part is a bound on one unknown per contact node in the node's frame
(:mod:`vpcontact.model.frames`), ũ_ν ≤ g. Terms that act on the node's other, tangential unknowns
(friction, :mod:`vpcontact.model.nodal_friction`; the tangential part of a force along the
obstacle's normal, :mod:`vpcontact.model.obstacle_normals`) read the node's normal force off the
residual of its normal unknown, λ_i = −s_i F̃_ν,i (s_i the frame's sign), where the node is on its
bound and λ_i > 0, and take 0 elsewhere: off the bound −s_i F̃_ν,i is an iterate's imbalance, not
a contact force. At a solution the two agree. The derivative of λ_i is then −s_i times the normal
unknown's Jacobian row, whose columns (the node's neighbours, and with the mixed formulation the
pressure unknowns) are already in the pattern.

Indices: ``u_slots``/``u_tangential`` are local indices of u's dofs, ``slots``/``tangential`` the
same unknowns' local positions in SNES's vector (set by :meth:`NodalTerm.bind`).
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

#: A node is on its bound (in contact) within this distance of it in SNES's units (SNES VI's
#: own tolerance for an active bound).
ON_BOUND = 1e-8


def displacement_positions(layout) -> tuple[np.ndarray, int]:
    """(where each of u's local dofs sits in SNES's local vector, the vector's global size): the
    layout's ``field_indices()`` (frames and force-driven unknowns keep its numbering,
    :mod:`vpcontact.solver.variables`). Collective."""
    probe = layout.create_vector()
    start, size = probe.getOwnershipRange()[0], probe.getSize()
    probe.destroy()
    return layout.field_indices()["displacement"].getIndices() - start, size


class NodalTerm:
    """The framed nodes of a Signorini ``part`` and the multipliers λ at an iterate."""

    def __init__(self, part):
        V = part.u.function_space
        cd = part.nodes
        if cd.frames is None:
            raise ValueError("a nodal term of a Signorini part needs its nodes in frames")
        self.part = part
        self.bs = bs = V.dofmap.index_map_bs
        self.comm = V.mesh.comm
        self.u_slots = cd.dofs                     # the normal unknown of each node
        self.signs = cd.signs
        others = [np.array([k for k in range(bs) if k != s]) for s in cd.frames.slots]
        self.u_tangential = np.array([cd.nodes[i] * bs + o for i, o in enumerate(others)],
                                     dtype=np.int32).reshape(len(cd.nodes), bs - 1)
        self.slots, self.tangential = self.u_slots, self.u_tangential  # (u alone, until bind)
        self.free = np.ones(self.tangential.shape, dtype=bool)  # tangential rows not prescribed
        self.scale = 1.0
        blocks = cd.frames.blocks
        #: (n, bs, bs − 1): the frame's tangential columns τ at each node
        # (shaped even where this process holds none of the part's nodes)
        self.frame_tangents = np.array([blocks[i][:, o] for i, o in enumerate(others)],
                                       dtype=np.float64).reshape(len(cd.nodes), bs, bs - 1)
        self._lam = np.zeros(len(self.slots))            # λ at the last residual
        self._at: Optional[np.ndarray] = None             # ... and its iterate

    def bind(self, scale: float, dirichlet_dofs: np.ndarray, layout) -> None:
        """The solver's displacement scale, its Dirichlet dofs (local u indices: tangential rows
        they hold get no nodal term) and the field layout, whose ``field_indices()`` place u's
        dofs in SNES's vector (frames and force-driven unknowns keep the layout's numbering,
        :mod:`vpcontact.solver.variables`). Collective."""
        self.scale = scale
        self.free = ~np.isin(self.u_tangential, dirichlet_dofs)
        positions, self.num_fields = displacement_positions(layout)
        self.slots = positions[self.u_slots].astype(np.int32)
        self.tangential = positions[self.u_tangential].astype(np.int32)

    def at_prescribed_rows(self, force: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(local u dofs, values): the nodal forces ``force`` (n, bs − 1; frame components, on
        the body) at the tangential rows a Dirichlet part prescribes, as components of u (a
        prescribed component keeps its axis as the frame's column, :mod:`vpcontact.model.
        frames`). The solver leaves those rows to the support (u = u_D there), so the forces are
        not in its residual: the support forces take them from here."""
        i, a = np.nonzero(~self.free)
        dofs = self.u_tangential[i, a].astype(np.int32)
        return dofs, self.frame_tangents[i, dofs % self.bs, a] * force[i, a]

    def on_bound(self, xs: np.ndarray) -> np.ndarray:
        """Which nodes are on their bound at the iterate ``xs`` (SNES's local array)."""
        return self.signs * xs[self.slots] >= self.part.bound_gaps() / self.scale - ON_BOUND

    def read_multipliers(self, xs: np.ndarray, values: np.ndarray) -> np.ndarray:
        """λ at the iterate ``xs`` from the residual ``values`` (before any nodal term changed
        it; nodal terms change tangential rows only), kept for :meth:`current` and the Jacobian."""
        on = self.on_bound(xs)
        self._lam = np.where(on, np.maximum(-self.signs * values[self.slots], 0.0), 0.0)
        self._at = xs.copy()
        return self._lam

    def current(self, x: PETSc.Vec) -> bool:
        """Whether λ was read at x (on every rank: collective)."""
        here = self._at is not None and np.array_equal(self._at, x.getArray(readonly=True))
        return self.comm.allreduce(here, op=MPI.LAND)

    def normal_row(self, A: PETSc.Mat, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Columns and values of node i's normal unknown's Jacobian row: ∂λ_i/∂x̃ = −s_i times
        the values where λ_i > 0."""
        return A.getRow(A.getOwnershipRange()[0] + int(self.slots[i]))

    def predict(self, x: PETSc.Vec, first_try: int) -> None:
        """The step's initial guess, for a first try of ``first_try`` Newton iterations
        (nothing to change unless a term says so)."""

    def prepare_jacobian(self, x: PETSc.Vec) -> None:
        """Before the UFL Jacobian is assembled at x (nothing unless a term says so)."""

    #: Newton iterations SNES may take from the step's guess before it starts again from
    #: :meth:`fallback`'s (None: the term has no other guess; the step solver takes the
    #: longest first try its terms ask for)
    first_try: Optional[int] = None

    def has_fallback(self) -> bool:
        """Whether :meth:`fallback` has another initial guess for this step (collective; see
        :class:`~vpcontact.solver.retries.OtherGuess`)."""
        return False

    def fallback(self, x: PETSc.Vec) -> None:
        """Replace the guess x by the other one (see :meth:`has_fallback`)."""

    #: Newton iterations SNES may take from :meth:`fallback`'s guess before the term's
    #: predictor runs (None: the term has none; see :meth:`freeze` and
    #: :class:`~vpcontact.solver.retries.Predictor`)
    second_try: Optional[int] = None

    def freeze(self, stick: bool) -> None:
        """The predictor's stages: the term's thresholds fixed — infinite where a node is
        pressed (``stick``: every pressed node sticks) or from the multipliers λ of the last
        residual — until :meth:`thaw` (only terms with a ``second_try``)."""

    def thaw(self) -> None:
        """The term's own law again (see :meth:`freeze`)."""

    #: True while the term's last Jacobian held nodes that are still on their way to a
    #: solution (friction's unloading nodes): the step solver's crawl stop then waits (same on
    #: every rank; :data:`~vpcontact.solver.retries.CRAWL_ITERATIONS`)
    holding: bool = False
