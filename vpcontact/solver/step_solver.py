# SPDX-License-Identifier: MIT
"""One time step as a PETSc SNES solve (its options and reason names: :mod:`.snes_options`).

:class:`StepSolver` assembles the residual and Jacobian of a dolfinx problem whose coefficients
must be refreshed before every assembly (here: the quadrature-point stress and tangent, computed
by the C++ kernels from the current iterate). It follows dolfinx's ``fem/petsc.py`` pattern:
every solver has a rank-independent options prefix, user options pass through the PETSc options
database, and the converged reason is checked after every solve.

It is a thin wrapper of SNES: what it composes lives beside it, each in a module named after
what it does — its own options (:mod:`.step_options`), the convergence test
(:mod:`.convergence`), the retries of a step that does not converge (:mod:`.retries`, built from
the nodal terms' protocol), the line search (:mod:`.line_search`), the bounds of SNES VI
(:mod:`.vi_bounds`) and its linear solver (:mod:`.vi_solver`), and the iterative solver's
preconditioners (:mod:`.pc`, one factory: this module names none of them).
"""

from __future__ import annotations

import itertools
import time as _time
from typing import Callable, Optional, Sequence

import numpy as np
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.errors import ConvergenceError, InputError, SolverOptionError
from vpcontact.model.extent import mesh_extent
from vpcontact.solver import linear as linear_solvers
from vpcontact.solver import pc as preconditioners
from vpcontact.solver.assembly import StepAssembly
from vpcontact.solver.convergence import ConvergenceTest
from vpcontact.solver.near_nullspace import rigid_body_modes
from vpcontact.solver.option_reads import OptionReads
from vpcontact.solver.retries import StepRetries, longest_first_try
from vpcontact.solver.snes_options import (_SNES_REASON, DEFAULT_OPTIONS, _forget, reason_name,
                                          check_values, rejected_option, viewer_flags)
from vpcontact.solver.step_options import SolverTypes, read_step_options
from vpcontact.solver.vi_bounds import VIBounds
from vpcontact.solver.vi_linear import LaggedDirectSolve, LaggedMultigrid, options_in_database
from vpcontact.solver.vi_solver import LagPolicy, expire_if, use_lagged_solver

_counter = itertools.count()


