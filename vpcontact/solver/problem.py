# SPDX-License-Identifier: MIT
"""The fully discrete quasistatic contact problem (the paper's Problems 2 and 4).

At each time t_n find u_n ∈ V^h (u = 0 on Γ1) such that for all v ∈ V^h

    (σ_n, ε(v))_Q + ⟨contact(u_n), v⟩_Γ3 = (f_0(t_n), v)_H + (f_2(t_n), v)_Γ2,
    σ_n = σ_{n-1} + E(ε(u_n) - ε(u_{n-1})) + k G(σ_*, ε_*),

where (σ_*, ε_*) is the previous step for the explicit scheme (Problem 4) and the new one for the
implicit scheme (Problem 2). σ_n is computed at quadrature points by the C++ kernels from the
current Newton iterate; the Jacobian uses their consistent tangent dσ_n/dε_n.

The problem composes its parts: it is built from :mod:`~vpcontact.solver.builders`, holds its
time scheme (:mod:`~vpcontact.solver.time_scheme`), its support forces
(:mod:`~vpcontact.solver.support_forces`) and its contact parts, and writes its checkpoints
through :mod:`~vpcontact.solver.problem_state`.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable, Optional, Sequence

import numpy as np
import ufl
from dolfinx import fem
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI

from vpcontact.model.extent import mesh_extent
from vpcontact.errors import ConvergenceError, InputError, NonFiniteStateError, StepRejected
from vpcontact.solver.held import DRIFTING, NO_EQUILIBRIUM, HeldByContacts, check_held
from vpcontact.solver.line_search import line_search_for
from vpcontact.solver.step_solver import StepSolver
from vpcontact.solver.variables import ChangeOfVariables
from vpcontact.model.fields import Displacement, DisplacementPressure
from vpcontact.model.locking import check_formulation, locks
from vpcontact.model.quadrature import QuadratureState
from vpcontact.model.frames import rotation_matrix
from vpcontact.model.contact import (bounded_touching, merged_bounds, merged_frames,
                                     merged_report, moved_parts)
from vpcontact.model.contact_nodes import unrolled
from vpcontact.solver.bdf2 import check_time_scheme
from vpcontact.solver.builders import (check_choices, contact_parts, dirichlet_parts, load_terms,
                                       named_contacts, shear_modulus,
                                       stress_quadrature_degree)
from vpcontact.solver.dirichlet import Dirichlet
from vpcontact.solver.loads import Loads, PointDofs
from vpcontact.solver import problem_state
from vpcontact.solver.support_forces import SupportForces
from vpcontact.solver.time_scheme import StepHistory
from vpcontact.solver.time_scheme import time_scheme as make_time_scheme
from vpcontact.model.tensors import as_mandel_matrix, as_mandel_vector, mandel_strain

#: Obstacles driven by a force: the linearized gaps' largest error accepted, relative to the
#: mesh's extent, and the re-solves allowed per step to reach it.
REFIT_TOLERANCE = 1e-10
MAX_REFITS = 4


@dataclass
class StepReport:
    """What one accepted time step did."""

    step: int
    time: float
    newton_iterations: int
    reason: str = ""  # SNES converged reason, e.g. CONVERGED_FNORM_RELATIVE
    error_ratio: Optional[float] = None  # local error estimate / tolerance (when one was asked)
    order: int = 1                       # order of the estimate's scheme (1 Euler, 2 BDF2)


class QuasistaticProblem:
    """Time-stepping solver for a viscoplastic body held on Γ1, loaded, in contact on Γ3.

    Args:
        mesh: dolfinx mesh.
        facet_tags: meshtags on facets marking Γ1, Γ2 parts and Γ3.
        law: constitutive law (see :mod:`vpcontact.model.constitutive`).
        clamped_tag: facet tag of a clamped Γ1 (u = 0); it must mark at least one facet. None:
            ``dirichlet`` alone holds the body.
        dirichlet: further Dirichlet parts (prescribed displacements, symmetry planes; see
            :mod:`vpcontact.solver.dirichlet`). Without a clamped part they must remove every
            rigid motion.
        loads: body force and tractions.
        contact: the contact condition(s): None, one law (a part named "contact"), a sequence
            of laws (parts "contact1", "contact2", ...) or a dict part name -> law, in order (see
            :mod:`vpcontact.model.contact`: a node shared by parts belongs to the first).
        degree: polynomial degree of the displacement (1 = the paper's P1/P0 pairing; None: 1,
            or 2 for the mixed formulation).
        formulation: "displacement" (u alone) or "mixed" (Taylor–Hood P2–P1 displacement and
            pressure, free of volumetric locking; see :mod:`vpcontact.model.fields`). None:
            mixed where P_k displacements lock (:func:`~vpcontact.model.locking.locks`: 3-D or
            plane strain with Perzyna's isochoric flow, or ν ≥ 0.45) unless ``degree`` is 1,
            else displacement.
        linear: the linear solver, "direct" (MUMPS), "iterative" (multigrid; a block
            preconditioner for the mixed formulation) or "auto" (by size; see
            :mod:`vpcontact.solver.linear`).
        petsc_options: options for the SNES of each step. One that PETSc (or vpcontact) never
            reads is refused (:class:`~vpcontact.errors.SolverOptionError`) or, where that is
            only known after solving, reported by :meth:`StepSolver.unread_options
            <vpcontact.solver.step_solver.StepSolver.unread_options>`
            (:mod:`vpcontact.solver.option_reads`).
        options_prefix: PETSc options prefix of that SNES.
        predictor: initial guess of each step's Newton iteration. "linear" extrapolates the last
            step's displacement increment (u_n + k_n/k_{n-1} (u_n - u_{n-1})); "none" starts
            from u_n. Once a body flows (load beyond the plastic limit, k E/μ* >> 1), Newton
            started from u_n classifies points as elastic or plastic wrongly and diverges
            unless k is tiny; the extrapolated guess is O(k²) close and converges.
        unstable_steps: "error" refuses an explicit step beyond the law's stability limit,
            "warn" warns once and takes it.
        time_scheme: "euler" (the paper's: implicit or explicit Euler, as the law says) or
            "bdf2" (second-order backward differentiation of the law, for implicit laws; the
            first step is implicit Euler; see :class:`~vpcontact.solver.bdf2.Bdf2`).
        rotate_contact: Signorini parts only. None: local frames at the contact nodes where Γ3
            is not an axis-aligned plane, plain dofs where it is; True: local frames always
            (identity frames on an axis-aligned Γ3, to test one path against the other).
    """

    def __init__(self, mesh, facet_tags, law, clamped_tag: Optional[int] = None,
                 loads: Loads = Loads(), contact=None, degree: Optional[int] = None,
                 petsc_options: Optional[dict] = None, options_prefix: Optional[str] = None,
                 predictor: str = "linear", unstable_steps: str = "error",
                 time_scheme: str = "euler", dirichlet: Sequence[Dirichlet] = (),
                 rotate_contact: Optional[bool] = None, formulation: Optional[str] = None,
                 linear: str = "auto"):
        check_choices(predictor, unstable_steps)
        self.unstable_steps = unstable_steps
        self.time_scheme = check_time_scheme(time_scheme, law)
        self.scheme = make_time_scheme(time_scheme, law)
        self.history = StepHistory()
        self.predictor = predictor
        self.mesh = mesh
        self.law = law
        self._contact_laws = named_contacts(contact)
        self.contact = next(iter(self._contact_laws.values()), None)  # the first part's law
        degree = self._build_spaces(mesh, law, degree, formulation)
        self.dirichlet, free = dirichlet_parts(self.V, facet_tags, clamped_tag, dirichlet,
                                               bool(self._contact_laws))
        self.bcs = self.dirichlet.bcs
        residual, jacobian, v, du = self._build_forms(mesh, law, degree)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
        residual, external = self._build_equilibrium(mesh, loads, ds, v, residual)
        self.contacts = contact_parts(self._contact_laws, self.u, facet_tags, residual,
                                      self.dirichlet.prescribed, rotate_contact,
                                      shear_modulus(law))
        # an update affine in ε_n whose tangent depends on the state (the linearized scheme):
        # the tangent and Jacobian are fixed within a step and change between steps
        self._tangent_per_step = law.linear_in_strain and not law.constant_tangent
        defaults = line_search_for(law, self.contacts)  # (and the parts' other SNES needs)
        terms = self._contact_terms(mesh, du, v, ds)
        self._build_held(free, law, v, du, facet_tags, external, terms)
        for r, j in terms:
            residual += r
            jacobian += j
        scale, options = self._scaled_options(mesh, {**defaults, **(petsc_options or {})})
        self._build_point_loads(loads)
        nodal_terms = [t for p in self.contacts for t in p.solver_terms()]
        constant_jacobian, jacobian_per_step = self._jacobian_reuse(law, terms, nodal_terms)
        self.fields.compile(residual, jacobian)
        self._build_solver(mesh, scale, options, options_prefix, external, constant_jacobian,
                           jacobian_per_step, nodal_terms, linear, petsc_options)
        self._init_run_state()

    def _build_spaces(self, mesh, law, degree: Optional[int], formulation: Optional[str]) -> int:
        """The formulation (u alone or u and p), the displacement's space and u, the time; the
        displacement's degree."""
        if formulation is None:  # P1 asked for explicitly: the paper's displacement scheme
            formulation = "mixed" if locks(law) and degree != 1 else "displacement"
        self.formulation = check_formulation(formulation)
        mixed = self.formulation == "mixed"
        if degree is None:
            degree = 2 if mixed else 1
        el = getattr(law, "elasticity", None)
        if not mixed and el is not None and el.incompressible:
            raise InputError("Poisson's ratio nu = 0.5 (incompressible) needs the mixed "
                             "formulation (formulation = \"mixed\")", key="material.nu")
        self.V = fem.VectorFunctionSpace(mesh, ("Lagrange", degree), dim=mesh.topology.dim)
        self.u = fem.Function(self.V, name="displacement")
        self.time = fem.Constant(mesh, 0.0)
        self.dt = 0.0
        self._tangent_key = None  # the step whose tangent the state holds (affine laws only)
        return degree

    def _build_forms(self, mesh, law, degree: int) -> tuple:
        """The quadrature state and the fields; (σ, ε(v)) and its Jacobian, v and du."""
        dim = mesh.topology.dim
        # Stress quadrature: exact for ε(v) of degree-p displacements paired with the stress.
        self.state = QuadratureState(self.u, degree=stress_quadrature_degree(mesh, degree))
        self.fields = (DisplacementPressure(self.u, law, self.state)
                       if self.formulation == "mixed" else Displacement(self.u))
        self.p: Optional[fem.Function] = getattr(self.fields, "p", None)  # mixed: the pressure
        v, du = ufl.TestFunction(self.V), ufl.TrialFunction(self.V)
        n_q = self.state.size
        dxq = self.state.measure
        sigma = self.fields.stress(as_mandel_vector(self.state.stress, n_q))
        tangent = as_mandel_matrix(self.state.tangent, n_q)
        residual = ufl.dot(sigma, mandel_strain(v, dim)) * dxq
        jacobian = ufl.dot(self.fields.tangent(tangent, du), mandel_strain(v, dim)) * dxq
        return residual, jacobian, v, du

    def _build_equilibrium(self, mesh, loads: Loads, ds, v, residual) -> tuple:
        """(σ, ε(v)) − (f, v) (whose residual gives reactions and contact forces) from
        (σ, ε(v)) and the loads; and the loads' (f, v), which set the residual's force scale."""
        #: each load's (f, v) as a UFL form, by "body_force" or traction facet tag (for checks
        #: of the values at its quadrature points: vpcontact.scene.finite)
        self.load_terms = load_terms(mesh, loads, ds, v, self.time)
        external = list(self.load_terms.values())
        for term in external:
            residual -= term
        self.equilibrium = residual  # (σ, ε(v)) - (f, v): reactions and contact forces
        self._equilibrium_form = fem.form(residual)
        return residual, external

    def _build_point_loads(self, loads: Loads) -> None:
        """The point loads at their dofs; a point load at a contact node is an applied force,
        not the obstacle's (the Signorini parts' monitors leave it out)."""
        self._point_loads = [PointDofs(self.V, p) for p in loads.points]
        for part in self.contacts:
            if part.bounded and self._point_loads:
                part.monitor.set_point_loads(self._point_loads, self.time)

    def _jacobian_reuse(self, law, terms: list, nodal_terms: list) -> tuple[bool, bool]:
        """(a Jacobian constant over the run, one fixed within each step): only what is called
        for — a constitutive update linear in ε with no compliance term has a Jacobian that
        changes with the step size only; it is factorized once per size (an obstacle driven by
        a force changes the unknowns' map P at every step)."""
        fixed = not terms and not nodal_terms and not any(p.driven for p in self.contacts)
        return law.constant_tangent and fixed, self._tangent_per_step and fixed

    def _contact_terms(self, mesh, du, v, ds) -> list:
        """The contact parts' (residual, Jacobian) UFL terms, and the forms of the parts whose
        force is their own term's (:attr:`~vpcontact.model.contact.ContactPart.
        reports_law_force`: R_c assembled at their nodes, exactly 0 where nothing penetrates,
        not the residual left there)."""
        normal = ufl.FacetNormal(mesh)
        terms = []
        compliance_forces: dict = {}  # part index -> (form, owned dofs, vector)
        held_dofs = self.dirichlet.prescribed
        for part in self.contacts:
            if part.bounded:
                held_dofs = np.union1d(held_dofs, part.force_dofs)
        for i, part in enumerate(self.contacts):
            term = part.terms(self.u, du, v, normal, ds)
            if not term:
                continue
            terms.append(term)
            if part.reports_law_force:
                form = fem.form(term[0])
                dofs = unrolled(mesh.topology.dim, part.facet_blocks, held_dofs)
                compliance_forces[i] = (form, dofs, fem.petsc.create_vector(form))
        self._compliance_forces = compliance_forces
        return terms

    def _build_held(self, free: list, law, v, du, facet_tags, external: list,
                    terms: list) -> None:
        """A body whose free rigid motions only its contacts hold (see
        :mod:`vpcontact.solver.held`): its stabilising spring's term joins ``terms``."""
        self.held = None
        if free:
            self.held = HeldByContacts(self.u, free, shear_modulus(law))
            terms.append(self.held.terms(v, du))
            self._free_motions = free
            self._facet_tags = facet_tags
        self._load_form = (fem.form(sum(external[1:], external[0]))
                           if free and external else None)

    def _scaled_options(self, mesh, options: dict) -> tuple[float, dict]:
        """SNES's unknown scale and the options with the line search's longest step in it."""
        # Unknown scale for SNES: an exact power of two far below any displacement of interest.
        extent = mesh_extent(mesh)
        scale = 2.0 ** (np.floor(np.log2(extent)) - 40)
        self._extent = extent
        # A line search's longest step (bt's; PETSc's default 1e8) is in these scaled unknowns:
        # 1e8 is 1e-4 of the extent, and bt cut every longer Newton step to it (the linearized
        # scheme on a cantilever deflecting by 1e-2 of its length: DIVERGED_MAX_IT). Ten extents.
        return scale, {"snes_linesearch_maxstep": 10.0 * extent / scale, **options}

    def _build_solver(self, mesh, scale: float, options: dict, options_prefix, external: list,
                      constant_jacobian: bool, jacobian_per_step: bool, nodal_terms: list,
                      linear: str, petsc_options: Optional[dict]) -> None:
        """SNES's unknowns — u in local frames at the framed contact nodes, and the translations
        of obstacles driven by a force (:mod:`vpcontact.solver.variables`), or u itself —, the
        step solver, the VI's bounds and the nodal terms' places in it."""
        rotation = None
        frames = merged_frames(mesh.comm, self.contacts)
        if frames is not None:
            rotation = rotation_matrix(self.V, frames, self.fields)
        driven = [p for p in self.contacts if getattr(p, "driven", False)]
        for j, part in enumerate(driven):
            part.driven_index = j  # its unknown δ_j's place after the fields' (variables.py)
        self.variables = (None if rotation is None and not driven else
                          ChangeOfVariables(self.fields, rotation, driven, scale))
        self.solver = StepSolver(self.fields, self.bcs, self._update_stress,
                                 options, options_prefix, scale=scale,
                                 load=sum(external[1:], external[0]) if external else None,
                                 point_forces=self._point_forces if self._point_loads else None,
                                 constant_jacobian=constant_jacobian,
                                 jacobian_per_step=jacobian_per_step, variables=self.variables,
                                 nodal_terms=nodal_terms,
                                 linear=linear, given=tuple(petsc_options or {}))
        bounds = merged_bounds(self.u, self.contacts)
        if bounds is not None:
            self.solver.set_bounds(*bounds)
        for term in nodal_terms:
            term.bind(scale, self.dirichlet.prescribed, self.fields)

    def _init_run_state(self) -> None:
        """The support forces and the state before the first step."""
        self._forces = SupportForces(self.V, self.dirichlet, self.contacts,
                                     self._equilibrium_form, self._compliance_forces,
                                     self._point_forces if self._point_loads else None,
                                     self._load_form)
        self._correction_expr = None  # compiled on first use (outputs of the mixed formulation)
        self._contact_active = False  # after the last accepted step
        self.step_index = 0
        self.reports: list[StepReport] = []

    def set_initial_stress(self, sigma0: Callable[[np.ndarray], np.ndarray]) -> None:
        """σ_0 from a function of the quadrature-point coordinates (3, N) -> (N, size) Mandel."""
        coords = self.state.point_coordinates().T
        values = np.asarray(sigma0(coords), dtype=np.float64).reshape(self.state.num_points, -1)
        if values.shape[1] != self.state.size:
            raise InputError(f"initial stress must have {self.state.size} Mandel components",
                             key="initial.sigma0")
        self.state.set_stress(values)

    def _tangent_out(self, key) -> Optional[np.ndarray]:
        """Where the update writes the tangent, or None to skip it: a law whose tangent depends
        only on the step size (``key``) has it written once per size."""
        if self._tangent_per_step:
            key = (key, self.step_index, float(self.time.value))  # fixed within a step
        if self.law.linear_in_strain and key == self._tangent_key:
            return None
        self._tangent_key = key if self.law.linear_in_strain else None
        return self.state.tangent_view()

    def _update_stress(self) -> None:
        st = self.state
        self.scheme.update(self.law, st, st.strain_at_points(), self.dt, self._tangent_out)

    def step(self, dt: float, tolerance: Optional[float] = None) -> StepReport:
        """Advance from t_{n-1} to t_n = t_{n-1} + dt; on failure the state is rolled back.

        With ``tolerance``, a converged step whose local time-error estimate (see
        :mod:`vpcontact.solver.error_estimate`) exceeds ``tolerance`` · max|u_n| is rolled back too and
        :class:`StepRejected` raised; the report of an accepted step carries estimate/tolerance.
        The first step (and BDF2's second) has too little history for an estimate of its order:
        it is checked at order 1 when possible, else accepted unchecked.
        """
        if not dt > 0:
            raise InputError(f"time step must be > 0, got {dt}", key="time.k")
        self._check_stability(dt)
        t_new = float(self.time.value) + dt
        n = self.step_index + 1
        u_old, others_old = self._begin_step(dt, t_new, n)
        try:
            its, ratio, order = self._solve_step(dt, t_new, n, u_old, tolerance)
        except ConvergenceError:
            # a body that nothing holds drifts off on its stabilising spring (far: Newton stalls
            # on round-off): say that rather than "did not converge"
            try:
                self._check_held_step(t_new, DRIFTING)
            finally:
                self._roll_back(u_old, others_old, t_new - dt)
            raise
        except Exception:
            self._roll_back(u_old, others_old, t_new - dt)
            raise
        self._accept_step(dt, t_new, u_old, others_old)
        self.step_index = n
        report = StepReport(n, t_new, its, self.solver.last_reason, ratio, order)
        self.reports.append(report)
        return report

    def _begin_step(self, dt: float, t_new: float, n: int) -> tuple[np.ndarray, list]:
        """The step's initial guess (the predictor's), its time, the scheme's set-up and the
        prescribed displacements at ``t_new``; (u, the other fields) of the last step."""
        if n == 1 and hasattr(self.fields, "capture_initial_state"):
            self.fields.capture_initial_state(self.state)
        if n == 1:  # the initial state (u_0 included) is where the contact parts start from
            for part in self.contacts:
                part.commit(t_new - dt)
        u_old = self.u.x.array.copy()
        others_old = [f.x.array.copy() for f in self.fields.functions[1:]]
        if self.predictor == "linear":
            self.history.predict(self.u, self.fields.functions[1:], u_old, others_old, dt)
        self.dt = dt
        # the constant-Jacobian reuse is keyed on the law's effective step
        self.solver.dt = self.scheme.prepare(self.state, dt)
        self.time.value = t_new
        if self.dirichlet.moving:
            self.dirichlet.update(t_new)
            fem.petsc.set_bc(self.u.vector, self.bcs)
            self.u.x.scatter_forward()
        return u_old, others_old

    def _solve_step(self, dt: float, t_new: float, n: int, u_old: np.ndarray,
                    tolerance: Optional[float]) -> tuple:
        """(Newton iterations, error ratio or None, its order) of the step's solve; raises
        where it fails or its error is too large (the caller rolls back)."""
        if any(p.moving for p in self.contacts):
            self._move_obstacles(t_new)
        # Signorini with a Jacobian that is factorized once: while nothing touches, a plain
        # Newton step with that factorization is tried first, and the VI (which factorizes
        # its reduced matrix every iteration) runs only when the result would penetrate.
        # With a nonlinear law every iteration factorizes anyway; the VI costs no more.
        free_first = self.solver.constant_jacobian and not self._contact_active
        its = self.solver.solve(t_new, n, try_unconstrained=free_first)
        its += self._refit_driven(t_new, n)
        self._check_held_step(t_new)
        self._check_finite(t_new, n)
        ratio, order = (None, 1)
        if tolerance is not None:
            ratio, order = self.history.error_ratio(self.u.x.array, u_old, dt, self.scheme.order,
                                                    tolerance, self.mesh.comm)
        if ratio is not None and ratio > 1.0:
            raise StepRejected(ratio, order, t_new)
        return its, ratio, order

    def _accept_step(self, dt: float, t_new: float, u_old: np.ndarray, others_old: list) -> None:
        """Commit the step's state: the scheme's history (before the state's: it keeps w at
        t_{n-1}), the state, the contact parts, the held body, the law, the predictor's
        history."""
        self.scheme.accept(self.state, dt)
        self.state.commit()
        for part in self.contacts:
            part.commit(t_new, self.solver.unknowns_array())
        if self.held is not None:
            self.held.commit()
        if hasattr(self.law, "commit"):  # laws with internal variables of their own
            self.law.commit()
        self._contact_active = bounded_touching(self.mesh.comm, self.contacts,
                                                1e-6 * self.solver.scale)
        self.history.push(u_old, others_old, dt)

    def _roll_back(self, u_old: np.ndarray, others_old: list, t_old: float) -> None:
        """The state of the last accepted step, after a failed one."""
        self.u.x.array[:] = u_old
        for f, old in zip(self.fields.functions[1:], others_old):
            f.x.array[:] = old
        self.time.value = t_old
        self.state.rollback()

    def _check_held_step(self, t: float, share: float = NO_EQUILIBRIUM) -> None:
        """A body held by its contacts: refuse the step if the stabilising spring carries
        ``share`` of the applied forces (:meth:`~vpcontact.solver.held.HeldByContacts.check_step`)."""
        if self.held is not None:
            self.held.check_step(self._forces.applied_size(), t, share)

    def check_held(self, times) -> None:
        """A body held by its contacts: refuse (InputError at ``boundary``) a free rigid motion
        along which the loads push at one of ``times`` while no contact part can resist it (see
        :func:`~vpcontact.solver.held.check_held`; collective). The time is restored."""
        if self.held is None:
            return
        now = float(self.time.value)
        try:
            for t in times:
                self.time.value = t
                check_held(self.mesh, self._free_motions, self._forces.load_along,
                           self.contacts, self._facet_tags)
        finally:
            self.time.value = now

    def _refit_driven(self, t: float, n: int) -> int:
        """Obstacles driven by a force: solve again, linearized about the solved d, while the
        linearized gaps are off by more than REFIT_TOLERANCE × the mesh's extent (see :meth:`~
        vpcontact.model.signorini_part.DrivenSignoriniPart.refit`); the Newton iterations."""
        driven = [p for p in self.contacts if p.driven]
        its = 0
        for _ in range(MAX_REFITS):
            if not any([p.refit(REFIT_TOLERANCE * self._extent) for p in driven]):
                break
            self.variables.refresh()
            self.solver.update_bounds(*merged_bounds(self.u, self.contacts))
            its += self.solver.solve(t, n)
        return its

    def _move_obstacles(self, t: float) -> None:
        """The gaps at the contact nodes once the moving obstacles have reached their places at
        ``t``, and the bounds from them (collective: a ray that misses on one rank stops every
        rank with the same error, naming the part)."""
        moved_parts(self.mesh.comm, self.contacts, t)
        if self.variables is not None:
            self.variables.refresh()
        self.solver.update_bounds(*merged_bounds(self.u, self.contacts))

    def _check_stability(self, dt: float) -> None:
        """Refuse (or warn about) an explicit step beyond the law's stability limit."""
        limit = self.law.explicit_step_limit()
        if dt <= limit:
            return
        message = (f"time step {dt:.4g} exceeds the stability limit {limit:.4g} of the explicit "
                   f"scheme (2/L from the law's data); use the implicit scheme or k <= {limit:.4g}")
        if self.unstable_steps == "error":
            raise InputError(message, key="time.k")
        if not getattr(self, "_warned_unstable", False):
            warnings.warn(message, RuntimeWarning, stacklevel=3)
            self._warned_unstable = True

    def checkpoint(self) -> tuple[dict, dict]:
        """(scalars, arrays): the state at the last accepted step (see
        :func:`~vpcontact.solver.problem_state.checkpoint`)."""
        return problem_state.checkpoint(self)

    def restore(self, scalars: dict, arrays: dict) -> None:
        """Continue from :meth:`checkpoint` (same mesh, partition and scene)."""
        problem_state.restore(self, scalars, arrays)

    def support_forces(self, per_part: bool = False, split: bool = False) -> tuple:
        """(reactions, contact force) at the current state (collective): the force each
        Dirichlet part exerts on the body, shape (parts, dim), and the total force of the
        obstacles and foundations, shape (dim,) (zero without contact) — with ``per_part`` each
        contact part's, shape (contact parts, dim) —, from the equilibrium residual
        (σ, ε(v)) - (f, v) - P, P the point loads (:mod:`vpcontact.solver.dirichlet`; a part
        that reports its term's force: from the term, :mod:`vpcontact.solver.support_forces`)

        With ``split``, a third item: each contact part's force split along the body's outward
        normals ν_i at its nodes, shape (contact parts, 2): the normal force N = −Σ_i f_i·ν_i
        (positive where the obstacle presses) and the magnitude of the tangential resultant
        |Σ_i (f_i − (f_i·ν_i) ν_i)|, f_i the node's share of the part's force. On a flat part
        they are the normal and tangential components of its force; on a curved one, the
        resultants of the normal pressures and of the tangential (friction) forces."""
        return self._forces.support_forces(per_part, split)

    @property
    def contact_names(self) -> list[str]:
        """The contact parts' names, in order."""
        return [p.name for p in self.contacts]

    @property
    def contact_dofs(self):
        """The first bounded (Signorini) part's nodes, or None."""
        part = next((p for p in self.contacts if p.bounded), None)
        return None if part is None else part.nodes

    @property
    def contact_monitor(self):
        """The first bounded (Signorini) part's pressure monitor, or None."""
        part = next((p for p in self.contacts if p.bounded), None)
        return None if part is None else part.monitor

    def contact_report(self):
        """The contact state over every Signorini part, or None without one (collective)."""
        return merged_report(self.mesh.comm, self.contacts)

    def driving_displacement(self) -> Optional[float]:
        """What drives a displacement-controlled run at the current time, signed: the largest
        component of the first moving obstacle's translation d(t) (an indenter pushed down
        along z gives its negative z), else the mean u_D over the first time-dependent
        prescribed component (collective); None when nothing moves."""
        t = float(self.time.value)
        for part in self.contacts:
            d = part.driving_displacement(t)
            if d is not None:
                return d
        return self.dirichlet.mean_moving_value()

    def stress_correction_at_points(self) -> Optional[np.ndarray]:
        """What the formulation adds to each normal stress of the kernels' σ_q at the quadrature
        points (the mixed formulation's p − m_q, so that σ_h = σ_q + that · 1), or None."""
        correction = self.fields.stress_correction()
        if correction is None:
            return None
        if self._correction_expr is None:
            self._correction_expr = self.state.expression(correction)
        return self.state.at_points(self._correction_expr)[:, 0]

    def _point_forces(self):
        t = float(self.time.value)
        dofs = [p.dofs for p in self._point_loads]
        values = [p.values(t) for p in self._point_loads]
        return np.concatenate(dofs), np.concatenate(values)

    def _check_finite(self, t: float, n: int) -> None:
        local_ok = bool(all(np.isfinite(f.x.array).all() for f in self.fields.functions)
                        and np.isfinite(self.state.stress.x.array).all())
        if not self.mesh.comm.allreduce(local_ok, op=MPI.LAND):
            raise NonFiniteStateError(f"time step {n} (t = {t:.6g}) produced NaN/Inf in the state")
