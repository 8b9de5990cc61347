# SPDX-License-Identifier: MIT
"""Scene keys for posing contact problems: prescribed displacements (with free components),
symmetry planes, built-in and moving obstacles; their outputs (reactions.csv, reactions.png,
summary.json) and their located errors (exit 2, nothing written)."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli

from tests.support.mpi_launch import write_shared
from tests.support.scenes import scene_text

COMPRESSION = scene_text("compression")

INDENTATION = scene_text("indentation")


def _csv(path: Path):
    header = path.read_text().splitlines()[0].split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def test_rollers_and_prescribed_displacement_from_a_scene(shared_tmp_path):
    scene = write_shared(shared_tmp_path / "compression.toml", COMPRESSION)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    header, rows = _csv(out / "reactions.csv")
    assert header == ["t", "displacement", "bottom_x", "bottom_y", "left_x", "left_y", "top_x",
                      "top_y", "contact_x", "contact_y"]
    top = rows[:, header.index("top_y")]
    expected = -100.0 * 0.01 * rows[:, 0] * 2.0  # -E ε(t) W
    assert np.allclose(top, expected, rtol=1e-9, atol=1e-12)
    assert np.allclose(rows[:, header.index("displacement")], -0.01 * rows[:, 0])  # signed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["reactions"]["parts"] == ["bottom", "left", "top"]
    assert summary["reactions"]["final"]["bottom"][1] == pytest.approx(2.0, rel=1e-9)
    assert (out / "reactions.png").is_file()


def test_moving_cylinder_indents_a_block_from_a_scene(shared_tmp_path):
    scene = write_shared(shared_tmp_path / "indentation.toml", INDENTATION)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    header, rows = _csv(out / "reactions.csv")
    force = -rows[:, header.index("contact_y")]
    depth = rows[:, header.index("displacement")]
    assert np.allclose(depth, -0.02 * rows[:, 0])  # signed: the cylinder moves down
    assert force[0] == 0.0 and np.all(np.diff(force) > 0), force
    # reactions balance the contact force (no other load)
    assert np.allclose(rows[:, header.index("bottom_y")], force, rtol=1e-8, atol=1e-10)
    contact = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1)
    centre = contact[np.isclose(contact[:, 1], 0.0)]  # t, x, y, z, u_normal, gap, pressure
    assert np.allclose(centre[:, 5], -0.02 * centre[:, 0], atol=1e-12)  # the gap follows d(t)
    assert np.all(centre[:, 4] <= centre[:, 5] + 1e-12)  # u_ν ≤ g


@pytest.mark.parametrize("old, new, match", [
    ('displacement = ["free", "-0.01*t"]', 'displacement = ["free", "free"]',
     r"boundary\.top\.displacement: every component is 'free'"),
    ('displacement = ["free", "-0.01*t"]', 'displacement = ["free"]',
     r"boundary\.top\.displacement: expected 2 components, got 1"),
    ('displacement = ["free", "-0.01*t"]', 'displacement = ["free", "-0.01*s"]',
     r"boundary\.top\.displacement\[1\]: invalid expression"),
    ('[boundary.left]\nkind = "symmetry"', '[boundary.left]\nkind = "traction"',
     r"boundary: the Dirichlet parts do not hold the body: the rigid motion.*translation along x"),
    ('[boundary.bottom]\nkind = "symmetry"\nplane = { axis = "y", value = 0.0 }',
     '[boundary.bottom]\nkind = "symmetry"\nwhere = "x[1] < 1e-9 or x[0] > 2 - 1e-9"',
     r"boundary\.bottom: symmetry part 'bottom' must be a plane with an axis-aligned normal"),
])
def test_bad_dirichlet_parts_are_located(shared_tmp_path, capsys, old, new, match):
    assert old in COMPRESSION
    scene = write_shared(shared_tmp_path / "bad.toml", COMPRESSION.replace(old, new))
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert "bad.toml:" in err
        assert re.search(match, err), err
    assert not out.exists()


@pytest.mark.parametrize("old, new, match", [
    ('shape = "cylinder"', 'shape = "cone"', r"contact\.obstacle\.shape: must be one of"),
    ("radius = 0.5 }", "radius = -0.5 }", r"contact\.obstacle\.radius: must be > 0"),
    ("radius = 0.5 }", "radius = 0.5, axis = [0, 1] }",
     r"contact\.obstacle\.axis: not allowed: a cylinder's axis is the z axis in 2-D"),
    ("radius = 0.5 }", "radius = 0.5, normal = [0, 1] }",
     r"contact\.obstacle\.normal: not a parameter of shape 'cylinder'"),
    ('motion = [0, "-0.02*t"]', 'motion = ["-0.02*t"]', r"contact\.motion: expected 2 components"),
    ('motion = [0, "-0.02*t"]', 'motion = [0, "x[0]"]', r"contact\.motion\[1\]: invalid expression"),
    ('center = [0.0, 0.5]', 'center = [5.0, 0.5]',
     r"contact\.obstacle: no contact node's normal ray meets the obstacle within "
     r"max_distance = 1000: it is not in front of the contact part"),
    ('center = [0.0, 0.5]', 'center = [0.0, 0.3]',
     r"contact\.obstacle: contact point .* starts inside the obstacle"),
    # a plane above the block whose normal points up, away from the body: named as such
    ('shape = "cylinder", center = [0.0, 0.5], radius = 0.5',
     'shape = "plane", point = [0.0, 0.1], normal = [0.0, 1.0]',
     r"contact\.obstacle: the obstacle is on the body's side of its surface: .*a plane "
     r"obstacle's normal must point towards the body: reverse it"),
    ('motion = [0, "-0.02*t"]', 'rotation = { center = [0.0, 0.4] }',
     r"contact\.rotation\.angle: missing required key"),
    ('motion = [0, "-0.02*t"]', 'rotation = { center = [0.0, 0.4], angle = "t", axis = [0, 0, 1] }',
     r"contact\.rotation\.axis: not allowed: a 2-D rotation is about the point 'center'"),
    ('motion = [0, "-0.02*t"]', 'rotation = { center = [0.0], angle = "t" }',
     r"contact\.rotation\.center: expected 2 numbers, got 1"),
    ('motion = [0, "-0.02*t"]', 'rotation = { center = [0.0, 0.4], angle = "x[0]" }',
     r"contact\.rotation\.angle: invalid expression"),
    ('motion = [0, "-0.02*t"]', 'rotation = { center = [0.0, 0.4], angle = "log(t - 1)" }',
     r"contact\.rotation\.angle: 'log\(t - 1\)' evaluates to nan at t = 0"),
    ('motion = [0, "-0.02*t"]', 'rotation = { centre = [0.0, 0.4], angle = "t" }',
     r"contact\.rotation\.centre: unknown key"),
    ('type = "signorini"', 'type = "normal_compliance"\nmu = 1.0\nrotation = { center = [0, 0], angle = 1 }',
     r"contact\.rotation: not allowed: a foundation surface stays where it is"),
])
def test_bad_obstacles_are_located(shared_tmp_path, capsys, old, new, match):
    assert old in INDENTATION
    scene = write_shared(shared_tmp_path / "bad.toml", INDENTATION.replace(old, new))
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(match, err), err
    assert not out.exists()


@pytest.mark.parametrize("options, match", [
    ('snes_rtol = "abc"', r"solver\.petsc_options\.snes_rtol: invalid solver option\(s\) "
                          r"\(snes_rtol = 'abc'\): Input string abc has no numeric value"),
    ('snes_type = "newtonls", ksp_type = "bogus"',
     r"solver\.petsc_options\.ksp_type: .*Unable to find requested KSP type bogus"),
    ('pc_type = "bogus"', r"solver\.petsc_options\.pc_type: .*Unable to find requested PC type"),
    ('vpcontact_vi_linear = "bogus"',
     r"solver\.petsc_options\.vpcontact_vi_linear: .*must be lagged_lu, lagged_gamg or petsc"),
])
def test_options_petsc_refuses_are_located(shared_tmp_path, capsys, options, match):
    """Option values that only PETSc can judge (types, numbers) are refused when the solver is
    set up: a located error, exit 2, nothing written — not PETSc's error stack."""
    text = INDENTATION.replace("[time]", f"[solver]\npetsc_options = {{ {options} }}\n\n[time]")
    scene = write_shared(shared_tmp_path / "bad.toml", text)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(match, err) and "bad.toml:" in err, err
        assert "Traceback" not in err and "[0]" not in err, err
    assert not out.exists()


