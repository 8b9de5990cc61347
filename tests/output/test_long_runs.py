# SPDX-License-Identifier: MIT
"""Runs that survive interruption: real SIGINT/SIGTERM sent to real runs (serial and 2 ranks),
checkpoints and ``--resume`` (bit for bit in serial, to solver tolerance on 2 ranks), refused
resumes, and the bad inputs and output failures that must end in a clear message."""

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from vpcontact import cli
from vpcontact import scene as scenes

from tests.support.mpi_launch import clean_environment

pytestmark = pytest.mark.serial  # each test launches its own processes or writes shared files

TIMING_KEYS = {"wall_time_s", "wall_time_split_s", "resumed_from"}


def _scene(folder: Path, cells: int = 16, extra: str = "") -> Path:
    """The paper's 2-D Signorini test on a cells × cells mesh (about 50 steps with cuts)."""
    text = scenes.bundled()["signorini_2d"].read_text()
    text = re.sub(r"(?m)^cells = .*$", f"cells = [{cells}, {cells}]", text)
    path = folder / "scene.toml"
    path.write_text(text + extra)
    return path


def _command(scene: Path, out: Path, ranks: int, *extra) -> list:
    command = [sys.executable, "-m", "vpcontact", "run", str(scene), "--out", str(out), *extra]
    if ranks == 1:
        return command
    root = ["--allow-run-as-root"] if os.geteuid() == 0 else []
    return [shutil.which("mpirun"), *root, "-n", str(ranks), *command]


def _run(scene, out, ranks=1, *extra) -> subprocess.CompletedProcess:
    return subprocess.run(_command(scene, out, ranks, *extra), capture_output=True, text=True,
                          timeout=600, env=clean_environment())


def _interrupt(scene: Path, out: Path, sig: int, ranks: int = 1, after: str = "30.0%"):
    """Start a run, send ``sig`` once its progress passes ``after`` (to the ranks themselves,
    as a scheduler does), and return (exit status, stdout, stderr)."""
    process = subprocess.Popen(_command(scene, out, ranks), stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env=clean_environment())
    for line in process.stdout:
        if after in line:
            break
    else:
        pytest.fail(f"the run ended before {after}: {process.stderr.read()[-2000:]}")
    if ranks == 1:
        process.send_signal(sig)
    else:
        ranks_found = subprocess.run(["pgrep", "-f", f"vpcontact run {scene} --out {out}"],
                                     capture_output=True, text=True).stdout.split()
        for pid in ranks_found:
            if int(pid) != process.pid:
                os.kill(int(pid), sig)
    start = time.monotonic()
    stdout, stderr = process.communicate(timeout=120)
    assert time.monotonic() - start < 60, "the job must end promptly after the signal"
    return process.returncode, stdout, stderr


def _summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


def _xdmf_times(path: Path) -> list:
    import xml.etree.ElementTree as ElementTree
    return [float(e.get("Value")) for e in ElementTree.parse(path).getroot().iter("Time")]


