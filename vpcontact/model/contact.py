# SPDX-License-Identifier: MIT
"""Contact parts: the protocol every contact law implements, and what the problem asks of a list
of them.

A scene may have several contact parts (a specimen between two indenters, a punch on a body that
rests on a foundation). Each is a :class:`ContactPart` built by its law's ``part`` method
(:meth:`~vpcontact.model.signorini.Signorini.part`, :meth:`~vpcontact.model.normal_compliance.
NormalCompliance.part`); the problem composes the list and never asks which law a part has:

* a part with ``bounded = True`` (Signorini) imposes u_ν ≤ g at its nodes as SNES VI bounds,
  possibly in local frames; the bounds and frames of all such parts are merged here
  (:func:`merged_bounds`, :func:`merged_frames`);
* a part with UFL terms (normal compliance) adds them to the residual and the Jacobian.

**Nodes shared with a Dirichlet part.** A node every component of which is prescribed is no
contact node: its residual is the support's reaction. At a node with some components prescribed
(the corner where a pushed face meets the contact face) the part's law still acts on the
prescribed ones (friction, a foundation's push): the part reports that force
(:meth:`ContactPart.prescribed_forces`) and the support's reaction is the residual less it.

**Nodes shared by two parts.** A node lies in at most one part: the first listed part that
reaches it owns it, and later parts leave it out (its constraint, its force, its output row).
Normal compliance still integrates over all of its own facets, so a shared node gets the
compliance force of every compliance part whose facets touch it; its *reported* force goes to
the owner. Two Signorini parts meeting at an edge: the edge nodes are held by the first part's
obstacle only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Protocol, Sequence

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.errors import InputError, ObstacleOutOfReach
from vpcontact.model.contact_nodes import ContactReport
from vpcontact.model.frames import Frames


@dataclass(frozen=True)
class NodalOutput:
    """A quantity a contact part reports at each of its nodes beyond u_ν, the gap and σ_ν
    (friction's tangential traction, say), for the outputs to record without knowing what it
    is.

    Attributes:
        key: its name for :meth:`ContactPart.nodal_values` and in checkpoints
            (``history_<key>``).
        column: its column in contact.csv.
        running: the name of a second column with its running sum over the records, or None.
        integer: written as an integer (a flag).
        field: the name of its XDMF field (a P1 field on the contact nodes), or None.
    """

    key: str
    column: str
    running: Optional[str] = None
    integer: bool = False
    field: Optional[str] = None


class ContactPart(Protocol):
    """One contact part of the boundary, at run time.

    Attributes:
        name: the boundary part's name (outputs: columns, warnings).
        law: the law's specification (:class:`~vpcontact.model.signorini.Signorini`,
            :class:`~vpcontact.model.normal_compliance.NormalCompliance`).
        bounded: the part imposes SNES VI bounds at ``nodes.dofs``.
        driven: its obstacle is pressed by a force and its displacement is an unknown (then it
            is a :class:`~vpcontact.solver.variables.DrivenUnknown` too).
        moving: its gaps change with time (a moving obstacle).
        force_dofs: owned unrolled displacement dofs of its nodes (Dirichlet dofs left out):
            its force on the body is the equilibrium residual summed over them.
        node_blocks: owned node (block) indices of its nodes.
        splits_force: the outputs list its force split into a normal and a tangential part.
        reports_law_force: its force on the body is its own term's (a frictionless compliant
            part: R_c assembled at its nodes), not the residual left at its nodes.
        resists_sliding: where it presses the body it also resists the body's motion along its
            face (friction), so it may hold a body along a rigid motion parallel to the face.
    """

    name: str
    law: object
    bounded: bool
    driven: bool
    moving: bool
    force_dofs: np.ndarray
    node_blocks: np.ndarray
    splits_force: bool
    reports_law_force: bool
    resists_sliding: bool

    def snes_defaults(self, linear_law: bool) -> dict:
        """SNES options the part needs (e.g. the VI solver), under the user's own."""

    def terms(self, u, du, v, normal, ds) -> Optional[tuple]:
        """(residual, Jacobian) UFL boundary terms, or None (a bounded part)."""

    @property
    def nodes(self):
        """The :class:`~vpcontact.model.contact_nodes.ContactDofs` of the part (normals, gaps)."""

    def update(self, time: float) -> None:
        """Move the obstacle to its place at ``time`` (new gaps at the nodes)."""

    def bound_gaps(self) -> np.ndarray:
        """Bounded parts: the right-hand sides of their bounds at ``nodes.dofs``."""

    def bind_prescribed(self, prescribed: np.ndarray) -> None:
        """The Dirichlet dofs (local u indices), before :meth:`prescribed_forces` (collective)."""

    def prescribed_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """(owned local u dofs, values): the part's force on the body at the dofs of its nodes
        that a Dirichlet part prescribes — its law acts there (friction at a node whose
        tangential motion is prescribed), but the solver's row is the support's, so the
        equilibrium residual there holds the support's reaction and this force together
        (:mod:`vpcontact.solver.support_forces` separates them). Collective."""

    def solver_terms(self) -> list:
        """Nodal terms the step solver adds to its residual and Jacobian (friction on a
        Signorini part: :class:`~vpcontact.model.nodal_friction.NodalFriction`), or []."""

    def commit(self, time: float, x=None) -> None:
        """The step to ``time`` is accepted (``x``: the step solver's unknowns there)."""

    def state(self) -> dict:
        """What a checkpoint must hold to continue (JSON-able; {} for most parts)."""

    def arrays(self) -> dict:
        """This rank's arrays a checkpoint must hold to continue ({} for most parts)."""

    def restore(self, state: dict, time: float, arrays: Optional[dict] = None) -> None:
        """Continue from :meth:`state` and :meth:`arrays` at ``time``."""

    def pressure(self) -> np.ndarray:
        """σ_ν at this rank's nodes (collective)."""

    def nodal_outputs(self) -> tuple[NodalOutput, ...]:
        """The quantities it reports at its nodes beyond u_ν, the gap and σ_ν (() for most)."""

    def nodal_values(self, key: str) -> np.ndarray:
        """This rank's values at its nodes of its :meth:`nodal_outputs` ``key``."""

    def report(self):
        """A :class:`~vpcontact.model.contact_nodes.ContactReport` (bounded parts; collective), or
        None."""

    def touching(self, tolerance: float) -> bool:
        """Some node of this rank touches (u_ν ≥ g − tolerance)."""

    def driving_displacement(self, time: float) -> Optional[float]:
        """The signed largest component of the obstacle's translation at ``time``, or None."""


