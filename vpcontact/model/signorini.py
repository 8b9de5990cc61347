# SPDX-License-Identifier: MIT
"""Signorini contact with a rigid foundation as bounds of a variational inequality.

The discrete constraint u_ν ≤ g holds at every node of Γ3, ν the outward normal there. On a planar
Γ3 whose normal is a coordinate axis ±e_i it is a bound on single displacement dofs: u_i ≤ g(x)
where ν = +e_i and u_i ≥ -g(x) where ν = -e_i (the fast path: no change of variables). On any
other Γ3 (inclined, curved, piecewise planar) each contact node gets a local frame containing its
vertex normal (:mod:`vpcontact.model.frames`); SNES then works on ũ = Rᵀu, in which u_ν is again
a single dof with a bound. Either way PETSc's SNES VI (``vinewtonrsls``) solves each time step as a
complementarity problem.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional, Union

import numpy as np
import ufl
from dolfinx import fem
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.model.extent import mesh_extent
from vpcontact.errors import InputError
from vpcontact.model.frames import Frames, frames, vertex_normals
from vpcontact.model.obstacle import LevelSet, gap_along_normal

Gap = Union[float, Callable[[np.ndarray], np.ndarray]]


@dataclass(frozen=True)
class Signorini:
    """Signorini condition u_ν ≤ g, σ_ν ≤ 0, σ_ν (u_ν - g) = 0 on the facets tagged ``tag``.

    Attributes:
        tag: facet tag of Γ3.
        gap: constant gap g ≥ 0 or a function g(x) of points (3, N) -> (N,).
        obstacle: level set φ of a rigid obstacle {φ ≤ 0} (φ > 0 on the body's side), φ(x) of
            points (3, N), or φ(x, t) when ``obstacle_moves``; when given, g is the distance to it
            along the outward normal (``gap`` is then ignored).
        max_distance: longest ray searched for the obstacle.
        obstacle_moves: φ depends on t (the gap is recomputed at every step).
        translation: rigid translation d(t) of the obstacle (t -> (3,) array): the obstacle at t is
            {x : φ(x - d(t)) ≤ 0}; None: it stays where φ puts it.
        rotation: rigid rotation Q(t) of the obstacle about ``rotation_center`` c (t -> (3, 3)
            orthogonal matrix), applied before the translation: the obstacle at t is
            {x : φ(c + Q(t)ᵀ(x − c − d(t))) ≤ 0}; None: it does not turn.
        rotation_center: the point c the rotation turns about (3 coordinates).
        force: F(t) (t -> (dim,) array), the force pressing the obstacle on the body, instead
            of a prescribed motion: the obstacle translates by an unknown d along
            ``force_direction`` e, solved with u so that the contact force balances F(t) · e
            (see :class:`DrivenSignoriniPart`); F(t) = |F(t)| e with |F(t)| > 0 for t > 0.
        force_direction: e, the unit vector F(t) keeps (3 coordinates).
        friction: Coulomb or Tresca friction (:class:`~vpcontact.model.friction.Friction`; see
            :mod:`vpcontact.model.nodal_friction`), or None.
        normals: the direction of the contact force: ``"body"``, the body's outward normal (the
            paper's condition), or ``"obstacle"``, the obstacle's normal where each node's ray
            meets it (:mod:`vpcontact.model.obstacle_normals`; ploughing); the bound is u_ν ≤ g
            either way.
    """

    tag: int
    gap: Gap = 0.0
    obstacle: Optional[Callable] = None
    max_distance: float = 1e3
    obstacle_moves: bool = False
    translation: Optional[Callable[[float], np.ndarray]] = None
    rotation: Optional[Callable[[float], np.ndarray]] = None
    rotation_center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    force: Optional[Callable[[float], np.ndarray]] = None
    force_direction: Optional[tuple[float, float, float]] = None
    friction: Optional[object] = None
    normals: str = "body"

    def __post_init__(self):
        if isinstance(self.gap, (int, float)) and not (math.isfinite(self.gap) and self.gap >= 0):
            raise InputError(f"Signorini gap g must be finite and >= 0, got {self.gap}",
                             key="contact.gap")
        if self.normals not in ("body", "obstacle"):
            raise InputError(f"normals must be \"body\" or \"obstacle\", got {self.normals!r}",
                             key="contact.normals")
        if self.normals == "obstacle" and self.obstacle is None:
            raise InputError("normals = \"obstacle\" needs an obstacle (a shape or a level set): "
                             "a gap g alone has no surface to take normals from",
                             key="contact.normals")
        if self.normals == "obstacle" and self.force is not None:
            raise InputError("normals = \"obstacle\" is not available on an obstacle driven by a "
                             "force (its equation balances the forces along the body's normals "
                             "only): give it a motion instead", key="contact.normals")

    @property
    def moving(self) -> bool:
        """Whether the gap changes with time."""
        return self.obstacle is not None and (self.obstacle_moves or self.translation is not None
                                              or self.rotation is not None
                                              or self.force is not None)

    def part(self, u: fem.Function, facet_tags, equilibrium, name: str = "contact",
             exclude: np.ndarray = np.zeros(0, dtype=np.int32),
             rotate: Optional[bool] = None, shear_modulus: float = 1.0) -> "SignoriniPart":
        """This condition on the mesh of ``u``: a :class:`~vpcontact.model.contact.ContactPart`
        (see :class:`SignoriniPart`)."""
        kind = SignoriniPart if self.force is None else DrivenSignoriniPart
        framed = self.friction is not None or self.normals == "obstacle"
        part = kind(self, u, facet_tags, equilibrium, name, exclude, True if framed else rotate)
        if self.friction is not None:
            from vpcontact.model.nodal_friction import NodalFriction
            if self.obstacle_moves:
                raise InputError("friction on a deforming obstacle (a level set of x and t) is "
                                 "not available: its surface has no material points to slip "
                                 "against (give it a translation and a rotation instead)",
                                 key="contact.friction")
            part.friction = NodalFriction(part, shear_modulus, facet_tags)
        if self.normals == "obstacle":
            from vpcontact.model.obstacle_normals import ObstacleNormalForce
            part.obstacle_normals = ObstacleNormalForce(part)
        return part

    def _translation(self, time: float) -> np.ndarray:
        d = np.zeros(3)
        if self.translation is not None:
            shift = np.asarray(self.translation(time), dtype=np.float64).reshape(-1)
            d[:len(shift)] = shift
        return d

    def obstacle_motion(self, t0: float, t1: float, points: np.ndarray) -> np.ndarray:
        """How far (N, 3) the obstacle's material points at ``points`` (N, 3) at ``t0`` move
        until ``t1``: a point X of φ's frame is at c + Q(t)(X − c) + d(t), so y at t0 goes to
        c + Q(t1) Q(t0)ᵀ (y − c − d(t0)) + d(t1)."""
        d0, d1 = self._translation(t0), self._translation(t1)
        if self.rotation is None:
            return np.broadcast_to(d1 - d0, np.shape(points)).copy()
        q0 = np.asarray(self.rotation(t0), dtype=np.float64).reshape(3, 3)
        q1 = np.asarray(self.rotation(t1), dtype=np.float64).reshape(3, 3)
        c = np.asarray(self.rotation_center, dtype=np.float64)
        y = np.asarray(points, dtype=np.float64)
        return c + (y - c - d0) @ (q1 @ q0.T).T + d1 - y

    def obstacle_at(self, time: float) -> LevelSet:
        """The obstacle's level set at ``time``, as a function of points (3, N)."""
        phi = self.obstacle
        at_t = (lambda x: phi(x, time)) if self.obstacle_moves else phi
        if self.translation is None and self.rotation is None:
            return at_t
        d = self._translation(time)
        if self.rotation is None:
            return lambda x: at_t(x - d[:, None])
        q = np.asarray(self.rotation(time), dtype=np.float64).reshape(3, 3)
        c = np.asarray(self.rotation_center, dtype=np.float64).reshape(3, 1)
        return lambda x: at_t(c + q.T @ (np.asarray(x, dtype=np.float64) - c - d[:, None]))


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


def contact_dofs(V: fem.FunctionSpace, facet_tags, contact: Signorini,
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


def _check_reach(comm, contact: Signorini, cd: ContactDofs) -> None:
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


def contact_gap(contact: Signorini, cd: ContactDofs, time: float, comm) -> np.ndarray:
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
                         f"{normals[i].round(12).tolist()}), whose ray met it at t = 0",
                         key="contact.obstacle")


def _local_gap(contact: Signorini, cd: ContactDofs, time: float) -> np.ndarray:
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


class ContactMonitor:
    """Nodal σ_ν on Γ3 from the equilibrium residual R(u) = (σ, ε(v)) - (f, v) at the solution.

    At a contact node i, ν_i · R_i = ∫_Γ3 σ_ν φ_i da (R_i the block of the node's components),
    so the nodal contact pressure is σ_ν,i = ν_i · R_i / ∫_Γ3 φ_i da (lumped). A point load P
    at a contact node is an applied force like f: R − P is the obstacle's force there
    (:meth:`set_point_loads`).

    For P2 the lumped weights fail: a vertex function of P2 integrates to zero over a triangle.
    The residual is then also tested with the P1 hat functions (each one a combination of P2
    functions, so ν_a · R¹_a = ∫ σ_ν φ¹_a da exactly), σ_ν is lumped at the vertices as for P1,
    and a node on an edge gets the mean of its end vertices (the P1 interpolant).
    """

    def __init__(self, u: fem.Function, cdofs: ContactDofs, equilibrium_form, facet_tags, tag: int):
        self.u = u
        self.cdofs = cdofs
        self._form = fem.form(equilibrium_form)
        self._vec = fem.petsc.create_vector(self._form)
        V = u.function_space
        v = ufl.TestFunction(V)
        ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=facet_tags)(tag)
        axis = cdofs.axis if cdofs.axis is not None else 0
        weights = fem.petsc.assemble_vector(fem.form(v[axis] * ds))
        weights.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        at = cdofs.dofs if cdofs.axis is not None else cdofs.nodes * V.dofmap.index_map_bs
        self.weights = weights.array[at].copy()
        weights.destroy()
        self.comm = V.mesh.comm
        self._vertices = None
        if V.ufl_element().degree() > 1:
            self._vertices = _VertexPressure(V, equilibrium_form, facet_tags, tag, cdofs)
        self._points = None  # (PointDofs, time Constant): the point loads, subtracted from R

    def set_point_loads(self, loads, time: fem.Constant) -> None:
        """Subtract the point loads ``loads`` (the problem's located
        :class:`~vpcontact.solver.loads.PointDofs`, F at ``time``) from the residual: they
        are applied forces, not the obstacle's (collective)."""
        self._points = (loads, time)
        if self._vertices is not None:
            self._vertices.set_point_loads(self.u.function_space, loads, time)

    def _subtract_point_loads(self, vec: PETSc.Vec) -> None:
        """R − P on this rank's owned entries of the assembled (ghost-updated) ``vec``."""
        if self._points is None:
            return
        loads, time = self._points
        t = float(time.value)
        array = vec.array
        for load in loads:
            array[load.dofs] -= load.values(t)

    def nodal_pressure(self) -> np.ndarray:
        """σ_ν at the contact nodes (lumped; P2: through the vertices, see the class docstring)."""
        if self._vertices is not None:
            return self._vertices.pressure()
        return self.nodal_forces() / self.weights

    def nodal_forces(self) -> np.ndarray:
        """ν_i · R_i at the contact nodes (= ∫ σ_ν φ_i da)."""
        with self._vec.localForm() as local:
            local.set(0.0)
        fem.petsc.assemble_vector(self._vec, self._form)
        self._vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self._subtract_point_loads(self._vec)
        return self.cdofs.normal_component(self._vec.array)

    def report(self, active_tol: float = 1e-10) -> ContactReport:
        forces = self.nodal_forces()
        pressure = self.nodal_pressure()
        gap = self.cdofs.normal_displacement(self.u) - self.cdofs.gap
        scale = max(self.comm.allreduce(float(np.max(np.abs(self.cdofs.gap), initial=0.0)), op=MPI.MAX), 1.0)
        active = int(np.count_nonzero(gap >= -active_tol * scale))
        red = self.comm.allreduce
        return ContactReport(
            active=red(active, op=MPI.SUM),
            max_penetration=red(float(np.max(gap, initial=-np.inf)), op=MPI.MAX),
            min_pressure=red(float(np.min(pressure, initial=np.inf)), op=MPI.MIN),
            max_pressure=red(float(np.max(pressure, initial=-np.inf)), op=MPI.MAX),
            complementarity=red(float(np.max(np.abs(pressure * gap), initial=0.0)), op=MPI.MAX),
            normal_force=red(float(np.sum(forces)), op=MPI.SUM))


