# SPDX-License-Identifier: MIT
"""One simulation of a built scene and everything it writes.

Into the output folder: the XDMF series (u, stress, von Mises norm, viscoplastic strain and its
equivalent, contact pressure; if ``[output] xdmf``),
``contact.csv`` (per contact node and step: u_ν, gap, pressure p = −σ_ν; if
``[output] contact_csv``), ``probes.csv`` (``[output] probes``: u, stress and ε_vp at points),
``reactions.csv`` (per step: the reaction of each Dirichlet part and the contact force; always),
PNG figures of the final state, the contact history and the forces (if ``[output] figures``)
and always
``summary.json``: versions, scene hash, steps, Newton iterations, rejected steps with their
converged reasons, wall-time split and active-set sizes. A run that fails after its budget of
step halvings keeps the completed steps and is marked ``"completed": false``.
"""

from __future__ import annotations

import json
import shutil
import platform
import sys
import time
from pathlib import Path
from dataclasses import dataclass
from typing import Callable, Optional

import dolfinx
import numpy as np
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact import __version__
from vpcontact.errors import InputError, Interrupted, ObstacleOutOfReach, OutputError
from vpcontact.model.constitutive import Perzyna
from vpcontact.output import checkpoint, contact_figures, plots, runner
from vpcontact.output.fields import CellStress, ContactHistory, nodal_values, on_rank0
from vpcontact.output.probes import probe_history
from vpcontact.output.strains import ViscoplasticStrain
from vpcontact.output.forces import ForceHistory
from vpcontact.scene.builder import Model
from vpcontact.scene.schema import SceneError
from vpcontact.solver.snes_options import time_split

#: k E/μ* above which a run with the linearized Perzyna step is warned (see
#: Session._law_warnings)
LINEARIZED_STIFF_RATIO = 1e7
#: The largest strain |ε| (Frobenius) a run ends with before it is warned that its
#: small-strain model is out of its range (Session._strain_warnings). Not lower: strains
#: concentrate where loads are singular (a point load: 15 % at the paper's 2-D test's load
#: point, 10–30 % under the bundled indenters and the scratch tip), and those answers are the
#: paper's and the scenes' own.
SMALL_STRAIN_LIMIT = 0.5


@dataclass(frozen=True)
class SessionResult:
    """What a completed run reports (the command line prints it)."""

    name: str
    final_time: float
    steps: int
    newton_iterations: int
    rejected: int
    wall_time: float
    #: the Newton iterations of the rejected steps too (summary.json's newton_iterations_total)
    newton_iterations_total: int
    ranks: int
    out: Path
    warnings: tuple