@pytest.mark.slow
@pytest.mark.parametrize("sig, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_stops_cleanly_and_resume_ends_bit_for_bit(tmp_path, sig, status):
    scene = _scene(tmp_path)
    full, cut = tmp_path / "full", tmp_path / "cut"
    assert _run(scene, full, 1, "--quiet").returncode == 0

    code, stdout, stderr = _interrupt(scene, cut, sig)
    name = signal.Signals(sig).name
    assert code == status, stderr[-2000:]
    assert "Traceback" not in stderr and f"interrupted by {name}" in stderr
    assert len([line for line in stderr.splitlines() if line.strip()]) == 1, stderr
    summary = _summary(cut)
    assert summary["completed"] is False and summary["interrupted_by"] == name
    assert summary["error"].startswith(f"interrupted by {name}")
    steps = summary["steps"]
    assert 0 < steps < _summary(full)["steps"]
    # the outputs are readable up to the last step written
    rows = np.loadtxt(cut / "contact.csv", delimiter=",", skiprows=1)
    assert rows[:, 0].max() == pytest.approx(summary["final_time"])
    assert max(_xdmf_times(cut / "signorini_2d.xdmf")) == pytest.approx(summary["final_time"])
    manifest = json.loads((cut / "checkpoint" / "latest.json").read_text())
    assert manifest["step"] == steps

    resumed = _run(scene, cut, 1, "--resume", "--quiet")
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    for name in ("contact.csv", "reactions.csv"):
        assert (cut / name).read_bytes() == (full / name).read_bytes(), name
    a, b = _summary(cut), _summary(full)
    assert a["resumed_from"]["step"] == steps
    assert {k: v for k, v in a.items() if k not in TIMING_KEYS} == \
        {k: v for k, v in b.items() if k not in TIMING_KEYS}
    assert _xdmf_times(cut / "signorini_2d.xdmf") == _xdmf_times(full / "signorini_2d.xdmf")


@pytest.mark.mpi
def test_sigterm_on_two_ranks_and_resume(tmp_path):
    """On 2 ranks a resumed run ends where an uninterrupted one does to solver tolerance (MUMPS'
    parallel factorization is not bitwise reproducible: two uninterrupted 2-rank runs differ in
    round-off too). The scene is the bundled indentation (contact spreading while the specimen
    flows), whose steps are never cut, so both runs take the same steps and can be compared row
    by row; on the paper's 2-D test round-off can turn a borderline Newton solve into a cut step
    and the two runs then take different step sequences. (Its own mesh, graded towards the
    contact, has 1 519 vertices.)"""
    scene = tmp_path / "scene.toml"
    scene.write_text(scenes.bundled()["indentation_relaxation"].read_text())
    full, cut = tmp_path / "full", tmp_path / "cut"
    assert _run(scene, full, 2, "--quiet").returncode == 0
    assert _summary(full)["rejected_steps"] == []
    code, _, stderr = _interrupt(scene, cut, signal.SIGTERM, ranks=2)
    assert code == 143, stderr[-3000:]
    assert "Traceback" not in stderr
    summary = _summary(cut)
    assert summary["interrupted_by"] == "SIGTERM" and summary["mpi_ranks"] == 2
    resumed = _run(scene, cut, 2, "--resume", "--quiet")
    assert resumed.returncode == 0, resumed.stderr[-3000:]
    a = np.loadtxt(cut / "contact.csv", delimiter=",", skiprows=1)
    b = np.loadtxt(full / "contact.csv", delimiter=",", skiprows=1)
    assert a.shape == b.shape
    np.testing.assert_allclose(a[:, :4], b[:, :4], rtol=0, atol=1e-12)
    for column in (4, 7):  # u_normal, pressure
        np.testing.assert_allclose(a[:, column], b[:, column], rtol=0,
                                   atol=1e-8 * np.abs(b[:, column]).max())
    assert np.abs(b[:, 7]).max() > 0  # contact happened
    iterations = [_summary(out)["newton_iterations"] for out in (cut, full)]
    assert len(iterations[0]) == len(iterations[1])
    assert max(abs(i - j) for i, j in zip(*iterations)) <= 1, iterations
    # another rank count is refused
    other = _run(scene, cut, 1, "--resume", "--quiet")
    assert other.returncode == 2 and "written by 2 MPI rank(s), this run has 1" in other.stderr


def test_resume_refusals(tmp_path, capsys):
    scene = _scene(tmp_path, extra="\n")
    out = tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--resume", "--quiet"]) == 2
    assert "holds no checkpoint" in capsys.readouterr().err
    assert not (out / "summary.json").exists()

    text = scene.read_text().replace("T = 1.0", "T = 0.2")
    short = tmp_path / "short.toml"
    short.write_text(text)
    assert cli.main(["run", str(short), "--out", str(out), "--quiet"]) == 0
    short.write_text(text.replace("T = 0.2", "T = 0.3"))  # the scene changed
    assert cli.main(["run", str(short), "--out", str(out), "--resume", "--quiet"]) == 2
    assert "the scene changed since the checkpoint" in capsys.readouterr().err


@pytest.mark.slow
def test_a_torn_checkpoint_write_leaves_the_last_one_usable(tmp_path):
    """A crash while writing (a half-written archive and manifest) does not spoil the previous
    checkpoint: --resume uses it and ends where an uninterrupted run ends."""
    scene = _scene(tmp_path)
    text = scene.read_text().replace("T = 1.0", "T = 0.3")
    scene.write_text(text)
    out, full = tmp_path / "out", tmp_path / "full"
    assert _run(scene, full, 1, "--quiet").returncode == 0
    assert _run(scene, out, 1, "--quiet").returncode == 0
    folder = out / "checkpoint"
    (folder / "step-999999").mkdir()
    (folder / "step-999999" / "rank-0000.npz").write_bytes(b"PK\x03\x04 torn")
    (folder / "latest.json.tmp").write_text('{"format": 1, "st')
    resumed = _run(scene, out, 1, "--resume", "--quiet")
    assert resumed.returncode == 0, resumed.stderr
    assert (out / "contact.csv").read_bytes() == (full / "contact.csv").read_bytes()


@pytest.mark.slow
def test_resume_after_a_crash_that_spoiled_the_xdmf_file(tmp_path):
    """A run killed while writing leaves its HDF5 file unreadable (its header zeroed) though the
    checkpoint is intact: --resume sets the series aside (<name>.broken1.xdmf/.h5), starts it
    again at the checkpoint, says so in one warning (stderr and summary.json) and ends where an
    uninterrupted run ends. It failed with exit 1 (HDF5 could not open the file to append)."""
    scene = _scene(tmp_path)
    scene.write_text(scene.read_text().replace("T = 1.0", "T = 0.3"))
    out, full = tmp_path / "out", tmp_path / "full"
    assert _run(scene, full, 1, "--quiet").returncode == 0
    assert _run(scene, out, 1, "--quiet").returncode == 0
    series = next(out.glob("*.xdmf"))
    with open(series.with_suffix(".h5"), "r+b") as h5:
        h5.write(bytes(512))
    resumed = _run(scene, out, 1, "--resume", "--quiet")
    assert resumed.returncode == 0, resumed.stderr
    assert f"set aside as {series.stem}.broken1.xdmf" in resumed.stderr, resumed.stderr
    assert "HDF5-DIAG" not in resumed.stderr, resumed.stderr  # HDF5's error stack: noise
    assert series.with_name(f"{series.stem}.broken1.h5").exists() and series.exists()
    assert any("set aside" in w for w in _summary(out)["warnings"])
    assert (out / "contact.csv").read_bytes() == (full / "contact.csv").read_bytes()
    restart = _summary(out)["resumed_from"]["time"]
    assert _xdmf_times(series) and min(_xdmf_times(series)) > restart


def test_out_is_an_existing_file(tmp_path, capsys):
    scene = _scene(tmp_path)
    target = tmp_path / "result"
    target.write_text("keep me\n")
    assert cli.main(["run", str(scene), "--out", str(target), "--quiet"]) == 2
    assert "an existing file, not a folder" in capsys.readouterr().err
    assert target.read_text() == "keep me\n"
    assert cli.main(["run", str(scene), "--out", str(target / "sub"), "--quiet"]) == 2
    assert "is a file, so no folder can be made there" in capsys.readouterr().err


def test_non_finite_expressions_are_reported_before_the_first_step(tmp_path, capsys):
    base = _scene(tmp_path).read_text()
    for old, new, expected in (
            ('body_force = [0.0, "-10*t"]', 'body_force = [0.0, "log(x[0] - 2)"]',
             r"loads\.body_force\[1\]: 'log\(x\[0\] - 2\)' evaluates to nan at x = \[[-0-9.e]+, "
             r"[-0-9.e]+\], t = 0"),
            ('body_force = [0.0, "-10*t"]', 'body_force = [0.0, "1/(t - 0.5)"]',
             r"loads\.body_force\[1\]: '1/\(t - 0\.5\)' evaluates to inf at t = 0\.5")):
        assert old in base
        scene = tmp_path / "bad.toml"
        scene.write_text(base.replace(old, new))
        out = tmp_path / "out"
        assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
        err = capsys.readouterr().err
        assert re.search(rf"bad\.toml:\d+: {expected}", err), err
        assert "did not converge" not in err and not out.exists()


def test_a_second_run_into_the_same_folder_is_refused(tmp_path, capsys):
    from mpi4py import MPI

    from vpcontact.output.lock import LOCK_NAME, OutputLock
    scene = _scene(tmp_path)
    out = tmp_path / "out"
    held = OutputLock(out, MPI.COMM_WORLD)  # as a run in progress holds it
    try:
        assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
        err = capsys.readouterr().err
        assert f"another vpcontact run (pid {os.getpid()} on " in err
        assert not (out / "summary.json").exists()
    finally:
        held.release()
    # a lock file left by a run that died (no process holds the lock) does not block
    (out / LOCK_NAME).write_text('{"host": "elsewhere", "pid": 1, "started": "yesterday"}\n')
    small = tmp_path / "short.toml"
    small.write_text(scene.read_text().replace("T = 1.0", "T = 0.1"))
    assert cli.main(["run", str(small), "--out", str(out), "--quiet"]) == 0
    assert not (out / LOCK_NAME).exists()


def test_a_full_disk_is_a_clear_error_and_the_record_is_kept(tmp_path, capsys):
    scene = _scene(tmp_path)
    scene.write_text(scene.read_text().replace("T = 1.0", "T = 0.1"))
    out = tmp_path / "out"
    out.mkdir()
    (out / "contact.csv").symlink_to("/dev/full")  # writes there fail with ENOSPC
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "cannot write the outputs into" in err and "No space left on device" in err
    assert "Traceback" not in err
    summary = _summary(out)
    assert summary["completed"] is False and "No space left on device" in summary["error"]
    assert summary["steps"] > 0 and (out / "signorini_2d.xdmf").is_file()


def test_a_signal_during_set_up_stops_before_the_first_step(tmp_path, monkeypatch, capsys):
    """SIGINT while the mesh and forms are being built (the JIT compiles on a fresh machine):
    no step is taken, the run stops at once with a checkpoint at t = 0, and --resume runs it."""
    from vpcontact.scene import builder
    build = builder.build

    def build_then_signal(*args, **kwargs):
        model = build(*args, **kwargs)
        os.kill(os.getpid(), signal.SIGINT)  # noted by the handler vpcontact run installed
        return model

    monkeypatch.setattr(builder, "build", build_then_signal)
    out = tmp_path / "out"
    assert cli.main(["run", "elastic_2d", "--out", str(out), "--quiet"]) == 130
    assert "interrupted by SIGINT at t = 0" in capsys.readouterr().err
    assert _summary(out)["steps"] == 0
    monkeypatch.setattr(builder, "build", build)
    assert cli.main(["run", "elastic_2d", "--out", str(out), "--quiet", "--resume"]) == 0
    assert _summary(out)["completed"] and _summary(out)["steps"] == 4


def test_a_signal_during_the_last_step_leaves_a_completed_run(tmp_path, monkeypatch, capsys):
    """SIGINT while the last step is being solved: the run has reached T, so it is complete
    (exit 0, summary completed). It used to end as interrupted (exit 130), and its --resume
    then found nothing to resume."""
    from vpcontact.output import runner
    advance = runner.advance

    def signal_in_last_step(problem, t_final, control):
        for step in advance(problem, t_final, control):
            if step.time >= t_final * (1 - 1e-12):
                os.kill(os.getpid(), signal.SIGINT)  # noted by the handler vpcontact run installed
            yield step

    monkeypatch.setattr(runner, "advance", signal_in_last_step)
    out = tmp_path / "out"
    assert cli.main(["run", "elastic_2d", "--out", str(out), "--quiet"]) == 0
    assert "interrupted" not in capsys.readouterr().err
    summary = _summary(out)
    assert summary["completed"] and summary["steps"] == 4 and not summary.get("interrupted_by")


def test_ctrl_c_still_stops_cleanly_after_gmsh_read_a_mesh(tmp_path):
    """gmsh's Python module resets SIGINT when imported and again when finalized; a scene on a
    Gmsh mesh read after gmsh was imported elsewhere still stops cleanly on Ctrl-C."""
    from vpcontact.studies import hertz
    hertz.cylinder_msh(tmp_path / "cylinder.msh", h_contact=0.02)
    (tmp_path / "scene.toml").write_text(
        'name = "cylinder"\n[mesh]\ntype = "gmsh"\nfile = "cylinder.msh"\ndim = 2\n'
        '[boundary.top]\nkind = "clamped"\ntag = 2\n[boundary.axis]\nkind = "symmetry"\ntag = 3\n'
        '[material]\nE = 1.0\nnu = 0.3\nplane = "stress"\n[time]\nT = 1.0\nk = 0.1\n')
    script = tmp_path / "run.py"
    script.write_text(
        "import os, signal, sys\n"
        "import gmsh  # imported first, as a study driver or another tool might\n"
        "from vpcontact import cli\n"
        "from vpcontact.scene import builder\n"
        "build = builder.build\n"
        "def build_then_signal(*a, **k):\n"
        "    model = build(*a, **k)  # reads the mesh in a gmsh session\n"
        "    os.kill(os.getpid(), signal.SIGINT)\n"
        "    return model\n"
        "builder.build = build_then_signal\n"
        f"sys.exit(cli.main(['run', {str(tmp_path / 'scene.toml')!r}, '--out', "
        f"{str(tmp_path / 'out')!r}, '--quiet']))\n")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300, env=clean_environment())
    assert done.returncode == 130, done.stderr[-2000:]
    assert "interrupted by SIGINT" in done.stderr and "Traceback" not in done.stderr
