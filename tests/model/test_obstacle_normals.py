# SPDX-License-Identifier: MIT
"""Contact forces along the obstacle's normal (``[contact] normals = "obstacle"``,
vpcontact.model.obstacle_normals).

* An elastic block pressed against a rigid plane inclined at α to its top face: every contact
  node's force is along the plane's normal, so the total tangential force over the normal one is
  tan α exactly (to solver tolerance), whichever nodes touch — P1 and the mixed P2–P1
  formulation, and in 3-D along the direction the plane rises in. With the body's normals (the
  default, the paper's condition) it is 0.
* The Jacobian stays exact: the same Newton iterations as with the body's normals.
* The key is validated (located errors, exit 2) and written back by ``show``.
"""

import json
import re

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli
from tests.support.mpi_launch import write_shared
from tests.support.scenes import scene_text

ALPHA = np.deg2rad(2.0)

#: The plane's normal, at ALPHA from the block's top face.
NORMAL = f"[{np.sin(ALPHA)!r}, {-np.cos(ALPHA)!r}]"


def _inclined(normals: str) -> str:
    """The block pressed against the inclined plane (tests/scenes/inclined.toml), with the
    ``normals`` line (``""`` for none) in its ``[contact]`` table."""
    return scene_text("inclined", normal=NORMAL, normals=normals)


def _run(tmp, name, normals, discretization=""):
    text = _inclined(normals) + discretization
    scene = write_shared(tmp / f"{name}.toml", text)
    out = tmp / name
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    return _reactions(out), summary["newton_iterations"]


def _reactions(out):
    """reactions.csv of a run: its columns by name."""
    lines = (out / "reactions.csv").read_text().splitlines()
    header = lines[0].split(",")
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    return {h: rows[:, i] for i, h in enumerate(header)}


@pytest.mark.parametrize("discretization", [
    "", '\n[discretization]\ndegree = 2\nformulation = "mixed"\n'], ids=["P1", "mixed"])
def test_the_force_on_an_inclined_plane_is_along_its_normal(shared_tmp_path, discretization):
    tag = "p1" if not discretization else "mixed"
    f, its = _run(shared_tmp_path, f"obstacle_{tag}", 'normals = "obstacle"', discretization)
    pressed = f["t"] > 0
    ratio = f["contact_x"][pressed] / -f["contact_y"][pressed]
    assert np.all(-f["contact_y"][pressed] > 0.1)            # pressed, more nodes each step
    assert np.allclose(ratio, np.tan(ALPHA), rtol=1e-8), ratio - np.tan(ALPHA)
    g, its_body = _run(shared_tmp_path, f"body_{tag}", "", discretization)
    assert np.all(np.abs(g["contact_x"]) <= 1e-12 * np.abs(g["contact_y"]).max()), g["contact_x"]
    # the tangential forces change the normal ones a little (the block shears): not the same run
    assert not np.allclose(f["contact_y"], g["contact_y"], rtol=1e-3)
    # the exact Jacobian: no more Newton iterations than with the body's normals
    assert sum(its) <= sum(its_body), (its, its_body)


def test_3d_the_force_on_a_plane_inclined_diagonally_is_along_its_normal(shared_tmp_path):
    """3-D (two tangential unknowns per node): a plane inclined by α about the direction
    ⊥ e = (1, 2, 0)/√5 gives a tangential force tan α × the normal one, along e."""
    e = np.array([1.0, 2.0, 0.0]) / np.sqrt(5.0)
    n = np.sin(ALPHA) * e + np.array([0.0, 0.0, -np.cos(ALPHA)])
    text = (_inclined('normals = "obstacle"').replace('type = "rectangle"', 'type = "box"')
            .replace("upper = [1.0, 0.25]", "upper = [1.0, 1.0, 0.25]")
            .replace("lower = [0.0, 0.0]", "lower = [0.0, 0.0, 0.0]")
            .replace("cells = [32, 8]", "cells = [6, 6, 2]")
            .replace('axis = "y", value = 0.0', 'axis = "z", value = 0.0')
            .replace('axis = "y", value = 0.25', 'axis = "z", value = 0.25')
            .replace('plane = "strain"\n', "")
            .replace('motion = ["0", "-0.01*t"]', 'motion = ["0", "0", "-0.01*t"]'))
    text = re.sub(r"obstacle = \{.*\}", "obstacle = { shape = \"plane\", point = [0.0, 0.0, 0.25], "
                  f"normal = [{n[0]!r}, {n[1]!r}, {n[2]!r}] }}", text)
    scene = write_shared(shared_tmp_path / "box.toml", text)
    out = shared_tmp_path / "box"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    f = _reactions(out)
    force = np.column_stack([f[f"contact_{c}"] for c in "xyz"])[1:]
    assert np.all(-force[:, 2] > 0.1)
    assert np.allclose(force[:, :2] / -force[:, 2:], np.tan(ALPHA) * e[:2], rtol=1e-8, atol=0), \
        force[:, :2] / -force[:, 2:] - np.tan(ALPHA) * e[:2]


