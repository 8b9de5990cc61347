# SPDX-License-Identifier: MIT
"""Time loop with outputs: XDMF series, contact history and per-step diagnostics."""

from __future__ import annotations

import logging
import sys
import time as _time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

from vpcontact.output.fields import CellStress, ContactHistory, XdmfSeries
from vpcontact.errors import INTERNAL_ERROR, OutputError, VpcontactError
from vpcontact.output.checkpoint import Checkpointer, Restart, restore_control
from vpcontact.output.forces import ForceHistory
from vpcontact.output.lock import check_folder
from vpcontact.output.probes import ProbeHistory
from vpcontact.output.strains import ViscoplasticStrain

#: Step lines (``verbose``) go to this logger at INFO; :func:`vpcontact.cli.configure_logging`
#: shows vpcontact's INFO messages on standard output.
log = logging.getLogger(__name__)
from vpcontact.solver.problem import QuasistaticProblem
from vpcontact.model.contact_nodes import ContactReport
from vpcontact.solver.stepping import Cut, StepControl, advance


@dataclass
class RunRecord:
    """What a run did, step by step."""

    times: list = field(default_factory=list)
    newton_iterations: list = field(default_factory=list)
    reasons: list = field(default_factory=list)      # SNES converged reason per step
    contact: list = field(default_factory=list)      # ContactReport per step (Signorini)
    cuts: list = field(default_factory=list)         # stepping.Cut per rejected step
    completed: bool = False                          # reached t_final
    interrupted: Optional[str] = None                # the signal that stopped the run, if any
    wall_time: float = 0.0                           # [s] the whole run, outputs included
    output_time: float = 0.0                         # [s] writing XDMF, recording the history
    warnings: list = field(default_factory=list)     # what the user should know (one line each)


@contextmanager
def _timed(record: RunRecord, out: Optional[Path] = None):
    """Add the wall time of the block (which writes outputs) to ``record.output_time``; a
    failure to write (a full disk, an unwritable folder: OSError, or HDF5's RuntimeError) becomes
    an :class:`OutputError` naming the folder."""
    start = _time.perf_counter()
    try:
        yield
    except (OSError, RuntimeError) as err:
        if isinstance(err, VpcontactError):
            raise
        raise OutputError(f"cannot write the outputs into {out}: {err}") from err
    finally:
        record.output_time += _time.perf_counter() - start


@dataclass(frozen=True)
class RunOptions:
    """How a run steps and what it writes (a scene's [time] and [output] choices).

    Attributes:
        name: stem of the XDMF file.
        xdmf: write the XDMF series, every ``xdmf_every``-th step and the last one.
        csv_name: file of the contact history (None: not written).
        verbose: a log line (INFO) per step.
        max_cuts: step halvings allowed in a row when a step fails.
        tolerance: relative local time-error tolerance of adaptive steps (None: fixed steps).
    """

    name: str = "result"
    xdmf: bool = True
    xdmf_every: int = 1
    csv_name: Optional[str] = "contact_history.csv"
    verbose: bool = True
    max_cuts: int = 12
    tolerance: Optional[float] = None
    #: on several ranks, end the MPI job at an unexpected exception (a bug) instead of raising
    #: it: it may have been raised on some ranks only, and the outputs' collective calls would
    #: then wait for the others for ever (the command line's runs)
    abort_on_bug: bool = False


@dataclass
class RunParts:
    """What a run records into and answers to, besides the problem.

    Attributes:
        history: records the contact nodes (default: those of the Signorini parts).
        forces: records the support reactions and the contact force (``reactions.csv``).
        xdmf_extra: (Function, refresh) pairs written besides u, stress and von Mises norm.
        progress: ``progress(step, report)`` after every accepted step, on every rank.
        stop: a :class:`~vpcontact.output.interrupt.StopRequest`, asked after every step.
        checkpoints: writes checkpoints; ``restart`` continues a run from one (the problem has
            been restored already; outputs are appended).
        record: filled in place (so that a caller keeps it when the run fails).
        cells: the cell stress fields (default: made for the problem).
        strain: the viscoplastic strain fields (default: made for the problem's law), written
            into the XDMF series where the law flows.
        probes: the point histories (``probes.csv``), made with ``cells`` and ``strain``.
    """

    history: Optional[ContactHistory] = None
    forces: Optional[ForceHistory] = None
    xdmf_extra: tuple = ()
    progress: Optional[object] = None
    stop: Optional[object] = None
    checkpoints: Optional[Checkpointer] = None
    restart: Optional[Restart] = None
    record: Optional[RunRecord] = None
    cells: Optional[CellStress] = None
    strain: Optional[ViscoplasticStrain] = None
    probes: Optional[ProbeHistory] = None


