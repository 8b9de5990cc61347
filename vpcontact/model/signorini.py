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
from typing import Callable, Optional

import numpy as np
from dolfinx import fem

from vpcontact.errors import InputError
from vpcontact.model.contact_nodes import Gap
from vpcontact.model.nodal_friction import NodalFriction
from vpcontact.model.obstacle import LevelSet
from vpcontact.model.obstacle_normals import ObstacleNormalForce
from vpcontact.model.signorini_part import DrivenSignoriniPart, SignoriniPart


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
        friction: Coulomb or Tresca friction (:class:`~vpcontact.model.friction.FrictionLaw`; see
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
        (see :class:`~vpcontact.model.signorini_part.SignoriniPart`)."""
        kind = SignoriniPart if self.force is None else DrivenSignoriniPart
        framed = self.friction is not None or self.normals == "obstacle"
        part = kind(self, u, facet_tags, equilibrium, name, exclude, True if framed else rotate)
        if self.friction is not None:
            if self.obstacle_moves:
                raise InputError("friction on a deforming obstacle (a level set of x and t) is "
                                 "not available: its surface has no material points to slip "
                                 "against (give it a translation and a rotation instead)",
                                 key="contact.friction")
            part.friction = NodalFriction(part, shear_modulus, facet_tags)
        if self.normals == "obstacle":
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