def test_obstacle_that_moves_out_of_reach_stops_the_run_with_its_record(shared_tmp_path, capsys):
    """A cylinder pushed deeper than its own height passes the contact face: at t = 1 it lies
    behind the outer contact nodes, whose rays met it at t = 0. The run stops there on every
    rank with the motion's place in the file (exit 2) and keeps its record of the steps
    before."""
    text = INDENTATION.replace('motion = [0, "-0.02*t"]', 'motion = [0, "-1.0*t"]')
    scene = write_shared(shared_tmp_path / "deep.toml", text)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(r"deep\.toml:\d+: contact\.motion: at t = 1, where the moving obstacle "
                         r"has gone: the obstacle has passed through the body: it lies behind "
                         r"contact point ", err), err
    MPI.COMM_WORLD.barrier()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] is False and summary["steps"] == 3
    assert "contact.motion" in summary["error"]


def test_an_obstacle_sliding_sideways_past_the_face_releases_its_nodes(shared_tmp_path):
    """A cylinder pressed lightly onto the left half of a block's top, then slid 0.8 to the
    right: the rays of the nodes it leaves behind no longer meet it. Those nodes are out of
    contact (gap = max_distance); the run stopped there (exit 2, 'where the moving obstacle
    has gone'), as for an indenter driven through the body."""
    text = INDENTATION.replace("box = { lower = [-0.4, 0.0], upper = [0.4, 0.0] }",
                               'plane = { axis = "y", value = 0.0 }').replace(
        'center = [0.0, 0.5]', 'center = [-0.5, 0.5]').replace(
        'motion = [0, "-0.02*t"]', 'motion = ["0.8*t", "-0.02*t"]')
    scene = write_shared(shared_tmp_path / "slide.toml", text)
    out = shared_tmp_path / "slide"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    header, rows = _csv(out / "contact.csv")
    last = rows[rows[:, 0] == rows[:, 0].max()]
    x, gap, pressure = (last[:, header.index(k)] for k in ("x", "gap", "pressure"))
    largest = np.abs(pressure).max()
    assert largest > 10.0 and np.all(pressure[np.abs(x - 0.3) < 0.1] > 1.0), pressure
    assert np.all(gap[x < -0.2] >= 1e3) and np.all(np.abs(pressure[x < 0.1]) <= 1e-9 * largest)


