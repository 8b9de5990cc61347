# SPDX-License-Identifier: MIT
"""The fully discrete quasistatic contact problem (the paper's Problems 2 and 4).

At each time t_n find u_n ∈ V^h (u = 0 on Γ1) such that for all v ∈ V^h

    (σ_n, ε(v))_Q + ⟨contact(u_n), v⟩_Γ3 = (f_0(t_n), v)_H + (f_2(t_n), v)_Γ2,
    σ_n = σ_{n-1} + E(ε(u_n) - ε(u_{n-1})) + k G(σ_*, ε_*),

where (σ_*, ε_*) is the previous step for the explicit scheme (Problem 4) and the new one for the
implicit scheme (Problem 2). σ_n is computed at quadrature points by the C++ kernels from the
current Newton iterate; the Jacobian uses their consistent tangent dσ_n/dε_n.

(About 430 lines: the step, its error estimate, the checkpoint/restore pair and the support
forces all read and write the problem's state; loads and BDF2 live in their own modules.)
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
from petsc4py import PETSc

from vpcontact.model.extent import mesh_extent
from vpcontact.solver.error_estimate import extrapolation_weights, milne_factor, past_nodes
from vpcontact.errors import (ConvergenceError, InputError, NonFiniteStateError,
                              ObstacleOutOfReach, StepRejected)
from vpcontact.solver.held import HeldByContacts, check_held
from vpcontact.solver.line_search import line_search_for
from vpcontact.solver.step_solver import StepSolver
from vpcontact.solver.variables import ChangeOfVariables
from vpcontact.model.fields import Displacement, DisplacementPressure
from vpcontact.model.locking import check_formulation, locks
from vpcontact.model.quadrature import QuadratureState
from vpcontact.model.frames import rotation_matrix
from vpcontact.model.contact import merged_bounds, merged_frames, merged_report, unrolled
from vpcontact.solver.bdf2 import Bdf2, check_time_scheme
from vpcontact.solver.dirichlet import Dirichlet, DirichletParts, rigid_mode_values
from vpcontact.solver.loads import Loads, PointDofs, as_vector
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
        if predictor not in ("linear", "none"):
            raise InputError(f"predictor must be 'linear' or 'none', got {predictor!r}",
                             key="solver.predictor")
        if unstable_steps not in ("error", "warn"):
            raise InputError(f"unstable_steps must be 'error' or 'warn', got {unstable_steps!r}")
        self.unstable_steps = unstable_steps
        self.time_scheme = check_time_scheme(time_scheme, law)
        self._bdf2 = Bdf2(law) if time_scheme == "bdf2" else None
        self.predictor = predictor
        self.mesh = mesh
        self.law = law
        self._contact_laws = _named(contact)
        self.contact = next(iter(self._contact_laws.values()), None)  # the first part's law
        dim = mesh.topology.dim
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
        self.V = fem.VectorFunctionSpace(mesh, ("Lagrange", degree), dim=dim)
        self.u = fem.Function(self.V, name="displacement")
        self.time = fem.Constant(mesh, 0.0)
        self.dt = 0.0
        self._tangent_key = None  # the step whose tangent the state holds (affine laws only)

        parts = list(dirichlet)
        if clamped_tag is not None:
            clamped = facet_tags.find(clamped_tag)
            if mesh.comm.allreduce(len(clamped), op=MPI.SUM) == 0:
                raise InputError(f"the clamped boundary (tag {clamped_tag}) has no facets: "
                                 "meas(Γ1) > 0 is required", key="boundary")
            parts.insert(0, Dirichlet.clamped(clamped_tag, dim))
        if not parts and not self._contact_laws:
            raise InputError("no Dirichlet part: meas(Γ1) > 0 is required (a clamped part, or "
                             "prescribed displacements and symmetry planes that hold the body)",
                                 key="boundary")
        self.dirichlet = DirichletParts(self.V, facet_tags, parts)
        free = [] if any(p.all_zero for p in parts) else self.dirichlet.free_rigid_motions()
        if free and not self._contact_laws:
            self.dirichlet.check_rigid_motions()  # (raises: nothing else can hold the body)
        self.bcs = self.dirichlet.bcs

        # Stress quadrature: exact for ε(v) of degree-p displacements paired with the stress.
        self.state = QuadratureState(self.u, degree=stress_quadrature_degree(mesh, degree))
        self.fields = (DisplacementPressure(self.u, law, self.state) if mixed
                       else Displacement(self.u))
        self.p: Optional[fem.Function] = getattr(self.fields, "p", None)  # mixed: the pressure
        v, du = ufl.TestFunction(self.V), ufl.TrialFunction(self.V)
        n_q = self.state.size
        dxq = self.state.measure
        sigma = self.fields.stress(as_mandel_vector(self.state.stress, n_q))
        tangent = as_mandel_matrix(self.state.tangent, n_q)
        residual = ufl.dot(sigma, mandel_strain(v, dim)) * dxq
        jacobian = ufl.dot(self.fields.tangent(tangent, du), mandel_strain(v, dim)) * dxq

        x = ufl.SpatialCoordinate(mesh)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
        external = []  # (f, v): the applied loads, whose size sets the residual's force scale
        #: each load's (f, v) as a UFL form, by "body_force" or traction facet tag (for checks
        #: of the values at its quadrature points: vpcontact.scene.finite)
        self.load_terms: dict = {}
        if loads.body_force is not None:
            self.load_terms["body_force"] = ufl.dot(
                as_vector(loads.body_force(x, self.time), dim), v) * ufl.dx
        for tag, traction in loads.tractions.items():
            self.load_terms[tag] = ufl.dot(as_vector(traction(x, self.time), dim), v) * ds(tag)
        external.extend(self.load_terms.values())
        for term in external:
            residual -= term
        self.equilibrium = residual  # (σ, ε(v)) - (f, v): reactions and contact forces
        self._equilibrium_form = fem.form(residual)
        self._equilibrium_vec = None
        # The contact parts, in order: a node belongs to the first part that reaches it.
        self.contacts = []
        taken = self.dirichlet.prescribed
        for name, condition in self._contact_laws.items():
            try:
                part = condition.part(self.u, facet_tags, residual, name=name, exclude=taken,
                                      rotate=rotate_contact,
                                      shear_modulus=_shear_modulus(law))
                # (a compliant part makes its nodes and gaps on first use: asked for here, a
                # bad gap is refused by every process before anything runs)
                _ = part.nodes
            except InputError as err:
                err.part = name
                raise
            self.contacts.append(part)
            taken = np.union1d(taken, _node_dofs(self.V, part.node_blocks)).astype(np.int32)
        # an update affine in ε_n whose tangent depends on the state (the linearized scheme):
        # the tangent and Jacobian are fixed within a step and change between steps
        self._tangent_per_step = law.linear_in_strain and not law.constant_tangent
        defaults = line_search_for(law, self.contacts)  # (and the parts' other SNES needs)
        normal = ufl.FacetNormal(mesh)
        terms = []
        # A frictionless compliance part's force is its law's: the part's own term R_c,
        # assembled at its nodes (exactly 0 where nothing penetrates), not the residual left
        # there.
        self._compliance_forces: dict = {}  # part index -> (form, owned dofs, vector)
        held_dofs = self.dirichlet.prescribed
        for part in self.contacts:
            if part.bounded:
                held_dofs = np.union1d(held_dofs, part.force_dofs)
        for i, part in enumerate(self.contacts):
            term = part.terms(self.u, du, v, normal, ds)
            if not term:
                continue
            terms.append(term)
            # (with friction the term, assembled after the step, would see the committed slip
            # history instead of the step's: such a part's force is the residual left at its
            # nodes, as a rigid part's is — a sweep's block was 1 % out of balance)
            if not part.bounded and getattr(part.law, "friction", None) is None:
                form = fem.form(term[0])
                dofs = unrolled(dim, part.facet_blocks, held_dofs)
                self._compliance_forces[i] = (form, dofs, fem.petsc.create_vector(form))
        # A body whose free rigid motions only its contacts hold (see vpcontact.solver.held).
        self.held = None
        if free:
            shear = _shear_modulus(law)
            self.held = HeldByContacts(self.u, free, shear)
            terms.append(self.held.terms(v, du))
            self._free_motions = free
            self._facet_tags = facet_tags
            self._load_form = fem.form(sum(external[1:], external[0])) if external else None
        for r, j in terms:
            residual += r
            jacobian += j
        options = {**defaults, **(petsc_options or {})}

        # Unknown scale for SNES: an exact power of two far below any displacement of interest.
        extent = mesh_extent(mesh)
        scale = 2.0 ** (np.floor(np.log2(extent)) - 40)
        self._extent = extent
        # A line search's longest step (bt's; PETSc's default 1e8) is in these scaled unknowns:
        # 1e8 is 1e-4 of the extent, and bt cut every longer Newton step to it (the linearized
        # scheme on a cantilever deflecting by 1e-2 of its length: DIVERGED_MAX_IT). Ten extents.
        options = {"snes_linesearch_maxstep": 10.0 * extent / scale, **options}
        self._point_loads = [PointDofs(self.V, p) for p in loads.points]
        for part in self.contacts:  # a point load at a contact node is not the obstacle's force
            if part.bounded and self._point_loads:
                part.monitor.set_point_loads(self._point_loads, self.time)
        # Only what is called for: a constitutive update linear in ε with no compliance term
        # has a Jacobian that changes with the step size only; it is factorized once per size.
        # (an obstacle driven by a force changes the unknowns' map P at every step)
        nodal_terms = [t for p in self.contacts for t in p.solver_terms()]
        fixed = not terms and not nodal_terms and not any(p.driven for p in self.contacts)
        constant_jacobian = law.constant_tangent and fixed
        jacobian_per_step = self._tangent_per_step and fixed
        self.fields.compile(residual, jacobian)
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
        self._correction_expr = None  # compiled on first use (outputs of the mixed formulation)
        self._contact_active = False  # after the last accepted step
        self.step_index = 0
        self.reports: list[StepReport] = []
        self._u_prev: Optional[np.ndarray] = None  # u_{n-1}, for the predictor
        self._others_prev: list = []  # the other fields at t_{n-1} (the mixed formulation's p)
        self._dt_prev = 0.0
        self._u_prev2: Optional[np.ndarray] = None  # u_{n-2}, for the BDF2 error estimate
        self._dt_prev2 = 0.0

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
        eps = st.strain_at_points()
        if self._bdf2 is not None and self._bdf2.active:
            sigma_hist, zero, dt = self._bdf2.inputs()
            self.law.update(sigma_hist, zero, eps, dt, st.view(st.stress),
                            self._tangent_out(("bdf2", dt)))
            return
        self.law.update(st.view(st.stress_old), st.view(st.strain_old), eps, self.dt,
                        st.view(st.stress), self._tangent_out(("euler", self.dt)))

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
        if n == 1 and hasattr(self.fields, "capture_initial_state"):
            self.fields.capture_initial_state(self.state)
        if n == 1:  # the initial state (u_0 included) is where the contact parts start from
            for part in self.contacts:
                part.commit(t_new - dt)
        u_old = self.u.x.array.copy()
        others_old = [f.x.array.copy() for f in self.fields.functions[1:]]
        if self.predictor == "linear" and self._u_prev is not None:
            # Ghost entries are extrapolated from ghost entries: consistent without a scatter.
            self.u.x.array[:] += (dt / self._dt_prev) * (u_old - self._u_prev)
            for f, old, prev in zip(self.fields.functions[1:], others_old, self._others_prev):
                f.x.array[:] += (dt / self._dt_prev) * (old - prev)
        self.dt = dt
        self.solver.dt = dt  # the constant-Jacobian reuse is keyed on the law's effective step
        if self._bdf2 is not None:
            self.solver.dt = self._bdf2.prepare(self.state, dt)
        self.time.value = t_new
        if self.dirichlet.moving:
            self.dirichlet.update(t_new)
            fem.petsc.set_bc(self.u.vector, self.bcs)
            self.u.x.scatter_forward()
        try:
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
                ratio, order = self._error_ratio(u_old, dt, tolerance)
            if ratio is not None and ratio > 1.0:
                raise StepRejected(ratio, order, t_new)
        except ConvergenceError:
            # a body that nothing holds drifts off on its stabilising spring (far: Newton stalls
            # on round-off): say that rather than "did not converge"
            try:
                self._check_held_step(t_new)
            finally:
                self._roll_back(u_old, others_old, t_new - dt)
            raise
        except Exception:
            self._roll_back(u_old, others_old, t_new - dt)
            raise
        if self._bdf2 is not None:

            self._bdf2.accept(self.state, dt)  # before the commit: it keeps w at t_{n-1}
        self.state.commit()
        for part in self.contacts:
            part.commit(t_new, self.solver.unknowns_array())
        if self.held is not None:
            self.held.commit()
        if hasattr(self.law, "commit"):  # laws with internal variables of their own
            self.law.commit()
        self._contact_active = self._any_contact_active()
        self._u_prev2, self._dt_prev2 = self._u_prev, self._dt_prev
        self._u_prev, self._dt_prev = u_old, dt
        self._others_prev = others_old
        self.step_index = n
        report = StepReport(n, t_new, its, self.solver.last_reason, ratio, order)
        self.reports.append(report)
        return report

    def _roll_back(self, u_old: np.ndarray, others_old: list, t_old: float) -> None:
        """The state of the last accepted step, after a failed one."""
        self.u.x.array[:] = u_old
        for f, old in zip(self.fields.functions[1:], others_old):
            f.x.array[:] = old
        self.time.value = t_old
        self.state.rollback()

    def _check_held_step(self, t: float) -> None:
        """A body held by its contacts: refuse the step if the stabilising spring carries a
        share of the applied forces (see :meth:`~vpcontact.solver.held.HeldByContacts.
        check_step`; collective)."""
        if self.held is None:
            return
        reactions, forces = self.support_forces(per_part=True)
        applied = float(np.abs(forces).sum() + np.abs(reactions).sum())
        applied += self.mesh.comm.allreduce(float(np.abs(self._nodal_loads()).sum()),
                                            op=MPI.SUM)
        self.held.check_step(applied, t)

    def _nodal_loads(self) -> np.ndarray:
        """This rank's owned entries of the nodal load vector at the current time (tractions,
        body force, point loads)."""
        loads = fem.Function(self.V)
        if self._load_form is not None:
            fem.petsc.assemble_vector(loads.vector, self._load_form)
            loads.vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if self._point_loads:
            dofs, values = self._point_forces()
            loads.x.array[dofs] += values
        return loads.x.array[:self.V.dofmap.index_map.size_local * self.V.dofmap.index_map_bs]

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
                check_held(self.mesh, self._free_motions, lambda m: self._load_along(m, t),
                           self.contacts, self._facet_tags)
        finally:
            self.time.value = now

    def _load_along(self, coefficients, t: float) -> tuple[float, float]:
        """(generalised force L · m of the applied loads on the rigid motion m (its
        ``coefficients``) at t, and its scale Σ |L_i m_i|), L the nodal load vector (tractions,
        body force, point loads)."""
        loads = self._nodal_loads()
        products = loads * rigid_mode_values(self.V, coefficients)[:len(loads)]
        comm = self.mesh.comm
        return (comm.allreduce(float(products.sum()), op=MPI.SUM),
                comm.allreduce(float(np.abs(products).sum()), op=MPI.SUM))

    def _refit_driven(self, t: float, n: int) -> int:
        """Obstacles driven by a force: solve again, linearized about the solved d, while the
        linearized gaps are off by more than REFIT_TOLERANCE × the mesh's extent (see
        :meth:`~vpcontact.model.signorini.DrivenSignoriniPart.refit`); the Newton iterations."""
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
        message, part_name = None, None
        for part in self.contacts:
            try:
                part.update(t)
            except InputError as err:
                message = f"at t = {t:.6g}, where the moving obstacle has gone: {err}"
                part_name = part.name
                break
        found = next(((m, n) for m, n in self.mesh.comm.allgather((message, part_name)) if m),
                     None)
        if found is not None:
            raise ObstacleOutOfReach(found[0], part=found[1])
        if self.variables is not None:
            self.variables.refresh()
        self.solver.update_bounds(*merged_bounds(self.u, self.contacts))

    def _error_ratio(self, u_old: np.ndarray, dt: float, tolerance: float):
        """(local error estimate / (tolerance · max|u_n|), order), or (None, 1) without history."""
        order = 2 if self._bdf2 is not None and self._bdf2.active else 1
        history = [u_old] + [u for u in (self._u_prev, self._u_prev2) if u is not None]
        order = min(order, len(history) - 1)
        if order < 1:
            return None, 1
        steps = [dt, self._dt_prev, self._dt_prev2][: order + 1]
        weights = extrapolation_weights(past_nodes(steps, order), 0.0)
        predicted = sum(w * u for w, u in zip(weights, history))
        u = self.u.x.array
        comm = self.mesh.comm
        difference = comm.allreduce(float(np.max(np.abs(u - predicted), initial=0.0)), op=MPI.MAX)
        size = comm.allreduce(float(np.max(np.abs(u), initial=0.0)), op=MPI.MAX)
        estimate = abs(milne_factor(order, steps)) * difference
        if estimate == 0.0:
            return 0.0, order
        return estimate / (tolerance * max(size, np.finfo(float).tiny)), order

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
        """(scalars, arrays): the state at the last accepted step — u, the quadrature-point
        stress, strain and tangent, the law's own internal variables, the predictor's and BDF2's
        history, the time and step, the contact flag, and the solver's (see
        :meth:`StepSolver.checkpoint`). Arrays are this rank's local values (ghosts included)."""
        st = self.state
        arrays = {"u": self.u.x.array, "stress": st.stress.x.array,
                  "stress_old": st.stress_old.x.array, "strain_old": st.strain_old.x.array,
                  "tangent": st.tangent.x.array}
        arrays.update({f"field_{k}": f.x.array for k, f in self.fields.saved_functions().items()})
        for i, prev in enumerate(self._others_prev):
            arrays[f"_others_prev{i}"] = prev
        for name in ("_u_prev", "_u_prev2"):
            if getattr(self, name) is not None:
                arrays[name] = getattr(self, name)
        if hasattr(self.law, "internal_state"):
            arrays.update({f"law_{k}": v for k, v in self.law.internal_state().items()})
        if self._bdf2 is not None and self._bdf2.w_prev is not None:
            arrays["bdf2_w_prev"] = self._bdf2.w_prev
        for i, part in enumerate(self.contacts):
            arrays.update({f"contact{i}_{k}": v for k, v in part.arrays().items()})
        solver_flags, solver_arrays = self.solver.checkpoint()
        arrays.update({f"solver_{k}": v for k, v in solver_arrays.items()})
        scalars = {"time": float(self.time.value), "dt": self.dt, "step_index": self.step_index,
                   "dt_prev": self._dt_prev, "dt_prev2": self._dt_prev2,
                   "contact_active": self._contact_active, "tangent_key": self._tangent_key,
                   "bdf2_dt_prev": self._bdf2.dt_prev if self._bdf2 is not None else None,
                   "solver": solver_flags, "contacts": [p.state() for p in self.contacts]}
        return scalars, {k: np.asarray(v) for k, v in arrays.items()}

    def restore(self, scalars: dict, arrays: dict) -> None:
        """Continue from :meth:`checkpoint` (same mesh, partition and scene)."""
        st = self.state
        saved = [(f"field_{k}", f) for k, f in self.fields.saved_functions().items()]
        for name, function in [("u", self.u), ("stress", st.stress), ("stress_old", st.stress_old),
                               ("strain_old", st.strain_old), ("tangent", st.tangent)] + saved:
            if name not in arrays:
                raise InputError(f"the checkpoint has no {name}: it was written by another "
                                 "formulation")
            if arrays[name].shape != function.x.array.shape:
                raise InputError(f"the checkpoint's {name} has {arrays[name].size} values here, "
                                 f"the problem {function.x.array.size}: another mesh or partition")
            function.x.array[:] = arrays[name]
        self._u_prev = arrays["_u_prev"].copy() if "_u_prev" in arrays else None
        self._others_prev = [arrays[f"_others_prev{i}"].copy()
                             for i in range(len(self.fields.functions) - 1)
                             if f"_others_prev{i}" in arrays]
        self._u_prev2 = arrays["_u_prev2"].copy() if "_u_prev2" in arrays else None
        law_state = {k[4:]: v for k, v in arrays.items() if k.startswith("law_")}
        if law_state:
            self.law.set_internal_state(law_state)
        if self._bdf2 is not None:
            self._bdf2.w_prev = arrays["bdf2_w_prev"].copy() if "bdf2_w_prev" in arrays else None
            self._bdf2.dt_prev = scalars["bdf2_dt_prev"]
        self.time.value = scalars["time"]
        self.dt = scalars["dt"]
        self.step_index = int(scalars["step_index"])
        self._dt_prev, self._dt_prev2 = scalars["dt_prev"], scalars["dt_prev2"]
        self._contact_active = bool(scalars["contact_active"])
        key = scalars["tangent_key"]
        self._tangent_key = tuple(key) if key is not None else None
        if self.dirichlet.moving:
            self.dirichlet.update(scalars["time"])
        for i, (part, state) in enumerate(zip(self.contacts, scalars.get(
                "contacts", [{}] * len(self.contacts)))):
            prefix = f"contact{i}_"
            part.restore(state, scalars["time"], {k[len(prefix):]: v for k, v in arrays.items()
                                                  if k.startswith(prefix)})
        if self.variables is not None:
            self.variables.refresh()
        if any(p.moving for p in self.contacts):
            self.solver.update_bounds(*merged_bounds(self.u, self.contacts))
        self.solver.restore(scalars["solver"], {k[7:]: v for k, v in arrays.items()
                                                if k.startswith("solver_")})

    def support_forces(self, per_part: bool = False, split: bool = False) -> tuple:
        """(reactions, contact force) at the current state (collective): the force each
        Dirichlet part exerts on the body, shape (parts, dim), and the total force of the
        obstacles and foundations, shape (dim,) (zero without contact) — with ``per_part`` each
        contact part's, shape (contact parts, dim) —, from the equilibrium residual
        (σ, ε(v)) - (f, v) - P, P the point loads (see :mod:`vpcontact.solver.dirichlet`;
        a frictionless compliance part's from its own term, :meth:`_contact_forces`)

        With ``split``, a third item: each contact part's force split along the body's outward
        normals ν_i at its nodes, shape (contact parts, 2): the normal force N = −Σ_i f_i·ν_i
        (positive where the obstacle presses) and the magnitude of the tangential resultant
        |Σ_i (f_i − (f_i·ν_i) ν_i)|, f_i the node's share of the part's force. On a flat part
        they are the normal and tangential components of its force; on a curved one, the
        resultants of the normal pressures and of the friction forces."""
        values = self._equilibrium_values()
        reactions = self.dirichlet.reactions(values)
        dim = self.V.dofmap.index_map_bs
        parts = self._contact_forces(values)
        local = np.array([f.reshape(-1, dim).sum(axis=0) for f in parts]).reshape(-1, dim)
        forces = self.mesh.comm.allreduce(local, op=MPI.SUM)
        result = (reactions, forces if per_part else forces.sum(axis=0))
        return result + (self._normal_and_tangential(parts),) if split else result

    def _contact_forces(self, values: np.ndarray) -> list[np.ndarray]:
        """Each contact part's force on the body at this rank's owned dofs (0 elsewhere), from
        the residual ``values`` of :meth:`_equilibrium_values` (bounded parts: the multiplier
        of the bound, applied loads left out) or from the part's compliance term (collective)."""
        forces = []
        for i, part in enumerate(self.contacts):
            f = np.zeros(values.size)
            if i in self._compliance_forces:
                form, dofs, vec = self._compliance_forces[i]
                with vec.localForm() as local:
                    local.set(0.0)
                fem.petsc.assemble_vector(vec, form)
                vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
                f[dofs] = 0.0 - vec.array[dofs]  # (R_c is the body's push on the foundation)
            else:
                f[part.force_dofs] = values[part.force_dofs]
            forces.append(f)
        return forces

    def _normal_and_tangential(self, parts: list[np.ndarray]) -> np.ndarray:
        """The ``split`` of :meth:`support_forces` from each part's nodal forces ``parts``."""
        dim = self.V.dofmap.index_map_bs
        local = np.zeros((len(self.contacts), 1 + dim))
        for i, part in enumerate(self.contacts):
            nodes = part.nodes
            at = nodes.nodes[:, None] * dim + np.arange(dim)
            f = parts[i][at]
            normal = np.einsum("ij,ij->i", f, nodes.normals)
            local[i, 0] = 0.0 - normal.sum()  # (0, not -0, where nothing touches)
            local[i, 1:] = (f - normal[:, None] * nodes.normals).sum(axis=0)
        total = self.mesh.comm.allreduce(local, op=MPI.SUM)
        return np.column_stack([total[:, 0], np.linalg.norm(total[:, 1:], axis=1)])

    def _equilibrium_values(self) -> np.ndarray:
        """The equilibrium residual (σ, ε(v)) − (f, v) − P at the current state, P the point
        loads, this rank's owned entries (collective): at a node held by a support or an
        obstacle, the force that holds it (a point load there is an applied force, not a
        reaction)."""
        if self._equilibrium_vec is None:
            self._equilibrium_vec = fem.petsc.create_vector(self._equilibrium_form)
        vec = self._equilibrium_vec
        with vec.localForm() as local:
            local.set(0.0)
        fem.petsc.assemble_vector(vec, self._equilibrium_form)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        values = vec.array
        if self._point_loads:
            values = values.copy()
            dofs, forces = self._point_forces()
            np.add.at(values, dofs, -forces)  # (owned dofs: each load on one rank)
        return values

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

    def _any_contact_active(self) -> bool:
        bounded = [p for p in self.contacts if p.bounded]
        if not bounded:
            return False
        local = any(p.touching(1e-6 * self.solver.scale) for p in bounded)
        return self.mesh.comm.allreduce(local, op=MPI.LOR)

    def _check_finite(self, t: float, n: int) -> None:
        local_ok = bool(all(np.isfinite(f.x.array).all() for f in self.fields.functions)
                        and np.isfinite(self.state.stress.x.array).all())
        if not self.mesh.comm.allreduce(local_ok, op=MPI.LAND):
            raise NonFiniteStateError(f"time step {n} (t = {t:.6g}) produced NaN/Inf in the state")