def run(problem: QuasistaticProblem, t_final: float, dt: float, out: Optional[Path] = None,
        options: RunOptions = RunOptions(), parts: Optional[RunParts] = None
        ) -> tuple[RunRecord, Optional[ContactHistory], CellStress]:
    """Advance ``problem`` to ``t_final`` with steps of at most ``dt``, writing outputs into ``out``.

    A step that does not converge is rejected and retried with half the step, at most
    ``options.max_cuts`` times in a row; with ``options.tolerance`` k also follows a local
    time-error estimate (see :mod:`vpcontact.solver.stepping`). If it still fails, the outputs
    of the accepted steps are written, ``record.completed`` stays False and the error is
    re-raised. When ``parts.stop`` reports a signal, the outputs are closed, a checkpoint is
    written and :class:`Interrupted` is raised.

    Returns the run record, the contact history (Signorini problems) and the cell stress fields.
    """
    parts = parts if parts is not None else RunParts()
    history, forces, stop, checkpoints = parts.history, parts.forces, parts.stop, parts.checkpoints
    restart, record = parts.restart, parts.record
    control = StepControl(dt, max_cuts=options.max_cuts, tolerance=options.tolerance)
    if restart is not None:
        restore_control(control, restart)
    comm = problem.mesh.comm
    cells = parts.cells if parts.cells is not None else CellStress.of(problem)
    strain = parts.strain if parts.strain is not None else ViscoplasticStrain.of(problem, cells)
    probes = parts.probes
    if out is not None:
        check_folder(out)  # (a file there, or a path under one: a located refusal)
        if comm.rank == 0:
            Path(out).mkdir(parents=True, exist_ok=True)
        comm.barrier()
    record = record if record is not None else RunRecord()
    if restart is not None:
        _restore_record(record, restart.record)
    start = _time.perf_counter()  # wall_time covers everything output_time counts
    series = (_open_series(problem, out, options, parts, (cells, strain), record)
              if out is not None and options.xdmf else None)
    if history is None and problem.contact_dofs is not None:
        history = ContactHistory(problem, [p for p in problem.contacts if p.bounded])
    _start_histories((history, forces, probes), restart)
    interrupted = stop.agreed(comm) if stop is not None else None  # a signal during set-up
    try:
        if interrupted and checkpoints is not None:
            with _timed(record, out):
                checkpoints.write(record, control, history, forces, probes)
        for step in advance(problem, t_final, control) if not interrupted else ():
            last = step.time >= t_final * (1 - 1e-12)
            _record_step(problem, step, last, record, out, options, parts.progress,
                         (history, forces, series, probes))
            interrupted = stop.agreed(comm) if stop is not None else None
            if last:  # a signal during the last step came too late: the run is done
                interrupted = None
            if checkpoints is not None and (interrupted or checkpoints.due(step.step)):
                with _timed(record, out):
                    checkpoints.write(record, control, history, forces, probes)
            if interrupted:
                break
        else:
            record.completed = not interrupted
    except Exception as err:
        if options.abort_on_bug and comm.size > 1 and not isinstance(err, VpcontactError):
            _abort(comm, err)
        raise
    finally:
        record.cuts = list(control.cuts)
        _close_outputs(record, out, options, cells, (history, forces, series, probes))
        record.wall_time = _time.perf_counter() - start
    record.interrupted = interrupted
    return record, history, cells


def _open_series(problem, out: Path, options: RunOptions, parts: RunParts, fields: tuple,
                 record: RunRecord) -> XdmfSeries:
    """The XDMF series of u, the cell stress, the viscoplastic strain (where the law flows)
    and the extra fields (appended to on a restart; an unreadable one is set aside, with a
    warning in ``record``)."""
    name, restart = options.name, parts.restart
    cells, strain = fields
    with _timed(record, out):
        extra = [(f, lambda: None) for f in problem.fields.output_functions()]
        if strain is not None and not getattr(problem.law, "rate_free", False):
            extra += strain.xdmf_fields()
        series = XdmfSeries(Path(out) / f"{name}.xdmf", problem.u, cells,
                            extra=extra + list(parts.xdmf_extra),
                            append=restart is not None)
    if series.set_aside is not None:
        note = (f"{name}.xdmf/.h5 could not be appended to (a run that died while writing "
                f"leaves them unreadable): set aside as {series.set_aside.name} and .h5; the "
                f"series starts again at the checkpoint's t = {restart.time:g}")
        record.warnings.append(note)  # (the command line prints them at the end)
    return series


