# SPDX-License-Identifier: MIT
"""The default scene shows the physics quickly without losing accuracy (issue 45, §6).

``indentation_relaxation`` (what ``bash scripts/run.sh`` runs) used a uniform 128×64 mesh
(16 577 vertices) and took minutes; it now refines a 16×8 mesh three times towards the contact
(1 519 vertices). Its contact force must follow the former run's history, stored in
``tests/reference/indentation_relaxation_128x64.json``, within 1 % at every step (measured:
0.02 %).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REFERENCE = Path(__file__).resolve().parents[1] / "reference" / "indentation_relaxation_128x64.json"


@pytest.mark.serial
@pytest.mark.slow
def test_the_default_scene_follows_the_fine_uniform_mesh(tmp_path):
    done = subprocess.run([sys.executable, "-m", "vpcontact", "run", "--out", str(tmp_path),
                           "--quiet"], capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["scene"]["name"] == "indentation_relaxation"
    reference = json.loads(REFERENCE.read_text())
    expected = np.array(reference["contact_force"])[:, 1]
    got = np.array(summary["reactions"]["contact_force"])[:, 1]
    assert got.shape == expected.shape
    loaded = np.abs(expected) > 0.0
    error = np.abs(got - expected)[loaded] / np.abs(expected)[loaded]
    assert error.max() <= 0.01, f"largest relative deviation {error.max():.2%}"
    assert got[0] == expected[0] == 0.0
