# SPDX-License-Identifier: MIT
"""One time step as a PETSc SNES solve (its options and reason names: :mod:`.snes_options`).

:class:`StepSolver` assembles the residual and Jacobian of a dolfinx problem whose coefficients
must be refreshed before every assembly (here: the quadrature-point stress and tangent, computed
by the C++ kernels from the current iterate). It follows dolfinx's ``fem/petsc.py`` pattern:
every solver has a rank-independent options prefix, user options pass through the PETSc options
database, and the converged reason is checked after every solve.
"""

from __future__ import annotations

import contextlib
import itertools
import time as _time
from typing import Callable, Optional, Sequence

import numpy as np
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.model.extent import mesh_extent
from vpcontact.errors import ConvergenceError, InputError, SolverOptionError
from vpcontact.solver import linear as linear_solvers
from vpcontact.solver import p_multigrid
from vpcontact.solver.option_reads import (OptionReads, decided_at_setup, judged_after_solves,
                                           unread_error)
from vpcontact.solver.snes_options import (_SNES_REASON, DEFAULT_OPTIONS, _forget, reason_name,
                                          check_values, rejected_option, viewer_flags)
from vpcontact.solver.vi_linear import (LaggedDirectSolve, LaggedMultigrid, options_in_database,
                                        rigid_body_modes)

_counter = itertools.count()
#: Newton iterations of a failed step's second try with the rescue line search
#: (:meth:`StepSolver._rescue`): a quick attempt before the step is cut (where it converged, it
#: took 7; in a scene whose dragging steps fail either way, 50 more per failed step cost 1 184
#: iterations in the run against 680)
RESCUE_ITERATIONS = 15
#: Newton iterations of each stage of a nodal term's predictor (:meth:`StepSolver._predictor`)
PREDICTOR_ITERATIONS = 20
#: The try before a predictor (:meth:`StepSolver._run_with_fallback`) gives up once this many
#: Newton iterations in a row have not halved its best ||F||: a crawl the predictor cuts short.
#: On the dragged block's hard step (its slip zone spreading over the face) 19 / 21 / 22 / 27
#: Newton iterations on 64×16 / 128×32 / 256×64 / 512×128 cells became 13 / 15 / 16 / 21; the
#: squeezed block's first step 19 → 15 and the rigid-and-compliant scene 109 → 106 in its run;
#: every other step and the viscoplastic scratch benchmark took what they took (2: the dragged
#: block's first dragging step, which converges in 6–7, went to the predictor: 10–12). Not
#: while a term is still bringing nodes back into their cones (``holding``: friction's
#: unloading nodes, :meth:`~vpcontact.model.nodal_friction.NodalFriction._unloading`): on
#: 512×128 cells the hard step converges at the 12th iteration, and stopped at the 11th, it
#: took 31 through the predictor
CRAWL_ITERATIONS = 3
#: A first try (:meth:`StepSolver._run_with_fallback`) whose budget runs out while its last
#: iteration cut ||F|| by at least this factor is in Newton's fast phase: it goes on, for at
#: most FINISHING_ITERATIONS more, from where it is (and toward the same target), instead of
#: starting again from the other guess. The paper's 3-D beam on a compliant foundation with
#: Tresca friction and the mixed formulation (6×2×2 cells, k = 0.02): the first try fell 0.117 →
#: 9.1e-4 in its 5 iterations (ratios 0.47, 0.16, 0.18 at the end), the sticking guess then
#: started at 1.15 and crawled for 50, and the run took 24 steps for 10 (17 cut, 24.5 s).
FINISHING_RATIO, FINISHING_ITERATIONS = 0.25, 5
#: The other guess's try (a compliant part's sticking guess) stops when after this many Newton
#: iterations its best ||F|| is still above its own first one and above the first try's last
#: one, and the step goes on from the first try's last iterate instead. On the beam above (P2
#: displacements or the mixed formulation) the sticking guess put the contact nodes back where
#: the last step left them, 10–100 times the extrapolation's ||F||, and from there Newton
#: wandered between 1.4 and 3 for 50 iterations where the first try was converging, slowly
#: (||F|| × 0.7–0.9 per iteration).
NO_PROGRESS_ITERATIONS = 5
#: A Newton iteration "stagnates" while ||F|| stays above this many times its best value in the
#: step (see :meth:`StepSolver._converged`).
STAGNATION_FACTOR = 10.0


def _longest_first_try(terms) -> int:
    """The longest ``first_try`` among nodal terms (None or absent: the term has no other
    guess); 0 when none has one."""
    tries = [getattr(term, "first_try", None) for term in terms]
    return max([n for n in tries if n is not None] or [0])


def _both_splits(options: dict, option: str, decide: Callable[[str, str], bool]) -> bool:
    """Whether ``decide(key, value)`` holds for the ``pmg_`` ``option`` of both of the mixed
    formulation's field splits (Newton's and SNES VI's lagged one; an invalid value counts as
    no: it is refused when the options are read)."""
    try:
        return all(decide(key, options.get(key, "auto"))
                   for key in (f"fieldsplit_u_pmg_{option}", f"lagged_fieldsplit_u_pmg_{option}"))
    except ValueError:
        return False


def _uses_stars(options: dict, rows: int) -> bool:
    """Whether both field splits smooth a displacement block of ``rows`` rows over the stars."""
    return _both_splits(options, "smooth_stars",
                        lambda key, value: p_multigrid.uses_stars(key, value, rows))