class Session:
    """Run ``model`` to its final time, writing into ``out``.

    Args:
        progress: called after every step with (t, Newton iterations, active contact nodes or
            None), on every rank (the command line draws its progress bar on rank 0).
    """

    def __init__(self, model: Model, out: Path,
                 progress: Optional[Callable[[float, int, Optional[int]], None]] = None,
                 stop=None, resume: bool = False):
        self.model = model
        self.out = Path(out)
        self.comm = model.problem.mesh.comm
        self.progress = progress
        self.stop = stop  # a StopRequest (SIGINT/SIGTERM), asked after every step
        self.resume = resume
        self.restart = None

    def run(self) -> SessionResult:
        """Simulate; return what the completed run reports.

        Raises:
            Interrupted: a signal stopped the run (outputs, checkpoint and summary written).
            OutputError: an output could not be written (what could be written was).
        """
        scene, problem = self.model.scene, self.model.problem
        cells, strain, probes = self._cell_fields()  # (a probe off the mesh: refused here)
        if self.resume:
            self.restart = checkpoint.load(self.out, problem, scene, self.comm)
        else:  # a fresh run: an older run's checkpoint must not be resumed on top of it
            on_rank0(self.comm, lambda: shutil.rmtree(self.out / checkpoint.FOLDER,
                                                      ignore_errors=True))
        history = self._history()
        self.forces = ForceHistory(problem)
        checkpoints = checkpoint.Checkpointer(self.out, problem, scene, self.comm,
                                              scene.output.checkpoint_every)
        start = time.perf_counter()
        record = runner.RunRecord()
        error: Optional[Exception] = None
        try:
            options = runner.RunOptions(
                name=scene.name, xdmf=scene.output.xdmf, xdmf_every=scene.output.every,
                csv_name="contact.csv" if scene.output.contact_csv else None, verbose=False,
                max_cuts=scene.time.max_cuts, tolerance=scene.time.tolerance,
                abort_on_bug=True)
            parts = runner.RunParts(
                history=history, forces=self.forces,
                xdmf_extra=tuple(self._pressure_field(history)), progress=self._progress,
                stop=self.stop, checkpoints=checkpoints, restart=self.restart, record=record,
                cells=cells, strain=strain, probes=probes)
            _, history, cells = runner.run(problem, scene.time.T, scene.time.k, out=self.out,
                                           options=options, parts=parts)
        except Exception as err:  # re-raised below once the summary is on disk
            error = _located(scene, err)
        wall = time.perf_counter() - start
        if record is not None and record.interrupted and error is None:
            error = Interrupted(record.interrupted, record.times[-1] if record.times else 0.0)
        warnings = list(record.warnings) if record is not None else []
        warnings += self._contact_warnings(history, record) if error is None else []
        warnings += self._option_warnings() if error is None else []
        warnings += self._law_warnings() if error is None else []
        warnings += self._strain_warnings() if error is None else []
        held = self.model.problem.held  # a body held by its contacts that was unloaded
        warnings += held.warnings if held is not None and error is None else []
        try:
            self._write_summary(record, wall, error, warnings)
        except OSError as err:
            if error is None or isinstance(error, Interrupted):
                error = OutputError(f"cannot write {self.out / 'summary.json'}: {err}")
        if record is None or error is not None:
            raise error
        if scene.output.figures:
            self._figures(history, cells)
        self.comm.barrier()  # rank 0 has written every file
        return SessionResult(scene.name, record.times[-1], len(record.times),
                             sum(record.newton_iterations), len(record.cuts), wall,
                             self.model.problem.solver.total_iterations,
                             self.comm.size, self.out.resolve(), tuple(warnings))

    def _cell_fields(self) -> tuple:
        """The cell stress, the viscoplastic strain and the probes' history (None without
        ``[output] probes``); a probe outside the mesh is a located error (collective)."""
        problem = self.model.problem
        cells = CellStress.of(problem)
        strain = ViscoplasticStrain.of(problem, cells)
        try:
            probes = probe_history(problem, self.model.scene.output.probes, cells, strain)
        except InputError as err:
            if err.key is None:
                raise
            raise self.model.scene.error(err.key, str(err)) from None
        return cells, strain, probes

    def _contact_warnings(self, history: Optional[ContactHistory], record) -> list:
        """Per contact part: nodes whose rays miss the obstacle, and a part that never touched
        during the run (an obstacle that moved away, or never came into reach), with its
        closest approach (collective)."""
        if history is None:
            return []
        warnings = []
        for index, (name, missed) in enumerate(zip(history.names, history.unreachable())):
            if missed:
                warnings.append(
                    f"{missed} node(s) of the contact part '{name}' face away from the obstacle "
                    "(their normal rays miss it within max_distance, e.g. at the rim of a curved "
                    "face): no contact there (contact.csv: gap = max_distance)")
            approach = self.comm.bcast(history.closest_approach(index), root=0)
            if approach is None or approach["touched"]:
                continue
            point = ", ".join(f"{c:.4g}" for c in approach["point"][:self.model.scene.dim])
            warnings.append(
                f"the contact part '{name}' never touched the obstacle or foundation: closest "
                f"approach {approach['clearance']:.4g} at t = {approach['time']:.4g}, at "
                f"({point}); check its contact table (gap, obstacle and motion) if contact "
                "was expected")
        return warnings

    def _law_warnings(self) -> list:
        """The linearized Perzyna step far into its stiff range (k E/μ* above
        :data:`LINEARIZED_STIFF_RATIO`): where the body flows its tangent along the flow is
        that many times softer than E, nearly singular, and the displacements of a flowing
        region can come out ill-determined (a sweep's plane-strain block at 2.5e8: 60 times
        the exact displacement, exit 0; 2.5e7 and below were right). The implicit step is
        not affected."""
        law = self.model.problem.law
        law = getattr(law, "law", law)  # (plane strain wraps the 3-D law)
        if not isinstance(law, Perzyna) or law.scheme != "linearized":
            return []
        ratio = self.model.scene.time.k * law.elasticity.E / law.mu_star
        if ratio <= LINEARIZED_STIFF_RATIO:
            return []
        return [f"k E/mu* = {ratio:.3g} ({self.model.scene.where('law.scheme')}): the "
                "linearized step this far into its stiff range is nearly singular where the "
                "body flows, and its displacements there can be ill-determined; check them, "
                "or use scheme = \"implicit\" (not affected) or a smaller k"]

    def _strain_warnings(self) -> list:
        """Strains beyond :data:`SMALL_STRAIN_LIMIT` at the end of the run: the model's
        kinematics are linearized (ε = sym ∇u), so such answers lie outside its validity (a
        sweep's blocks squeezed to 400 % strain finished without a word). Collective."""
        state = self.model.problem.state
        strain = state.view(state.strain_old)
        local = float(np.linalg.norm(strain, axis=1).max()) if strain.size else 0.0
        largest = self.comm.allreduce(local, op=MPI.MAX)
        if not largest > SMALL_STRAIN_LIMIT:
            return []
        return [f"the strain reaches {largest:.3g} ({100 * largest:.3g} %, the largest |ε| at "
                "the end of the run): the model is small-strain (ε = sym grad u, no change of "
                "geometry), valid to a few per cent, and its answers there are outside that "
                "range"]

    def _option_warnings(self) -> list:
        """The scene's PETSc options that the run's solves never read, though they would have
        if PETSc knew them (a misspelt viewer, a ``mat_mumps_*`` the factorization did not
        take; see :mod:`vpcontact.solver.option_reads`; collective)."""
        solver = self.model.problem.solver
        return [f"PETSc never read the solver option {key} "
                f"({self.model.scene.where('solver.petsc_options.' + key)}) in this run's "
                f"solves ({solver.solvers}): a misspelt name, or one these solvers do not "
                "take; it had no effect" for key in solver.unread_options()]

    def _history(self) -> Optional[ContactHistory]:
        """Every contact part's nodes (recorded whenever the scene has contact: the warning of
        a part that never touched needs it even when neither contact.csv nor the figures are
        written)."""
        problem = self.model.problem
        if not problem.contacts:
            return None
        return ContactHistory(problem)

    def _pressure_field(self, history):
        """Nodal contact pressure p = −σ_ν (positive in compression) as a P1 field (zero off
        the contact parts; P_k: its vertex values) and the fields of what the parts report at their nodes (with friction
        the tangential traction |σ_τ| and whether each node slipped in the step, 1, or not, 0:
        :attr:`ContactHistory.outputs` with a ``field``)."""
        if history is None:
            return ()
        fields = [self._nodal_field(history, "contact_pressure",
                                    lambda part: 0.0 - part.pressure())]
        fields += [self._nodal_field(history, o.field, lambda part, key=o.key:
                                     nodal_values(part, key))
                   for o in history.outputs if o.field is not None]
        return fields

    def _nodal_field(self, history, name: str, values):
        """(P1 field, refresh) of ``values(part)`` at every contact part's nodes."""
        problem = self.model.problem
        field = fem.Function(fem.FunctionSpace(problem.mesh, ("Lagrange", 1)), name=name)
        V = problem.V
        bs = V.dofmap.index_map_bs
        nodes = [part.nodes.dofs // bs for part in history.parts]  # vector dof -> node
        nodal = field
        if V.ufl_element().degree() != 1:
            scalar, to_parent = V.sub(0).collapse()
            index_map = V.dofmap.index_map  # (nodes, ghosts included; a 1-D body's
            # one-component vector space cannot tabulate its coordinates)
            of_node = np.empty(index_map.size_local + index_map.num_ghosts, dtype=np.int32)
            of_node[np.asarray(to_parent) // bs] = np.arange(len(to_parent), dtype=np.int32)
            nodes = [of_node[n] for n in nodes]
            nodal = fem.Function(scalar)

        def refresh():
            for part, at in zip(history.parts, nodes):
                nodal.x.array[at] = values(part)
            nodal.x.scatter_forward()
            if nodal is not field:
                field.interpolate(nodal)
                field.x.scatter_forward()

        return field, refresh

    def _progress(self, step, report) -> None:
        if self.progress is not None:
            self.progress(step.time, step.newton_iterations,
                          report.active if report is not None else None)

    def _figures(self, history, cells) -> None:
        scene, problem = self.model.scene, self.model.problem
        if scene.dim >= 2:
            plots.deformed_configuration(self.out / "final_state.png", problem.u, cells.von_mises,
                                         f"{scene.name}: von Mises norm at t = {scene.time.T:g}")
        plots.force_history(self.out / "reactions.png", self.forces,
                            f"{scene.name}: support reactions and contact force")
        if history is None or scene.dim < 2:
            return
        for i, part in enumerate(history.parts):
            suffix = "" if i == 0 else f"_{part.name}"
            self._contact_figures(history, i, suffix)

    def _contact_figures(self, history, i: int, suffix: str) -> None:
        """The contact part ``i``'s pressure and normal displacement: along the boundary over
        time (2-D), maps of the contact face at a few times (3-D)."""
        scene, part = self.model.scene, history.parts[i]
        name = f"{scene.name}: '{part.name}'"
        pressure_png = self.out / f"contact_pressure{suffix}.png"
        history_png = self.out / f"contact_history{suffix}.png"
        if scene.dim == 2:
            contact_figures.pressure_profiles(pressure_png, history, i,
                                              f"{name}: contact pressure along the boundary")
            plots.contact_evolution(history_png, history, axis=None, obstacle=part.bounded,
                                    title=f"{name}: normal displacement of the contact nodes",
                                    part=i)
            return
        contact_figures.face_maps(pressure_png, history, i, history.pressure,
                                  "contact pressure −σ_ν", f"{name}: contact pressure")
        sign = part.nodes.sign
        contact_figures.face_maps(history_png, history, i,
                                  [sign * u for u in history.normal_displacement],
                                  "normal displacement component",
                                  f"{name}: normal displacement of the contact nodes")

    def _write_summary(self, record, wall: float, error: Optional[Exception],
                       warnings: list) -> None:
        scene, problem = self.model.scene, self.model.problem
        solver = problem.solver
        summary = {
            "scene": {"name": scene.name, "path": str(scene.path), "sha256": scene.hash},
            "overrides": dict(scene.overrides),  # the keys set by `run --set KEY=VALUE`
            "versions": _versions(),
            "mpi_ranks": self.comm.size,
            "completed": bool(record is not None and record.completed and error is None),
            "error": None if error is None else str(error),
            "interrupted_by": None if record is None else record.interrupted,
            "resumed_from": None if self.restart is None else {"step": self.restart.step,
                                                               "time": self.restart.time},
            "steps": 0 if record is None else len(record.times),
            "final_time": None if record is None or not record.times else record.times[-1],
            "newton_iterations": [] if record is None else record.newton_iterations,
            "newton_iterations_total": solver.total_iterations,
            "converged_reasons": [] if record is None else record.reasons,
            "rejected_steps": [] if record is None else [
                {"time": c.time, "dt": c.dt, "reason": c.reason} for c in record.cuts],
            "active_contact_nodes": [] if record is None else [c.active for c in record.contact],
            "reactions": self.forces.summary(),
            "wall_time_s": wall,
            "wall_time_split_s": {**time_split(solver.timings),
                                  "output": 0.0 if record is None else record.output_time},
            "jacobian_assemblies": solver.jacobian_assemblies,
            "kernel_calls": solver.kernel_calls,
            "vi_solves": solver.vi_solves,
            "vi_linear_solves": None if solver.lagged_lu is None else solver.lagged_lu.counters(),
            "stabilization": None if problem.held is None else problem.held.report(),
            "warnings": warnings,
        }
        def write():
            self.out.mkdir(parents=True, exist_ok=True)
            (self.out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
        on_rank0(self.comm, write)  # the summary is on disk when any rank returns


def _located(scene, err: Exception) -> Exception:
    """A moving obstacle that leaves the reach of the contact nodes' rays during the run is an
    error of the scene's motion (or rotation, or force, or moving level set): say where in the
    file. Other run-time refusals (an :class:`InputError` naming its scene key, e.g. no
    equilibrium, an obstacle pressed through the body) are located at their key."""
    if isinstance(err, InputError) and not isinstance(err, (ObstacleOutOfReach, SceneError)):
        if err.key is None:
            return err
        key = err.key
        if err.part is not None and key.split(".")[0] == "contact":
            key = scene.contact_key(scene.contact_part(err.part)[0]) + key[len("contact"):]
        return scene.error(key, str(err))
    if not isinstance(err, ObstacleOutOfReach):
        return err
    index, contact = scene.contact_part(err.part)
    where = scene.contact_key(index)
    key = (f"{where}.motion" if contact.motion is not None else
           f"{where}.rotation" if contact.rotation is not None else
           f"{where}.force" if contact.force is not None else f"{where}.obstacle")
    return scene.error(key, str(err))


def _versions() -> dict:
    return {"vpcontact": __version__, "dolfinx": dolfinx.__version__,
            "petsc": ".".join(map(str, PETSc.Sys.getVersion())), "python": sys.version.split()[0],
            "platform": platform.platform()}
