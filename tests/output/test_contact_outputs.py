# SPDX-License-Identifier: MIT
"""The outputs a contact engineer looks at first (issue 45 §4): the contact pressure positive
in compression (contact.csv, the XDMF field), the contact-pressure figure and the 3-D face
maps, figures that draw a uniform field in one colour, name quantities without units and do
not overlap their tick labels, force–displacement panels only where they mean something, and
the warning of a contact part that never touched in a run that writes no contact output.

The block of tests/scenes/block_on_floor.toml is pressed onto a frictionless rigid floor by
the traction 5t: its stress is uniform, σ_yy = −5t, so the floor's pressure is 5t at every node.
"""

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli
from vpcontact import scene as scenes
from vpcontact.output import contact_figures, plots
from vpcontact.output.fields import ContactHistory
from vpcontact.output.session import Session
from vpcontact.scene import build

from tests.support.mpi_launch import write_shared

BLOCK_3D = """\
name = "block_3d"

[mesh]
type = "box"
upper = [1.0, 1.0, 0.5]
cells = [3, 3, 1]

[boundary.floor]
kind = "contact"
plane = { axis = "z", value = 0.0 }

[boundary.top]
kind = "traction"
plane = { axis = "z", value = 0.5 }
traction = [0, 0, "-5*t"]

[material]
E = 1000.0
nu = 0.3

[contact]
type = "signorini"
boundary = "floor"
gap = 0.0

[time]
T = 1.0
k = 0.5

[discretization]
degree = 1

[output]
xdmf = false
"""


def _run(folder: Path, name: str, text: str) -> Path:
    scene = write_shared(folder / f"{name}.toml", text)
    out = folder / name
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    return out


def _block_2d(scene_text) -> str:
    return scene_text("block_on_floor").replace("xdmf = false\nfigures = false\n", "")


def test_contact_csv_and_the_xdmf_field_give_the_pressure_positive_in_compression(
        shared_tmp_path, scene_text):
    out = _run(shared_tmp_path, "block", _block_2d(scene_text))
    rows = np.genfromtxt(out / "contact.csv", delimiter=",", names=True)
    assert len(np.unique(rows["t"])) == 3 and len(rows) == 3 * 9
    np.testing.assert_allclose(rows["pressure"], 5.0 * rows["t"], rtol=1e-8, atol=1e-9)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["reactions"]["contact_force_final"][1] == pytest.approx(5.0, rel=1e-8)
    try:
        import h5py
    except ImportError:  # the field's sign is the CSV's (one function gives both)
        return
    if MPI.COMM_WORLD.rank == 0:
        with h5py.File(out / "on_floor.h5", "r") as f:
            group = f["Function/contact_pressure"]
            last = max(group, key=lambda key: float(key.replace("_", ".")))
            values = np.asarray(group[last]).ravel()
        assert values.max() == pytest.approx(5.0, rel=1e-8) and values.min() >= -1e-9


def test_the_xdmf_contact_pressure_field_is_positive_in_compression(shared_tmp_path,
                                                                      scene_text):
    """The nodal field written into the XDMF series (checked before writing: the values the
    series gets): 5 at the floor's nodes at t = 1, 0 elsewhere."""
    path = write_shared(shared_tmp_path / "block.toml", _block_2d(scene_text))
    model = build(scenes.load(path))
    for _ in range(2):
        model.problem.step(0.5)
    history = ContactHistory(model.problem)
    (field, refresh), *_ = Session(model, shared_tmp_path / "unused")._pressure_field(history)
    assert field.name == "contact_pressure"
    refresh()
    comm = MPI.COMM_WORLD
    largest = comm.allreduce(float(field.x.array.max(initial=-np.inf)), op=MPI.MAX)
    smallest = comm.allreduce(float(field.x.array.min(initial=np.inf)), op=MPI.MIN)
    assert largest == pytest.approx(5.0, rel=1e-8) and smallest >= -1e-9, (smallest, largest)


class Drawn:
    """Records every figure a run saves (its path and what it holds), then saves it."""

    def __init__(self, monkeypatch):
        self.figures = {}
        original = plots.save

        def save(fig, path):
            fig.canvas.draw()
            self.figures[Path(path).name] = _contents(fig)
            original(fig, path)

        for module in (plots, contact_figures):
            monkeypatch.setattr(module, "save", save)


def _contents(fig) -> dict:
    """What the tests check of a drawn figure."""
    axes = []
    for ax in fig.axes:
        three_d = hasattr(ax, "zaxis")
        labels = [ax.get_xlabel(), ax.get_ylabel()] + ([ax.get_zlabel()] if three_d else [])
        overlaps = [] if three_d else _overlapping_ticks(fig, ax)
        offsets = [a.get_offset_text().get_text() for a in (ax.xaxis, ax.yaxis)]
        axes.append({"labels": labels, "overlaps": overlaps, "offsets": offsets,
                     "lines": len(ax.lines), "collections": len(ax.collections)})
    return {"axes": axes}


def _overlapping_ticks(fig, ax) -> list:
    """The pairs of visible tick labels of one axis of ``ax`` whose boxes overlap."""
    renderer = fig.canvas.get_renderer()
    found = []
    for axis in (ax.xaxis, ax.yaxis):
        boxes = [t.get_window_extent(renderer) for t in axis.get_ticklabels()
                 if t.get_visible() and t.get_text()]
        found += [(a, b) for i, a in enumerate(boxes) for b in boxes[i + 1:] if a.overlaps(b)]
    return found