def _uses_coarse_schur(options: dict) -> bool:
    """Whether both field splits' Schur blocks take the cycle's coarse term (with the stars)."""
    return _both_splits(options, "schur_coarse", p_multigrid.uses_coarse_schur)


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
            stop (see :meth:`_converged`). None: the initial residual alone sets that scale.
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
            :meth:`_run_with_fallback`), ``second_try``/``freeze(stick)``/``thaw()`` (a
            predictor from that guess, see :meth:`_predictor`; ``holding``: the crawl stop
            waits, :data:`CRAWL_ITERATIONS`), ``prepare_jacobian(x)``
            (before the UFL Jacobian's assembly) and ``current(x)`` (friction on Signorini parts, the obstacle's normals,
            the sticking guess of friction on compliant parts;
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
        u = self.u
        self.bcs = list(bcs)
        self._refresh = refresh
        self._P = variables
        self._nodal = list(nodal_terms)
        #: the longest first try a term with another guess may ask for, which :meth:`solve`
        #: tells the terms' ``predict``
        self._first_try = _longest_first_try(self._nodal)
        driven = variables is not None and not variables.square
        self._b = variables.create_vector() if driven else fields.create_vector()
        self._xp = fields.physical_vector()  # the physical unknowns (u's own vector for u alone)
        self._columns = fields.column_scales(self.scale)  # None: every column scaled by scale
        self._load = fem.form(load) if load is not None else None
        self._load_vec = u.vector.duplicate() if load is not None or point_forces is not None else None
        self._bc_dofs = np.concatenate([bc.dof_indices()[0] for bc in self.bcs] or
                                       [np.zeros(0, dtype=np.int32)])
        self._force_scale = 0.0
        self._round_off_scale = 0.0
        self._b_free = None  # residual without Dirichlet conditions (the round-off scale)
        self._point_forces = point_forces
        self.constant_jacobian = constant_jacobian
        self.jacobian_per_step = jacobian_per_step and not constant_jacobian
        self._step_key = None  # (t_n, k) of the solve under way (jacobian_per_step)
        self._jacobian_step_key = None  # ... and of the assembled Jacobian
        self._jacobian_dt: Optional[float] = None  # step size of the assembled constant Jacobian
        self._restored_jacobian_dt: Optional[float] = None  # the same before a restart
        self.dt = 0.0  # set by the owner before each solve (only the constant-Jacobian reuse reads it)
        self._A = fields.create_matrix()
        self._b_phys = self._A_phys = None  # physical residual and Jacobian (with P)
        if variables is not None:
            self._b_phys = fields.create_vector()
            self._A_phys = self._A
            fields.assemble_jacobian(self._A_phys, self.bcs)  # a pattern for PtAP
            self._A = variables.jacobian(self._A_phys)
        self._x = variables.create_vector() if driven else fields.create_vector()
        self._xs = None  # scratch: the physical unknowns in SNES units (with P)
        comm = u.function_space.mesh.comm
        self.prefix = options_prefix or f"vpcontact_step_{next(_counter)}_"

        self.snes = PETSc.SNES().create(comm)
        self.snes.setOptionsPrefix(self.prefix)
        mixed = len(fields.functions) > 1
        self._linear_given = linear
        self.linear = linear_solvers.choose(linear, self._x.getSize(),
                                            "mixed" if mixed else "displacement",
                                            per_step=self.jacobian_per_step,
                                            iterative_possible=not driven)
        self._modes = None  # rigid-body modes (in the SNES layout), for multigrid
        self._block = None  # the fieldsplit set-up of the mixed formulation
        defaults = dict(DEFAULT_OPTIONS)
        if self.linear == "iterative" and driven:
            raise InputError("an obstacle driven by a force needs the direct linear solver "
                             "(linear = \"direct\")", key="solver.linear")
        if self.linear == "iterative":
            defaults.update(linear_solvers.iterative_options(mixed))
            defaults.update({"lagged_" + k: v
                             for k, v in linear_solvers.lagged_options(mixed).items()})
            defaults["vpcontact_vi_linear"] = "lagged_gamg"
            self._modes = rigid_body_modes(u.function_space, variables, layout=fields)
            if mixed:
                rotation = None if variables is None else variables.matrix
                rows = fields.field_indices()["displacement"].getSize()
                stars = _uses_stars(petsc_options or {}, rows)
                coarse = _uses_coarse_schur(petsc_options or {})
                if coarse and not stars:
                    raise SolverOptionError(
                        "pmg_schur_coarse needs the vertex-star smoothing: give "
                        "pmg_smooth_stars = true to both field splits (fieldsplit_u_ and "
                        f"lagged_fieldsplit_u_), or leave it to auto with at least "
                        f"{p_multigrid.STARS_FROM} displacement unknowns (here {rows})",
                        "fieldsplit_u_pmg_schur_coarse")
                if coarse:  # the stars' Schur complement with the cycle's coarse term
                    defaults = linear_solvers.coarse_schur_options(defaults)
                elif stars:  # the Schur complement from the stars' factors
                    defaults = linear_solvers.star_schur_options(defaults)
                self._block = linear_solvers.BlockPreconditioner(
                    fields, self._modes, self.scale, prefix=self.prefix, rotation=rotation,
                    stars=stars, coarse=coarse)
            else:
                self._A.setNearNullSpace(self._modes)
        petsc_options = viewer_flags(petsc_options or {})
        check_values(petsc_options)
        self._options = {**defaults, **petsc_options}
        self._reads = OptionReads(key for key in given if key in self._options)
        try:
            self._read_options()
            self._setup(self.snes)
        except (PETSc.Error, ValueError) as err:
            _forget(self.prefix, self._options)
            raise rejected_option(err, petsc_options or {}) from None
        self._reads.note(self.prefix)
        _forget(self.prefix, self._options)
        self._refuse_unread(comm)
        self.lagged_lu: Optional[LaggedDirectSolve | LaggedMultigrid] = None
        self._aimed_solves = False  # Krylov tolerances set per Newton iteration (_converged)
        self._free_snes: Optional[PETSc.SNES] = None  # unconstrained Newton of a VI problem
        self._bounds = None
        self._last_active: Optional[np.ndarray] = None  # the last solve's active bounds
        mesh = self.u.function_space.mesh
        self._extent = mesh_extent(mesh)
        self._fnorm0 = 0.0
        self._fnorm0_kept: Optional[float] = None  # ||F_0|| of a try that goes on (see above)
        self._last_ratio = 1.0  # ||F|| of the last iteration against the one before
        self._best, self._above, self.stagnated = 0.0, 0, False  # (see _converged)
        self._crawl_its = 0
        self._no_progress_its = 0  # (see NO_PROGRESS_ITERATIONS)
        self._no_progress_level = np.inf  # ... and the ||F|| a try must get below
        self._start = 0.0  # ||F|| at the solve's first iterate
        self._loaded = self._x.duplicate()  # the iterate whose refresh is current
        self._loaded_valid = False
        self.total_iterations = 0
        self.jacobian_assemblies = 0
        self.last_reason = ""  # converged reason of the last successful solve
        self.vi_solves = 0  # SNES VI runs (Signorini steps not settled by plain Newton)
        self.kernel_calls = 0
        #: wall time [s] spent in the refresh hook (kernels), residual and Jacobian assembly,
        #: in PETSc's KSPSolve (linear solves, factorizations included) and in SNES solves
        #: altogether (the rest of which is VI/active-set work, line searches and vector work)
        self.timings = {"kernel": 0.0, "residual": 0.0, "jacobian": 0.0, "linear_solve": 0.0,
                        "snes": 0.0}
        PETSc.Log.begin()  # PETSc's event log, for the time spent in KSPSolve
        self._ksp_event = PETSc.Log.Event("KSPSolve")

    def unknowns_array(self) -> np.ndarray:
        """SNES's unknowns of the last solve (this rank's entries)."""
        return self._x.getArray(readonly=True)

    @property
    def unknowns(self) -> int:
        """Global size of SNES's unknown (every field)."""
        return self._x.getSize()

    def _read_options(self) -> None:
        """Put the options into PETSc's database under this solver's prefix and read
        vpcontact's own (the SNES, KSP and PC read theirs in :meth:`_setup`)."""
        opts = PETSc.Options()
        opts.prefixPush(self.prefix)
        try:
            for key, value in self._options.items():
                opts[key] = value
            self._stall_rtol = float(opts.getReal(self.prefix + "vpcontact_stall_rtol"))
            self._stagnation_its = int(opts.getReal(self.prefix + "vpcontact_stagnation_its"))
            self._force_rtol = float(opts.getReal(self.prefix + "vpcontact_force_rtol"))
            self._lag_below = float(opts.getReal(self.prefix + "vpcontact_vi_lag_below"))
            self._vi_linear = opts.getString(self.prefix + "vpcontact_vi_linear")
            self._rescue_line_search = opts.getString(
                self.prefix + "vpcontact_rescue_linesearch", "")
        finally:
            opts.prefixPop()
        if self._rescue_line_search not in ("", "basic", "bt", "l2", "cp", "nleqerr"):
            raise ValueError("vpcontact_rescue_linesearch must be one of basic, bt, l2, cp, "
                             f"nleqerr or empty (none), got {self._rescue_line_search!r}")
        if self._vi_linear not in ("lagged_lu", "lagged_gamg", "petsc"):
            raise ValueError("vpcontact_vi_linear must be lagged_lu, lagged_gamg or petsc, got "
                             f"{self._vi_linear!r}")
        if not 0.0 <= self._force_rtol < 1.0:
            raise ValueError(f"vpcontact_force_rtol must be in [0, 1), got {self._force_rtol}")
        if not 0.0 < self._stall_rtol < 1.0:
            raise ValueError(f"vpcontact_stall_rtol must be in (0, 1), got {self._stall_rtol}")
        if self._stagnation_its < 0:
            raise ValueError("vpcontact_stagnation_its must be >= 0 (0: off), got "
                             f"{self._stagnation_its}")
        p_multigrid.check_options(self._options)

    def _refuse_unread(self, comm) -> None:
        """Refuse the user's options that nothing read at set-up, among those every reader of
        has run by then (:func:`~.option_reads.decided_at_setup`; collective)."""
        ksp = self.snes.getKSP()
        #: the step's solver types as set up, e.g. ``SNES newtonls, KSP preonly, PC lu``
        self.solvers = (f"SNES {self.snes.getType()}, KSP {ksp.getType()}, "
                        f"PC {ksp.getPC().getType()}")
        # ksp_/pc_ options are judged at set-up only where the user chose the direct solver:
        # under "auto" they may be meant for the iterative one, which larger meshes get (a
        # warning after the solves then says the direct solver did not read them)
        self._direct = (ksp.getType() == "preonly"
                        and ksp.getPC().getType() in ("lu", "cholesky"))
        self._direct_chosen = self._direct and self._linear_given == "direct"
        unread = self._reads.unread(comm, lambda key: decided_at_setup(key, self._direct_chosen))
        if unread:
            own = [key for key in DEFAULT_OPTIONS if key.startswith("vpcontact_")]
            raise unread_error(unread, self.solvers, own)

    def unread_options(self) -> list[str]:
        """The user's options that no solve read and that the run's solves would have read if
        PETSc knew them (:func:`~.option_reads.judged_after_solves`); empty before any solve
        ran with the options in PETSc's database. Collective."""
        comm = self.u.function_space.mesh.comm
        if not comm.allreduce(self._reads.solves, op=MPI.MAX):
            return []
        return self._reads.unread(comm, lambda key: not decided_at_setup(key, self._direct_chosen)
                                  and judged_after_solves(key, self._direct))

    def _setup(self, snes: PETSc.SNES) -> None:
        snes.setFunction(self._residual, self._b)
        snes.setJacobian(self._jacobian, self._A)
        snes.setFromOptions()
        snes.getKSP().setFromOptions()
        if self._block is not None:
            self._block.configure(snes.getKSP().getPC())
        snes.setConvergenceTest(self._converged)

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
        lower, upper = (self._embedded(lower, PETSc.NINFINITY),
                        self._embedded(upper, PETSc.INFINITY))
        for vec in (lower, upper):
            finite = np.abs(vec.array) < PETSc.INFINITY
            vec.array[finite] /= self.scale
        self._bounds = (lower, upper)
        self.snes.setVariableBounds(lower, upper)
        if self._vi_linear != "petsc" and self.snes.getType() == "vinewtonrsls":
            self._use_lagged_solver()
        # Same options under "<prefix>free_", except the type (and the VI's line search).
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

    def _embedded(self, vec_u: PETSc.Vec, fill: float) -> PETSc.Vec:
        """A bound on u as a vector of the SNES layout (other fields: ``fill``); ``vec_u`` is
        destroyed when a new vector is made."""
        vec = self.fields.embed(vec_u, fill)
        if vec.handle != vec_u.handle:
            vec_u.destroy()
        if self._P is not None:
            full = self._P.extend(vec, fill)
            if full.handle != vec.handle:
                vec.destroy()
            vec = full
        return vec

    def update_bounds(self, lower: PETSc.Vec, upper: PETSc.Vec) -> None:
        """New values (physical units) for the bounds given to :meth:`set_bounds` (a moving
        obstacle); the vectors passed are destroyed."""
        lower, upper = (self._embedded(lower, PETSc.NINFINITY),
                        self._embedded(upper, PETSc.INFINITY))
        for new, old in zip((lower, upper), self._bounds):
            finite = np.abs(new.array) < PETSc.INFINITY
            new.array[finite] /= self.scale
            new.copy(old)
            new.destroy()

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
        """Reduced VI systems solved with a kept full-size preconditioner (vpcontact.solver.vi_linear)."""
        inner = {k[len("lagged_"):]: v for k, v in self._options.items()
                 if k.startswith("lagged_")}
        if self._vi_linear == "lagged_lu":
            self.lagged_lu = LaggedDirectSolve(self.snes, self._A, self.prefix + "lagged_", inner)
            self.lagged_lu.lag_allowed = self._lag_allowed
        else:
            modes = self._modes or rigid_body_modes(self.u.function_space, self._P,
                                                    layout=self.fields)
            self.lagged_lu = LaggedMultigrid(self.snes, self._A, self.prefix + "lagged_", modes,
                                             inner)
            if self._block is not None:  # a saddle point: GMRES, and the fields on M
                self.lagged_lu.allow_cg = False
                self.lagged_lu.configure = self._block.configure
                self._block.solver = self.lagged_lu  # its rebuilds: the block's policy
        ksp = self.snes.getKSP()
        ksp.setType("python")
        ksp.setPythonContext(self.lagged_lu)
        ksp.getPC().setType("none")  # the context solves; PETSc must not factorize J_II
        # Direct (lagged factors): GMRES to 1e-9 costs a few substitutions. The block
        # preconditioner of the mixed formulation: an inexact Newton step (rtol
        # ITERATIVE_RTOL) keeps Newton's iteration count (see vpcontact.solver.linear).
        rtol = linear_solvers.ITERATIVE_RTOL if self._block is not None else 1e-9
        ksp.setTolerances(rtol=rtol, atol=0.0)
        # With a Jacobian fixed within the step, each solve aims at what the step needs
        # (linear_solvers.step_rtol, set by _converged); one that stops short of it but within
        # ITERATIVE_RTOL is still a usable Newton direction.
        self._aimed_solves = (self._block is not None
                              and (self.constant_jacobian or self.jacobian_per_step))
        if self._aimed_solves:
            self.lagged_lu.accept_rtol = linear_solvers.ITERATIVE_RTOL
            self.lagged_lu.bounds = self._bounds
            self.lagged_lu.probe_rtol = linear_solvers.STEP_FIRST_RTOL

    def _lag_allowed(self) -> bool:
        """When to try lagged factors (measured on the paper's 3-D test, k = 0.01-0.02): with a
        constant tangent; at a step's first iteration (the last step's factors usually still
        fit); and once Newton is in its final phase, ||F|| <= vpcontact_vi_lag_below ||F_0||.
        In between, quadrature points still switch between the elastic and the plastic branch:
        allowing the lag there too (lag_below = 1) halves the factorizations but doubles the
        substitutions, a net loss of 30-45 %."""
        return (self.constant_jacobian or self.jacobian_per_step
                or self.snes.getIterationNumber() == 0
                or self.snes.getFunctionNorm() <= self._lag_below * self._fnorm0)

    #: Entries of the initial guess this close to a bound (a length relative to the mesh's
    #: extent) start on it.
    SNAP = 1e-9

    def _snap_to_bounds(self, x: PETSc.Vec) -> None:
        """Start SNES VI with the last step's active set: an entry that ended the last solve on a
        bound starts on that bound (which may have moved), and so does an entry within
        :data:`SNAP` × the mesh's extent of a bound. SNES VI takes a bound as active only
        within 1e-8 in x's units (about 1e-20 of the extent), which a contact node predicted
        by extrapolation misses when its bound moves (an obstacle with a motion, or driven by
        a force); an obstacle driven by a force whose nodes are all inactive has no
        equilibrium (a singular Jacobian). Entries whose residual pulls them off the bound
        are released by the VI itself."""
        array = x.getArray()
        near = self.SNAP * self._extent / self.scale  # in x's units
        for side, bound in zip((-1, 1), self._bounds):
            values = bound.getArray(readonly=True)
            finite = np.abs(values) < PETSc.INFINITY
            snap = finite & (np.abs(array - values) <= near)
            if self._last_active is not None:
                snap |= finite & (self._last_active == side)
            array[snap] = values[snap]

    def _record_active(self) -> None:
        """Which entries ended the solve on their lower (−1) or upper (+1) bound."""
        array = self._x.getArray(readonly=True)
        active = np.zeros(len(array), dtype=np.int8)
        for side, bound in zip((-1, 1), self._bounds):
            values = bound.getArray(readonly=True)
            finite = np.abs(values) < PETSc.INFINITY
            active[finite & (np.abs(array - values) <= 1e-8)] = side
        self._last_active = active

    def _feasible(self, x: PETSc.Vec) -> bool:
        """x within the bounds (to 1e-6 in units of x, i.e. round-off in physical units)."""
        lower, upper = self._bounds
        ok = bool(np.all(x.array <= upper.array + 1e-6) and np.all(x.array >= lower.array - 1e-6))
        return self.u.function_space.mesh.comm.allreduce(ok, op=MPI.LAND)

    def _converged(self, snes, it: int, norms) -> int:
        """PETSc's default test, applied to VI solvers too (their own test ignores snes_stol).

        Converged when ||F|| <= atol, or ||F|| <= rtol ||F_0||, or when the step is round-off
        relative to the solution (||dx|| <= stol ||x||) while ||F|| <= stall_rtol max(||F_0||,
        ||load||, ||f||): with E ~ 1e8 and accumulated strains ~ 1e-2 the residual cannot drop
        below ~ eps E |ε| however small the step's load increment (and so ||F_0||) is. f is
        the residual at the step's initial guess without Dirichlet conditions (its Dirichlet
        rows are the support reactions): in a run driven by prescribed displacements, with no
        load, it is what sets the round-off floor (a held step in stiff units, E = 1e9, stalled
        there).

        Diverged (``stagnated``) when ``vpcontact_stagnation_its`` iterations in a row have left
        ||F|| above STAGNATION_FACTOR times its best value so far (||F_0|| included): a step that
        overshoots the onset of plastic flow (the paper's 3-D beam at k = 0.02 on 18×6×6 cells
        and finer) wanders 17–300 times above ||F_0|| for its 50 iterations and never comes
        back, before the step is cut and its halves converge in 8 and 2; stopping it after 12
        saves three quarters of the wasted factorizations. Slow steps that do converge stay near
        their best meanwhile (a plane-strain Perzyna cantilever, mixed: ||F|| within 10 % of
        ||F_0|| for 20 iterations, then converged at the 41st) and are left alone.

        In a try that may stop where it crawls (``self._crawl_its``, see :meth:`_run_limited`),
        ``crawl_its`` iterations in a row that have not halved the best ||F|| stop it too, unless
        a nodal term is ``holding`` at the last Jacobian (see :data:`CRAWL_ITERATIONS`).

        Where the step's solves are aimed (a Jacobian fixed within the step, the block
        preconditioner), the next Krylov solve's tolerance is set here from ||F|| and the target
        (:func:`vpcontact.solver.linear.step_rtol`).

        The round-off stop also applies when ||F|| comes out the same to the last bit three
        times in a row: the iterate no longer moves. SNES VI's step, projected back onto the
        bounds, can leave it where it is while the step's own norm is not small: the scratch
        demo's pressing reached 3.14e-11 (rtol × ||F_0|| = 2.56e-11) and repeated it for 47
        iterations before the step was cut (twice in the run, 100 of its 320 iterations).
        """
        xnorm, ynorm, fnorm = norms
        rtol, atol, stol, _ = snes.getTolerances()
        if not np.isfinite(fnorm):
            return _SNES_REASON.DIVERGED_FNORM_NAN
        if it == 0:
            self._fnorm0 = fnorm if self._fnorm0_kept is None else self._fnorm0_kept
            self._last_ratio, self._start = 1.0, fnorm
            self._best, self._above, self.stagnated = fnorm, 0, False
            self._halved_at, self._halved_best = 0, fnorm
            self._repeats = 0
        else:
            self._above = self._above + 1 if fnorm > STAGNATION_FACTOR * self._best else 0
            if fnorm <= 0.5 * self._halved_best:
                self._halved_at, self._halved_best = it, fnorm
            self._best = min(self._best, fnorm)
            self._repeats = self._repeats + 1 if fnorm == self._last_fnorm else 0
            self._last_ratio = fnorm / self._last_fnorm if self._last_fnorm > 0 else 1.0
        self._last_fnorm = fnorm
        if fnorm <= atol or fnorm <= self._force_rtol * self._force_scale:
            return _SNES_REASON.CONVERGED_FNORM_ABS
        if self._aimed_solves:
            target = max(atol, self._force_rtol * self._force_scale, rtol * self._fnorm0)
            snes.getKSP().setTolerances(rtol=linear_solvers.step_rtol(it, fnorm, target),
                                        atol=0.0)
        if it == 0:
            return _SNES_REASON.ITERATING
        if fnorm <= rtol * self._fnorm0:
            return _SNES_REASON.CONVERGED_FNORM_RELATIVE
        at_round_off = fnorm <= self._stall_rtol * max(self._fnorm0, self._round_off_scale)
        if at_round_off and (ynorm <= stol * xnorm or self._repeats >= 2):
            # (or the same ||F||, to the last bit, three times: the iterate no longer moves —
            # SNES VI projecting each step back onto the bounds)
            return _SNES_REASON.CONVERGED_SNORM_RELATIVE
        if (self._crawl_its and it - self._halved_at >= self._crawl_its
                and not any(term.holding for term in self._nodal)):
            return _SNES_REASON.DIVERGED_DTOL
        if (self._no_progress_its and it >= self._no_progress_its
                and self._best >= min(self._start, self._no_progress_level)):
            return _SNES_REASON.DIVERGED_DTOL
        if self._stagnation_its and self._above >= self._stagnation_its:
            self.stagnated = True
            return _SNES_REASON.DIVERGED_DTOL
        return _SNES_REASON.ITERATING

    def _load_iterate(self, x: PETSc.Vec) -> None:
        # SNES may evaluate at vectors other than the solution: always copy x into u first.
        # The Jacobian is usually requested at the iterate whose residual was just computed:
        # then u and the quadrature state are current and the kernel need not run again.
        if self._loaded_valid and x.equal(self._loaded):
            return
        start = _time.perf_counter()
        xp = self._xp
        if self._P is None:
            x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            x.copy(xp)
        else:
            self._P.to_physical(x, xp)
        if self._columns is not None:
            xp.pointwiseMult(xp, self._columns)
        elif self.scale != 1.0:
            xp.scale(self.scale)
        self.fields.to_functions(xp)
        self._refresh()
        self.kernel_calls += 1
        x.copy(self._loaded)
        self._loaded_valid = True
        self.timings["kernel"] += _time.perf_counter() - start

    def _free_residual_norm(self) -> float:
        """||F|| at the initial guess with no Dirichlet condition applied: the interior
        imbalance and, in the Dirichlet rows, the support reactions (physical units)."""
        self._load_iterate(self._x)
        if self._b_free is None:
            self._b_free = self.fields.create_vector()
        start = _time.perf_counter()
        self.fields.assemble_residual(self._b_free, self._xp, [], self._free_point_forces())
        self.timings["residual"] += _time.perf_counter() - start
        return self._b_free.norm()

    def _free_point_forces(self):
        """(dofs, values) of the point forces at dofs no Dirichlet condition prescribes, or None."""
        if self._point_forces is None:
            return None
        dofs, values = self._point_forces()
        keep = ~np.isin(dofs, self._bc_dofs)
        return dofs[keep], values[keep]

    def _residual(self, snes, x, b_snes) -> None:
        self._load_iterate(x)
        start = _time.perf_counter()
        b = b_snes if self._P is None else self._b_phys
        # physical units: b = u - g on Dirichlet rows
        self.fields.assemble_residual(b, self._xp, self.bcs, self._free_point_forces())
        if self._P is not None:
            self._P.residual(b, b_snes)
        for term in self._nodal:
            term.residual(x, b_snes)
        self.timings["residual"] += _time.perf_counter() - start

    def _jacobian(self, snes, x, A_snes, P) -> None:
        if self.constant_jacobian and self._jacobian_dt == self.dt:
            return  # A unchanged: the preconditioner (factorization) is reused as it is
        if self.jacobian_per_step and self._jacobian_step_key == self._step_key:
            # The same matrix within the step: direct factors are kept; a multigrid hierarchy
            # is rebuilt for the new active set (kept, it cost 1.1-2x the Krylov iterations)
            if isinstance(self.lagged_lu, LaggedMultigrid):
                self.lagged_lu.expire()
            return
        self._load_iterate(x)
        start = _time.perf_counter()
        for term in self._nodal:
            term.prepare_jacobian(x)
        A = A_snes if self._P is None else self._A_phys
        self.fields.assemble_jacobian(A, self.bcs)
        if self._columns is not None:
            A.diagonalScale(None, self._columns)  # d(residual)/dx = d(residual)/du * scales
        elif self.scale != 1.0:
            A.scale(self.scale)  # d(residual)/dx = d(residual)/du * scale
        if self._P is not None:
            self._P.jacobian(A, A_snes)
            self._P.stabilize(A_snes, x, self._b, self._bounds)
        if self._nodal and not all(term.current(x) for term in self._nodal):
            # (the line search's last residual was elsewhere: λ must be read at x)
            self._read_multipliers(x)
        for term in self._nodal:
            term.jacobian(x, A_snes)
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
        self._force_scale = 0.0
        if self._load_vec is not None:
            with self._load_vec.localForm() as local:
                local.set(0.0)
            if self._load is not None:
                fem_petsc.assemble_vector(self._load_vec, self._load)
            self._load_vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            if self._point_forces is not None:
                dofs, values = self._point_forces()
                self._load_vec.array[dofs] += values
            fem_petsc.set_bc(self._load_vec, self.bcs, scale=0.0)
            self._force_scale = self._load_vec.norm()
        self.fields.from_functions(self._xp)
        xs = self._x
        if self._P is not None:
            if self._xs is None:
                self._xs = self._xp.duplicate()
            self._xp.copy(self._xs)
            xs = self._xs
        else:
            self._xp.copy(xs)
        if self._columns is not None:
            xs.pointwiseDivide(xs, self._columns)
        elif self.scale != 1.0:
            xs.scale(1.0 / self.scale)
        if self._P is not None:
            self._P.to_snes(xs, self._x)
        if self._bounds is not None:
            self._snap_to_bounds(self._x)
        self._predict()  # (new step: same u, but new dt, loads and committed state)
        start = _time.perf_counter()  # (kernel and assembly outside SNES count as SNES work,
        self._round_off_scale = max(self._force_scale, self._free_residual_norm())
        self.timings["snes"] += _time.perf_counter() - start  # so that the split adds up)
        its = 0
        snes = self.snes
        if try_unconstrained and self._free_snes is not None:
            guess = self._x.copy()
            reason, free_its = self._run(self._free_snes)
            its += free_its
            if reason > 0 and self._feasible(self._x):
                snes = self._free_snes
            else:
                guess.copy(self._x)
            guess.destroy()
        if snes is self.snes:
            start_guess = self._x.copy() if self._rescue_line_search else None
            reason, more = self._run_with_fallback()
            its += more
            if reason <= 0 and start_guess is not None and not self.stagnated:
                reason, more = self._rescue(start_guess)
                its += more
            if start_guess is not None:
                start_guess.destroy()
            self.vi_solves += self._bounds is not None
        finite = self.u.function_space.mesh.comm.allreduce(
            bool(np.isfinite(self._x.array).all()), op=MPI.LAND)
        start = _time.perf_counter()
        if reason > 0 or finite:  # (a diverged, non-finite iterate is not loaded: the kernels
            self._load_iterate(self._x)  # refuse it, and the caller rolls the step back)
        self.timings["snes"] += _time.perf_counter() - start
        if reason <= 0:
            ksp_reason = snes.getKSP().getConvergedReason()
            detail = f"last linear solve reason {ksp_reason}" if ksp_reason < 0 else ""
            name = reason_name(reason)
            if self.stagnated and reason == _SNES_REASON.DIVERGED_DTOL:
                name = (f"stagnated ({self._stagnation_its} iterations with a residual above "
                        f"{STAGNATION_FACTOR:g} × its best, {self._best:.3g})")
            raise ConvergenceError(name, its, time, step, detail)
        self.last_reason = reason_name(reason)
        if self._bounds is not None:
            self._record_active()
        return its

    def _predict(self) -> None:
        """The nodal terms' first guesses in self._x (for a first try of self._first_try
        iterations); nothing loaded is current any more."""
        for term in self._nodal:
            term.predict(self._x, self._first_try)
        self._loaded_valid = False

    def _rescue(self, guess: PETSc.Vec) -> tuple[int, int]:
        """The step once more from ``guess`` with the rescue line search
        (``vpcontact_rescue_linesearch``), before the caller cuts the step; the usual one is
        restored after it. (A block clamped at one end and squeezed by a frictionless rigid plane
        onto a rigid floor with Coulomb friction: the critical-point search stalled at every
        step size, ``l2`` converges in 7 iterations; ``l2`` alone cut the steps of other
        dragged blocks, README.)"""
        guess.copy(self._x)
        self._predict()
        with self._snes_settings(RESCUE_ITERATIONS, self._rescue_line_search):
            return self._run_with_fallback(predict=False)  # (a quick try: no predictor)

    def _read_multipliers(self, x: PETSc.Vec) -> None:
        """The residual at x, evaluated for the nodal terms: they read their multipliers λ."""
        scratch = self._b.duplicate()
        self._residual(self.snes, x, scratch)
        scratch.destroy()

    def _set_line_search(self, kind: str) -> None:
        """Switch SNES's line search (through PETSc's options: petsc4py 3.18 has no handle on
        it); every other setting keeps its value."""
        opts = PETSc.Options()
        key = self.prefix + "snes_linesearch_type"
        opts[key] = kind
        try:
            # (SNESSetFromOptions gives the KSP the full-size Jacobian again; SNES VI left it the
            # reduced one of its last iteration: reset it, as SNES VI does when the set changes)
            self.snes.getKSP().reset()
            self.snes.setFromOptions()
        finally:
            opts.delValue(key)

    def _run_with_fallback(self, predict: bool = True) -> tuple[int, int]:
        """SNES from the guess; where a nodal term has another guess (friction on a compliant
        part: sticking, see :class:`~vpcontact.model.friction.StickingGuess`), the first try
        stops after the longest ``first_try`` of the terms that have one this step (friction
        on a compliant part: 5, :data:`~vpcontact.model.friction.FIRST_TRY`, or 8 at the onset
        of contact; on a Signorini part 0: its extrapolated guess is kept only where it already
        solves the step) and, unconverged, SNES starts again from the other guess. Where a term
        has a predictor (Coulomb friction on a Signorini part: ``second_try`` = 15), that second
        try is limited too (and stops where it crawls, :data:`CRAWL_ITERATIONS`) and,
        unconverged, the step starts once more from the other guess with the predictor
        (:meth:`_predictor`; not if ``predict`` is False). (Iterations of all count.)"""
        having = [term.has_fallback() for term in self._nodal]  # (collective: no short cut)
        if not any(having):
            return self._run(self.snes)
        first_try = _longest_first_try([t for t, has in zip(self._nodal, having) if has])
        guess = self._x.copy()
        reason, first = self._run_limited(first_try)
        if reason <= 0 and first_try > 0 and self._last_ratio <= FINISHING_RATIO:
            reason, more = self._finish()
            first += more
        if reason > 0:
            guess.destroy()
            return reason, first
        predictors = [t for t, has in zip(self._nodal, having)
                      if predict and has and getattr(t, "second_try", None) is not None]
        tried, tried_norm = self._x.copy(), self._last_fnorm  # the first try's last iterate
        try:
            self._fall_back(guess)
            if not predictors:
                with self._snes_settings(no_progress=(NO_PROGRESS_ITERATIONS, tried_norm)):
                    reason, more = self._run(self.snes)
                if reason <= 0 and self._best >= min(self._start, tried_norm):
                    # no progress from the other guess: on from the first try's iterate
                    tried.copy(self._x)
                    self._loaded_valid = False
                    reason, last = self._run(self.snes)
                    more += last
                return reason, first + more
            reason, more = self._run_limited(max(t.second_try for t in predictors),
                                             crawl_its=CRAWL_ITERATIONS)
            if reason > 0:
                return reason, first + more
            self._fall_back(guess)
            reason, last = self._predictor(predictors)
        finally:
            guess.destroy()
            tried.destroy()
        return reason, first + more + last

    def _finish(self) -> tuple[int, int]:
        """A try that ran out of iterations in Newton's fast phase goes on from its last iterate
        (in self._x) toward the same target (its ||F_0||), :data:`FINISHING_ITERATIONS` more."""
        self._fnorm0_kept = self._fnorm0
        try:
            return self._run_limited(FINISHING_ITERATIONS)
        finally:
            self._fnorm0_kept = None

    def _fall_back(self, guess: PETSc.Vec) -> None:
        """self._x ← the terms' fallback guesses from ``guess`` (from the last try's iterate
        where a term takes something from it: friction on a compliant part at the onset)."""
        guess.copy(self._x)
        for term in self._nodal:
            term.fallback(self._x)
        self._loaded_valid = False

    def _predictor(self, terms) -> tuple[int, int]:
        """SNES from the fallback guess in self._x once the terms' predictor has moved it
        (Coulomb friction on a Signorini part, :meth:`~vpcontact.model.nodal_friction.
        NodalFriction.freeze`): first every pressed node sticks, then the thresholds are fixed
        at that iterate's (Tresca's law, whose Newton iteration spreads a slip zone in a few
        iterations; kept only where it converged), then the step is solved with the terms' own
        law from there, with the rescue line search if there is one (a block pressed by a rigid
        plane with friction onto a compliant floor with friction and dragged: no step cut and
        109 Newton iterations in the run, against 308 and a cut step with ``cp``). The first
        two stages have :data:`PREDICTOR_ITERATIONS` each. (Iterations of all count.)"""
        try:
            for term in terms:
                term.freeze(stick=True)
            _, its = self._run_limited(PREDICTOR_ITERATIONS)
            self._read_multipliers(self._x)
            for term in terms:
                term.freeze(stick=False)
            stuck = self._x.copy()
            reason, more = self._run_limited(PREDICTOR_ITERATIONS)
            its += more
            if reason <= 0:
                stuck.copy(self._x)
            stuck.destroy()
        finally:
            for term in terms:
                term.thaw()
        self._loaded_valid = False
        with self._snes_settings(line_search=self._rescue_line_search):
            reason, more = self._run(self.snes)
        return reason, its + more

    def _run_limited(self, max_its: int, crawl_its: int = 0) -> tuple[int, int]:
        """:meth:`_run` with at most ``max_its`` Newton iterations (fewer if SNES allows fewer);
        with ``crawl_its``, stopped (diverged) once that many in a row have not halved the best
        ||F|| (:data:`CRAWL_ITERATIONS`)."""
        with self._snes_settings(max_its, crawl_its=crawl_its):
            return self._run(self.snes)

    @contextlib.contextmanager
    def _snes_settings(self, max_its: Optional[int] = None, line_search: str = "",
                       crawl_its: int = 0, no_progress: tuple = (0, np.inf)):
        """SNES with at most ``max_its`` Newton iterations (None: as set; fewer if SNES allows
        fewer), the line search ``line_search`` (empty: the usual one, left alone), the crawl
        stop after ``crawl_its`` iterations and the no-progress stop ``no_progress`` (after so
        many iterations, the level to get below; 0: none; see :meth:`_converged` and
        :data:`NO_PROGRESS_ITERATIONS`) inside the block; all restored after it."""
        if line_search:
            self._set_line_search(line_search)
        max_it = self.snes.getTolerances()[3]
        if max_its is not None:
            self.snes.setTolerances(max_it=min(max_its, max_it))
        self._crawl_its = crawl_its
        self._no_progress_its, self._no_progress_level = no_progress
        try:
            yield
        finally:
            self._crawl_its = self._no_progress_its = 0
            self._no_progress_level = np.inf
            if max_its is not None:
                self.snes.setTolerances(max_it=max_it)
            if line_search:
                self._set_line_search(self._options.get("snes_linesearch_type", "basic"))

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
        for obj in (self.snes, self._free_snes, self._A, self._b, self._x, self._loaded, self._b_free,
                    self._load_vec, self._A_phys, self._b_phys, self._columns, self._block,
                    self._xs):
            if obj is not None:
                obj.destroy()