def test_show_writes_the_new_keys_back(shared_tmp_path, capsys):
    scene = write_shared(shared_tmp_path / "indentation.toml", INDENTATION)
    assert cli.main(["show", str(scene)]) == 0
    text = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:
        assert 'obstacle = { shape = "cylinder", center = [0.0, 0.5], radius = 0.5 }' in text
        assert 'motion = [0.0, "-0.02*t"]' in text or "motion = [0, " in text
    scene = write_shared(shared_tmp_path / "compression.toml", COMPRESSION)
    assert cli.main(["show", str(scene)]) == 0
    text = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:
        assert 'displacement = ["free", "-0.01*t"]' in text


def test_turning_obstacle_is_the_same_motion_as_its_translation(shared_tmp_path):
    """A circle turned about a point off its centre moves as the translation of its centre: the
    runs with ``rotation`` and with the equivalent ``motion`` give the same contact forces and
    gaps (to the bisection's round-off), and the obstacle pushes the block down and sideways."""
    turned = INDENTATION.replace('motion = [0, "-0.02*t"]',
                                 'rotation = { center = [0.0, 0.38], angle = "0.6*t" }')
    # centre (0, 0.5) turned by θ about (0, 0.38): d(θ) = (-0.12 sin θ, 0.12 cos θ - 0.12)
    moved = INDENTATION.replace('motion = [0, "-0.02*t"]',
                                'motion = ["-0.12*sin(0.6*t)", "0.12*cos(0.6*t) - 0.12"]')
    results = {}
    for name, text in (("turned", turned), ("moved", moved)):
        out = shared_tmp_path / name
        scene = write_shared(shared_tmp_path / f"{name}.toml", text)
        assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
        header, rows = _csv(out / "reactions.csv")
        contact = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1)
        results[name] = (rows[:, [header.index("contact_x"), header.index("contact_y")]],
                         contact)
    (f_turned, c_turned), (f_moved, c_moved) = results["turned"], results["moved"]
    assert np.allclose(f_turned, f_moved, rtol=1e-8, atol=1e-10 * np.abs(f_moved).max())
    assert np.allclose(c_turned[:, :6], c_moved[:, :6], rtol=1e-8, atol=1e-11)
    assert -f_moved[-1, 1] > 0 and f_moved[-1, 0] != 0.0  # pushed down, and sideways