def merged_bounds(u, parts: Sequence[ContactPart]) -> Optional[tuple[PETSc.Vec, PETSc.Vec]]:
    """(lower, upper) for SNES VI from every bounded part (−∞ < ũ < ∞ elsewhere), or None."""
    bounded = [p for p in parts if p.bounded]
    if not bounded:
        return None
    lower, upper = u.vector.duplicate(), u.vector.duplicate()
    lower.set(PETSc.NINFINITY)
    upper.set(PETSc.INFINITY)
    for part in bounded:
        cd, gap = part.nodes, part.bound_gaps()
        up = cd.signs > 0
        upper.array[cd.dofs[up]] = gap[up]
        lower.array[cd.dofs[~up]] = -gap[~up]
    for vec in (lower, upper):
        vec.assemble()
    return lower, upper


def merged_frames(comm, parts: Sequence[ContactPart]) -> Optional[Frames]:
    """The local frames of every bounded part that works in them (None if none does on any
    rank; collective)."""
    framed = [p.nodes.frames for p in parts if p.bounded and p.nodes.rotated]
    if not comm.allreduce(bool(framed), op=MPI.LOR):
        return None
    if not framed:
        return Frames(np.zeros(0, np.int32), np.zeros((0, 0)), np.zeros(0, np.int32),
                      np.zeros(0), np.zeros((0, 0, 0)))
    return Frames(*(np.concatenate([getattr(f, name) for f in framed])
                    for name in ("nodes", "normals", "slots", "signs", "blocks")))


def merged_report(comm, parts: Sequence[ContactPart]):
    """One :class:`~vpcontact.model.contact_nodes.ContactReport` over the bounded parts (active
    nodes summed, extremes over parts, forces summed), or None without one (collective)."""
    reports = [r for r in (p.report() for p in parts) if r is not None]
    if not reports:
        return None
    return ContactReport(
        active=sum(r.active for r in reports),
        max_penetration=max(r.max_penetration for r in reports),
        min_pressure=min(r.min_pressure for r in reports),
        max_pressure=max(r.max_pressure for r in reports),
        complementarity=max(r.complementarity for r in reports),
        normal_force=sum(r.normal_force for r in reports))


def moved_parts(comm, parts: Sequence[ContactPart], time: float) -> None:
    """Each part's obstacle moved to its place at ``time`` (:meth:`ContactPart.update`);
    collective: a ray that misses on one rank stops every rank with the same
    :class:`~vpcontact.errors.ObstacleOutOfReach`, naming the part."""
    message, part_name = None, None
    for part in parts:
        try:
            part.update(time)
        except InputError as err:
            message = f"at t = {time:.6g}, where the moving obstacle has gone: {err}"
            part_name = part.name
            break
    found = next(((m, n) for m, n in comm.allgather((message, part_name)) if m), None)
    if found is not None:
        raise ObstacleOutOfReach(found[0], part=found[1])


def bounded_touching(comm, parts: Sequence[ContactPart], tolerance: float) -> bool:
    """Whether a node of a bounded part touches its obstacle (within ``tolerance``) on some rank
    (collective where there is a bounded part)."""
    bounded = [p for p in parts if p.bounded]
    if not bounded:
        return False
    local = any(p.touching(tolerance) for p in bounded)
    return comm.allreduce(local, op=MPI.LOR)