class _VertexPressure:
    """σ_ν lumped at the vertices of Γ3 from the residual tested with P1 hat functions, then
    interpolated to the nodes of the P_k contact dofs (see :class:`ContactMonitor`)."""

    def __init__(self, V, equilibrium_form, facet_tags, tag: int, cdofs: ContactDofs):
        mesh = V.mesh
        bs = V.dofmap.index_map_bs
        V1 = fem.VectorFunctionSpace(mesh, ("Lagrange", 1), dim=bs)
        v = equilibrium_form.arguments()[0]
        v1 = ufl.TestFunction(V1)
        self._form = fem.form(ufl.replace(equilibrium_form, {v: v1}))
        self._vec = fem.petsc.create_vector(self._form)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(tag)
        weights = fem.petsc.assemble_vector(fem.form(v1[0] * ds))
        weights.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        facets = facet_tags.find(tag)
        vertices = fem.locate_dofs_topological(V1, mesh.topology.dim - 1, facets)
        vertices = vertices[vertices < V1.dofmap.index_map.size_local]
        # only the vertices that are contact nodes (not those every Dirichlet part holds, whose
        # residual is a support reaction)
        contact_points = {tuple(x) for x in np.round(cdofs.points, 12)}
        at_vertices = V1.tabulate_dof_coordinates()[vertices]
        keep = np.array([tuple(x) in contact_points for x in np.round(at_vertices, 12)], dtype=bool)
        self._vertices = vertices[keep] if len(vertices) else vertices
        self._weights = weights.array[self._vertices * bs].copy()
        weights.destroy()
        if cdofs.axis is not None:
            normals = np.zeros((len(self._vertices), bs))
            normals[:, cdofs.axis] = cdofs.sign
        else:
            normals = vertex_normals(V1, facet_tags, tag)[self._vertices]
            normals /= np.linalg.norm(normals, axis=1)[:, None]
        self._normals = normals
        self._bs = bs
        self._p1 = fem.Function(fem.FunctionSpace(mesh, ("Lagrange", 1)))
        V0, to_parent = V.sub(0).collapse()
        self._pk = fem.Function(V0)
        # a node on an edge with one end not a contact node takes the other end's value:
        # σ_ν = I(p¹) / I(1 at the contact vertices), I the interpolation into P_k
        self._p1.x.array[self._vertices] = 1.0
        self._p1.x.scatter_forward()
        self._pk.interpolate(self._p1)
        self._share = self._pk.x.array.copy()
        scalar_of_block = np.empty(V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts,
                                   dtype=np.int32)
        scalar_of_block[np.asarray(to_parent) // bs] = np.arange(len(to_parent), dtype=np.int32)
        self._at = scalar_of_block[cdofs.nodes]
        self._V1 = V1
        self._points = None  # (local V1 dofs incl. ghosts, (n, bs) weights, loads, time)

    def set_point_loads(self, V, loads, time: fem.Constant) -> None:
        """The point loads (located :class:`~vpcontact.solver.loads.PointDofs`) tested with the
        P1 hat functions: a load F at a node x_p of V gives φ¹_a(x_p) F at the vertices a of a
        cell around x_p (F at a vertex, F/2 at the ends of an edge whose midpoint it is, …);
        found by the rank that owns the node."""
        V1, bs = self._V1, self._bs
        mesh = V.mesh
        tdim = mesh.topology.dim
        num_cells = mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
        dofmap = V.dofmap.list.array.reshape(num_cells, -1)
        dofmap1 = V1.dofmap.list.array.reshape(num_cells, -1)
        coordinates = V.tabulate_dof_coordinates()
        hat = fem.Function(fem.FunctionSpace(mesh, ("Lagrange", 1)))
        rows, weights, loads = [], [], []
        for load in loads:
            if len(load.dofs) == 0:
                continue
            block = load.dofs[0] // bs
            cell = int(np.flatnonzero((dofmap == block).any(axis=1))[0])
            x = coordinates[block].reshape(1, 3)
            for a in dofmap1[cell]:
                hat.x.array[:] = 0.0
                hat.x.array[a] = 1.0
                w = float(hat.eval(x, np.array([cell], dtype=np.int32))[0])
                if abs(w) > 1e-12:
                    rows.append(a)
                    weights.append(w)
                    loads.append(load)
        self._points = (np.array(rows, dtype=np.int32), np.array(weights), loads, time)

    def pressure(self) -> np.ndarray:
        vec = self._vec
        with vec.localForm() as local:
            local.set(0.0)
        fem.petsc.assemble_vector(vec, self._form)
        if self._points is not None:  # R − P, tested with the P1 hats (before the ghosts add)
            rows, weights, loads, time = self._points
            t = float(time.value)
            with vec.localForm() as local:
                array = local.array
                for a, w, load in zip(rows, weights, loads):
                    array[a * self._bs:(a + 1) * self._bs] -= w * load.values(t)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        blocks = vec.array.reshape(-1, self._bs)[self._vertices]
        self._p1.x.array[:] = 0.0
        self._p1.x.array[self._vertices] = np.einsum("ij,ij->i", blocks, self._normals) / self._weights
        self._p1.x.scatter_forward()
        self._pk.interpolate(self._p1)
        share = self._share[self._at]
        return np.where(share > 0, self._pk.x.array[self._at] / np.where(share > 0, share, 1.0),
                        0.0)


class SignoriniPart:
    """A Signorini contact part at run time (a :class:`~vpcontact.model.contact.ContactPart`):
    its nodes and bounded dofs, the gap of a moving obstacle, the nodal pressure and the report.
    Its obstacle stays where it is or moves as prescribed (see :class:`DrivenSignoriniPart`
    for one pressed by a force).

    Args:
        law: the condition.
        u: the displacement.
        facet_tags: the mesh's facet tags (Γ3 is ``law.tag``).
        equilibrium: the UFL form (σ, ε(v)) − (f, v), whose residual gives the pressure.
        name: the boundary part's name.
        exclude: dofs held elsewhere (Dirichlet dofs, the nodes of earlier contact parts).
        rotate: see :func:`contact_dofs`.
    """

    bounded = True
    driven = False
    friction = None  # its NodalFriction, with friction
    obstacle_normals = None  # its ObstacleNormalForce, with normals = "obstacle"
    _time = 0.0  # of the last accepted step

    def __init__(self, law: Signorini, u: fem.Function, facet_tags, equilibrium, name: str,
                 exclude: np.ndarray, rotate: Optional[bool]):
        from vpcontact.model.contact import unrolled
        V = u.function_space
        self.law, self.name, self.u = law, name, u
        self.comm = V.mesh.comm
        self._nodes = contact_dofs(V, facet_tags, law, exclude=exclude, rotate=rotate)
        self.node_blocks = np.unique(self._nodes.nodes).astype(np.int32)
        self.force_dofs = unrolled(V.dofmap.index_map_bs, self.node_blocks, exclude)
        self.monitor = ContactMonitor(u, self._nodes, equilibrium, facet_tags, law.tag)

    @property
    def nodes(self) -> ContactDofs:
        return self._nodes

    @property
    def moving(self) -> bool:
        return self.law.moving

    def snes_defaults(self, linear_law: bool) -> dict:
        """SNES options this part needs: the VI solver; with Coulomb friction, the critical-point
        line search (measured on a block pressed onto a rigid floor, then dragged, 𝔣 = 0.3: 4, 0,
        0, 0, 0, 5, 2, 2, 0, 0 Newton iterations for k = 0.1, no step cut; with full steps or l2
        the first dragging step is cut 1–4 times, with backtracking it takes 16–46). Tresca's
        threshold switches on with λ > 0, which ``cp`` crosses slowly (16 iterations where full
        steps take 3): it keeps PETSc's default."""
        if self.friction is not None and self.friction.friction.type == "coulomb":
            return {"snes_type": "vinewtonrsls", "snes_linesearch_type": "cp",
                    "vpcontact_rescue_linesearch": "l2"}
        return {"snes_type": "vinewtonrsls"}

    def terms(self, u, du, v, normal, ds):
        return None

    def update(self, time: float) -> None:
        """The gaps at ``time`` (raises InputError where a ray loses the obstacle)."""
        if self.moving:
            self._nodes.gap = contact_gap(self.law, self._nodes, time,
                                          self.u.function_space.mesh.comm)
            if self.obstacle_normals is not None:
                self.obstacle_normals.refresh(time)
        if self.friction is not None and (self.law.translation is not None
                                          or self.law.rotation is not None):
            # the obstacle's points at the nodes' places at the last step, and where they go
            cd, bs = self._nodes, self.u.function_space.dofmap.index_map_bs
            places = cd.points.copy()
            places[:, :bs] += self.u.x.array[cd.nodes[:, None] * bs + np.arange(bs)]
            self.friction.move(self.law.obstacle_motion(self._time, time, places))

    @property
    def last_friction(self) -> Optional[dict]:
        """The accepted step's friction at the nodes: tangential traction (the nodal force over
        the node's area), slip over the step, whether the node slipped; None without."""
        if self.friction is None or self.friction.last is None:
            return None
        last, areas = self.friction.last, self.friction.areas
        return {"traction": last["force"] / np.where(areas > 0, areas, 1.0)[:, None],
                "slip": last["slip"], "slips": last["slips"]}

    def solver_terms(self) -> list:
        """Nodal terms of the step's residual and Jacobian (friction, the obstacle's normals), for
        the step solver."""
        return [t for t in (self.friction, self.obstacle_normals) if t is not None]

    def bound_gaps(self) -> np.ndarray:
        """The right-hand sides of the bounds u_ν ≤ g at the nodes."""
        return self._nodes.gap

    def commit(self, time: float, x=None) -> None:
        """The step to ``time`` is accepted (``x``: SNES's unknowns there, for friction)."""
        self._time = time
        if self.friction is not None and x is not None:
            self.friction.commit(x)

    def state(self) -> dict:
        """What a checkpoint must hold to continue (JSON-able)."""
        return {}

    def arrays(self) -> dict:
        """Arrays (this rank's) a checkpoint must hold to continue: friction's nodal history."""
        return {} if self.friction is None else self.friction.arrays()

    def restore(self, state: dict, time: float, arrays: Optional[dict] = None) -> None:
        """Continue from :meth:`state` (and :meth:`arrays`) at ``time``."""
        self._time = time  # the last accepted step's: the next step's slip is the obstacle's
        self.update(time)  # motion from there (from t = 0 it was, 44 % off in the force)
        if self.friction is not None:
            self.friction.restore(arrays or {})

    def pressure(self) -> np.ndarray:
        return self.monitor.nodal_pressure()

    def report(self) -> "ContactReport":
        return self.monitor.report()

    def touching(self, tolerance: float) -> bool:
        cd = self._nodes
        return bool(np.any(cd.normal_displacement(self.u) >= cd.gap - tolerance))

    def driving_displacement(self, time: float) -> Optional[float]:
        if self.law.translation is None:
            return None
        d = np.asarray(self.law.translation(time), dtype=float).ravel()
        return float(d[np.argmax(np.abs(d))]) if d.size else 0.0


class DrivenSignoriniPart(SignoriniPart):
    """A rigid obstacle pressed on the body by a force F(t) = F(t) e: it translates by d along
    e, an unknown of each step solved with u (see :mod:`vpcontact.solver.variables`), so that
    the contact force on it balances F(t).

    Over a step the gaps are linear in the unknown δ = d − d_p (:attr:`increment`; d_p the d
    predicted from the last two steps): g_i(d) ≈ g_i(d_p) + (e · ν_i) δ, g_i(d_p) by ray
    casting. The coefficient e · ν_i makes the obstacle's own equation the balance of the
    contact forces along e, Σ σ_ν,i ν_i · e = F(t) · e, exactly (to solver tolerance). It is
    the gap's exact sensitivity ∂g_i/∂d where the contact face is normal to e (any obstacle);
    where the face turns by θ from that (a curved body on a plane) the linearization is off by
    |δ| O(θ²) per step. The obstacle starts touching the body: at set-up it is moved along e
    until the first node's gap closes (a force on an obstacle in free flight has no
    equilibrium).
    """

    driven = True

    def __init__(self, law: Signorini, u, facet_tags, equilibrium, name: str, exclude, rotate):
        super().__init__(law, u, facet_tags, equilibrium, name, exclude, rotate)
        e = np.zeros(3)
        e[:len(law.force_direction)] = law.force_direction
        self._e = e / np.linalg.norm(e)
        V = u.function_space
        self._bs = V.dofmap.index_map_bs
        cd = self._nodes
        self._slopes = cd.normals @ self._e[:cd.normals.shape[1]]  # e · ν_i
        if cd.unreachable is not None:
            self._slopes[cd.unreachable] = 0.0  # (no contact there)
        self._delta = 1e-6 * mesh_extent(V.mesh)
        self._time = 0.0
        self.increment = 0.0
        self._predicted = self._touching_displacement()
        self._committed = [(0.0, self._predicted)]  # the last two accepted (t, d)
        self._linearize(self._predicted)

    @property
    def direction(self) -> np.ndarray:
        """e, the unit vector the obstacle moves along (3 components)."""
        return self._e

    @property
    def displacement(self) -> float:
        """d = d_p + δ at the current iterate."""
        return self._predicted + self.increment

    # -- the gaps as functions of d ---------------------------------------------------------
    def _gaps_at(self, d: float) -> np.ndarray:
        cd = self._nodes
        normals = np.zeros((len(cd.points), 3))
        normals[:, :cd.normals.shape[1]] = cd.normals
        phi = self.law.obstacle
        shifted = lambda x: phi(np.asarray(x, dtype=np.float64) - d * self._e[:, None])  # noqa: E731
        return gap_along_normal(shifted, cd.points, normals, max_distance=self.law.max_distance,
                                signed=True, check_side=False, may_miss=cd.unreachable)

    def _touching_displacement(self) -> float:
        """The d at which the obstacle, moved along e, first touches a node (collective)."""
        d = 0.0
        for _ in range(60):
            gaps = self._gaps_at(d)
            reach = ~self._nodes.unreachable if self._nodes.unreachable is not None else None
            local = gaps[reach] if reach is not None else gaps
            i = int(np.argmin(local)) if len(local) else -1
            g = float(local[i]) if len(local) else np.inf
            slope = 0.0
            if len(local):
                ahead, behind = (self._gaps_at(d + self._delta), self._gaps_at(d - self._delta))
                rows = np.flatnonzero(reach) if reach is not None else np.arange(len(gaps))
                slope = float(ahead[rows[i]] - behind[rows[i]]) / (2 * self._delta)
            g_min, slope = min(self.comm.allgather((g, slope)))
            if g_min <= 1e-12 * max(1.0, abs(d), self._delta * 1e6):
                return d
            if not slope < 0:
                raise InputError(f"the force's direction {self._e[:self._bs].round(12).tolist()} "
                                 "moves the obstacle away from the contact part (the force must "
                                 "press it on the body)", key="contact.force")
            d -= g_min / slope
        raise InputError("the obstacle cannot be brought into contact along the force's "
                         "direction", key="contact.force")

    def _linearize(self, d: float) -> None:
        """The gaps at d = d_p (the bounds: u_ν − (e · ν) δ ≤ g(d_p))."""
        self._predicted, self.increment = d, 0.0
        self._nodes.gap = self._gaps_at(d)
        self._bound = self._nodes.gap.copy()

    # -- the part's protocol ----------------------------------------------------------------
    def update(self, time: float) -> None:
        """Predict d at ``time`` from the last two accepted steps and linearize about it."""
        (t1, d1), (t0, d0) = self._committed[-1], self._committed[0]
        d = d1 if t1 == t0 else d1 + (time - t1) / (t1 - t0) * (d1 - d0)
        self._time = time
        self._linearize(d)

    def bound_gaps(self) -> np.ndarray:
        return self._bound

    def column(self) -> tuple[np.ndarray, np.ndarray]:
        """(owned unrolled dofs, values): u changes by (e · ν_i) ν_i per unit of δ at node i."""
        cd = self._nodes
        if cd.axis is not None:
            return cd.dofs, self._slopes * cd.sign
        dofs = (cd.nodes[:, None] * self._bs + np.arange(self._bs)).ravel().astype(np.int32)
        return dofs, (self._slopes[:, None] * cd.normals).ravel()

    def bounded_dofs(self) -> np.ndarray:
        """The bounded entries (w̃'s normal slots) of this rank's nodes."""
        return self._nodes.dofs

    def refit(self, tolerance: float) -> bool:
        """After a solve: if the linearized gaps g(d_p) + (e · ν) δ differ from the ray-cast gaps
        at the solved d by more than ``tolerance`` (a length) at some node in contact or within
        that difference of contact, linearize about d
        (the step is then solved again from where it is; the difference shrinks by about θ²
        per round, θ the face's turn from the normal to e). Collective; True if it did."""
        gaps = self._gaps_at(self.displacement)
        linear = self._bound + self._slopes * self.increment
        error = np.abs(gaps - linear)
        # the nodes whose contact the error could decide: in contact, or within it of contact
        clearance = np.minimum(gaps, linear) - self._nodes.normal_displacement(self.u)
        near = clearance <= error + tolerance
        if self._nodes.unreachable is not None:
            near &= ~self._nodes.unreachable
        local = float(np.max(error[near], initial=0.0))
        if self.comm.allreduce(local, op=MPI.MAX) <= tolerance:
            return False
        self._linearize(self.displacement)
        return True

    def applied_force(self) -> float:
        """F(t) · e at the step's time."""
        force = np.zeros(3)
        value = np.asarray(self.law.force(self._time), dtype=np.float64).ravel()
        force[:len(value)] = value
        return float(force @ self._e)

    def commit(self, time: float, x=None) -> None:
        self._committed = (self._committed + [(time, self.displacement)])[-2:]
        self._nodes.gap = self._gaps_at(self.displacement)  # where the obstacle is now
        if self.friction is not None and x is not None:
            self.friction.commit(x)

    def state(self) -> dict:
        return {"committed": [list(c) for c in self._committed]}

    def restore(self, state: dict, time: float, arrays: Optional[dict] = None) -> None:
        self._committed = [tuple(c) for c in state["committed"]]
        self._time = time
        self._linearize(self._committed[-1][1])
        if self.friction is not None:
            self.friction.restore(arrays or {})

    def driving_displacement(self, time: float) -> Optional[float]:
        d = self.displacement * self._e
        return float(d[np.argmax(np.abs(d))])