def test_show_writes_a_rotation_back(shared_tmp_path, capsys):
    text = INDENTATION.replace('motion = [0, "-0.02*t"]',
                               'rotation = { center = [0.0, 0.38], angle = "0.6*t" }')
    scene = write_shared(shared_tmp_path / "turned.toml", text)
    assert cli.main(["show", str(scene)]) == 0
    shown = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:
        assert 'rotation = { center = [0.0, 0.38], angle = "0.6*t" }' in shown
    again = write_shared(shared_tmp_path / "again.toml", shown if MPI.COMM_WORLD.rank == 0 else "")
    assert cli.main(["validate", str(again)]) == 0


@pytest.mark.slow
def test_curved_face_on_a_foundation_surface_from_a_scene(shared_tmp_path):
    """Normal compliance on a curved Γ3 (a Gmsh cylinder) against a foundation surface given as
    an obstacle: a stiff foundation carries the Signorini force, and contact.csv holds
    σ_ν = -(1/μ)(u_ν - g)_+ in the nodes' normals."""
    from vpcontact.studies import hertz
    hertz.cylinder_msh(shared_tmp_path / "cylinder.msh", h_contact=0.01)
    forces = {}
    for kind, contact in (
            ("signorini", 'type = "signorini"\nboundary = "contact"\n'
                          'obstacle = { shape = "plane", point = [0, 0], normal = [0, 1] }'),
            ("normal_compliance", 'type = "normal_compliance"\nboundary = "contact"\nmu = 1e-4\n'
                                  'obstacle = { shape = "plane", point = [0, 0], normal = [0, 1] }')):
        scene = write_shared(shared_tmp_path / f"{kind}.toml",
                             scene_text("cylinder_contact", contact=contact))
        out = shared_tmp_path / kind
        assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
        header, rows = _csv(out / "reactions.csv")
        forces[kind] = rows[-1, header.index("contact_y")]
        contact_rows = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1)
        last = contact_rows[contact_rows[:, 0] == 1.0]
        if kind == "normal_compliance":
            expected = np.maximum(last[:, 4] - last[:, 5], 0.0) / 1e-4
            # (u_ν and g are written to 11 digits; their difference loses some of them)
            assert np.allclose(last[:, 7], expected, atol=1e-6 * np.abs(expected).max())
            # the compliance law read off the clearance column: p = −σ_ν = (−clearance)_+/μ
            assert np.allclose(last[:, 7], np.maximum(-last[:, 6], 0.0) / 1e-4,
                               atol=1e-6 * np.abs(expected).max())
        assert (last[:, 7] > 0).sum() >= 5  # several nodes in contact
    assert forces["signorini"] > 1e-3
    assert abs(forces["normal_compliance"] / forces["signorini"] - 1) < 0.05, forces


def test_p2_normal_compliance_on_a_curved_face_validates_as_it_runs(shared_tmp_path, capsys):
    """Normal compliance with P2 on a curved Γ3 runs without contact output; with it (recorded in
    P1 vertex normals) `validate` and `run` refuse it alike, at discretization.degree."""
    from vpcontact.studies import hertz
    hertz.cylinder_msh(shared_tmp_path / "cylinder.msh", h_contact=0.02)
    contact = ('type = "normal_compliance"\nboundary = "contact"\nmu = 1e-4\n'
               'obstacle = { shape = "plane", point = [0, 0], normal = [0, 1] }\n\n'
               '[discretization]\ndegree = 2')
    text = scene_text("cylinder_contact", contact=contact)
    scene = write_shared(shared_tmp_path / "p2.toml", text)
    for command in (["validate", str(scene)],
                    ["run", str(scene), "--out", str(shared_tmp_path / "out"), "--quiet"]):
        assert cli.main(command) == 2
        err = capsys.readouterr().err
        if MPI.COMM_WORLD.rank == 0:
            assert re.search(r"p2\.toml:\d+: discretization\.degree: normal compliance with "
                             r"degree = 2 on a contact face \('contact'\) that is not an "
                             r"axis-aligned plane",
                             err), err
    assert not (shared_tmp_path / "out").exists()
    quiet = write_shared(shared_tmp_path / "p2_quiet.toml",
                   text + "\n[output]\ncontact_csv = false\nfigures = false\n")
    out = shared_tmp_path / "quiet"
    assert cli.main(["run", str(quiet), "--out", str(out), "--quiet"]) == 0
    header, rows = _csv(out / "reactions.csv")
    assert rows[-1, header.index("contact_y")] > 1e-3


