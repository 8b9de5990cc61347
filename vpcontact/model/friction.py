# SPDX-License-Identifier: MIT
"""Friction on a normal-compliance part: Coulomb's law with the compliance pressure (the model of
Klarbring, Mikelić and Shillor), or Tresca's with a given threshold.

On Γ3 the tangential traction t = σ_τ opposes the slip of the body over the (fixed) foundation
and is bounded by a threshold s:

    |t| ≤ s,   t = −s Δu_τ / |Δu_τ| where the body slips,
    s = 𝔣 p(u_ν) (Coulomb, p = (1/μ)(u_ν − g)_+^α the compliance pressure),
    s = g_T(x) where p > 0 (Tresca: a given threshold, on the part in contact),

incrementally (Δu_τ = (I − n ⊗ n)(u_n − u_{n−1}), the slip over the step). As in plasticity, a
stiff "elastic" stick and a return mapping make the step's equations semi-smooth, with an exact
slip law:

    t_trial = t_{n−1} − k_t Δu_τ,     t = t_trial if |t_trial| ≤ s, else s t_trial/|t_trial|,

k_t = STICK_STIFFNESS × G/h (G the body's shear modulus, h the size of the facets around each node
of Γ3, :func:`vpcontact.model.nodal_areas.facet_sizes`): where the body sticks it moves by
|t|/k_t — 1e-2 of the elastic displacement the same traction causes over one facet, on any mesh —
and where it slips |t| = s exactly, so a sliding part carries its threshold's integral to solver
tolerance. The friction traction and its exact (generalised) derivative are UFL boundary
integrals; the history t_{n−1} is kept at the nodes of Γ3 (a field of the displacement's space,
updated by the same return mapping at the nodes when a step is accepted).

On a Signorini part (a rigid obstacle) the normal force is the variational inequality's
multiplier and a Coulomb cone is not a box of SNES VI: there friction is nodal, with the same
return mapping (:mod:`vpcontact.model.nodal_friction`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np
import ufl
from mpi4py import MPI

from vpcontact.errors import InputError

#: k_t relative to G / h (h the local facet size). Stiffer sticks are closer to an exact one but
#: Newton crosses their narrower stick interval (2b/k_t) less reliably: with 1e3 G/h the block
#: of tests/test_friction.py pressed with P2 displacements cycles between stick and slip for 50
#: iterations in its first step; with 1e2 it takes 4 (the last mesh-extent stiffness, 1e3 G/L,
#: was 62 G/h on that mesh and far softer on refined ones).
STICK_STIFFNESS = 1e2

FRICTION_TYPES = ("coulomb", "tresca")


@dataclass(frozen=True)
class Friction:
    """Coulomb friction (``coefficient`` 𝔣 ≥ 0) or Tresca friction (``threshold`` g_T ≥ 0: a
    number, or a function of the spatial coordinate returning a UFL expression, with
    ``threshold_at`` the same as a function of points (3, N) -> (N,))."""

    type: str
    coefficient: Optional[float] = None
    threshold: object = None
    threshold_at: Optional[Callable[[np.ndarray], np.ndarray]] = None

    def __post_init__(self):
        if self.type not in FRICTION_TYPES:
            raise InputError(f"friction type must be one of {FRICTION_TYPES}, got {self.type!r}",
                             key="contact.friction.type")
        if self.type == "coulomb" and not (self.coefficient is not None
                                           and math.isfinite(self.coefficient)
                                           and self.coefficient >= 0):
            raise InputError(f"the friction coefficient must be finite and >= 0, got "
                             f"{self.coefficient}", key="contact.friction.coefficient")
        if self.type == "tresca" and callable(self.threshold) and self.threshold_at is None:
            raise InputError("a Tresca threshold that varies needs threshold_at (its values at "
                             "points)", key="contact.friction.threshold")

    def bound(self, pressure, x):
        """The threshold s (UFL): 𝔣 p, or g_T where p > 0."""
        if self.type == "coulomb":
            return self.coefficient * pressure
        threshold = self.threshold(x) if callable(self.threshold) else self.threshold
        return ufl.conditional(ufl.gt(pressure, 0.0), threshold, 0.0)

    def bound_derivative(self, dpressure):
        """ds along du (UFL): 𝔣 dp for Coulomb, 0 for Tresca."""
        return self.coefficient * dpressure if self.type == "coulomb" else 0.0

    def bound_at(self, pressure: np.ndarray, points: np.ndarray) -> np.ndarray:
        """s at nodes (numpy) with pressures p ≥ 0 at ``points`` (N, 3)."""
        if self.type == "coulomb":
            return self.coefficient * pressure
        if callable(self.threshold):
            values = np.asarray(self.threshold_at(points.T), dtype=np.float64)
        else:
            values = np.full(len(pressure), float(self.threshold))
        return np.where(pressure > 0, np.broadcast_to(values, pressure.shape), 0.0)


def tangential(w, normal):
    """(I − n ⊗ n) w."""
    return w - ufl.dot(w, normal) * normal


def return_mapping(t_trial: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """t_trial (N, d) projected onto the discs |t| ≤ bound (N,)."""
    size = np.linalg.norm(t_trial, axis=1)
    scale = np.where(size > bound, bound / np.where(size > 0, size, 1.0), 1.0)
    return t_trial * scale[:, None]


def friction_terms(friction: Friction, u, u_old, t_old, du, v, normal, pressure, dpressure, ds,
                   stiffness, stick_first=None):
    """(residual, Jacobian) of the friction traction (see the module docstring): ``pressure``
    the compliance pressure p(u) and ``dpressure`` its derivative along du (UFL), ``t_old`` the
    traction of the last accepted step, ``stiffness`` k_t (a number or a field).
    ``stick_first``: a constant; where it is 1 the Jacobian takes the stick branch wherever the
    face is pressed (the first linearisation of a step, :class:`StickingGuess`)."""
    x = ufl.SpatialCoordinate(u.ufl_domain())
    trial = tangential(t_old, normal) - stiffness * tangential(u - u_old, normal)
    dtrial = -stiffness * tangential(du, normal)
    size = ufl.sqrt(ufl.dot(trial, trial) + 1e-300)
    s = friction.bound(pressure, x)
    sticks = ufl.le(size, s)
    traction = ufl.conditional(sticks, trial, s * trial / size)
    direction = trial / size
    slip = (s / size * (dtrial - direction * ufl.dot(direction, dtrial))
            + friction.bound_derivative(dpressure) * direction)
    if stick_first is not None:
        sticks = ufl.Or(sticks, ufl.And(ufl.gt(stick_first, 0.5), ufl.gt(s, 0.0)))
    dtraction = ufl.conditional(sticks, dtrial, slip)
    return -ufl.dot(traction, v) * ds, -ufl.dot(dtraction, v) * ds


#: Newton iterations from the extrapolated guess before a step on a compliant part with friction
#: starts again sticking (:class:`StickingGuess`): the issue "Friction" asks for at most 6 per
#: step.
FIRST_TRY = 5
#: The same for a step that starts with no node pressed (the onset of contact), where the first
#: try usually converges (the dragged block's first step: 6 iterations) and the sticking guess is
#: only a rescue.
ONSET_TRY = 8


class StickingGuess:
    """A step's second guess on a normal-compliance part with friction: sticking (a nodal term of
    the step solver: hooks ``bind``, ``predict``, ``has_fallback``, ``fallback``,
    ``prepare_jacobian``, ``holding``).

    SNES starts from the problem's guess, which extrapolates the last steps' motion; where that
    does not converge within :data:`FIRST_TRY` iterations it
    starts again from this one: the tangential unknowns of the nodes pressed at the last step
    where that step left them (the normal ones keep the extrapolation), and the Jacobian at that
    guess on the stick branch wherever the face is pressed (``stick_first``, a constant of the UFL
    Jacobian, 1 there and 0 at every other iterate). From the extrapolated guess alone, a step
    that reverses the drag started with every node slipping forward; the stick interval, 2b/k_t
    wide, was jumped over and Newton cycled between slipping forward and back (the dragged block
    of tests/test_friction.py pulled back by 1e−5 / 1e−4 / 1e−3 within a step: 34 / 32 / 22
    iterations and a step cut; from the sticking guess 1 / 1 / 1, so 6 in all with the try
    before). Starting every step sticking instead costs monotone steps, where the extrapolation
    has the slip right: 5 Newton iterations per pressing step instead of 1, 3 per dragging step
    instead of 0–1. Shorter first tries were measured (the same block, reversals by 1e−5 / 1e−4
    / 1e−3, and bench/friction_step.py's drag on 64×16 and 256×64 cells): after 0 iterations the
    pressing steps take 4–5 instead of 1 (the extrapolation is close, not exact, on this
    foundation); after 1, the reversals take 2 instead of 6 and the drag's first step 8 / 6
    instead of 12 / 10, but the step after the 1e−3 reversal 6 instead of 4 — not adopted. On
    rigid obstacles (:class:`~vpcontact.model.nodal_friction.NodalFriction`) the first try is 0
    iterations: there the extrapolation of a steady step is exact. (Choosing between the two
    guesses by their residuals fails: at the reversal the extrapolated guess has the smaller
    one.)

    Args:
        part: the :class:`~vpcontact.model.normal_compliance.CompliancePart`.
        stick_first: the constant of its friction Jacobian.
    """

    #: (the step solver's crawl stop never waits for this term: it holds no node back)
    holding = False

    def __init__(self, part, stick_first):
        self.part = part
        self.comm = part.u.function_space.mesh.comm
        self.stick_first = stick_first
        self.u_rows = part.node_rows
        self.normals = part.nodes.normals
        self.rows = self.u_rows
        self.free = np.ones(self.rows.shape, dtype=bool)
        self.scale = 1.0
        self._guess: Optional[np.ndarray] = None
        self._onset = False  # this step starts with no node pressed (see has_fallback)

    def bind(self, scale: float, dirichlet_dofs: np.ndarray, layout) -> None:
        """Place u's rows in SNES's vector (``layout.field_indices()``; SNES's u is u/scale);
        prescribed ones stay as the solver set them."""
        from vpcontact.model.nodal_terms import displacement_positions
        self.scale = scale
        self.free = ~np.isin(self.u_rows, dirichlet_dofs)
        self.rows = displacement_positions(layout)[0][self.u_rows].astype(np.int32)

    def predict(self, x, first_try: int) -> None:
        """The problem's (extrapolated) guess is tried first: nothing to change."""
        self._guess = None

    @property
    def first_try(self) -> int:
        """Newton iterations from the extrapolated guess before the sticking one (as of the
        last :meth:`has_fallback`)."""
        return ONSET_TRY if self._onset else FIRST_TRY

    def _held(self) -> np.ndarray:
        return self.free & self.part.pressed_at(self.part.u_old)[:, None]

    def _touching(self) -> np.ndarray:
        """The nodes whose gap u_old closes (to round-off)."""
        cd = self.part.nodes
        closed = cd.normal_displacement(self.part.u_old) - cd.gap
        return closed >= -1e-12 * (1.0 + np.abs(cd.gap))

    def has_fallback(self) -> bool:
        """A sticking guess exists where nodes were pressed at the last step, or, at the onset of
        contact (none pressed), where they touch the foundation (collective)."""
        pressed = self.comm.allreduce(bool(self._held().any()), op=MPI.LOR)
        self._onset = not pressed and self.comm.allreduce(
            bool((self.free & self._touching()[:, None]).any()), op=MPI.LOR)
        return pressed or self._onset

    def fallback(self, x) -> None:
        """Stick the tangential unknowns of the nodes pressed at the last step (the part's
        u_old, restored with a checkpoint) in the guess x (SNES's vector); the Jacobian there
        takes the stick branch.

        At the onset of contact no node was pressed, and the guess presses none either (its
        bound 𝔣p is 0, so the stick branch would not apply): the nodes the first try's last
        iterate presses (the part's u) take their normal motion from it and stick
        tangentially. (A block clamped at one end and pressed onto a frictional foundation
        cycled between two iterates from the extrapolated guess, at every step size: Newton
        jumped the far end's nodes across the stick interval, 2b/k_t wide, one way and back.)"""
        values = x.getArray()
        old = self.part.u_old.x.array[self.u_rows] / self.scale
        guess, held = values[self.rows], self._held()
        if self._onset:
            guess = self.part.u.x.array[self.u_rows] / self.scale
            held = self.free & self.part.pressed_at(self.part.u)[:, None]
        along = np.einsum("ij,ij->i", guess - old, self.normals)[:, None] * self.normals
        values[self.rows] = np.where(held, old + along, values[self.rows])
        self._guess = values.copy()

    def prepare_jacobian(self, x) -> None:
        """Before the Jacobian's assembly at x: the stick branch at the step's guess (collective)."""
        here = self._guess is not None and np.array_equal(self._guess, x.getArray(readonly=True))
        self.stick_first.value = 1.0 if self.comm.allreduce(here, op=MPI.LAND) else 0.0

    def residual(self, x, b) -> None:
        """(Nothing: the traction is in the UFL residual.)"""

    def jacobian(self, x, A) -> None:
        """(Nothing: :meth:`prepare_jacobian` chose the branch.)"""

    def current(self, x) -> bool:
        return True
