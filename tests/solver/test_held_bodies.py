# SPDX-License-Identifier: MIT
"""Bodies held by their contacts, with no Dirichlet part (vpcontact.solver.held): a block
pressed onto a rigid floor, a block squeezed between two indenters driven by equal forces; and
the scenes with no equilibrium — pushed along the frictionless floor (refused by `validate`),
pulled off it (refused at the step where it lifts off)."""

import json
import re

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli

from tests.support.mpi_launch import write_shared


def _rows(path):
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    return {name: np.array([float(line.split(",")[i]) for line in lines[1:]])
            for i, name in enumerate(header)}


def test_a_block_pressed_onto_a_floor_is_held_by_it(scene_text, shared_tmp_path):
    """No Dirichlet part: the floor holds the block vertically, nothing horizontally (the
    loads do not push it that way). The floor carries the whole load, the stabilising spring
    a negligible share, reported in summary.json."""
    scene = write_shared(shared_tmp_path / "on_floor.toml", scene_text("block_on_floor"))
    assert cli.main(["validate", str(scene)]) == 0
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    forces = _rows(out / "reactions.csv")
    assert np.allclose(forces["contact_y"], 5.0 * forces["t"], rtol=1e-8, atol=1e-9)
    assert np.allclose(forces["contact_x"], 0.0, atol=1e-8)
    summary = json.loads((out / "summary.json").read_text())
    held = summary["stabilization"]
    assert set(held["free_rigid_motions"]) == {"translation along x", "translation along y",
                                               "rotation about z"} or len(
        held["free_rigid_motions"]) == 3
    assert held["largest_share_of_applied"] < 1e-6, held


def test_a_block_pushed_along_the_floor_is_refused_by_validate(scene_text, shared_tmp_path, capsys):
    text = scene_text("block_on_floor") + '\n[boundary.right]\nkind = "traction"' \
                                          '\nplane = { axis = "x", value = 1.0 }\ntraction = ["t", 0]\n'
    scene = write_shared(shared_tmp_path / "pushed.toml", text)
    assert cli.main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(r"pushed\.toml:\d+: boundary: the body is not held along its "
                         r"translation along x", err), err


def test_a_block_pulled_off_the_floor_stops_with_no_equilibrium(scene_text, shared_tmp_path,
                                                                capsys):
    text = scene_text("block_on_floor").replace('traction = [0, "-5*t"]', 'traction = [0, "5*t"]')
    scene = write_shared(shared_tmp_path / "pulled.toml", text)
    out = shared_tmp_path / "pulled"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) != 0
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert "no equilibrium at t = 0.5: nothing holds the body along its translation" in err, \
            err
    summary = json.loads((out / "summary.json").read_text())
    assert not summary["completed"] and "no equilibrium" in summary["error"]


def test_a_block_squeezed_by_two_indenters_with_equal_forces(shared_tmp_path):
    """No Dirichlet part: two indenters driven by equal and opposite forces hold the block
    between them; each carries its force."""
    text = """\
name = "squeezed"

[mesh]
type = "rectangle"
lower = [-1.0, -0.5]
upper = [1.0, 0.5]
cells = [16, 8]

[boundary.top]
kind = "contact"
plane = { axis = "y", value = 0.5 }

[boundary.bottom]
kind = "contact"
plane = { axis = "y", value = -0.5 }

[material]
E = 1000.0
nu = 0.3
plane = "strain"

[[contact]]
type = "signorini"
boundary = "top"
obstacle = { shape = "cylinder", center = [0.0, 2.5], radius = 2.0 }
force = [0, "-10*t"]

[[contact]]
type = "signorini"
boundary = "bottom"
obstacle = { shape = "cylinder", center = [0.0, -2.5], radius = 2.0 }
force = [0, "10*t"]

[time]
T = 1.0
k = 0.5

[output]
xdmf = false
figures = false
"""
    scene = write_shared(shared_tmp_path / "squeezed.toml", text)
    out = shared_tmp_path / "squeezed"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    forces = _rows(out / "reactions.csv")
    assert np.allclose(forces["top_y"], -10.0 * forces["t"], rtol=1e-8, atol=1e-9)
    assert np.allclose(forces["bottom_y"], 10.0 * forces["t"], rtol=1e-8, atol=1e-9)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stabilization"]["largest_share_of_applied"] < 1e-6
