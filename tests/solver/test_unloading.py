# SPDX-License-Identifier: MIT
"""Bodies held by their contacts can be unloaded (issue 45): a load that ramps back to exactly
zero, one that stays at zero for a while, one that passes through zero to a reversed value on
a frictional contact — each completes (it stopped with "no equilibrium … the stabilising spring
carries 1 of the applied forces": the spring's share was measured against the forces of the
unloaded step, which are its own footprint). A body pulled off its floor still stops, with a
message located at its scene line (vpcontact.solver.held)."""

import json
import re

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli

from tests.support.mpi_launch import write_shared

ROOT0 = MPI.COMM_WORLD.rank == 0


def _rows(path):
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    return {name: np.array([float(line.split(",")[i]) for line in lines[1:]])
            for i, name in enumerate(header)}


def _on_floor(scene_text, traction: str, T: float, k: float = 0.5, friction: str = "") -> str:
    text = scene_text("block_on_floor").replace('traction = [0, "-5*t"]', f"traction = {traction}")
    text = text.replace("T = 1.0", f"T = {T}").replace("k = 0.5", f"k = {k}")
    return text.replace("gap = 0.0", "gap = 0.0" + (f"\nfriction = {friction}" if friction else ""))


def _run(shared_tmp_path, name: str, text: str) -> tuple[int, object]:
    scene = write_shared(shared_tmp_path / f"{name}.toml", text)
    out = shared_tmp_path / name
    return cli.main(["run", str(scene), "--out", str(out), "--quiet"]), out


COULOMB = '{ type = "coulomb", coefficient = 0.3 }'


@pytest.mark.parametrize("traction, T, friction, load", [
    # up and back to exactly 0 at the end
    ('[0, "-5*t*(2 - t)"]', 2.0, "", lambda t: -5 * t * (2 - t)),
    # back to 0 at t = 2, then left there for two steps
    ('[0, "-5*max(min(t, 2 - t), 0)"]', 3.0, "", lambda t: -5 * np.maximum(np.minimum(t, 2 - t), 0)),
    # the same cycle on a frictional floor
    ('[0, "-5*t*(2 - t)"]', 2.0, COULOMB, lambda t: -5 * t * (2 - t)),
])
def test_a_load_unload_cycle_completes(scene_text, shared_tmp_path, capsys, traction, T, friction,
                                       load):
    """The floor carries the load on the way up and down; at zero load it carries nothing, and
    the run ends normally with a warning that the body was unloaded at t = 2 (kept where it
    was)."""
    code, out = _run(shared_tmp_path, "cycle", _on_floor(scene_text, traction, T,
                                                         friction=friction))
    err = capsys.readouterr().err
    assert code == 0, err
    forces = _rows(out / "reactions.csv")
    assert np.allclose(forces["contact_y"], -load(forces["t"]), rtol=1e-7, atol=1e-7), forces
    summary = json.loads((out / "summary.json").read_text())
    held = summary["stabilization"]
    assert summary["completed"] and held["unloaded_at"] == 2.0, held
    assert held["largest_share_of_applied"] < 1e-6, held
    assert any("at t = 2 the body was unloaded" in w for w in summary["warnings"]), summary
    if ROOT0:
        assert "warning: at t = 2 the body was unloaded" in err, err


BETWEEN = """\
name = "between"

[mesh]
type = "rectangle"
lower = [0.0, 0.0]
upper = [1.0, 0.5]
cells = [8, 4]

[boundary.floor]
kind = "contact"
plane = { axis = "y", value = 0.0 }

[boundary.ceiling]
kind = "contact"
plane = { axis = "y", value = 0.5 }

[loads]
body_force = [0, "-10*(1 - 2*t)"]

[material]
E = 1000.0
nu = 0.3
plane = "strain"

[[contact]]
type = "signorini"
boundary = "floor"
gap = 0.0
friction = { type = "coulomb", coefficient = 0.3 }

[[contact]]
type = "signorini"
boundary = "ceiling"
gap = 0.0
friction = { type = "coulomb", coefficient = 0.3 }

[time]
T = 0.55
k = 0.05

[output]
xdmf = false
figures = false
"""


