# SPDX-License-Identifier: MIT
"""Several contact parts in one scene (``[[contact]]``): a block squeezed between two indenters
against its half with a symmetry plane, an indenter on a body that rests on a deformable
foundation, two obstacles meeting at a corner node, the per-part outputs, and the located errors
of the new array of tables."""

import json
import re

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli

from tests.support.mpi_launch import write_shared
from tests.support.scenes import scene_text


TOP = """
[[contact]]
type = "signorini"
boundary = "top"
obstacle = { shape = "cylinder", center = [0.3, 2.5], radius = 2.0 }
motion = [0, "-0.02*t"]
"""

BOTTOM = """
[boundary.bottom]
kind = "contact"
plane = { axis = "y", value = -0.5 }

[[contact]]
type = "signorini"
boundary = "bottom"
obstacle = { shape = "cylinder", center = [0.3, -2.5], radius = 2.0 }
motion = [0, "0.02*t"]
"""

HALF = """
[boundary.middle]
kind = "symmetry"
plane = { axis = "y", value = 0.0 }
"""


def _csv(path):
    header = path.read_text().splitlines()[0].split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def _run(tmp, name, text, capsys=None):
    scene = write_shared(tmp / f"{name}.toml", text)
    out = tmp / name
    code = cli.main(["run", str(scene), "--out", str(out), "--quiet"])
    return code, out


def test_two_indenters_squeeze_a_block_as_its_symmetric_half_says(shared_tmp_path):
    """A block clamped at one end, pressed by one indenter from above and one from below,
    mirror images of each other: the contact force of each equals the one indenter's on the
    half block with a symmetry plane (the same discrete problem), the two are opposite, and
    every force balances."""
    full = scene_text("clamped_quad_block", name="full", bottom=-0.5, rows=8) + TOP + BOTTOM
    half = scene_text("clamped_quad_block", name="half", bottom=0.0, rows=4) + HALF + TOP
    (code_full, out_full), (code_half, out_half) = (_run(shared_tmp_path, "full", full),
                                                    _run(shared_tmp_path, "half", half))
    assert code_full == 0 and code_half == 0
    header, rows = _csv(out_full / "reactions.csv")
    assert header == ["t", "displacement", "left_x", "left_y", "contact_x", "contact_y",
                      "top_x", "top_y", "bottom_x", "bottom_y"], header
    col = {name: i for i, name in enumerate(header)}
    _, half_rows = _csv(out_half / "reactions.csv")
    half_col = {name: i for i, name in enumerate(_csv(out_half / "reactions.csv")[0])}
    top_y, bottom_y = rows[:, col["top_y"]], rows[:, col["bottom_y"]]
    scale = np.abs(top_y).max()
    assert scale > 0 and top_y[-1] < 0 < bottom_y[-1], (top_y, bottom_y)
    assert np.allclose(top_y, -bottom_y, atol=1e-8 * scale), (top_y, bottom_y)
    assert np.allclose(top_y, half_rows[:, half_col["contact_y"]], atol=1e-7 * scale)
    assert np.allclose(rows[:, col["top_x"]], half_rows[:, half_col["contact_x"]],
                       atol=1e-7 * scale)
    # the parts add up to the total, and the total balances the clamp
    for a in "xy":
        total = rows[:, col[f"top_{a}"]] + rows[:, col[f"bottom_{a}"]]
        assert np.allclose(rows[:, col[f"contact_{a}"]], total, atol=1e-9 * scale)
        assert np.allclose(rows[:, col[f"left_{a}"]] + total, 0.0, atol=1e-7 * scale)
    summary = json.loads((out_full / "summary.json").read_text())
    parts = summary["reactions"]["contact_parts"]
    assert list(parts) == ["top", "bottom"]
    assert np.isclose(parts["top"]["final"][1], top_y[-1], rtol=1e-9)
    # contact.csv names the part of every row; each part's nodes touch where it presses
    text = (out_full / "contact.csv").read_text().splitlines()
    assert text[0] == "t,x,y,z,u_normal,gap,clearance,pressure,part"
    last = [line.split(",") for line in text[1:] if float(line.split(",")[0]) == 1.0]
    for part, y in (("top", 0.5), ("bottom", -0.5)):
        mine = [r for r in last if r[-1] == part]
        assert mine and all(float(r[2]) == y for r in mine)
        assert min(float(r[6]) for r in mine) < 1e-9  # zero clearance: in contact
        assert max(float(r[7]) for r in mine) > 0     # a compressive pressure