def stress_quadrature_degree(mesh, degree: int) -> int:
    """Quadrature degree of the stress: ε(u):ε(v) integrated exactly. On simplices ε of P_p
    displacements has degree p − 1 (one point per cell for P1); on quadrilaterals and hexahedra
    Q_p's gradient keeps degree p in each coordinate, so the rule needs degree 2p (2×2 or 2×2×2
    Gauss points for Q1: one point would leave the hourglass modes without stiffness)."""
    if mesh.ufl_cell().cellname() in ("quadrilateral", "hexahedron"):
        return 2 * degree
    return max(2 * (degree - 1), 1)


def _shear_modulus(law) -> float:
    """G of the law's elasticity (E in 1-D), the body's stiffness scale."""
    return law.elasticity.shear_modulus


def _named(contact) -> dict:
    """The contact argument of :class:`QuasistaticProblem` as a dict part name -> law."""
    if contact is None:
        return {}
    if isinstance(contact, dict):
        return dict(contact)
    if isinstance(contact, (list, tuple)):
        return {f"contact{i + 1}": c for i, c in enumerate(contact)}
    return {"contact": contact}


def _node_dofs(V, blocks: np.ndarray) -> np.ndarray:
    """Every unrolled dof of the nodes ``blocks``."""
    bs = V.dofmap.index_map_bs
    return (np.asarray(blocks, dtype=np.int64)[:, None] * bs + np.arange(bs)).ravel()
