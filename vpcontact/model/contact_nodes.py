# SPDX-License-Identifier: MIT
"""The contact nodes of a part of the boundary: where they are, their normals (or local frames),
the dofs that carry a bound, and the gap to an obstacle along each node's normal.

What this needs of the obstacle is its geometry alone (an :class:`Obstacle`): a Signorini
condition (:class:`~vpcontact.model.signorini.Signorini`) is one, and a compliant foundation's
surface (:class:`Surface`) is another, so normal compliance locates its nodes without a contact
law of another kind.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional, Protocol, Union

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.errors import InputError
from vpcontact.model.frames import Frames, frames, vertex_normals
from vpcontact.model.obstacle import LevelSet, gap_along_normal

Gap = Union[float, Callable[[np.ndarray], np.ndarray]]


class Obstacle(Protocol):
    """The geometry of what the nodes of a contact part face: the facets ``tag``, and either a
    gap g (a number or g(x) of points (3, N) -> (N,)) or a level set φ (``obstacle``, the
    region {φ ≤ 0}) searched along each node's normal up to ``max_distance``; ``moving``: the
    gaps change with time, ``obstacle_at(t)`` the level set at t."""

    tag: int
    gap: Gap
    obstacle: Optional[Callable]
    max_distance: float

    @property
    def moving(self) -> bool:
        """Whether the gaps change with time."""

    def obstacle_at(self, time: float) -> LevelSet:
        """The level set at ``time``."""


@dataclass(frozen=True)
class Surface:
    """A surface that stays where it is (a compliant foundation's): the facets ``tag`` and a gap
    g ≥ 0 (a number or g(x)), or a level set φ searched up to ``max_distance`` (an
    :class:`Obstacle`)."""

    tag: int
    gap: Gap = 0.0
    obstacle: Optional[Callable] = None
    max_distance: float = 1e3

    def __post_init__(self):
        if isinstance(self.gap, (int, float)) and not (math.isfinite(self.gap) and self.gap >= 0):
            raise InputError(f"gap g must be finite and >= 0, got {self.gap}", key="contact.gap")

    @property
    def moving(self) -> bool:
        return False

    def obstacle_at(self, time: float) -> LevelSet:
        return self.obstacle


def unrolled(bs: int, blocks: np.ndarray, exclude: np.ndarray) -> np.ndarray:
    """The unrolled dofs of the node ``blocks`` (block size ``bs``), without those in
    ``exclude``."""
    dofs = (np.asarray(blocks, dtype=np.int64)[:, None] * bs + np.arange(bs)).ravel()
    return dofs[~np.isin(dofs, exclude)].astype(np.int32)


@dataclass
class ContactDofs:
    """The contact nodes of Γ3 owned by this rank and their bounded dofs.

    On an axis-aligned planar Γ3 (``axis`` is not None) ν = sign · e_axis at every node and
    ``dofs`` are displacement components; otherwise ``frames`` holds each node's local frame and
    ``dofs`` index ũ = Rᵀu (the normal slot of each node's block).
    """

    axis: Optional[int]       # normal = sign * e_axis on a planar, axis-aligned Γ3; else None
    sign: float               # that sign (1.0 on a general Γ3)
    dofs: np.ndarray          # local indices (owned only) of the bounded dofs
    points: np.ndarray        # (n, 3) coordinates
    gap: np.ndarray           # g at the points
    nodes: np.ndarray         # node (block) indices of the points
    normals: np.ndarray       # (n, dim) unit outward normals
    signs: np.ndarray         # per node: ũ_slot = sign u·ν
    frames: Optional[Frames] = None  # local frames (general Γ3 only)
    #: nodes whose normal ray missed the obstacle at t = 0 (gap = max_distance: no contact)
    unreachable: Optional[np.ndarray] = None

    @property
    def rotated(self) -> bool:
        """Whether SNES works in local frames (ũ = Rᵀu) rather than on u itself."""
        return self.frames is not None

    def normal_displacement(self, u: fem.Function) -> np.ndarray:
        """u_ν at the contact nodes."""
        return self.normal_component(u.x.array)

    def normal_component(self, values: np.ndarray) -> np.ndarray:
        """ν · (the entries at the contact nodes) of an array laid out like u's dofs."""
        if self.axis is not None:
            return self.sign * values[self.dofs]
        bs = self.normals.shape[1]
        return np.einsum("ij,ij->i", values[self.nodes[:, None] * bs + np.arange(bs)],
                         self.normals)


def axis_aligned_normal(mesh, facet_tags, tag: int,
                        tol: float = 1e-10) -> Optional[tuple[int, float]]:
    """(axis, sign) with ν = sign · e_axis on the facets ``tag`` if they form a plane with an
    axis-aligned normal, else None."""
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(tag)
    n = ufl.FacetNormal(mesh)
    comm = mesh.comm

    def integral(expr):
        return comm.allreduce(fem.assemble_scalar(fem.form(expr * ds)), op=MPI.SUM)

    area = integral(fem.Constant(mesh, 1.0))
    if area <= 0:
        raise InputError(f"the contact boundary (tag {tag}) has no facets", key="contact.boundary")
    dim = mesh.geometry.dim
    mean = np.array([integral(n[i]) for i in range(dim)]) / area
    spread = integral(ufl.dot(n - ufl.as_vector(mean.tolist()), n - ufl.as_vector(mean.tolist()))) / area
    if spread > tol or abs(np.linalg.norm(mean) - 1.0) > tol:
        return None
    axis = int(np.argmax(np.abs(mean)))
    if abs(abs(mean[axis]) - 1.0) > 1e-8:
        return None
    return axis, float(np.sign(mean[axis]))


def contact_dofs(V: fem.FunctionSpace, facet_tags, contact: Obstacle,
                 exclude: np.ndarray = np.zeros(0, dtype=np.int32),
                 rotate: Optional[bool] = None, time: float = 0.0) -> ContactDofs:
    """Locate the contact nodes of Γ3, their normals and bounded dofs, and evaluate the gap.

    Dofs in ``exclude`` (the Dirichlet dofs) are prescribed already: a node whose every component
    is prescribed is left out (so that clamp reactions on the edge shared by Γ1 and Γ3 are not
    reported as contact forces); at a node with some prescribed components the frame keeps
    their axes (:mod:`vpcontact.model.frames`). ``rotate``: None or False takes the fast path on
    an axis-aligned planar Γ3 and local frames otherwise; True forces local frames (identity
    blocks on an axis-aligned Γ3: one path tested against the other).
    """
    aligned = axis_aligned_normal(V.mesh, facet_tags, contact.tag)
    if aligned is not None and not rotate:
        cd = _aligned_contact_dofs(V, facet_tags, contact, exclude, aligned, time)
    else:
        cd = _framed_contact_dofs(V, facet_tags, contact, exclude, time)
    _check_reach(V.mesh.comm, contact, cd)
    return cd


def _framed_contact_dofs(V, facet_tags, contact, exclude, time) -> ContactDofs:
    mesh = V.mesh
    bs = V.dofmap.index_map_bs
    facets = facet_tags.find(contact.tag)
    weighted = vertex_normals(V, facet_tags, contact.tag)
    nodes = fem.locate_dofs_topological(V, mesh.topology.dim - 1, facets)
    nodes = nodes[nodes < V.dofmap.index_map.size_local]
    prescribed = np.isin(nodes[:, None] * bs + np.arange(bs), exclude)
    free = ~prescribed.all(axis=1)
    nodes, prescribed = nodes[free].astype(np.int32), prescribed[free]
    normals = weighted[nodes]
    length = np.linalg.norm(normals, axis=1)
    fr = frames(nodes, normals / np.where(length > 0, length, 1.0)[:, None], prescribed)
    points = V.tabulate_dof_coordinates()[nodes]
    dofs = (nodes * bs + fr.slots).astype(np.int32)
    cd = ContactDofs(None, 1.0, dofs, points, np.zeros(len(nodes)), nodes, fr.normals, fr.signs, fr)
    cd.gap = contact_gap(contact, cd, time, mesh.comm)
    return cd


def _check_reach(comm, contact: Obstacle, cd: ContactDofs) -> None:
    """Nodes whose rays miss the obstacle are left without contact, but not all of them: then
    the obstacle is not in front of the contact part at all (collective)."""
    missed = 0 if cd.unreachable is None else int(np.count_nonzero(cd.unreachable))
    missed, total = comm.allreduce(missed), comm.allreduce(len(cd.gap))
    if total and missed == total:
        raise InputError(f"no contact node's normal ray meets the obstacle within "
                         f"max_distance = {contact.max_distance:g}: it is not in front of the "
                         "contact part (check the obstacle's place, or raise "
                         "contact.max_distance if it is farther)", key="contact.obstacle")


def _aligned_contact_dofs(V, facet_tags, contact, exclude, aligned, time) -> ContactDofs:
    axis, sign = aligned
    sub = V.sub(axis)
    collapsed, _ = sub.collapse()
    facets = facet_tags.find(contact.tag)
    parent, child = fem.locate_dofs_topological((sub, collapsed), V.mesh.topology.dim - 1, facets)
    bs = V.dofmap.index_map_bs
    owned = V.dofmap.index_map.size_local * bs
    keep = (parent < owned) & ~np.isin(parent, exclude)
    parent, child = parent[keep].astype(np.int32), child[keep]
    points = collapsed.tabulate_dof_coordinates()[child]
    normals = np.zeros((len(parent), bs))
    normals[:, axis] = sign
    cd = ContactDofs(axis, sign, parent, points, np.zeros(len(parent)),
                     (parent // bs).astype(np.int32), normals, np.full(len(parent), sign))
    cd.gap = contact_gap(contact, cd, time, V.mesh.comm)
    return cd


def contact_gap(contact: Obstacle, cd: ContactDofs, time: float, comm) -> np.ndarray:
    """g at the contact nodes at time ``time``: the distance along each node's normal to the
    obstacle (in its position at that time), or the scene's g(x). Collective: a bad gap on one
    process is every process's error (raised on one alone, it left the others waiting in
    their next collective call: a 2-rank run hung)."""
    error = None
    try:
        gap = _local_gap(contact, cd, time)
    except InputError as err:
        error = err
    errors = comm.allgather(None if error is None else (str(error), error.key))
    first = next((e for e in errors if e is not None), None)
    if first is not None:
        raise error if error is not None else InputError(first[0], key=first[1])
    return gap


def _check_not_passed(obstacle, points, normals, gap, unreachable, max_distance) -> None:
    """A moving obstacle may leave a node's ray (one sliding sideways past the body: no contact
    there, gap = max_distance), but not by passing through the body: raise if it now lies behind
    a node that could reach it at t = 0."""
    lost = np.flatnonzero((gap >= max_distance) & ~unreachable)
    if not len(lost):
        return
    behind = gap_along_normal(obstacle, points[lost], -normals[lost], max_distance=max_distance,
                              check_side=False, may_miss=np.ones(len(lost), bool))
    if np.any(behind < max_distance):
        i = lost[int(np.argmax(behind < max_distance))]
        raise InputError(f"the obstacle has passed through the body: it lies behind contact "
                         f"point {points[i].round(12).tolist()} (along the normal "
                         f"{normals[i].round(12).tolist()}), whose ray met it at t = 0. Its "
                         "prescribed motion takes it deeper than the body is thick: a smaller "
                         "motion (check its size and units) or an earlier end of the run",
                         key="contact.obstacle")


def _local_gap(contact: Obstacle, cd: ContactDofs, time: float) -> np.ndarray:
    """:func:`contact_gap` at this process's nodes."""
    points = cd.points
    if contact.obstacle is not None:
        normals = np.zeros((len(points), 3))
        normals[:, :cd.normals.shape[1]] = cd.normals
        first = cd.unreachable is None  # the nodes set up: rays may miss (no contact there)
        obstacle = contact.obstacle_at(time)
        gap = gap_along_normal(obstacle, points, normals,
                               max_distance=contact.max_distance, signed=contact.moving,
                               check_side=time == 0.0 or not contact.moving,
                               may_miss=np.ones(len(points), bool) if first or contact.moving
                               else cd.unreachable)
        if first:
            cd.unreachable = gap >= contact.max_distance
        elif contact.moving:
            _check_not_passed(obstacle, points, normals, gap, cd.unreachable,
                              contact.max_distance)
    elif callable(contact.gap):
        gap = np.broadcast_to(np.asarray(contact.gap(points.T), dtype=np.float64),
                              (len(points),)).copy()
    else:
        gap = np.full(len(points), float(contact.gap))
    # A moving obstacle may move into the reference configuration (g < 0 later on), but the
    # initial state must be admissible.
    bad = np.flatnonzero(~np.isfinite(gap) | ((gap < 0) & (not contact.moving or time == 0.0)))
    if len(bad) and contact.obstacle is not None:
        raise InputError(f"contact point {points[bad[0]].round(12).tolist()} starts inside the "
                         f"obstacle at t = {time:g} (gap {gap[bad[0]]:.6g})",
                             key="contact.obstacle")
    if len(bad):
        raise InputError(f"the gap must be finite and >= 0 at every contact point (the body "
                         f"starts out of contact); it is {gap[bad[0]]:.6g} at "
                         f"{points[bad[0]].round(12).tolist()}", key="contact.gap")
    return gap


def variable_bounds(u: fem.Function, cdofs: ContactDofs) -> tuple[PETSc.Vec, PETSc.Vec]:
    """Bounds for SNES VI: -∞ < ũ < ∞ except ũ_slot ≤ g (s = +1) or ũ_slot ≥ -g (s = -1) at
    each contact node (ũ = u on the fast path, where the slot is the normal axis)."""
    lower = u.vector.duplicate()
    upper = u.vector.duplicate()
    lower.set(PETSc.NINFINITY)
    upper.set(PETSc.INFINITY)
    up = cdofs.signs > 0
    upper.array[cdofs.dofs[up]] = cdofs.gap[up]
    lower.array[cdofs.dofs[~up]] = -cdofs.gap[~up]
    for vec in (lower, upper):
        vec.assemble()
    return lower, upper


@dataclass
class ContactReport:
    """Contact state after a step (global over ranks)."""

    active: int                    # contact dofs with u_ν = g
    max_penetration: float         # max (u_ν - g); ≤ 0 up to solver tolerance
    min_pressure: float            # min σ_ν (most compressive)
    max_pressure: float            # max σ_ν; ≤ 0 up to round-off (no adhesion)
    complementarity: float         # max |σ_ν (u_ν - g)|
    normal_force: float            # ∫_Γ3 σ_ν da (sum of nodal normal forces)
