# SPDX-License-Identifier: MIT
"""The small bundled scenes give the summary.json they gave before the solver was restructured.

Issue 44 reorganizes the step solver, the problem and the contact parts without changing any
answer. This test runs the bundled scenes that take seconds through the command line and compares
their ``summary.json`` with the values stored in ``tests/reference/bundled_summaries.json``
(recorded at 5cd2df3, the last commit before the restructuring, with this file's ``record``):

- the Newton iterations of every step, the converged reasons and the rejected steps: exactly;
- the reactions and contact forces (every number under ``reactions``): to 1e-7 of the largest
  force of the scene (a reordered sum changes the last digits, nothing more);
- the active contact nodes per step: exactly.

Record again (``python3 tests/regression/test_bundled_regression.py [scene ...]``) only where an
answer is meant to change, and say so in the commit.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

STORE = Path(__file__).resolve().parents[1] / "reference" / "bundled_summaries.json"
#: the bundled scenes that run in seconds; with VPCONTACT_REGRESSION_ALL=1 every stored scene
#: (the others take minutes: run them by hand before landing a change to the solver)
SMALL = ("elastic_2d", "signorini_2d", "normal_compliance_2d", "normal_compliance_1d",
         "indentation_creep")
SCENES = (tuple(sorted(json.loads(STORE.read_text()))) if os.environ.get("VPCONTACT_REGRESSION_ALL")
          else SMALL)
EXACT = ("steps", "final_time", "newton_iterations", "newton_iterations_total",
         "converged_reasons", "rejected_steps", "active_contact_nodes")
RELATIVE = 1e-7


def _run(scene: str, out: Path) -> dict:
    """The scene's summary.json after ``vpcontact run`` (serially, in a fresh process)."""
    done = subprocess.run([sys.executable, "-m", "vpcontact", "run", scene, "--out", str(out),
                           "--quiet"], capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, f"{scene}: exit {done.returncode}\n{done.stderr[-2000:]}"
    return json.loads((out / "summary.json").read_text())


def _numbers(value) -> list[float]:
    """Every number in a nested JSON value, in document order."""
    if isinstance(value, dict):
        return [x for key in sorted(value) for x in _numbers(value[key])]
    if isinstance(value, list):
        return [x for item in value for x in _numbers(item)]
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return [float(value)]
    return []


def _kept(summary: dict) -> dict:
    """The parts of a summary that the restructuring must not change."""
    return {**{key: summary[key] for key in EXACT}, "reactions": summary["reactions"]}


def _structure(value):
    """``value`` with every number replaced by 0 (the layout the numbers sit in)."""
    if isinstance(value, dict):
        return {key: _structure(item) for key, item in value.items()}
    if isinstance(value, list):
        return [_structure(item) for item in value]
    return 0 if isinstance(value, (int, float)) and not isinstance(value, bool) else value


@pytest.mark.serial
@pytest.mark.slow
@pytest.mark.parametrize("scene", SCENES)
def test_bundled_scene_unchanged(scene, tmp_path):
    stored = json.loads(STORE.read_text())[scene]
    now = _kept(_run(scene, tmp_path / scene))
    for key in EXACT:
        assert now[key] == stored[key], f"{scene}: {key} changed: {now[key]} (was {stored[key]})"
    assert _structure(now["reactions"]) == _structure(stored["reactions"]), \
        f"{scene}: the reactions' layout changed"
    got, want = np.array(_numbers(now["reactions"])), np.array(_numbers(stored["reactions"]))
    scale = max(np.abs(want).max(initial=0.0), 1e-300)
    worst = np.abs(got - want).max(initial=0.0) / scale
    assert worst <= RELATIVE, f"{scene}: reactions moved by {worst:.2e} of the largest ({scale:.3g})"


def record(scenes, folder: Path) -> None:
    """Store the kept parts of the scenes' summaries (run serially)."""
    store = json.loads(STORE.read_text()) if STORE.exists() else {}
    for scene in scenes:
        store[scene] = _kept(_run(scene, folder / scene))
    STORE.parent.mkdir(exist_ok=True)
    STORE.write_text(json.dumps(store, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        record(sys.argv[1:] or SMALL, Path(tmp))
