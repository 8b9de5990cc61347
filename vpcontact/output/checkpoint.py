# SPDX-License-Identifier: MIT
"""Checkpoints of a run, to continue it exactly with ``vpcontact run SCENE --out DIR --resume``.

Format (version 1), in ``DIR/checkpoint/``:

* ``latest.json``: the manifest — format version, scene name and sha256, MPI ranks, step index
  and time, the folder holding the arrays, the run record so far (times, Newton iterations,
  converged reasons, contact reports, rejected steps), the step control (the proposed next step
  and the cuts), and the problem's and solver's scalars (time, steps, predictor and BDF2 step
  sizes, contact flag, solver counters and flags).
* ``step-NNNNNN/rank-RRRR.npz``: one NumPy archive per MPI rank with that rank's local arrays
  (ghosts included): u, the quadrature-point stress, previous stress and strain, tangent, the
  law's internal variables (σ33 in plane strain), the predictor's last two displacements, the
  BDF2 history, the values of the matrix the VI's lagged solver had factorized; on every rank the
  reaction history and on rank 0 the contact history (times, u_ν, gap, and under the key
  ``history_pressure`` the normal stress σ_ν per node, negative in compression: the model's
  sign, which the outputs turn into the pressure −σ_ν) and the probes' history.

A checkpoint is written every ``[output] checkpoint_every`` steps (default 10; 0: only when
interrupted) and when the run is interrupted. Writing is atomic: every rank writes its archive
under a temporary name and renames it, then rank 0 replaces ``latest.json`` (also by rename) and
only then deletes the older step folders, so a crash at any moment leaves ``latest.json``
pointing to a complete checkpoint. Only the last one is kept; its size is dominated by the
lagged matrix (one Jacobian's nonzeros): 7 MB for the paper's 3-D test on 24×8×8 cells, whose
50-step XDMF series takes 39 MB.

Restarting needs the same scene file (its sha256 is compared) and the same number of ranks
(dolfinx partitions the mesh the same way each time: vpcontact pins PT-Scotch to one thread).
"""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
from pathlib import Path
from typing import Optional

import numpy as np

from vpcontact.errors import InputError
from vpcontact.output.fields import on_rank0
from vpcontact.solver.stepping import Cut

FORMAT = 1
FOLDER = "checkpoint"
MANIFEST = "latest.json"


@dataclasses.dataclass
class Restart:
    """What a checkpoint gives back to the time loop."""

    step: int
    time: float
    record: dict        # RunRecord fields
    control: dict       # next_dt, cuts
    history: dict       # contact history arrays (rank 0; empty elsewhere)
    forces: dict        # reaction history arrays
    probes: dict = dataclasses.field(default_factory=dict)  # probe history (rank 0; may be empty)


def _jsonable(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, tuple):
        return list(value)
    raise TypeError(f"cannot write {type(value).__name__} in a checkpoint manifest")


class Checkpointer:
    """Writes checkpoints of ``problem`` into ``out/checkpoint`` (collective)."""

    def __init__(self, out: Path, problem, scene, comm, every: int):
        self.folder = Path(out) / FOLDER
        self.problem = problem
        self.scene = scene
        self.comm = comm
        self.every = int(every)
        self.written = 0

    def due(self, step: int) -> bool:
        return self.every > 0 and step % self.every == 0

    def write(self, record, control, history, forces, probes=None) -> None:
        problem, comm = self.problem, self.comm
        scalars, arrays = problem.checkpoint()
        step = problem.step_index
        name = f"step-{step:06d}"
        target = self.folder / name
        failure = None
        try:  # every rank (the folder is usually shared, and then made once)
            target.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            failure = f"rank {comm.rank}: {err}"
        failure = next((f for f in comm.allgather(failure) if f), None)
        if failure is not None:
            raise OSError(f"cannot write the checkpoint: {failure}")
        arrays = dict(arrays)
        if forces is not None:
            arrays.update(forces_arrays(forces))
        if history is not None and comm.rank == 0:
            arrays.update(history_arrays(history))
        if probes is not None and comm.rank == 0:
            arrays.update({f"probes_{k}": v for k, v in probes.arrays().items()})
        path = target / f"rank-{comm.rank:04d}.npz"
        try:
            tmp = path.with_suffix(".tmp")
            with open(tmp, "wb") as f:
                np.savez(f, **arrays)
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, path)
        except OSError as err:
            failure = f"rank {comm.rank}: {err}"
        failure = next((f for f in comm.allgather(failure) if f), None)
        if failure is not None:
            raise OSError(f"cannot write the checkpoint: {failure}")

        def manifest():
            content = {
                "format": FORMAT, "scene": self.scene.name, "scene_sha256": self.scene.hash,
                "mpi_ranks": comm.size, "step": step, "time": scalars["time"], "folder": name,
                "problem": scalars,
                "record": {"times": record.times, "newton_iterations": record.newton_iterations,
                           "reasons": record.reasons,
                           "contact": [dataclasses.asdict(c) for c in record.contact],
                           "cuts": [dataclasses.asdict(c) for c in record.cuts]},
                "control": {"next_dt": control.next_dt,
                            "cuts": [dataclasses.asdict(c) for c in control.cuts]},
            }
            tmp = self.folder / (MANIFEST + ".tmp")
            tmp.write_text(json.dumps(content, indent=1, default=_jsonable) + "\n")
            os.replace(tmp, self.folder / MANIFEST)
            for old in self.folder.glob("step-*"):
                if old.name != name:
                    shutil.rmtree(old, ignore_errors=True)
        on_rank0(comm, manifest)
        self.written += 1


