# SPDX-License-Identifier: MIT
"""Friction at nodes that a contact face shares with a face whose displacement is prescribed
(issue 45): a block squeezed between a fixed frictional floor and a frictional plate pressed by
10 N, and pushed along x by a prescribed u_x on its left face. While it slides the push — the
left face's reaction — is 𝔣_floor · 10 + 𝔣_plate · 10 = 6, to 1e-6.

The two corners of the left face lie on the floor and under the plate: their tangential motion
is prescribed, and their friction was lost (the solver's row there is the support's, and the
reaction was read off the residual with the friction left in it). The push came out 5.897 on
32×16 cells (the compliant floor 5.8965), short by the corners' friction (vpcontact.solver.support_forces,
vpcontact.model.nodal_friction). The same with Tresca's law on the floor (threshold 1 per unit
length: 2) and with a compliant frictional floor (its UFL friction term at the corner).
"""

import numpy as np
import pytest

from vpcontact import cli

from tests.support.mpi_launch import write_shared

SQUEEZED = """
name = "squeezed"

[mesh]
type = "rectangle"
lower = [0.0, 0.0]
upper = [2.0, 1.0]
cells = [32, 16]

[boundary.left]
kind = "displacement"
plane = { axis = "x", value = 0.0 }
displacement = ["0.05*max(t - 0.4, 0)", "free"]

[boundary.bottom]
kind = "contact"
plane = { axis = "y", value = 0.0 }

[boundary.top]
kind = "contact"
plane = { axis = "y", value = 1.0 }

[material]
E = 1000.0
nu = 0.3
plane = "strain"

[[contact]]
boundary = "bottom"
${floor}

[[contact]]
type = "signorini"
boundary = "top"
obstacle = { shape = "plane", point = [0.0, 1.0], normal = [0.0, -1.0] }
force = [0.0, "-10*min(t/0.3, 1)"]
friction = { type = "coulomb", coefficient = 0.4 }

[time]
T = 1.2
k = 0.1

[output]
xdmf = false
figures = false
"""

RIGID = """type = "signorini"
obstacle = { shape = "plane", point = [0.0, 0.0], normal = [0.0, 1.0] }
"""

FLOORS = {
    "coulomb": RIGID + 'friction = { type = "coulomb", coefficient = 0.2 }',
    "tresca": RIGID + 'friction = { type = "tresca", threshold = 1.0 }',
    "compliant": 'type = "normal_compliance"\nmu = 1e-5\n'
                 'friction = { type = "coulomb", coefficient = 0.2 }',
}


def _reactions(out):
    lines = (out / "reactions.csv").read_text().splitlines()
    header = lines[0].split(",")
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    return {name: rows[:, i] for i, name in enumerate(header)}


@pytest.mark.parametrize("floor", [
    "coulomb", "compliant",
    # (its first two steps hit DIVERGED_MAX_IT and are cut, as before the fix: 12 s)
    pytest.param("tresca", marks=pytest.mark.slow)])
def test_the_push_on_a_block_sliding_between_two_frictional_faces_is_their_friction(
        shared_tmp_path, floor):
    text = SQUEEZED.replace("${floor}", FLOORS[floor])
    scene = write_shared(shared_tmp_path / f"{floor}.toml", text)
    out = shared_tmp_path / floor
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    f = _reactions(out)
    sliding = f["t"] >= 0.8 - 1e-9
    assert sliding.sum() >= 3
    # the plate presses with 10, the floor carries it (the corners' normal forces included:
    # the left face holds nothing along y)
    assert np.allclose(f["top_y"][sliding], -10.0, rtol=1e-8), f["top_y"]
    assert np.allclose(f["bottom_y"][sliding], 10.0, rtol=1e-8), f["bottom_y"]
    assert np.allclose(f["left_y"], 0.0, atol=1e-8), f["left_y"]
    # each face's friction at its limit, against the push; the push is their sum
    floor_friction = 1.0 * 2.0 if floor == "tresca" else 0.2 * 10.0
    assert np.allclose(f["bottom_x"][sliding], -floor_friction, rtol=1e-8), f["bottom_x"]
    assert np.allclose(f["top_x"][sliding], -0.4 * 10.0, rtol=1e-8), f["top_x"]
    assert np.allclose(f["left_x"][sliding], floor_friction + 4.0, rtol=1e-6), f["left_x"]
    assert np.allclose(f["left_x"][sliding] + f["contact_x"][sliding], 0.0, atol=1e-8 * 6.0)


def _in_3d(text: str) -> str:
    """The squeezed block as a box [0, 2] × [0, 1] × [0, 1] (8 × 4 × 4 cells), floor and plate
    normal to z, the left face pushed along x (y and z free)."""
    for old, new in (('type = "rectangle"', 'type = "box"'),
                     ("lower = [0.0, 0.0]", "lower = [0.0, 0.0, 0.0]"),
                     ("upper = [2.0, 1.0]", "upper = [2.0, 1.0, 1.0]"),
                     ("cells = [32, 16]", "cells = [8, 4, 4]"),
                     ('"0.05*max(t - 0.4, 0)", "free"]', '"0.05*max(t - 0.4, 0)", "free", "free"]'),
                     ('axis = "y", value', 'axis = "z", value'), ('plane = "strain"\n', ""),
                     ("point = [0.0, 1.0], normal = [0.0, -1.0]",
                      "point = [0.0, 0.0, 1.0], normal = [0.0, 0.0, -1.0]"),
                     ("point = [0.0, 0.0], normal = [0.0, 1.0]",
                      "point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0]"),
                     ('force = [0.0, "-10', 'force = [0.0, 0.0, "-10')):
        assert old in text, old
        text = text.replace(old, new)
    return text


def test_3d_edges_keep_their_friction_across_the_push(shared_tmp_path):
    """3-D: the left face's edges on the floor and under the plate have u_x prescribed and u_y
    free, so their cone couples a prescribed and a free tangential component. The push tends to
    6 as the block slides (the Poisson traction across it turning into the push's direction:
    6 − 2.4e−5, 1.5e−5, 1.0e−5 over the last steps); it was 5.571 (−7 %), with a cut step and
    149 Newton iterations where the run now takes 66."""
    text = _in_3d(SQUEEZED.replace("${floor}", FLOORS["coulomb"]))
    scene = write_shared(shared_tmp_path / "box.toml", text)
    out = shared_tmp_path / "box"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    f = _reactions(out)
    sliding = f["t"] >= 1.0 - 1e-9
    assert np.allclose(f["top_z"][sliding], -10.0, rtol=1e-8), f["top_z"]
    assert np.all(np.diff(f["left_x"][sliding]) > 0)
    assert abs(f["left_x"][-1] / 6.0 - 1.0) < 1e-5, f["left_x"]
    assert np.allclose(f["left_x"] + f["contact_x"], 0.0, atol=1e-8 * 6.0)