def _start_histories(histories: tuple, restart: Optional[Restart]) -> None:
    """The contact, force and probe histories from a checkpoint's records, or from the
    initial state's."""
    history, forces, probes = histories
    if restart is not None:
        if history is not None:
            history.restore(restart.history)
        if forces is not None:
            forces.restore(restart.forces)
        if probes is not None:
            probes.restore(restart.probes)
    else:
        for recorder in histories:
            if recorder is not None:
                recorder.record(0.0)


def _record_step(problem, step, last: bool, record: RunRecord, out: Optional[Path],
                 options: RunOptions, progress, outputs: tuple) -> None:
    """An accepted step into the run record, the histories and (every ``xdmf_every``-th step
    and the last) the XDMF series; then the progress callback and the log line."""
    history, forces, series, probes = outputs
    record.times.append(step.time)
    record.newton_iterations.append(step.newton_iterations)
    record.reasons.append(step.reason)
    report: Optional[ContactReport] = problem.contact_report()
    if report is not None:
        record.contact.append(report)
    with _timed(record, out):
        if history is not None:
            history.record(step.time)
        if forces is not None:
            forces.record(step.time)
        if probes is not None:
            probes.record(step.time)
        if series is not None and (step.step % options.xdmf_every == 0 or last):
            series.write(step.time)
    if progress is not None:
        progress(step, report)
    if options.verbose and problem.mesh.comm.rank == 0:
        active = f"  active contact dofs {report.active:4d}" if report else ""
        log.info("step %4d  t = %.4f  Newton its %d%s", step.step, step.time,
                 step.newton_iterations, active)


def _close_outputs(record: RunRecord, out: Optional[Path], options: RunOptions,
                   cells: CellStress, outputs: tuple) -> None:
    """Close the XDMF series, update the cell stress and write the CSV histories."""
    history, forces, series, probes = outputs
    with _timed(record, out):
        if series is not None:
            series.close()
    cells.update()
    with _timed(record, out):
        if out is not None and history is not None and options.csv_name:
            history.write_csv(Path(out) / options.csv_name)
        if out is not None and forces is not None:
            forces.write_csv(Path(out) / "reactions.csv")
        if out is not None and probes is not None:
            probes.write_csv(Path(out) / "probes.csv")


def _abort(comm, err: Exception) -> None:
    """End every rank's process: ``err``, unexpected, may be this rank's alone (the others then
    wait in a collective call). The one place in the library that writes to stderr itself: the
    process ends here, before the command line could."""
    print(f"error: internal error on rank {comm.rank}, a bug in vpcontact rather than in the "
          f"scene: {type(err).__name__}: {err}. Aborting the MPI job (the run's outputs are "
          "incomplete); please report it with the scene file.", file=sys.stderr, flush=True)
    comm.Abort(INTERNAL_ERROR)


def _restore_record(record: RunRecord, saved: dict) -> None:
    """``record`` as a checkpoint's manifest has it."""
    record.times = list(saved["times"])
    record.newton_iterations = list(saved["newton_iterations"])
    record.reasons = list(saved["reasons"])
    record.contact = [ContactReport(**c) for c in saved["contact"]]
    record.cuts = [Cut(**c) for c in saved["cuts"]]


def summary_text(record: RunRecord, out: Path, comm, force_unit: str = "N") -> str:
    """Two lines: final contact state, Newton effort, rejected steps, wall time; the outputs'
    folder (for a script or the command line to print)."""
    last = f"t = {record.times[-1]:.4g}" if record.times else "no step"
    contact = ""
    if record.contact:
        c = record.contact[-1]
        contact = (f"{c.active} contact nodes active, max penetration {c.max_penetration:.2e} m, "
                   f"contact force {c.normal_force:.4g} {force_unit}; ")
    return (f"{last}: {contact}{sum(record.newton_iterations)} Newton iterations in "
            f"{len(record.times)} steps ({len(record.cuts)} rejected and retried with half the "
            f"step), {record.wall_time:.1f} s on {comm.size} rank(s)\n"
            f"outputs written to {Path(out).resolve()}")
