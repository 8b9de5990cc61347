# SPDX-License-Identifier: MIT
"""Coulomb and Tresca friction: the laws (:class:`Coulomb`, :class:`Tresca`, behind the
:class:`FrictionLaw` protocol; :func:`Friction` turns a scene's name into one), what a part with
friction reports at its nodes (:data:`OUTPUTS`), and friction on a normal-compliance part
(:class:`CompliantFriction`): Coulomb's law with the compliance pressure (the model of
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
from typing import Callable, ClassVar, Optional, Protocol

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from vpcontact.errors import InputError
from vpcontact.model.contact import NodalOutput
from vpcontact.model.nodal_areas import at_blocks, facet_sizes
from vpcontact.model.nodal_terms import displacement_positions

#: k_t relative to G / h (h the local facet size). Stiffer sticks are closer to an exact one but
#: Newton crosses their narrower stick interval (2b/k_t) less reliably: with 1e3 G/h the block
#: of tests/model/test_friction.py pressed with P2 displacements cycles between stick and slip for 50
#: iterations in its first step; with 1e2 it takes 4 (the last mesh-extent stiffness, 1e3 G/L,
#: was 62 G/h on that mesh and far softer on refined ones).
STICK_STIFFNESS = 1e2

FRICTION_TYPES = ("coulomb", "tresca")


class FrictionLaw(Protocol):
    """What a part with friction asks of its law: the threshold s of the tangential traction,
    |t| ≤ s, and what the solver needs for it.

    Attributes:
        threshold_slope: ∂b/∂λ where the threshold follows the normal force (Coulomb's 𝔣: the
            nodal Jacobian couples the tangential rows to the normal one, and a Signorini step
            that the sticking guess does not solve gets the predictor with frozen thresholds,
            :meth:`~vpcontact.model.nodal_friction.NodalFriction.freeze`), or None (a given
            threshold).
        rigid_snes_defaults: SNES options a Signorini part with this law adds to the VI's.
        compliant_snes_defaults: SNES options a normal-compliance part with this law needs.
    """

    threshold_slope: Optional[float]
    rigid_snes_defaults: dict
    compliant_snes_defaults: dict

    def bound(self, pressure, x):
        """The threshold s (UFL) at pressure p ≥ 0 and the spatial coordinate x."""

    def bound_derivative(self, dpressure):
        """ds along du (UFL), dp the pressure's derivative along du."""

    def bound_at(self, pressure: np.ndarray, points: np.ndarray) -> np.ndarray:
        """s at nodes (numpy) with pressures p ≥ 0 at ``points`` (N, 3)."""

    def nodal_bound(self, lam: np.ndarray, points: np.ndarray, areas: np.ndarray) -> np.ndarray:
        """A node's threshold b_i on its force (numpy) from its normal force λ_i ≥ 0, at
        ``points`` (N, 3) with shares ``areas`` of Γ3."""


#: With friction, a normal-compliance part takes the secant (``l2``) line search: where a held
#: load stops pressing (a block clamped at one end, pressed by a rigid plane onto the frictional
#: floor until t = 0.5, then held) full steps cycled between two iterates from both guesses and
#: the step was cut 10 times (291 Newton iterations in the run); ``l2`` takes 20 there (49 in
#: the run), ``cp`` 17 (46). On the dragged block of tests/model/test_friction.py ``l2`` takes what
#: full steps take (6, 1, 1, 1, 1 pressing, 2, 1, 0, 0, 0 sliding), ``cp`` 7 in the first step;
#: backtracking 40 and cut steps.
COMPLIANT_SNES_DEFAULTS = {"snes_linesearch_type": "l2"}


@dataclass(frozen=True)
class Coulomb:
    """Coulomb friction, s = 𝔣 p (𝔣 = ``coefficient`` ≥ 0, p the contact pressure; on a
    Signorini node b_i = 𝔣 λ_i, λ_i its normal force)."""

    coefficient: float

    #: On a Signorini part, the critical-point line search (measured on a block pressed onto a
    #: rigid floor, then dragged, 𝔣 = 0.3: 4, 0, 0, 0, 0, 5, 2, 2, 0, 0 Newton iterations for
    #: k = 0.1, no step cut; with full steps or l2 the first dragging step is cut 1–4 times,
    #: with backtracking it takes 16–46), with ``l2`` as the rescue line search.
    rigid_snes_defaults: ClassVar[dict] = {"snes_linesearch_type": "cp",
                                           "vpcontact_rescue_linesearch": "l2"}
    compliant_snes_defaults: ClassVar[dict] = COMPLIANT_SNES_DEFAULTS

    def __post_init__(self):
        if not (self.coefficient is not None and math.isfinite(self.coefficient)
                and self.coefficient >= 0):
            raise InputError(f"the friction coefficient must be finite and >= 0, got "
                             f"{self.coefficient}", key="contact.friction.coefficient")

    @property
    def threshold_slope(self) -> float:
        return self.coefficient

    def bound(self, pressure, x):
        return self.coefficient * pressure

    def bound_derivative(self, dpressure):
        return self.coefficient * dpressure

    def bound_at(self, pressure: np.ndarray, points: np.ndarray) -> np.ndarray:
        return self.coefficient * pressure

    def nodal_bound(self, lam: np.ndarray, points: np.ndarray, areas: np.ndarray) -> np.ndarray:
        return self.coefficient * lam