def test_a_load_through_zero_to_a_reversed_value_on_frictional_contacts(shared_tmp_path,
                                                                        capsys):
    """A block between a frictional floor and a frictional ceiling (both touching, no
    Dirichlet part), its weight reversed through exactly zero at t = 0.5 to a small upward
    load (a tenth of the start's): the floor carries it down to zero, the ceiling after; the
    run completes (it stopped at t = 0.5 with "no equilibrium")."""
    code, out = _run(shared_tmp_path, "between", BETWEEN)
    err = capsys.readouterr().err
    assert code == 0, err
    forces = {name: column[1:] for name, column in _rows(out / "reactions.csv").items()}
    t = forces["t"]  # (from the first step: t = 0 is the initial state, not solved)
    weight = -10 * (1 - 2 * t) * 0.5  # body force × area
    assert np.allclose(forces["floor_y"], np.where(t <= 0.5, -weight, 0.0), atol=1e-7), forces
    assert np.allclose(forces["ceiling_y"], np.where(t > 0.5, -weight, 0.0), atol=1e-7), forces
    assert np.allclose(forces["contact_x"], 0.0, atol=1e-7)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] and summary["stabilization"]["unloaded_at"] == 0.5


@pytest.mark.parametrize("tangential, friction, held", [
    ('"0.5 - t"', COULOMB, True),   # through zero to -0.1 at t = 0.6: friction holds it
    ('"2 - t"', COULOMB, False),    # beyond the friction (0.3 × 5): it slides off
])
def test_a_tangential_load_on_a_frictional_floor(scene_text, shared_tmp_path, capsys, tangential,
                                                 friction, held):
    """A block pressed onto a floor by 5 and pushed along it: within the friction (|t_x| ≤ 1.5)
    the floor holds it, the push passing through zero to a reversed value (refused by
    `validate` before: "no contact part can resist it … contact is frictionless"); beyond the
    friction there is no equilibrium, refused at that step, located."""
    text = _on_floor(scene_text, f"[{tangential}, -5]", 0.6, k=0.1, friction=friction)
    code, out = _run(shared_tmp_path, "pushed", text)
    err = capsys.readouterr().err
    if held:
        assert code == 0, err
        forces = _rows(out / "reactions.csv")
        t = forces["t"][1:]
        assert np.allclose(forces["contact_x"][1:], t - 0.5, atol=1e-7), forces["contact_x"]
        assert np.allclose(forces["contact_y"][1:], 5.0, rtol=1e-8)
        return
    assert code == 2
    if ROOT0:
        assert re.search(r"pushed\.toml:\d+: boundary: no equilibrium at t = 0\.1: nothing holds "
                         r"the body along its translation along x .*beyond its friction", err), err


def test_a_checkpoint_keeps_the_held_anchor(scene_text):
    """A run resumed from a checkpoint goes on exactly as without it: the spring's anchor
    (u at the last step) and the force scale are in the checkpoint (the anchor was not, and a
    resumed spring pulled the body back to u = 0)."""
    from vpcontact.scene import loads_text
    from vpcontact.scene.builder import build
    from vpcontact.solver.stepping import StepControl, advance
    scene = loads_text(_on_floor(scene_text, '[0, "-5*t*(2 - t)"]', 2.0))
    whole, first = (build(scene, MPI.COMM_WORLD).problem for _ in range(2))
    for problem in (whole, first):
        list(advance(problem, 1.0, StepControl(0.5)))
    scalars, arrays = first.checkpoint()
    resumed = build(scene, MPI.COMM_WORLD).problem
    resumed.restore(scalars, arrays)
    assert np.array_equal(resumed.held.held.x.array, first.held.held.x.array)
    assert resumed.held.state() == first.held.state() and first.held.last_applied > 0
    for problem in (whole, resumed):
        list(advance(problem, 2.0, StepControl(0.5)))
    assert np.array_equal(resumed.u.x.array, whole.u.x.array)
    assert resumed.held.unloaded_at == whole.held.unloaded_at == 2.0
