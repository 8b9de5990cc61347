# SPDX-License-Identifier: MIT
"""The benchmark scripts (bench/*.py) refuse bad command-line values before any work: exit
status 2 with one line naming the option, no traceback, and nothing written (neither the JSON
of ``--out`` nor, through benchlib.save, any other).

Each case runs the script's ``main(argv)`` in this process (argparse refuses during parsing, so
no mesh is made). The bad value comes after small valid values of the other options, so that a
script which let it through would fail fast instead of starting its full-size benchmark."""

import importlib

import pytest

#: Small valid values per script (a later occurrence of an option replaces them).
SMALL = {
    "contact_frames": ["--n2d", "2", "--n3d", "1", "--steps", "1", "--repeat", "1"],
    "friction_scratch": ["--cells", "8", "2", "--k", "0.25"],
    "friction_step": ["--cells", "8", "2"],
    "kernel_throughput": ["--points", "10", "--repeats", "1"],
    "locking_3d": ["--sizes", "1", "--formulations", "p1", "--T", "0.02"],
    "p_multigrid": ["--sizes", "1", "--forms", "dev", "--variants", "gamg"],
    "scene_dispatch": ["--cells", "4", "2", "--steps", "1"],
    "signorini_step": ["--n", "1", "--dt", "0.5", "--t-final", "0.5"],
    "step_cost": ["--sizes2d", "--sizes3d", "--ranks", "1"],
    "work_precision_1d": ["--paper-min-r", "0.1", "--bdf2-levels", "1"],
}
NO_OUT = {"work_precision_1d"}  # (writes bench/results/work_precision_1d.json: save is watched)

CASES = [  # (script, bad arguments, the option the error must name)
    ("contact_frames", ["--n2d", "0"], "--n2d"),
    ("contact_frames", ["--n3d", "100000"], "--n3d"),  # more cells than dolfinx can number
    ("contact_frames", ["--steps", "0"], "--steps"),
    ("contact_frames", ["--repeat", "-1"], "--repeat"),
    ("friction_scratch", ["--k", "nan"], "--k"),
    ("friction_scratch", ["--k", "0.5"], "--k"),  # the press phase (t <= 0.25) gets no step
    ("friction_scratch", ["--cells", "8", "0"], "--cells"),
    ("friction_step", ["--cells", "0", "2"], "--cells"),
    ("friction_step", ["--cells", "100000", "100000"], "--cells"),
    ("kernel_throughput", ["--points", "0"], "--points"),
    ("kernel_throughput", ["--repeats", "-3"], "--repeats"),
    ("locking_3d", ["--T", "inf"], "--T"),
    ("locking_3d", ["--sizes", "1", "-2"], "--sizes"),
    ("p_multigrid", ["--sizes", "-2"], "--sizes"),
    ("scene_dispatch", ["--steps", "0"], "--steps"),
    ("scene_dispatch", ["--cells", "-1", "2"], "--cells"),
    ("signorini_step", ["--n", "0"], "--n"),
    ("signorini_step", ["--dt", "0.5", "0"], "--dt"),
    ("signorini_step", ["--t-final", "-1"], "--t-final"),
    ("signorini_step", ["--dt", "1e-9"], "--dt"),  # 5e8 steps
    ("signorini_step", ["-o", "snes_type"], "-o"),
    ("step_cost", ["--sizes3d", "-1"], "--sizes3d"),
    ("step_cost", ["--single", "3", "0"], "--single"),
    ("step_cost", ["--single", "4", "2"], "--single"),
    ("step_cost", ["--window3d", "0.4", "0.3"], "--window3d"),
    ("step_cost", ["--window3d", "0", "0.1"], "--window3d"),
    ("step_cost", ["--ranks", "0"], "--ranks"),
    ("step_cost", ["--mu-star", "nan"], "--mu-star"),
    ("step_cost", ["--sigma-y", "0"], "--sigma-y"),
    ("step_cost", ["-o", "=1"], "-o"),
    ("work_precision_1d", ["--bdf2-levels", "40"], "--bdf2-levels"),
    ("work_precision_1d", ["--paper-min-r", "1e-9"], "--paper-min-r"),
]


def refused(monkeypatch, capsys, script: str, argv: list, option: str) -> str:
    """Run ``script``'s main(argv): exit status 2, ``option`` named on stderr, save() not called."""
    module = importlib.import_module(f"bench.{script}")
    saved = []
    if hasattr(module, "save"):
        monkeypatch.setattr(module, "save", lambda *a, **k: saved.append(a))
    with pytest.raises(SystemExit) as exit_:
        module.main(SMALL[script] + argv)
    err = capsys.readouterr().err
    assert exit_.value.code == 2, err
    assert "Traceback" not in err
    line = err.strip().splitlines()[-1]
    assert "error:" in line and option in line, err
    assert saved == []
    return err


@pytest.mark.parametrize("script, argv, option", CASES,
                         ids=[f"{s}:{' '.join(a)}" for s, a, _ in CASES])
def test_bad_value_is_refused(monkeypatch, capsys, tmp_path, script, argv, option):
    out = tmp_path / "out.json"
    refused(monkeypatch, capsys, script,
            ([] if script in NO_OUT else ["--out", str(out)]) + argv, option)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("script", ["contact_frames", "step_cost", "friction_step"])
def test_bad_out_is_refused(monkeypatch, capsys, tmp_path, script):
    """--out an existing folder, or a file under an existing file (a missing folder is made
    when the result is saved)."""
    folder = tmp_path / "folder"
    folder.mkdir()
    refused(monkeypatch, capsys, script, ["--out", str(folder)], "--out")
    assert list(folder.iterdir()) == []
    (tmp_path / "plain").write_text("keep\n")
    refused(monkeypatch, capsys, script, ["--out", str(tmp_path / "plain" / "sub" / "r.json")],
            "--out")
    assert (tmp_path / "plain").read_text() == "keep\n"