@dataclass(frozen=True)
class Tresca:
    """Tresca friction, s = g_T where the part is pressed (p > 0), 0 elsewhere: ``threshold``
    g_T ≥ 0 a number, or a function of the spatial coordinate returning a UFL expression, with
    ``threshold_at`` the same as a function of points (3, N) -> (N,). On a Signorini node
    b_i = g_T(x_i) A_i (A_i its lumped share of Γ3, :mod:`vpcontact.model.nodal_friction`)."""

    threshold: object
    threshold_at: Optional[Callable[[np.ndarray], np.ndarray]] = None

    #: Tresca's threshold switches on with λ > 0, which ``cp`` crosses slowly (16 iterations
    #: where full steps take 3): a Signorini part keeps PETSc's default line search.
    rigid_snes_defaults: ClassVar[dict] = {}
    compliant_snes_defaults: ClassVar[dict] = COMPLIANT_SNES_DEFAULTS
    threshold_slope: ClassVar[Optional[float]] = None

    def __post_init__(self):
        if callable(self.threshold) and self.threshold_at is None:
            raise InputError("a Tresca threshold that varies needs threshold_at (its values at "
                             "points)", key="contact.friction.threshold")

    def bound(self, pressure, x):
        threshold = self.threshold(x) if callable(self.threshold) else self.threshold
        return ufl.conditional(ufl.gt(pressure, 0.0), threshold, 0.0)

    def bound_derivative(self, dpressure):
        return 0.0

    def bound_at(self, pressure: np.ndarray, points: np.ndarray) -> np.ndarray:
        if callable(self.threshold):
            values = np.asarray(self.threshold_at(points.T), dtype=np.float64)
        else:
            values = np.full(len(pressure), float(self.threshold))
        return np.where(pressure > 0, np.broadcast_to(values, pressure.shape), 0.0)

    def nodal_bound(self, lam: np.ndarray, points: np.ndarray, areas: np.ndarray) -> np.ndarray:
        return self.bound_at(lam, points) * areas


def Friction(type: str, coefficient: Optional[float] = None, threshold: object = None,
             threshold_at: Optional[Callable] = None) -> FrictionLaw:
    """The friction law of a contact table: ``"coulomb"`` (:class:`Coulomb`, ``coefficient``)
    or ``"tresca"`` (:class:`Tresca`, ``threshold`` and ``threshold_at``); the one place that
    turns the scene's name into a law."""
    if type == "coulomb":
        return Coulomb(coefficient)
    if type == "tresca":
        return Tresca(threshold, threshold_at)
    raise InputError(f"friction type must be one of {FRICTION_TYPES}, got {type!r}",
                     key="contact.friction.type")


def tangential(w, normal):
    """(I − n ⊗ n) w."""
    return w - ufl.dot(w, normal) * normal


