# SPDX-License-Identifier: MIT
"""Refusals during a run name the scene line they concern (issue 45): an obstacle pressed by a
force through the body (it stopped with an unlocated message advising to raise
contact.max_distance), the same driven by a motion, and a body held by its contacts that is
pulled off them. Each says what happened, where (``scene.toml:LINE: key``) and what helps;
exit 2, no traceback, and the record of the steps before is kept (summary.json)."""

import json
import re

import pytest
from mpi4py import MPI

from vpcontact import cli

from tests.support.mpi_launch import write_shared

ROOT0 = MPI.COMM_WORLD.rank == 0


def _line(text: str, start: str) -> int:
    """The 1-based line of ``text`` that starts with ``start``."""
    return next(i for i, line in enumerate(text.splitlines(), 1) if line.startswith(start))


def _refused(shared_tmp_path, capsys, name: str, text: str) -> tuple[str, dict]:
    scene = write_shared(shared_tmp_path / f"{name}.toml", text)
    out = shared_tmp_path / name
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    MPI.COMM_WORLD.barrier()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] is False
    if ROOT0:
        assert "Traceback" not in err and err.count("error:") == 1, err
    return err, summary


@pytest.mark.parametrize("force, steps", [("1e5", 0), ("1e4", 1)])
def test_an_indenter_pressed_through_the_body_by_a_force(scene_text, shared_tmp_path, capsys,
                                                         force, steps):
    """A force far beyond what the clamped block can carry (E = 1000) drives the cylinder
    through it: 1e5 in the first step's solve, 1e4 at the second step's prediction. The message
    locates the force and advises a smaller force or a stiffer body, not contact.max_distance;
    the steps before are kept."""
    text = scene_text("pressed_by_force").replace('force = [0, "-10*t"]',
                                                  f'force = [0, "-{force}*t"]')
    err, summary = _refused(shared_tmp_path, capsys, "through", text)
    line = _line(text, "force =")
    if ROOT0:
        assert re.search(rf"through\.toml:{line}: contact\.force: .*the obstacle pressed by the "
                         r"force has passed through the body", err), err
        assert "A smaller force, a stiffer or stronger body" in err, err
        assert "max_distance" not in err, err
    assert "contact.force" in summary["error"] and summary["steps"] == steps


def test_an_indenter_driven_through_the_body_by_a_motion(scene_text, shared_tmp_path, capsys):
    """The same with a motion: located at the motion, with what helps."""
    text = scene_text("indentation").replace('motion = [0, "-0.02*t"]', 'motion = [0, "-1.0*t"]')
    err, summary = _refused(shared_tmp_path, capsys, "deep", text)
    line = _line(text, "motion =")
    if ROOT0:
        assert re.search(rf"deep\.toml:{line}: contact\.motion: .*the obstacle has passed "
                         r"through the body", err), err
        assert "a smaller motion" in err and "max_distance" not in err, err


def test_a_body_pulled_off_its_contacts_is_located(scene_text, shared_tmp_path, capsys):
    """Genuinely unstable (pulled off the floor, nothing else holds it): still refused, now at
    the scene's boundary table, with what helps."""
    text = scene_text("block_on_floor").replace('traction = [0, "-5*t"]', 'traction = [0, "5*t"]')
    err, summary = _refused(shared_tmp_path, capsys, "pulled", text)
    line = _line(text, "[boundary.")
    if ROOT0:
        assert re.search(rf"pulled\.toml:{line}: boundary: no equilibrium at t = 0\.5: nothing "
                         r"holds the body along its translation", err), err
        assert "Hold it with a Dirichlet part" in err, err
    assert "no equilibrium" in summary["error"]