@pytest.mark.parametrize("change, key, message", [
    ('normals = "sideways"', "contact.normals", "must be one of"),
    ('normals = "obstacle"\ntype = "normal_compliance"\nmu = 1e-3', "contact.normals",
     "only for type = 'signorini'"),
])
def test_normals_errors_are_located(shared_tmp_path, capsys, change, key, message):
    text = _inclined(change)
    if "normal_compliance" in change:
        text = text.replace('type = "signorini"\n', "").replace('motion = ["0", "-0.01*t"]\n', "")
    scene = write_shared(shared_tmp_path / "bad.toml", text)
    assert cli.main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(rf"bad\.toml:\d+: {re.escape(key)}: .*{re.escape(message)}", err), err


def test_normals_need_an_obstacle(shared_tmp_path, capsys):
    text = re.sub(r"obstacle = \{.*\}\n", "gap = 0.0\n", _inclined(
        'normals = "obstacle"').replace('motion = ["0", "-0.01*t"]\n', ""))
    scene = write_shared(shared_tmp_path / "gap.toml", text)
    assert cli.main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(r"gap\.toml:\d+: contact\.normals: .*only with an obstacle", err), err


def test_show_writes_the_normals_back():
    from vpcontact.scene import loads_text
    scene = loads_text(_inclined('normals = "obstacle"'))
    assert scene.contact.normals == "obstacle"
    assert loads_text(scene.to_toml()) == scene
    default = loads_text(_inclined(""))
    assert default.contact.normals == "body" and "normals" not in default.to_toml()


@pytest.mark.slow
def test_the_3d_scratch_scene_ploughs(shared_tmp_path):
    """The bundled ``scratch_3d`` (a sphere pressed into a Perzyna block and dragged, 𝔣 = 0.2,
    mixed formulation) on 16 × 8 × 4 cells, k = 0.05: while the sphere slides, F_1/(−F_3) is
    above 𝔣 by the ploughing and below 𝔣 + the steepest slope of the sphere over the nodes in
    contact; the force across the drag is nil by symmetry (up to the mesh's diagonals); a groove
    stays behind the sphere."""
    from vpcontact import scene as scenes
    from vpcontact.output import Session
    from vpcontact.scene import build
    out = shared_tmp_path / "scratch_3d"
    session = Session(build(scenes.load_bundled("scratch_3d", (16, 8, 4), 0.05)), out)
    session.run()
    MPI.COMM_WORLD.barrier()
    assert session.model.problem.formulation == "mixed"
    times = np.array(session.forces.times)
    force = np.array(session.forces.contact)
    sliding = times >= 0.4
    ratio = force[sliding, 0] / -force[sliding, 2]
    assert np.all(ratio > 0.2 + 0.03), ratio
    assert np.all(np.abs(force[sliding, 1]) < 0.02 * -force[sliding, 2]), force[sliding]
    if MPI.COMM_WORLD.rank == 0:
        rows = np.genfromtxt(out / "contact.csv", delimiter=",", names=True)
        for t, r in zip(times[sliding], ratio):
            now = rows[np.isclose(rows["t"], t) & (rows["pressure"] > 1e-6)]
            centre = -0.5 + 0.8 * (t - 0.25) / 0.75
            offset = np.hypot(now["x"] - centre, now["y"])
            assert r <= 0.2 + np.max(offset / np.sqrt(0.25 - offset ** 2)), (t, r)
        last = rows[np.isclose(rows["t"], times[-1])]
        behind = (np.abs(last["y"]) < 1e-9) & (last["x"] > -0.45) & (last["x"] < 0.0)
        assert np.all(last["u_normal"][behind] < -0.01), last["u_normal"][behind]