@pytest.mark.parametrize("dim", [2, 3])
def test_the_figures_of_a_contact_run(shared_tmp_path, scene_text, monkeypatch, dim):
    """2-D: the pressure along the floor, one curve per output time; 3-D: maps of the contact
    face (pressure and u_ν), no curves. Every figure: no unit, no overlapping tick label, and
    the uniform fields (the pressure 5t, the von Mises norm) without an offset."""
    drawn = Drawn(monkeypatch)
    text = _block_2d(scene_text) if dim == 2 else BLOCK_3D
    out = _run(shared_tmp_path, f"figures_{dim}d", text)
    names = {"final_state.png", "reactions.png", "contact_pressure.png", "contact_history.png"}
    for name in names:
        assert (out / name).stat().st_size > 1000, name
    if MPI.COMM_WORLD.rank != 0:
        return
    assert names <= set(drawn.figures), drawn.figures.keys()
    for name, figure in drawn.figures.items():
        for ax in figure["axes"]:
            assert not any("[" in label for label in ax["labels"]), (name, ax["labels"])
            assert ax["overlaps"] == [], (name, ax["labels"])
    pressure = drawn.figures["contact_pressure.png"]["axes"]
    if dim == 2:  # the curves and their time colour bar
        assert pressure[0]["lines"] == 3 and pressure[0]["labels"][1] == "contact pressure −σ_ν"
        assert pressure[0]["offsets"] == ["", ""], pressure[0]
    else:  # four maps (t = 0 is left out: two records after it) and a colour bar
        for name in ("contact_pressure.png", "contact_history.png"):
            maps = drawn.figures[name]["axes"][:-1]
            assert len(maps) == 2 and all(ax["lines"] == 0 and ax["collections"] == 1
                                          for ax in maps), (name, maps)
    bar = drawn.figures["final_state.png"]["axes"][-1]  # the von Mises colour bar
    assert bar["offsets"] == ["", ""], bar


@pytest.mark.parametrize("values, expected", [
    (5.0 + 1e-13 * np.sin(np.arange(40.0)), (4.75, 5.25)),  # uniform with round-off: ±5 %
    (np.full(7, -2.0), (-2.1, -1.9)),
    (np.zeros(5), (-1.0, 1.0)),
    (np.array([1.0, 3.0, np.nan]), (1.0, 3.0)),             # a field that varies: its range
    (np.array([1.0, 1.0 + 1e-6]), (1.0, 1.0 + 1e-6)),
])
def test_a_uniform_field_gets_a_fixed_colour_range_around_its_value(values, expected):
    assert plots.colour_range(values) == pytest.approx(expected, rel=1e-12)


def _forces(driver, parts, reactions=None):
    times = list(range(len(driver)))
    parts = [np.array(p, dtype=float).reshape(-1, 2) for p in parts]
    return SimpleNamespace(driver=list(driver), parts=parts, times=times,
                           reactions=reactions or [np.zeros((1, 2)) for _ in times])


@pytest.mark.parametrize("driver, parts, panels", [
    ([None, None, None], [[[0, 0]], [[0, 1]], [[0, 2]]], []),        # force-driven
    ([0.1, 0.1, 0.1], [[[0, 0]], [[0, 1]], [[0, 2]]], []),          # the driver stands still
    ([0.0, -0.1, -0.2], [[[0, 0]], [[0, 0]], [[0, 0]]], []),        # nothing carries a force
    ([0.0, -0.1, -0.2], [[[0, 0], [0, 0]], [[0, 1], [0, 0]], [[0, 2], [1e-14, 0]]], [0]),
    ([0.0, -0.1, -0.2], [[[0, 0], [0, 0]], [[0, 1], [0, 3]], [[0, 2], [0, 4]]], [0, 1]),
])
def test_force_displacement_panels_only_where_they_mean_something(driver, parts, panels):
    assert plots._driven_parts(_forces(driver, parts)) == panels


@pytest.mark.parametrize("law", ['type = "normal_compliance"\nmu = 1e-3',
                                 'type = "signorini"'])
def test_a_contact_part_that_never_touched_is_warned_without_contact_output(shared_tmp_path,
                                                                             capsys, law):
    """The elastic cantilever with a floor far below it, contact.csv and figures off: the
    run still says that the floor never touched (a compliant floor was not recorded, and not
    warned about, without contact output)."""
    text = scenes.bundled()["elastic_2d"].read_text().replace(
        "[boundary.end]", '[boundary.floor]\nkind = "contact"\nplane = { axis = "y", value = '
        '0.0 }\n\n[boundary.end]').replace("figures = false", "figures = false\n"
                                          "contact_csv = false\nxdmf = false")
    text += f'\n[contact]\n{law}\nboundary = "floor"\ngap = 10.0\n'
    out = _run(shared_tmp_path, "far_floor", text)
    assert not (out / "contact.csv").exists()
    warnings = json.loads((out / "summary.json").read_text())["warnings"]
    assert len(warnings) == 1 and "'floor' never touched" in warnings[0], warnings
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert "warning: the contact part 'floor' never touched" in err, err