def history_arrays(history) -> dict:
    """The contact history's records (rank 0) as arrays."""
    if not history.times:
        return {"history_times": np.zeros(0)}
    arrays = {"history_times": np.array(history.times),
              "history_un": np.array(history.normal_displacement),
              "history_pressure": np.array(history.normal_stress),   # σ_ν
              "history_gap": np.array(history.gaps)}
    arrays.update({f"history_{key}": np.array(records)
                   for key, records in history.records.items()})
    return arrays


def forces_arrays(forces) -> dict:
    driver = [np.nan if d is None else d for d in forces.driver]
    return {"forces_times": np.array(forces.times), "forces_reactions": np.array(forces.reactions),
            "forces_contact": np.array(forces.parts), "forces_driver": np.array(driver),
            "forces_driven": np.array([d is not None for d in forces.driver]),
            **({"forces_components": np.array(forces.components)} if forces.split else {})}


def load(out: Path, problem, scene, comm) -> Restart:
    """Restore ``problem`` from the checkpoint in ``out`` and return the rest of the run's
    state; InputError (exit 2) when there is none or it does not belong to this scene or rank
    count (checked on rank 0, the verdict shared)."""
    folder = Path(out) / FOLDER
    manifest, problem_text = None, None
    if comm.rank == 0:
        try:
            manifest = json.loads((folder / MANIFEST).read_text())
        except FileNotFoundError:
            problem_text = (f"--resume: {out} holds no checkpoint ({FOLDER}/{MANIFEST} is "
                            "missing); run without --resume to start from t = 0")
        except (OSError, ValueError) as err:
            problem_text = f"--resume: cannot read {folder / MANIFEST}: {err}"
        if manifest is not None and problem_text is None:
            problem_text = _mismatch(manifest, scene, comm)
        if problem_text is None and manifest["time"] >= scene.time.T * (1 - 1e-12):
            problem_text = (f"--resume: the run in {out} already reached T = {scene.time.T:g} "
                            "(its last checkpoint is at its last step): nothing to resume")
    problem_text = comm.bcast(problem_text, root=0)
    if problem_text is not None:
        raise InputError(problem_text)
    manifest = comm.bcast(manifest, root=0)
    path = folder / manifest["folder"] / f"rank-{comm.rank:04d}.npz"
    try:
        with np.load(path) as data:
            arrays = {k: data[k] for k in data.files}
    except (OSError, ValueError) as err:
        arrays, problem_text = None, f"--resume: cannot read {path}: {err}"
    problem_text = next((p for p in comm.allgather(problem_text) if p), None)
    if problem_text is not None:
        raise InputError(problem_text)
    problem.restore(manifest["problem"], arrays)
    history = {k[8:]: v for k, v in arrays.items() if k.startswith("history_")}
    forces = {k[7:]: v for k, v in arrays.items() if k.startswith("forces_")}
    probes = {k[7:]: v for k, v in arrays.items() if k.startswith("probes_")}
    return Restart(manifest["step"], manifest["time"], manifest["record"], manifest["control"],
                   history, forces, probes)


def _mismatch(manifest: dict, scene, comm) -> Optional[str]:
    if manifest.get("format") != FORMAT:
        return f"--resume: checkpoint format {manifest.get('format')} is not {FORMAT}"
    if manifest.get("scene_sha256") != scene.hash:
        return (f"--resume: the scene changed since the checkpoint (its sha256 was "
                f"{str(manifest.get('scene_sha256'))[:12]}…, now {scene.hash[:12]}…); run "
                "without --resume to start again")
    if manifest.get("mpi_ranks") != comm.size:
        return (f"--resume: the checkpoint was written by {manifest.get('mpi_ranks')} MPI "
                f"rank(s), this run has {comm.size}; resume with the same number")
    return None


def restore_control(control, restart: Restart) -> None:
    """The step control as it was: the proposed next step and the cuts so far."""
    control.next_dt = restart.control["next_dt"]
    control.cuts = [Cut(**c) for c in restart.control["cuts"]]
    control.resume = True