def test_contact_csv_off_is_not_written(shared_tmp_path):
    text = INDENTATION + "\n[output]\ncontact_csv = false\nfigures = false\nxdmf = false\n"
    scene = write_shared(shared_tmp_path / "quiet.toml", text)
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    assert not (out / "contact.csv").exists()
    assert not list(out.glob("*.png")) and not list(out.glob("*.xdmf"))
    assert (out / "reactions.csv").is_file() and (out / "summary.json").is_file()


def test_obstacle_that_moves_away_is_reported_with_its_closest_approach(shared_tmp_path, capsys):
    """An indenter driven away from the block runs (nothing is wrong with the scene) but the run
    says that its contact part never touched, with the closest approach; a run with contact
    says nothing."""
    away = INDENTATION.replace('motion = [0, "-0.02*t"]', 'motion = [0, "0.02*t"]')
    for name, text, warned in (("away", away, True), ("into", INDENTATION, False)):
        scene = write_shared(shared_tmp_path / f"{name}.toml", text)
        out = shared_tmp_path / name
        assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
        warnings = json.loads((out / "summary.json").read_text())["warnings"]
        err = capsys.readouterr().err
        if warned:
            assert len(warnings) == 1 and "'top' never touched" in warnings[0], warnings
            # the cylinder starts touching the block at one node and leaves: clearance 0 at t = 0
            assert re.search(r"closest approach [-0-9.e]+ at t = 0,", warnings[0]), warnings
            if MPI.COMM_WORLD.rank == 0:
                assert "warning: the contact part 'top' never touched" in err, err
        else:
            assert warnings == [] and "warning" not in err


@pytest.mark.slow
def test_contact_nodes_whose_rays_miss_the_obstacle_get_no_contact(shared_tmp_path, capsys):
    """The whole top as the contact part of the indentation: the vertical rays of the nodes
    beyond the cylinder's width miss it. They are left without contact (gap = max_distance),
    the run says how many, and the contact forces equal the run whose part is restricted to
    where the cylinder lies (they were refused with advice to raise max_distance)."""
    whole = INDENTATION.replace('box = { lower = [-0.4, 0.0], upper = [0.4, 0.0] }',
                                'plane = { axis = "y", value = 0.0 }')
    forces = {}
    for name, text in (("whole", whole), ("restricted", INDENTATION)):
        scene = write_shared(shared_tmp_path / f"{name}.toml", text)
        out = shared_tmp_path / name
        assert cli.main(["validate", str(scene)]) == 0
        assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
        header, rows = _csv(out / "reactions.csv")
        forces[name] = rows[:, header.index("contact_y")]
        warnings = json.loads((out / "summary.json").read_text())["warnings"]
        err = capsys.readouterr().err
        if name == "whole":
            assert len(warnings) == 1 and re.search(
                r"^\d+ node\(s\) of the contact part 'top' face away from the obstacle",
                warnings[0]), warnings
            if MPI.COMM_WORLD.rank == 0:
                assert "face away from the obstacle" in err
            contact = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1)
            far = contact[np.abs(contact[:, 1]) > 0.55]
            # no gap within reach, and no pressure beyond the residual's round-off
            assert len(far) and np.all(far[:, 5] == 1000.0)
            assert np.abs(far[:, 7]).max() <= 1e-9 * np.abs(contact[:, 7]).max()
        else:
            assert warnings == []
    assert np.abs(forces["whole"]).max() > 0
    np.testing.assert_allclose(forces["whole"], forces["restricted"], rtol=1e-8,
                               atol=1e-10 * np.abs(forces["restricted"]).max())


LOADED_FLOOR = """\
name = "loaded_floor"

[mesh]
type = "rectangle"
lower = [0.0, 0.0]
upper = [1.0, 0.5]
cells = [8, 4]
cell_type = "triangle"

HOLD

[boundary.bottom]
kind = "contact"
plane = { axis = "y", value = 0.0 }

[loads]
body_force = [0.0, "-2.0*t"]

[material]
E = 1000.0
nu = 0.3
plane = "strain"

[contact]
type = "LAW"
boundary = "bottom"
gap = GAP

[time]
T = 1.0
k = 0.5

[output]
figures = false

[[loads.point]]
at = [0.5, 0.0]
force = [0.0, "F*t"]
"""