def return_mapping(t_trial: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """t_trial (N, d) projected onto the discs |t| ≤ bound (N,)."""
    size = np.linalg.norm(t_trial, axis=1)
    scale = np.where(size > bound, bound / np.where(size > 0, size, 1.0), 1.0)
    return t_trial * scale[:, None]


#: What a part with friction reports at its nodes (contact.csv's columns
#: ``tangential_traction,slip_increment,slip,slipping``; the XDMF fields
#: ``tangential_traction`` and ``slipping``): |t| (the nodal force over the node's area on a
#: Signorini part), the slip |Δu_τ| of the last accepted step and its sum over the run, whether
#: the node slipped in it.
OUTPUTS = (NodalOutput("traction", "tangential_traction", field="tangential_traction"),
           NodalOutput("slip", "slip_increment", running="slip"),
           NodalOutput("slipping", "slipping", integer=True, field="slipping"))
_STATE_KEYS = {"traction": "traction", "slip": "slip", "slipping": "slips"}


def nodal_values(state: Optional[dict], key: str, count: int) -> np.ndarray:
    """The :data:`OUTPUTS` ``key`` at a part's ``count`` nodes from its accepted step's
    ``state`` (traction (N, d), slip (N, d), slips (N,)): norms of the vectors, 0/1 of the
    flags; zeros before the first step (``state`` None)."""
    if state is None:
        return np.zeros(count)
    value = state[_STATE_KEYS[key]]
    return np.linalg.norm(value, axis=1) if value.ndim == 2 else value.astype(float)


def friction_terms(friction: FrictionLaw, u, u_old, t_old, du, v, normal, pressure, dpressure, ds,
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
    of tests/model/test_friction.py pulled back by 1e−5 / 1e−4 / 1e−3 within a step: 34 / 32 / 22
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


class CompliantFriction:
    """The friction of one normal-compliance part, a term the part composes (see the module
    docstring): the traction of the last accepted step t_{n−1} and u_{n−1} (fields of the
    displacement's space), the stick stiffness k_t (a field on Γ3's nodes), the UFL terms, the
    sticking guess, the outputs and the checkpoint arrays.

    Args:
        part: the :class:`~vpcontact.model.normal_compliance.CompliancePart`.
        law: its :class:`FrictionLaw`.
        facet_tags: the mesh's facet tags (Γ3 is ``part.law.tag``).
        shear_modulus: the body's G.
    """

    def __init__(self, part, law: FrictionLaw, facet_tags, shear_modulus: float):
        V = part.u.function_space
        self.part, self.law = part, law
        self.u_old = fem.Function(V, name="u_old")
        self.t_old = fem.Function(V, name="friction_traction")
        # k_t = STICK_STIFFNESS G / h, h the local facet size (a field on Γ3's nodes)
        h, self._scalar_of = facet_sizes(V, facet_tags, part.law.tag)
        self.stick_stiffness = fem.Function(h.function_space, name="stick_stiffness")
        self.stick_stiffness.x.array[:] = STICK_STIFFNESS * shear_modulus / h.x.array
        self.stick_first = fem.Constant(V.mesh, 0.0)  # see StickingGuess
        self._guess: Optional[StickingGuess] = None
        self.last: Optional[dict] = None  # the accepted step's state()

    def snes_defaults(self) -> dict:
        """The line search the law needs on a compliant part."""
        return dict(self.law.compliant_snes_defaults)

    def terms(self, u, du, v, normal, pressure, dpressure, ds) -> tuple:
        """(residual, Jacobian) of the friction traction on ``ds`` (Γ3), ``pressure`` the
        compliance pressure and ``dpressure`` its derivative along du (UFL)."""
        return friction_terms(self.law, u, self.u_old, self.t_old, du, v, normal, pressure,
                              dpressure, ds, self.stick_stiffness, stick_first=self.stick_first)

    def state(self) -> dict:
        """At the part's nodes on this rank: the tangential traction t (N, d), the slip
        increment of the step Δu_τ (N, d), whether the node slips (|t| at its bound), and the
        rows of u's dofs there."""
        part = self.part
        cd, rows = part.nodes, part.node_rows
        normals = cd.normals

        def tangential_part(values):
            w = values[rows]
            return w - np.einsum("ij,ij->i", w, normals)[:, None] * normals

        slip = tangential_part(part.u.x.array - self.u_old.x.array)
        trial = (tangential_part(self.t_old.x.array)
                 - self.nodal_stick_stiffness()[:, None] * slip)
        pressure = -part.law.normal_stress(cd.normal_displacement(part.u) - cd.gap)
        bound = self.law.bound_at(pressure, cd.points)
        traction = return_mapping(trial, bound)
        slips = (np.linalg.norm(trial, axis=1) > bound * (1 + 1e-12)) & (bound > 0)
        return {"traction": traction, "slip": slip, "slips": slips, "rows": rows}

    def nodal_stick_stiffness(self) -> np.ndarray:
        """k_t at this rank's contact nodes (the part's ``nodes.nodes``)."""
        part = self.part
        return at_blocks(part.u.function_space, self._scalar_of, self.stick_stiffness.x.array,
                         part.nodes.nodes)

    def solver_terms(self) -> list:
        """The step's sticking guess (:class:`StickingGuess`)."""
        if self._guess is None:
            self._guess = StickingGuess(self.part, self.stick_first)
        return [self._guess]

    def commit(self) -> None:
        """The step is accepted: the return mapping at the nodes, with the step's slip, gives
        the traction history."""
        state = self.state()
        self.last = state
        self.t_old.x.array[:] = 0.0
        self.t_old.x.array[state["rows"]] = state["traction"]
        self.t_old.x.scatter_forward()
        self.u_old.x.array[:] = self.part.u.x.array

    def arrays(self) -> dict:
        """The history a checkpoint must hold (u_{n−1} is the checkpoint's u)."""
        return {"friction_traction": self.t_old.x.array}

    def restore(self, arrays: dict) -> None:
        """Continue from :meth:`arrays` (u is the restored one: the slip starts from it)."""
        self.u_old.x.array[:] = self.part.u.x.array
        self.t_old.x.array[:] = arrays.get("friction_traction", 0.0)

    outputs = OUTPUTS

    def nodal_values(self, key: str) -> np.ndarray:
        """See :func:`nodal_values`."""
        return nodal_values(self.last, key, len(self.part.nodes.gap))

