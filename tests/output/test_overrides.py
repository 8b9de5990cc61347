# SPDX-License-Identifier: MIT
"""What the command line says about a scene before it runs it (issue 45):

* the run's first line names the law, yield set, plane and formulation taken, marking defaults;
  with the von Mises default in 3-D a relaxing Perzyna bar gives the von Mises answer (its
  end force tends to σ_Y × the section), not the paper's set's σ_Y/√2;
* ``--set KEY=VALUE`` overrides of scene keys for ``run``, ``validate`` and ``show``: located
  like the file's keys (exit 2, nothing written), recorded in ``summary.json``;
* warnings for data a small-strain model cannot mean, printed at ``validate`` and ``run``.
"""

import json
import math

import pytest
from mpi4py import MPI

from vpcontact import cli

from tests.support.mpi_launch import write_shared

ROOT = MPI.COMM_WORLD.rank == 0


def _summary(out):
    return json.loads((out / "summary.json").read_text())


def _end_force(out) -> float:
    """|the end part's reaction along x| at the final time."""
    return abs(_summary(out)["reactions"]["final"]["end"][0])


@pytest.mark.parametrize("yield_set, expected, shown", [
    ("", 1.0, "von_mises, default"),       # the default: von Mises, uniaxial yield at σ_Y
    ('yield_set = "von_mises"', 1.0, "von_mises"),
    ('yield_set = "paper"', 1.0 / math.sqrt(2.0), "paper"),  # the paper's set: σ_Y/√2
])
def test_a_3d_bar_relaxes_to_the_von_mises_yield_stress_by_default(
        yield_set, expected, shown, shared_tmp_path, scene_text, capsys):
    """A 3-D Perzyna bar (σ_Y = 1, section 1) stretched by 1 % and held: the stress relaxes onto
    the yield set (k E/μ* = 50 per step, 8 steps held), so the end force is the set's uniaxial
    yield stress. Without ``yield_set`` it was the paper's 0.7071 (the bar flowed 1.59× faster
    under a load); it must be von Mises' 1. The run's first line says which set it took."""
    name = shown.split(",")[0] + ("_default" if not yield_set else "")
    path = write_shared(shared_tmp_path / f"bar_{name}.toml",
                        scene_text("relaxing_bar_3d", yield_set=yield_set))
    out = shared_tmp_path / name
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert _end_force(out) == pytest.approx(expected, rel=1e-9)  # measured 8e-14
    if ROOT:
        assert printed.splitlines()[0] == (f"relaxing_bar: 3-D, law perzyna (yield set {shown}), "
                                           "displacement P1 (default)")


def test_run_first_line_names_the_2d_plane(shared_tmp_path, capsys):
    assert cli.main(["run", "elastic_2d", "--out", str(shared_tmp_path / "e"), "--quiet",
                     "--set", "time.k=0.5", "--set", "mesh.cells=[8, 2]"]) == 0
    printed = capsys.readouterr().out
    if ROOT:
        assert printed.splitlines()[0] == ("elastic_2d: 2-D, law elastic, plane stress, "
                                           "displacement P1 (default)")


def test_run_records_its_overrides_in_the_summary(shared_tmp_path):
    out = shared_tmp_path / "overridden"
    assert cli.main(["run", "elastic_2d", "--out", str(out), "--quiet", "--set", "time.k=0.5",
                     "--set", "mesh.cells=[8,2]", "--set", "material.plane=strain"]) == 0
    summary = _summary(out)
    assert summary["overrides"] == {"time.k": 0.5, "mesh.cells": [8, 2],
                                    "material.plane": "strain"}
    assert summary["steps"] == 2  # T = 1 in steps of 0.5
    plain = shared_tmp_path / "plain"
    assert cli.main(["run", "elastic_2d", "--out", str(plain), "--quiet"]) == 0
    assert _summary(plain)["overrides"] == {}
    assert _summary(plain)["scene"]["sha256"] != summary["scene"]["sha256"]


@pytest.mark.parametrize("command", ["run", "validate", "show"])
def test_a_bad_override_exits_2_located_and_writes_nothing(command, shared_tmp_path, capsys):
    out = shared_tmp_path / "never"
    extra = ["--out", str(out), "--quiet"] if command == "run" else []
    code = cli.main([command, "elastic_2d", *extra, "--set", "time.k=0.5",
                     "--set", "law.mu_sta=50"])
    captured = capsys.readouterr()
    assert code == 2 and not out.exists()
    if ROOT:
        assert captured.err == ("error: --set law.mu_sta: unknown key 'mu_sta'; did you mean "
                                "'mu_star'?\n"), captured.err
        assert captured.out == ""


def test_validate_and_show_take_overrides(capsys):
    assert cli.main(["validate", "elastic_2d", "--set", "material.plane=strain"]) == 0
    printed = capsys.readouterr().out
    if ROOT:
        assert "law elastic, plane strain, displacement P1 (default)" in printed, printed
    assert cli.main(["show", "elastic_2d", "--set", "time.k=0.5"]) == 0
    shown = capsys.readouterr().out
    if ROOT:
        assert "k = 0.5" in shown.splitlines() and "# with --set time.k=0.5" in shown


def test_validate_and_run_warn_about_implausible_data(shared_tmp_path, scene_text, capsys):
    """Mixed units (E in MPa, σ_Y in Pa) and a foundation read as a friction coefficient:
    warnings on stderr, located, at validate and before the run; the run goes on."""
    text = scene_text("base").replace("E = 1e8", "E = 2.1e5") + (
        '[law]\ntype = "perzyna"\nsigma_y = 2.5e8\nmu_star = 1.0\n')
    path = write_shared(shared_tmp_path / "units.toml", text)
    lines = text.splitlines()
    sigma_line = lines.index("sigma_y = 2.5e8") + 1
    mu_line = lines.index("mu = 100.0") + 1
    assert cli.main(["validate", str(path)]) == 0
    err = capsys.readouterr().err
    if ROOT:
        assert f"warning: {path}:{sigma_line}: law.sigma_y: the yield strain" in err, err
        assert f"warning: {path}:{mu_line}: contact.mu: mu = 100 is the foundation's " \
               "compliance" in err, err
    out = shared_tmp_path / "units"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet", "--set", "time.k=0.5",
                     "--set", "time.T=0.5"]) == 0
    err = capsys.readouterr().err
    if ROOT:
        assert f"warning: {path}:{sigma_line}: law.sigma_y: " in err, err