#: a block pressed onto the floor by its weight, a traction on its top and a point load at a
#: floor node; only a roller at x = 0 holds it besides the floor
PRESSED = """\
[boundary.left]
kind = "symmetry"
plane = { axis = "x", value = 0.0 }

[boundary.top]
kind = "traction"
plane = { axis = "y", value = 0.5 }
traction = [0.0, "-1.0*t"]"""

#: a block hung from its clamped top whose point load pulls a floor node away from the floor;
#: a second point load at a clamped node is carried by the clamp
PULLED = """\
[boundary.top]
kind = "clamped"
plane = { axis = "y", value = 0.5 }

[[loads.point]]
at = [0.5, 0.5]
force = ["1.0*t", 0.0]"""


@pytest.mark.parametrize("law", ["signorini", "normal_compliance"])
def test_point_load_at_a_contact_node_is_not_contact_force(shared_tmp_path, capsys, law):
    """A point load at a node of a contact part is an applied load like f_0 and f_2, not a force
    of the obstacle or foundation. Pressed onto the floor by its weight (1), a traction on its top
    (1) and a point load of 0.5 at a floor node, the block's contact force is 2.5, balancing
    them, and the loaded node has the most compressive pressure, about its load over its share of
    the floor (0.125); with the point load pulling the node away from a floor it never touches,
    the contact force and pressures are 0 (Signorini: to round-off). A point load at a clamped
    node is the clamp's to carry. (The residual at the loaded node was reported as contact force
    and pressure: 2.0 and a tensile pressure at the loaded node; 1e3 and −8e3 from a floor never
    touched; and the clamp's reaction left the point load out.)"""
    laws = {"signorini": "", "normal_compliance": "\nmu = 1e-4"}
    base = LOADED_FLOOR.replace("LAW", law).replace("gap = GAP", "gap = GAP" + laws[law])
    pressed = base.replace("HOLD", PRESSED).replace("GAP", "0.0").replace("F*t", "-0.5*t")
    pulled = base.replace("HOLD", PULLED).replace("GAP", "0.005").replace("F*t", "1e3*t")
    for name, text in (("pressed", pressed), ("pulled", pulled)):
        scene = write_shared(shared_tmp_path / f"{name}.toml", text)
        out = shared_tmp_path / name
        assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
        header, rows = _csv(out / "reactions.csv")
        final = dict(zip(header, rows[-1]))
        contact = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1)
        last = contact[contact[:, 0] == 1.0]  # t, x, y, z, u_normal, gap, clearance, pressure
        loaded = last[np.isclose(last[:, 1], 0.5)][0]
        warnings = json.loads((out / "summary.json").read_text())["warnings"]
        capsys.readouterr()
        if name == "pressed":
            assert final["contact_y"] == pytest.approx(2.5, rel=1e-6)
            assert abs(final["contact_x"]) < 1e-9
            assert warnings == []
            assert loaded[7] == last[:, 7].max()
            assert loaded[7] == pytest.approx(0.5 / 0.125 + 2.0, rel=0.3)
            # the lumped pressures add up to the contact force (P1: nodal shares h, h/2)
            shares = np.where(np.isclose(last[:, 1], 0.0) | np.isclose(last[:, 1], 1.0),
                              0.0625, 0.125)
            assert np.dot(shares, last[:, 7]) == pytest.approx(2.5, rel=1e-6)
        else:
            # (and the small-strain warning: the point load strains its node's cells by far)
            touched = [w for w in warnings if "small-strain" not in w]
            assert len(touched) == 1 and "never touched" in touched[0], warnings
            assert final["top_y"] == pytest.approx(-(1e3 - 2.0 * 0.5), rel=1e-9)
            assert final["top_x"] == pytest.approx(-1.0, rel=1e-9)
            if law == "normal_compliance":  # the foundation's law: exactly 0 off contact
                assert final["contact_x"] == 0.0 and final["contact_y"] == 0.0
                assert np.all(contact[:, 7] == 0.0)
            else:  # the residual at inactive nodes: round-off of the forces
                assert abs(final["contact_x"]) + abs(final["contact_y"]) < 1e-9 * 1e3
                assert np.abs(contact[:, 7]).max() < 1e-9 * 1e3 / 0.125