def test_indenter_on_a_body_resting_on_a_foundation(shared_tmp_path):
    """A Signorini indenter on top, normal compliance (a deformable foundation) below: both
    parts carry force, the foundation's equals the integral of its law over the nodes' pressures
    to discretization accuracy, and everything balances."""
    foundation = """
[boundary.bottom]
kind = "contact"
plane = { axis = "y", value = -0.5 }

[[contact]]
type = "normal_compliance"
boundary = "bottom"
mu = 1e-3
gap = 0.0
"""
    text = scene_text("clamped_quad_block", name="rest", bottom=-0.5, rows=8) + TOP + foundation
    code, out = _run(shared_tmp_path, "rest", text)
    assert code == 0
    header, rows = _csv(out / "reactions.csv")
    col = {name: i for i, name in enumerate(header)}
    top_y, bottom_y = rows[-1, col["top_y"]], rows[-1, col["bottom_y"]]
    assert top_y < 0 < bottom_y, (top_y, bottom_y)
    scale = abs(top_y)
    assert abs(rows[-1, col["left_y"]] + top_y + bottom_y) < 1e-7 * scale
    # the foundation's nodal pressures (trapezoid rule on the 16 edges) give its force
    lines = (out / "contact.csv").read_text().splitlines()[1:]
    rows_csv = [line.split(",") for line in lines]
    bottom = np.array([[float(v) for v in r[1:8]] for r in rows_csv
                       if r[-1] == "bottom" and float(r[0]) == 1.0])
    bottom = bottom[np.argsort(bottom[:, 0])]
    force = np.trapz(bottom[:, 6], bottom[:, 0])   # (the pressure, positive in compression)
    assert abs(force / bottom_y - 1) < 0.05, (force, bottom_y)


def test_two_obstacles_at_a_corner_node_the_first_part_owns_it(shared_tmp_path):
    """Contact on the top and on the right end of a block, each against its own plane: the
    corner node is in the first listed part only (one constraint, one output row)."""
    text = scene_text("clamped_quad_block", name="corner", bottom=-0.5, rows=8) + """
[boundary.right]
kind = "contact"
plane = { axis = "x", value = 1.0 }

[[contact]]
type = "signorini"
boundary = "top"
obstacle = { shape = "plane", point = [0, 0.5], normal = [0, -1] }
motion = [0, "-0.01*t"]

[[contact]]
type = "signorini"
boundary = "right"
obstacle = { shape = "plane", point = [1.0, 0], normal = [-1, 0] }
"""
    code, out = _run(shared_tmp_path, "corner", text)
    assert code == 0
    lines = (out / "contact.csv").read_text().splitlines()[1:]
    at_t0 = [line.split(",") for line in lines if float(line.split(",")[0]) == 0.0]
    corner = [r[-1] for r in at_t0 if float(r[1]) == 1.0 and float(r[2]) == 0.5]
    assert corner == ["top"], corner
    assert sum(r[-1] == "right" for r in at_t0) == 8  # 9 nodes on x = 1, less the corner
    assert sum(r[-1] == "top" for r in at_t0) == 16   # 17 on y = 0.5, less the clamped one


@pytest.mark.parametrize("edit, key, message", [
    (lambda t: t + TOP.replace('center = [0.3, 2.5]', 'center = [-0.3, 2.5]'),
     r"contact\[1\]\.boundary", r"boundary part 'top' has a contact table already \(contact\[0\]\)"),
    (lambda t: t + '\n[[contact]]\ntype = "none"\n', r"contact\[1\]\.type",
     r"'none' is for a single \[contact\] table"),
    (lambda t: t + '\n[boundary.bottom]\nkind = "contact"\nplane = { axis = "y", value = -0.5 }\n',
     r"boundary\.bottom\.kind", "boundary part 'bottom' has kind 'contact' but no contact "
     "table names it"),
    (lambda t: "contact = [1]\n" + t.replace(TOP, ""), r"contact\[0\]",
     "expected a table, got an integer"),
    (lambda t: t + TOP.replace('boundary = "top"', 'boundary = "left"'),
     r"contact\[1\]\.boundary", "boundary part 'left' has kind 'clamped', not 'contact'"),
])
def test_contact_array_errors_are_located(shared_tmp_path, capsys, edit, key, message):
    text = edit(scene_text("clamped_quad_block", name="bad", bottom=-0.5, rows=8) + TOP)
    scene = write_shared(shared_tmp_path / "bad.toml", text)
    out = shared_tmp_path / "bad"
    assert cli.main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    capsys.readouterr()
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(rf"bad\.toml:\d+: {key}: {message}", err), err
    assert not out.exists()


def test_an_obstacle_of_the_second_part_that_faces_away_is_located_at_its_table(
        shared_tmp_path, capsys):
    """A mesh-level refusal of the second contact part (its plane's normal points away from
    the body) names that part's table, contact[1]."""
    text = scene_text("clamped_quad_block", name="away", bottom=-0.5, rows=8) + TOP + """
[boundary.bottom]
kind = "contact"
plane = { axis = "y", value = -0.5 }

[[contact]]
type = "signorini"
boundary = "bottom"
obstacle = { shape = "plane", point = [0, -0.6], normal = [0, -1] }
"""
    scene = write_shared(shared_tmp_path / "away.toml", text)
    assert cli.main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(r"away\.toml:\d+: contact\[1\]\.obstacle", err), err


def test_show_writes_the_array_back(shared_tmp_path, capsys):
    """``show`` writes [[contact]] tables back, and reading them gives the same scene."""
    from vpcontact.scene import loads_text
    text = scene_text("clamped_quad_block", name="full", bottom=-0.5, rows=8) + TOP + BOTTOM
    scene = loads_text(text)
    again = loads_text(scene.to_toml())
    assert again == scene and len(again.contacts) == 2 and again.contact_array
    assert scene.to_toml().count("[[contact]]") == 2