class StepSolver:
    """Newton (SNES) solver for F(u; v) = 0 with a refresh hook run before each assembly.

    Args:
        fields: the unknowns, their compiled forms and their layout in the SNES vector
            (:mod:`vpcontact.model.fields`); they hold the initial guess before :meth:`solve`
            and the solution after.
        bcs: Dirichlet conditions (homogeneous or not).
        refresh: called after the iterate is copied into ``u`` and before assembling; updates
            coefficients that depend on ``u`` (e.g. quadrature stresses).
        petsc_options: options set under the prefix (override :data:`DEFAULT_OPTIONS`).
        options_prefix: PETSc options prefix; default ``vpcontact_step_<k>_`` with ``k`` counting
            solvers created (identical on all ranks since creation is collective).
        scale: SNES works on x = u / scale (and the layout's own scale for other fields, see
            :meth:`~vpcontact.model.fields.FieldLayout.column_scales`). PETSc's VI solvers decide whether a bound is active
            with an absolute tolerance of 1e-8 in the units of x, which is meaningless for
            displacements of 1e-9 m (E ~ 1e8 Pa); a power-of-two scale makes that tolerance
            negligible without any rounding. Residuals stay in physical units.
        load: UFL form of the applied loads (f, v); its norm is the force scale of the round-off
            stop (see :mod:`.convergence`). None: the initial residual alone sets that scale.
        point_forces: called at each residual evaluation; returns (dofs, values): nodal forces
            to add to the applied loads at local dof indices this rank owns.
        constant_jacobian: the Jacobian depends on the step size only (a constitutive update
            linear in ε and no nonlinear contact term): it is assembled once per step size and
            the linear solver's factorization is reused across iterations and steps.
        jacobian_per_step: the Jacobian is constant within a step but changes between steps (a
            constitutive update affine in ε with a state-dependent tangent: the linearized
            scheme): it is assembled once per step and the preconditioner or factorization
            reused across the step's iterations.
        variables: a change of variables u = P x̃ (:class:`~vpcontact.solver.variables.
            ChangeOfVariables`: local frames at contact nodes, and the displacements of
            obstacles driven by a force appended to the unknowns): SNES then solves
            Pᵀ F(P x̃) = 0 (less the driving forces) with Jacobian Pᵀ J P (:meth:`Mat.PtAP`),
            bounds apply to x̃. Dirichlet rows must be left alone by P. None: SNES works on u
            itself.
        linear: "direct", "iterative" or "auto" (by size), see :mod:`vpcontact.solver.linear`;
            user options (``ksp_*``, ``pc_*``, ``lagged_*``) override its choices.
        nodal_terms: objects with ``residual(x, b)`` and ``jacobian(x, A)`` that add their
            nodal terms to SNES's residual and Jacobian at x, ``predict(x)`` (the step's initial
            guess), ``has_fallback()``/``fallback(x)`` (another guess, see
            :class:`~vpcontact.solver.retries.OtherGuess`), ``second_try``/``freeze(stick)``/
            ``thaw()`` (a predictor from that guess, see :class:`~vpcontact.solver.retries.
            Predictor`; ``holding``: the crawl stop waits, :data:`~vpcontact.solver.retries.
            CRAWL_ITERATIONS`), ``prepare_jacobian(x)`` (before the UFL Jacobian's assembly)
            and ``current(x)`` (friction on Signorini parts, the obstacle's normals, the
            sticking guess of friction on compliant parts;
            :class:`~vpcontact.model.nodal_terms.NodalTerm` has the defaults).
        given: the names among ``petsc_options`` the user gave: those PETSc (or vpcontact)
            never reads are refused at set-up where that can be decided then, else reported by
            :meth:`unread_options` after the solves (:mod:`.option_reads`).
    """

    def __init__(self, fields, bcs: Sequence[fem.DirichletBCMetaClass],
                 refresh: Callable[[], None], petsc_options: Optional[dict] = None,
                 options_prefix: Optional[str] = None, scale: float = 1.0, load=None,
                 point_forces: Optional[Callable[[], tuple]] = None,
                 constant_jacobian: bool = False, jacobian_per_step: bool = False,
                 variables=None,
                 linear: str = "direct", nodal_terms: Sequence = (), given: Sequence[str] = ()):
        if not scale > 0:
            raise ValueError(f"scale must be > 0, got {scale}")
        self.scale = float(scale)
        self.fields = fields
        self.u = fields.u
        self.bcs = list(bcs)
        self._P = variables
        self._nodal = list(nodal_terms)
        #: the longest first try a term with another guess may ask for, which :meth:`solve`
        #: tells the terms' ``predict``
        self._first_try = longest_first_try(self._nodal)
        self.constant_jacobian = constant_jacobian
        self.jacobian_per_step = jacobian_per_step and not constant_jacobian
        self._step_key = None  # (t_n, k) of the solve under way (jacobian_per_step)
        self._jacobian_step_key = None  # ... and of the assembled Jacobian
        self._jacobian_dt: Optional[float] = None  # step size of the assembled constant Jacobian
        self._restored_jacobian_dt: Optional[float] = None  # the same before a restart
        self.dt = 0.0  # set by the owner before each solve (only the constant-Jacobian reuse reads it)
        #: wall time [s] spent in the refresh hook (kernels), residual and Jacobian assembly,
        #: in PETSc's KSPSolve (linear solves, factorizations included) and in SNES solves
        #: altogether (the rest of which is VI/active-set work, line searches and vector work)
        self.timings = {"kernel": 0.0, "residual": 0.0, "jacobian": 0.0, "linear_solve": 0.0,
                        "snes": 0.0}
        self._assembly = StepAssembly(fields, self.bcs, refresh, variables, self._nodal,
                                      self.scale, load, point_forces, self.timings)
        self._x, self._A, self._b = self._assembly.x, self._assembly.A, self._assembly.b
        comm = self.u.function_space.mesh.comm
        self.prefix = options_prefix or f"vpcontact_step_{next(_counter)}_"
        self.snes = PETSc.SNES().create(comm)
        self.snes.setOptionsPrefix(self.prefix)
        self._linear_given = linear
        defaults = self._choose_linear_solver(linear, petsc_options or {})
        self._set_options(defaults, petsc_options or {}, given, comm)
        self._init_state()

    @property
    def _driven(self) -> bool:
        """An obstacle driven by a force: P appends unknowns (it is not square)."""
        return self._P is not None and not self._P.square

    def _choose_linear_solver(self, linear: str, user_options: dict) -> dict:
        """The linear solver by ``[solver] linear`` and the size (:mod:`.linear`), and the
        step's default options with it: the iterative solver's preconditioner and its context
        come from the one factory of :mod:`.pc`."""
        mixed = len(self.fields.functions) > 1
        self.linear = linear_solvers.choose(linear, self._x.getSize(),
                                            "mixed" if mixed else "displacement",
                                            per_step=self.jacobian_per_step,
                                            iterative_possible=not self._driven)
        self._modes = None  # rigid-body modes (in the SNES layout), for multigrid
        self._block = None  # the preconditioner's context (the mixed formulation's field split)
        defaults = dict(DEFAULT_OPTIONS)
        if self.linear == "iterative" and self._driven:
            raise InputError("an obstacle driven by a force needs the direct linear solver "
                             "(linear = \"direct\")", key="solver.linear")
        if self.linear == "iterative":
            self._modes = rigid_body_modes(self.u.function_space, self._P, layout=self.fields)
            rotation = None if self._P is None else self._P.matrix
            defaults, self._block = preconditioners.configure(
                self.fields, self._modes, self.scale, self.prefix, rotation, user_options,
                defaults)
            if self._block is None:
                self._A.setNearNullSpace(self._modes)
        return defaults

    def _set_options(self, defaults: dict, user_options: dict, given: Sequence[str],
                     comm) -> None:
        """The options (the user's over ``defaults``) read by vpcontact and by the SNES, KSP and
        PC as they are set up; those of the user's that nothing read are refused."""
        given_options, user_options = user_options, viewer_flags(user_options)
        check_values(user_options)
        self._options = {**defaults, **user_options}
        self._reads = OptionReads(key for key in given if key in self._options)
        try:
            self._own = read_step_options(self.prefix, self._options,
                                          preconditioners.check_options)
            self.test = ConvergenceTest(self._nodal, self._own.stall_rtol,
                                        self._own.stagnation_its, self._own.force_rtol)
            self._setup(self.snes)
        except (PETSc.Error, ValueError) as err:
            _forget(self.prefix, self._options)
            raise rejected_option(err, given_options) from None
        self._reads.note(self.prefix)
        _forget(self.prefix, self._options)
        self._types = SolverTypes(self.snes, self._linear_given)
        #: the step's solver types as set up, e.g. ``SNES newtonls, KSP preonly, PC lu``
        self.solvers = self._types.solvers
        self._types.refuse_unread(self._reads, comm)
        self._retries = StepRetries(self, self._nodal, self._own.rescue_line_search)

    def _init_state(self) -> None:
        """The lagged VI solver, the bounds, the loaded iterate, the counters and timings."""
        self.lagged_lu: Optional[LaggedDirectSolve | LaggedMultigrid] = None
        self._free_snes: Optional[PETSc.SNES] = None  # unconstrained Newton of a VI problem
        self._bounds = None
        mesh = self.u.function_space.mesh
        self._vi = VIBounds(self.fields, self._P, self.scale, mesh_extent(mesh), mesh.comm)
        self.total_iterations = 0
        self.jacobian_assemblies = 0
        self.last_reason = ""  # converged reason of the last successful solve
        self.vi_solves = 0  # SNES VI runs (Signorini steps not settled by plain Newton)
        PETSc.Log.begin()  # PETSc's event log, for the time spent in KSPSolve
        self._ksp_event = PETSc.Log.Event("KSPSolve")

    @property
    def kernel_calls(self) -> int:
        """Runs of the refresh hook (the kernels)."""
        return self._assembly.kernel_calls

    @kernel_calls.setter
    def kernel_calls(self, value: int) -> None:
        self._assembly.kernel_calls = value

    @property
    def stagnated(self) -> bool:
        """The last run stopped because it stagnated (:mod:`.convergence`)."""
        return self.test.stagnated

    def unknowns_array(self) -> np.ndarray:
        """SNES's unknowns of the last solve (this rank's entries)."""
        return self._x.getArray(readonly=True)

    @property
    def unknowns(self) -> int:
        """Global size of SNES's unknown (every field)."""
        return self._x.getSize()

    def unread_options(self) -> list[str]:
        """The user's options that no solve read and that the run's solves would have read if
        PETSc knew them (:func:`~.option_reads.judged_after_solves`); empty before any solve
        ran with the options in PETSc's database. Collective."""
        return self._types.unread_after_solves(self._reads, self.u.function_space.mesh.comm)

    def _setup(self, snes: PETSc.SNES) -> None:
        snes.setFunction(self._assembly.residual, self._b)
        snes.setJacobian(self._jacobian, self._A)
        snes.setFromOptions()
        snes.getKSP().setFromOptions()
        if self._block is not None:
            self._block.configure(snes.getKSP().getPC())
        snes.setConvergenceTest(self.test)

    def set_bounds(self, lower: PETSc.Vec, upper: PETSc.Vec) -> None:
        """Bounds lower ≤ u ≤ upper (physical units) of a variational inequality (SNES VI).

        Also creates a plain Newton solver for the same equations under the same options:
        :meth:`solve` with ``try_unconstrained=True`` runs it first and keeps its solution when
        that satisfies the bounds (then it solves the VI too, with no active constraint).
        """
        if not self.snes.getType().startswith("vi"):
            raise SolverOptionError(f"snes_type {self.snes.getType()!r} cannot take the bounds "
                                    "of rigid contact (Signorini): use vinewtonrsls or "
                                    "vinewtonssls", "snes_type")
        self._bounds = self._vi.set(lower, upper)
        self.snes.setVariableBounds(*self._bounds)
        if self._own.vi_linear != "petsc" and self.snes.getType() == "vinewtonrsls":
            self._use_lagged_solver()
        self._create_free_snes()

    def _create_free_snes(self) -> None:
        """Plain Newton under ``<prefix>free_``: the same options, except the type (and the
        VI's line search)."""
        free_prefix = self.prefix + "free_"
        opts = PETSc.Options()
        for key, value in self._options.items():
            opts[free_prefix + key] = value
        opts[free_prefix + "snes_type"] = "newtonls"
        if self.snes.getType() != "newtonls" and "snes_linesearch_type" not in self._options:
            opts[free_prefix + "snes_linesearch_type"] = "basic"
        self._free_snes = PETSc.SNES().create(self.u.function_space.mesh.comm)
        self._free_snes.setOptionsPrefix(free_prefix)
        self._setup(self._free_snes)
        self._reads.note(free_prefix)
        _forget(free_prefix, {**self._options, "snes_type": 0, "snes_linesearch_type": 0})

    def update_bounds(self, lower: PETSc.Vec, upper: PETSc.Vec) -> None:
        """New values (physical units) for the bounds given to :meth:`set_bounds` (a moving
        obstacle); the vectors passed are destroyed."""
        self._vi.update(lower, upper)

    def checkpoint(self) -> tuple[dict, dict]:
        """(flags and counters, arrays) to continue exactly after a restart (see
        :mod:`vpcontact.output.checkpoint`)."""
        flags = {"total_iterations": self.total_iterations,
                 "jacobian_assemblies": self.jacobian_assemblies, "kernel_calls": self.kernel_calls,
                 "vi_solves": self.vi_solves, "last_reason": self.last_reason,
                 "jacobian_dt": self._jacobian_dt}
        arrays = {}
        if isinstance(self.lagged_lu, LaggedDirectSolve):
            flags["lagged"], arrays = self.lagged_lu.checkpoint()
        return flags, arrays

    def restore(self, flags: dict, arrays: dict) -> None:
        """Continue from :meth:`checkpoint`. A constant Jacobian is assembled again at the next
        solve (the same values: the same state and step size) without expiring the restored
        factors; the lagged multigrid (if used) rebuilds its hierarchy."""
        self.total_iterations = int(flags["total_iterations"])
        self.jacobian_assemblies = int(flags["jacobian_assemblies"])
        self.kernel_calls = int(flags["kernel_calls"])
        self.vi_solves = int(flags["vi_solves"])
        self.last_reason = flags["last_reason"]
        self._restored_jacobian_dt = flags["jacobian_dt"]
        if "lagged" in flags and isinstance(self.lagged_lu, LaggedDirectSolve):
            self.lagged_lu.restore(flags["lagged"], arrays)

    def _use_lagged_solver(self) -> None:
        """Reduced VI systems solved with a kept full-size preconditioner (:mod:`.vi_solver`)."""
        aimed = self._block is not None and (self.constant_jacobian or self.jacobian_per_step)
        lag = LagPolicy(self.snes, self.test, self._own.lag_below,
                        lambda: self.constant_jacobian or self.jacobian_per_step)
        self.lagged_lu = use_lagged_solver(
            self.snes, self._A, self.prefix, self._options, self._own.vi_linear,
            lambda: self._modes or rigid_body_modes(self.u.function_space, self._P,
                                                    layout=self.fields),
            self._block, lag, aimed, self._bounds)
        self.test.aimed = aimed

    def _jacobian(self, snes, x, A_snes, P) -> None:
        if self.constant_jacobian and self._jacobian_dt == self.dt:
            return  # A unchanged: the preconditioner (factorization) is reused as it is
        if self.jacobian_per_step and self._jacobian_step_key == self._step_key:
            # The same matrix within the step: direct factors are kept; a multigrid hierarchy
            # is rebuilt for the new active set (kept, it cost 1.1-2x the Krylov iterations)
            expire_if(self.lagged_lu, multigrid_only=True)
            return
        self._assembly.jacobian(x, A_snes, self._bounds)
        start = _time.perf_counter()
        if self._block is not None:
            self._block.update()
        self._jacobian_dt = self.dt
        self._jacobian_step_key = self._step_key
        self.jacobian_assemblies += 1
        restored, self._restored_jacobian_dt = self._restored_jacobian_dt, None
        if self.constant_jacobian and self.lagged_lu is not None and self.dt != restored:
            self.lagged_lu.expire()  # a new step size: the factors of M are out of date
        if self.jacobian_per_step and self.lagged_lu is not None:
            self.lagged_lu.expire()  # a new step: so are they
        self.timings["jacobian"] += _time.perf_counter() - start

    def solve(self, time: float, step: int, try_unconstrained: bool = False) -> int:
        """Solve from the current ``u`` as initial guess; return the Newton iteration count.

        With bounds and ``try_unconstrained``, plain Newton runs first; its solution is kept when
        it converged within the bounds, otherwise the VI is solved from the initial guess.

        Raises:
            ConvergenceError: SNES (or its linear solver) did not converge; ``u`` is then left at
                the last iterate and must not be used as a result.
        """
        self._step_key = (time, self.dt)
        self.test.force_scale = self._assembly.assemble_loads()
        self._assembly.initial_guess()
        if self._bounds is not None:
            self._vi.snap(self._x)
        self.predict()  # (new step: same u, but new dt, loads and committed state)
        start = _time.perf_counter()  # (kernel and assembly outside SNES count as SNES work,
        self.test.round_off_scale = max(self.test.force_scale,
                                        self._assembly.free_residual_norm())
        self.timings["snes"] += _time.perf_counter() - start  # so that the split adds up)
        its = 0
        snes = self.snes
        if try_unconstrained and self._free_snes is not None:
            guess = self._x.copy()
            reason, free_its = self._run(self._free_snes)
            its += free_its
            if reason > 0 and self._vi.feasible(self._x):
                snes = self._free_snes
            else:
                guess.copy(self._x)
            guess.destroy()
        if snes is self.snes:
            reason, more = self._retries.run()
            its += more
            self.vi_solves += self._bounds is not None
        self._end_solve(snes, reason, its, time, step)
        return its

    def _end_solve(self, snes: PETSc.SNES, reason: int, its: int, time: float,
                   step: int) -> None:
        """Load the last iterate (where finite or converged); raise where SNES did not
        converge."""
        finite = self.u.function_space.mesh.comm.allreduce(
            bool(np.isfinite(self._x.array).all()), op=MPI.LAND)
        start = _time.perf_counter()
        if reason > 0 or finite:  # (a diverged, non-finite iterate is not loaded: the kernels
            self._assembly.load_iterate(self._x)  # refuse it, and the caller rolls the step back)
        self.timings["snes"] += _time.perf_counter() - start
        if reason <= 0:
            ksp_reason = snes.getKSP().getConvergedReason()
            detail = f"last linear solve reason {ksp_reason}" if ksp_reason < 0 else ""
            name = reason_name(reason)
            if self.stagnated and reason == _SNES_REASON.DIVERGED_DTOL:
                name = self.test.stagnation_message()
            raise ConvergenceError(name, its, time, step, detail)
        self.last_reason = reason_name(reason)
        if self._bounds is not None:
            self._vi.record_active(self._x)

    # The runner of the retries (:mod:`.retries`)
    @property
    def x(self) -> PETSc.Vec:
        """SNES's unknown (the iterate the runs start from and end at)."""
        return self._x

    @property
    def usual_line_search(self) -> str:
        """The step's line search (restored after a retry's own)."""
        return self._options.get("snes_linesearch_type", "basic")

    def predict(self) -> None:
        """The nodal terms' first guesses in x (for a first try of self._first_try
        iterations); nothing loaded is current any more."""
        for term in self._nodal:
            term.predict(self._x, self._first_try)
        self._assembly.loaded_valid = False

    def invalidate(self) -> None:
        """x was changed outside SNES: the loaded iterate is no longer current."""
        self._assembly.loaded_valid = False

    def read_multipliers(self, x: PETSc.Vec) -> None:
        """The residual at x, evaluated for the nodal terms: they read their multipliers λ."""
        self._assembly.read_multipliers(x)

    def run(self) -> tuple[int, int]:
        """One run of the step's SNES from x: (converged reason, iterations)."""
        return self._run(self.snes)

    def _run(self, snes: PETSc.SNES) -> tuple[int, int]:
        """One SNES solve from self._x: (converged reason, iterations)."""
        start = _time.perf_counter()
        ksp_start = self._ksp_event.getPerfInfo()["time"]
        # The options are in PETSc's database only while SNES runs (it holds 512 entries per
        # process): inner solvers read theirs when they are first set up, in the solve (the
        # field split's blocks, multigrid levels, MUMPS). Not under the lagged VI solver (a
        # python KSP that keeps its own options): SNES VI sets its KSP from the options at
        # every iteration, which would replace it.
        lagged = snes.getKSP().getType() == "python"
        with options_in_database(snes.getOptionsPrefix(), {} if lagged else self._options):
            try:
                snes.solve(None, self._x)
            finally:
                if not lagged:  # (before the options leave the database: see .option_reads)
                    self._reads.note(snes.getOptionsPrefix())
                    self._reads.solves += 1
        self.timings["snes"] += _time.perf_counter() - start
        self.timings["linear_solve"] += self._ksp_event.getPerfInfo()["time"] - ksp_start
        its = snes.getIterationNumber()
        self.total_iterations += its
        return snes.getConvergedReason(), its

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for obj in (self.snes, self._free_snes, self._block):
            if obj is not None:
                obj.destroy()
        self._assembly.destroy()
