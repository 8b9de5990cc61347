# SPDX-License-Identifier: MIT
"""Frictionless contact conditions on Γ3 as UFL boundary terms.

Normal compliance (paper eq. (15)) models a deformable foundation,

    σ_ν = -(1/μ) (u_ν - g)_+^α   on Γ3,   α ∈ (0, 1],

and enters the equilibrium equation as the boundary term

    R_c(u; v) = ∫_Γ3 (1/μ) p_+^α v_ν da,   p = u_ν - g  (the penetration),

the derivative of j(u) = 1/(α+1) ∫_Γ3 (1/μ) p_+^{α+1} da. The residual is always this exact form;
``max(p, 0)^α`` is 0 (never NaN) where p ≤ 0, the power's argument being ≥ 0.

Newton's Jacobian is J_c(u; du, v) = ∫_Γ3 (1/μ) k(p) du_ν v_ν da with the slope

    k(p) = α max(p, δ)^(α-1)   for p > 0,      k(p) = 0   for p ≤ 0.

* α = 1: k = H(p), the exact derivative of the piecewise linear p_+ (zero at p = 0 itself: the
  inactive branch, as ``ufl.derivative`` of ``max_value`` gives), and δ plays no role.
* α < 1: the true slope α p^(α-1) is unbounded as p → 0+ (at a denormal p it overflows to inf
  for α < 0.05, and it swamps the elastic matrix entries long before that). Evaluating
  it at max(p, δ) caps it at α δ^(α-1) and leaves it exact wherever p ≥ δ. The Jacobian is thus
  finite and symmetric for every iterate, and the exact residual is what Newton drives to zero,
  so the converged state is the true discrete solution; only the iteration changes, and only at
  quadrature points with 0 < p < δ. The argument of the power is ≥ δ > 0 in every branch, so the
  generated code cannot form 0^(α-1) even where the compiler evaluates both sides of the
  conditional.

The floor δ is a length (a penetration). Default: δ = 1e-12 h_T, h_T the diameter of the cell
the facet belongs to; this is about the length unit the step solver works in (2^-40 ≈ 1e-12
times the mesh extent, chosen there as far below any displacement of interest). It is far below any penetration that matters — with E = 1e8 and loads of order 10, the
displacements of the paper's tests are 1e-7 or more — so the Jacobian is exact at the converged
state wherever the foundation carries a non-negligible force, and Newton converges quadratically;
and still far above the round-off of p = u_ν - g (about 1e-16 max(|u_ν|, g)), so the cap is
reached only by penetrations that are numerically zero. A user may set δ (``tangent_floor``) in
absolute units instead.

Two limits of α < 1 that no Jacobian removes:

* The law p ↦ p^α is concave. In a one-point model (body stiffness k, load F), from an iterate
  that penetrates more than the solution by a factor (1 - α)^(-1/α) (≥ e), a full Newton step
  overshoots past p = 0, and the next step
  (contact slope 0) returns to the unsupported prediction: full Newton steps can cycle at contact
  onset when the foundation is several times stiffer than the body. A line search damps the
  overshoot: the part asks for the critical-point one (``cp``) with laws linear in ε
  (:meth:`CompliancePart.snes_defaults`; viscoplastic laws get ``l2`` from the problem). On an
  elastic block (E = 1e3, plane strain, 64×16 cells) pressed by its top onto a foundation with
  μ = 1e-3, the first (onset) step took 10 / 4 Newton iterations with ``cp`` for α = 1/2 / 0.8
  against 46 / 27 and a cut step with ``bt``, and full steps cycled for α = 1/2. For α = 0.3 there
  no line search converged from the onset (steps cut to 1e-5 in vain); a secant slope p^(α-1) at
  the points that land in the step, kept until ||F|| fell 100-fold, did (15 iterations, then
  3-5 per step), not adopted: it slows the other cases.
* Floating point resolves p only to ~1e-16 max(|u_ν|, g): the contact force jumps from 0 to about
  (1/μ)(1e-16 max(|u_ν|, g))^α there. For small α and a stiff foundation this jump can exceed
  the solver's force tolerance, and no state satisfies the equations to that tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np
import ufl
from dolfinx import fem
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.errors import InputError
from vpcontact.model.contact_nodes import Surface, contact_dofs, unrolled
from vpcontact.model.friction import CompliantFriction

#: δ / h_T of the default Jacobian floor (see the module docstring).
RELATIVE_TANGENT_FLOOR = 1e-12
#: With friction, Γ3's terms are integrated with one rule of degree 2 k + this (k the
#: displacement's degree): exact for the traction of a sliding or sticking face (degree 2 k),
#: two more where stick turns to slip or the pressure to zero inside a facet.
FRICTION_QUADRATURE_EXTRA = 2


@dataclass(frozen=True)
class NormalCompliance:
    """Normal compliance on the facets tagged ``tag``.

    Attributes:
        tag: facet tag of Γ3.
        mu: deformability coefficient μ > 0 of the foundation (stiffness 1/μ).
        alpha: exponent α in (0, 1].
        gap: initial gap g ≥ 0: a number, a UFL expression (e.g. of ``ufl.SpatialCoordinate``),
            or a function x -> UFL expression called with the spatial coordinate of the mesh.
        tangent_floor: δ > 0 in the Jacobian slope α max(p, δ)^(α-1) for α < 1 (a length);
            None: 1e-12 times the cell diameter. Ignored for α = 1.
        surface: the foundation's surface (:class:`~vpcontact.model.contact_nodes.Surface`, on
            the same facets: its obstacle, or its gap as a function of points),
            from which the nodes of Γ3 get their normals and gaps for the outputs; None: a
            constant ``gap``.
        friction: Coulomb or Tresca friction on the part (:mod:`vpcontact.model.friction`), or
            None (frictionless).
    """

    tag: int
    mu: float
    alpha: float = 1.0
    gap: object = 0.0
    tangent_floor: Optional[float] = None
    surface: Optional[object] = None
    friction: Optional[object] = None

    def __post_init__(self):
        if not (math.isfinite(self.mu) and self.mu > 0):
            raise InputError(f"normal compliance mu must be finite and > 0, got {self.mu}",
                             key="contact.mu")
        if not 0.0 < self.alpha <= 1.0:
            raise InputError(f"normal compliance exponent alpha must lie in (0, 1], got {self.alpha}",
                             key="contact.alpha")
        if isinstance(self.gap, (int, float)) and not (math.isfinite(self.gap) and self.gap >= 0):
            raise InputError(f"gap g must be finite and >= 0, got {self.gap}", key="contact.gap")
        floor = self.tangent_floor
        if floor is not None and not (math.isfinite(floor) and floor > 0):
            raise InputError(f"normal compliance tangent_floor must be finite and > 0, got {floor}",
                             key="contact")

    def part(self, u, facet_tags, equilibrium=None, name: str = "contact",
             exclude: np.ndarray = np.zeros(0, dtype=np.int32),
             rotate: Optional[bool] = None, shear_modulus: float = 1.0) -> "CompliancePart":
        """This condition on the mesh of ``u``: a :class:`~vpcontact.model.contact.ContactPart`
        (see :class:`CompliancePart`; ``shear_modulus``: the body's, for friction's stick)."""
        return CompliancePart(self, u, facet_tags, name, exclude, shear_modulus)

    def _gap(self, mesh):
        if callable(self.gap) and not isinstance(self.gap, ufl.core.expr.Expr):
            return self.gap(ufl.SpatialCoordinate(mesh))
        return self.gap

    def penetration(self, u, normal):
        """p = u_ν - g, positive where the body penetrates the foundation."""
        return ufl.dot(u, normal) - self._gap(u.ufl_domain())

    def _law(self, pos):
        """(1/μ) pos^α: the one place the compliance law is written (UFL or numpy)."""
        return (1.0 / self.mu) * (pos if self.alpha == 1.0 else pos ** self.alpha)

    def pressure(self, u, normal):
        """Contact pressure -σ_ν = (1/μ) p_+^α ≥ 0 (UFL expression on Γ3)."""
        return self._law(ufl.max_value(self.penetration(u, normal), 0.0))

    def normal_stress(self, penetration: np.ndarray) -> np.ndarray:
        """σ_ν = −(1/μ) p_+^α at nodes with penetration p = u_ν − g (numpy, for outputs)."""
        return -self._law(np.maximum(np.asarray(penetration, dtype=np.float64), 0.0))

    def residual(self, u, v, normal, ds):
        """∫_Γ3 (1/μ)(u_ν - g)_+^α v_ν da (exact for every α)."""
        return self.pressure(u, normal) * ufl.dot(v, normal) * ds(self.tag)

    def slope(self, u, normal):
        """k(p): H(p) for α = 1 (exact), H(p) α max(p, δ)^(α-1) for α < 1 (exact for p ≥ δ)."""
        p = self.penetration(u, normal)
        if self.alpha == 1.0:
            return ufl.conditional(ufl.gt(p, 0.0), 1.0, 0.0)
        if self.tangent_floor is None:
            delta = RELATIVE_TANGENT_FLOOR * ufl.CellDiameter(u.ufl_domain())
        else:
            delta = self.tangent_floor
        return ufl.conditional(ufl.gt(p, 0.0), self.alpha * ufl.max_value(p, delta) ** (self.alpha - 1.0),
                               0.0)

    def jacobian(self, u, du, v, normal, ds):
        """∫_Γ3 (1/μ) k(p) du_ν v_ν da: the derivative of :meth:`residual` where p ∉ (0, δ)."""
        return ((1.0 / self.mu) * self.slope(u, normal) * ufl.dot(du, normal) * ufl.dot(v, normal)
                * ds(self.tag))


class CompliancePart:
    """A normal-compliance part at run time (a :class:`~vpcontact.model.contact.ContactPart`):
    the UFL terms, and the nodes of Γ3 with their normals and gaps for the outputs (located on
    first use, through the foundation's surface: :attr:`NormalCompliance.surface`). With
    friction it composes a :class:`~vpcontact.model.friction.CompliantFriction`
    (:attr:`friction`), which brings its terms, guess, outputs and checkpoint arrays."""

    bounded = False
    driven = False
    moving = False

    def __init__(self, law: NormalCompliance, u, facet_tags, name: str, exclude: np.ndarray,
                 shear_modulus: float = 1.0):
        V = u.function_space
        self.law, self.name, self.u = law, name, u
        self._facet_tags, self._exclude = facet_tags, exclude
        blocks = fem.locate_dofs_topological(V, V.mesh.topology.dim - 1, facet_tags.find(law.tag))
        blocks = blocks[blocks < V.dofmap.index_map.size_local]
        bs = V.dofmap.index_map_bs
        self.facet_blocks = blocks  # this rank's owned nodes of Γ3 (none excluded)
        self.force_dofs = unrolled(bs, blocks, exclude)
        self.node_blocks = np.unique(self.force_dofs // bs).astype(np.int32)
        self._nodes = None
        self._residual = None  # its UFL residual term (see terms)
        self._held: Optional[tuple] = None  # (form, dofs, vector): see bind_prescribed
        self._held_values = np.zeros(0)  # its force there at the last commit (with friction)
        #: the part's friction (None: frictionless)
        self.friction: Optional[CompliantFriction] = (
            None if law.friction is None
            else CompliantFriction(self, law.friction, facet_tags, shear_modulus))

    @property
    def nodes(self):
        if self._nodes is None:
            surface = self.law.surface
            if surface is None:
                gap = self.law.gap if isinstance(self.law.gap, (int, float)) else 0.0
                surface = Surface(self.law.tag, gap=gap)
            self._nodes = contact_dofs(self.u.function_space, self._facet_tags, surface,
                                       exclude=self._exclude)
        return self._nodes

    def snes_defaults(self, linear_law: bool) -> dict:
        """SNES options this part needs: for α < 1 with a law linear in ε, the critical-point
        line search (p ↦ p^α is concave: full steps can overshoot past contact onset and cycle;
        ``cp`` took fewer iterations than ``bt`` in every case measured, see the module
        docstring, and the stiff column of tests/model/test_normal_compliance_nd.py 4, 2, 2, …
        iterations from its onset step against 6, 4, 3, …). With friction, what its law asks
        for on a compliant part (:attr:`~vpcontact.model.friction.FrictionLaw.
        compliant_snes_defaults`; with α < 1 and a law linear in ε the part keeps ``cp``, for
        the onset's overshoot above)."""
        if linear_law and self.law.alpha < 1.0:
            return {"snes_linesearch_type": "cp"}
        return {} if self.friction is None else self.friction.snes_defaults()

    @property
    def splits_force(self) -> bool:
        """With friction the outputs split its force into normal and tangential parts."""
        return self.friction is not None

    @property
    def resists_sliding(self) -> bool:
        """With friction it resists the body's motion along its face where it presses."""
        return self.friction is not None

    @property
    def reports_law_force(self) -> bool:
        """A frictionless part's force is its law's term R_c at its nodes. (With friction the
        term, assembled after the step, would see the committed slip history instead of the
        step's: such a part's force is the residual left at its nodes, as a rigid part's is —
        a sweep's block was 1 % out of balance.)"""
        return self.friction is None

    def terms(self, u, du, v, normal, ds):
        law = self.law
        if self.friction is not None:
            # One rule for the residual and the Jacobian: left to FFCx, each form gets the degree
            # estimated for its integrand — 10 and 26 for P1, whose friction terms have
            # quotients and roots — and the Jacobian is then not the derivative of the discrete
            # residual: Newton converged linearly (11, 10, 14, 14, 11 iterations per pressing
            # step of the dragged block in tests/model/test_friction.py; 7, 1, 1, 1, 1 with one rule).
            degree = FRICTION_QUADRATURE_EXTRA + 2 * u.ufl_element().degree()
            ds = ufl.Measure("ds", domain=ds.ufl_domain(), subdomain_data=ds.subdomain_data(),
                             metadata={"quadrature_degree": degree})
        residual, jacobian = law.residual(u, v, normal, ds), law.jacobian(u, du, v, normal, ds)
        if self.friction is not None:
            pressure = law.pressure(u, normal)
            dpressure = (1.0 / law.mu) * law.slope(u, normal) * ufl.dot(du, normal)
            r, j = self.friction.terms(u, du, v, normal, pressure, dpressure, ds(law.tag))
            residual, jacobian = residual + r, jacobian + j
        self._residual = residual
        return residual, jacobian

    def bind_prescribed(self, prescribed: np.ndarray) -> None:
        """The Dirichlet dofs ``prescribed`` (local u indices). At the prescribed dofs of its
        nodes (a node of a pushed face that rests on the foundation: its tangential motion
        prescribed) the part's term still acts — the foundation's push, its friction — but the
        solver's row there is the support's (u = u_D), so the equilibrium residual there is the
        support's reaction and the term together. The part reports its term's share
        (:meth:`prescribed_forces`); a node every component of which is prescribed is no
        contact node (its whole residual stays the support's). Collective."""
        rows = self.node_rows.ravel()
        dofs = rows[np.isin(rows, prescribed)].astype(np.int32)
        if self._residual is None or not self.u.function_space.mesh.comm.allreduce(
                bool(len(dofs)), op=MPI.LOR):
            return
        form = fem.form(self._residual)
        self._held = (form, dofs, fem.petsc.create_vector(form))
        self._held_values = self._term_at_held()

    def _term_at_held(self) -> np.ndarray:
        """−R_c at the prescribed dofs of its nodes, the force on the body (collective)."""
        form, dofs, vec = self._held
        with vec.localForm() as local:
            local.set(0.0)
        fem.petsc.assemble_vector(vec, form)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return 0.0 - vec.array[dofs]

    def prescribed_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """(local u dofs, values): the part's force on the body at the prescribed dofs of its
        nodes (:meth:`bind_prescribed`): its term now; with friction its term as the last
        accepted step left it (assembled before the step's slip history is committed: assembled
        after, it sees the committed history instead; after a restart it is the restored
        state's until the next step). Collective."""
        if self._held is None:
            return np.zeros(0, np.int32), np.zeros(0)
        values = self._term_at_held() if self.friction is None else self._held_values
        return self._held[1], values

    def friction_state(self) -> Optional[dict]:
        """At this rank's nodes, with friction: the tangential traction t (N, d), the slip
        increment of the step Δu_τ (N, d) and whether the node slips (|t| at its bound)."""
        return None if self.friction is None else self.friction.state()

    @property
    def last_friction(self) -> Optional[dict]:
        """The accepted step's :meth:`friction_state` (None without friction or before)."""
        return None if self.friction is None else self.friction.last

    def nodal_stick_stiffness(self) -> np.ndarray:
        """k_t at this rank's contact nodes (``nodes.nodes``; with friction)."""
        return self.friction.nodal_stick_stiffness()

    def nodal_outputs(self) -> tuple:
        return () if self.friction is None else self.friction.outputs

    def nodal_values(self, key: str) -> np.ndarray:
        return self.friction.nodal_values(key)

    def update(self, time: float) -> None:
        pass

    def solver_terms(self) -> list:
        """With friction, the step's sticking guess (:class:`~vpcontact.model.friction.StickingGuess`)."""
        return [] if self.friction is None else self.friction.solver_terms()

    @property
    def node_rows(self) -> np.ndarray:
        """(n, d) local indices of u's dofs at this rank's contact nodes (``nodes.nodes``)."""
        bs = self.u.function_space.dofmap.index_map_bs
        return (self.nodes.nodes[:, None] * bs + np.arange(bs)).astype(np.int32)

    @property
    def u_old(self):
        """u at the last accepted step (with friction)."""
        return None if self.friction is None else self.friction.u_old

    def pressed_at(self, u) -> np.ndarray:
        """Which of this rank's contact nodes the displacement ``u`` presses into the foundation."""
        cd = self.nodes
        return cd.normal_displacement(u) - cd.gap > 0

    def commit(self, time: float, x=None) -> None:
        if self.friction is not None:
            if self._held is not None:  # (before the history moves on: see prescribed_forces)
                self._held_values = self._term_at_held()
            self.friction.commit()

    def state(self) -> dict:
        return {}

    def arrays(self) -> dict:
        return {} if self.friction is None else self.friction.arrays()

    def restore(self, state: dict, time: float, arrays: Optional[dict] = None) -> None:
        if self.friction is not None:
            self.friction.restore(arrays or {})
            if self._held is not None:
                self._held_values = self._term_at_held()

    def pressure(self) -> np.ndarray:
        cd = self.nodes
        return self.law.normal_stress(cd.normal_displacement(self.u) - cd.gap)

    def report(self):
        return None

    def touching(self, tolerance: float) -> bool:
        cd = self.nodes
        return bool(np.any(cd.normal_displacement(self.u) > cd.gap))

    def driving_displacement(self, time: float) -> Optional[float]:
        return None
