# SPDX-License-Identifier: MIT
"""Every demo runs (shortened) and writes what its header promises."""

import csv
import importlib.util
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

DEMOS = Path(__file__).resolve().parents[2] / "demos"


def _load(name):
    spec = importlib.util.spec_from_file_location(name, DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_normal_compliance_1d_demo(shared_tmp_path):
    demo = _load("normal_compliance_1d")
    out = shared_tmp_path / "nc1d"
    demo.main(["--out", str(out), "--r", "0.1", "0.05"])
    MPI.COMM_WORLD.barrier()
    with open(out / "errors.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["r", "h", "k", "err_VQ", "err_nodal"]
    assert [float(row["r"]) for row in rows] == [0.1, 0.05]
    assert all(0 < float(row["err_nodal"]) < 0.02 for row in rows)
    for name in ("fig5_displacements.png", "fig6_evolution.png", "fig7_error_constant.png"):
        assert (out / name).stat().st_size > 10_000, name


def test_normal_compliance_1d_demo_rejects_bad_r(capsys):
    demo = _load("normal_compliance_1d")
    with pytest.raises(SystemExit) as exc:
        demo.main(["--r", "0.3"])
    assert exc.value.code == 2
    assert "must be in (0, 1] and divide 1" in capsys.readouterr().err


@pytest.mark.slow
def test_signorini_3d_demo(shared_tmp_path, monkeypatch):
    monkeypatch.setenv("CI", "1")
    demo = _load("signorini_3d")
    out = shared_tmp_path / "s3d"
    record = demo.run(out)
    MPI.COMM_WORLD.barrier()
    assert record.contact[-1].active > 0 and record.contact[-1].max_penetration <= 1e-10
    for name in ("signorini_3d.xdmf", "signorini_3d.h5", "fig3_deformed.png",
                 "fig4_contact_evolution.png", "contact_history.csv"):
        assert (out / name).stat().st_size > 1000, name


@pytest.mark.slow
def test_signorini_2d_demo(shared_tmp_path, monkeypatch):
    # The paper's T = 1 s: the square flows past its limit load (t ≈ 0.38 s) but is still
    # above the obstacle (the smallest gap is 6.7 mm at x1 = 1).
    monkeypatch.setenv("CI", "1")
    demo = _load("signorini_2d")
    out = shared_tmp_path / "s2d"
    record = demo.run(out)
    MPI.COMM_WORLD.barrier()
    assert record.completed and abs(record.times[-1] - 1.0) < 1e-12
    last = record.contact[-1]
    assert last.active == 0 and -6.7e-3 < last.max_penetration < -1e-3, last
    for name in ("signorini_2d.xdmf", "signorini_2d.h5", "fig1_deformed.png",
                 "fig2_contact_evolution.png", "contact_history.csv"):
        assert (out / name).stat().st_size > 1000, name


@pytest.mark.slow
def test_indentation_relaxation_demo(shared_tmp_path, monkeypatch):
    monkeypatch.setenv("CI", "1")
    demo = _load("indentation_relaxation")
    out = shared_tmp_path / "relax"
    session = demo.run(out)
    MPI.COMM_WORLD.barrier()
    force = [-c[1] for c in session.forces.contact]
    peak = max(force)
    ramp_end = session.forces.times.index(min(session.forces.times, key=lambda t: abs(t - 0.25)))
    assert force[0] == 0 and abs(force.index(peak) - ramp_end) <= 1  # rises while pushed
    assert all(b < a for a, b in zip(force[ramp_end + 1:], force[ramp_end + 2:]))  # relaxes
    assert force[-1] < 0.9 * peak
    for name in ("indentation_relaxation.xdmf", "contact.csv", "reactions.csv", "summary.json",
                 "reactions.png", "relaxation.png", "final_state.png"):
        assert (out / name).stat().st_size > 500, name


@pytest.mark.slow
def test_hertz_indentation_demo(shared_tmp_path, monkeypatch):
    monkeypatch.setenv("CI", "1")
    demo = _load("hertz_indentation")
    out = shared_tmp_path / "hertz"
    rows = demo.run(out)
    MPI.COMM_WORLD.barrier()
    depth, force, force_hertz, radius, radius_hertz = rows.T[:5]
    assert len(rows) == 3 and np.all(np.diff(force) > 0)
    assert np.all(np.abs(radius / radius_hertz - 1) < 0.1)  # coarse CI mesh: within 10 %
    assert np.all((force / force_hertz > 1.0) & (force / force_hertz < 1.2))
    for name in ("force_depth.png", "indentation.csv"):
        assert (out / name).stat().st_size > 200, name


@pytest.mark.slow
def test_indentation_creep_demo(shared_tmp_path, monkeypatch):
    """The force-driven twin of the relaxation demo: the contact force is F(t) at every step,
    and the depth grows while F is held."""
    monkeypatch.setenv("CI", "1")
    demo = _load("indentation_creep")
    out = shared_tmp_path / "creep"
    session = demo.run(out)
    MPI.COMM_WORLD.barrier()
    times = np.array(session.forces.times)
    force = -np.array(session.forces.contact)[:, 1]
    assert np.allclose(force, 6.0 * np.minimum(times / 0.25, 1.0), rtol=1e-8, atol=1e-9)
    depth = -np.array(session.forces.driver, dtype=float)
    held = times >= 0.25 - 1e-12
    assert np.all(np.diff(depth[held]) > 0), depth  # creep under a constant force
    assert depth[-1] > 1.2 * depth[held][0]
    for name in ("indentation_creep.xdmf", "contact.csv", "reactions.csv", "summary.json",
                 "creep.png", "final_state.png"):
        assert (out / name).stat().st_size > 500, name


@pytest.mark.slow
def test_scratch_demo(shared_tmp_path, monkeypatch):
    """The scratch test: while the tip slides, the tangential force is 𝔣 × the normal one plus
    the ploughing of the groove's front (the contact force along the tip's normal, tilted
    against the motion where the tip's flank bears): more than 𝔣 by a clear margin, and no more
    than 𝔣 + the steepest slope of the tip's surface over the nodes in contact (each node's
    force has a tangential part λ_i (𝔣 + s_i), s_i the slope there). The block keeps a groove
    behind the tip, and the contact nodes under the sliding tip slip."""
    monkeypatch.setenv("CI", "1")
    demo = _load("scratch")
    out = shared_tmp_path / "scratch"
    session = demo.run(out)
    MPI.COMM_WORLD.barrier()
    times = np.array(session.forces.times)
    force = np.array(session.forces.contact)
    sliding = times >= 0.4
    ratio = force[sliding, 0] / -force[sliding, 1]
    assert np.all(ratio > 0.2 + 0.05), ratio
    if MPI.COMM_WORLD.rank == 0:
        rows = np.genfromtxt(out / "contact.csv", delimiter=",", names=True)
        for t, r in zip(times[sliding], ratio):
            now = rows[np.isclose(rows["t"], t) & (rows["pressure"] > 1e-6)]
            tip = -0.5 + 0.8 * (t - 0.25) / 0.75  # the tip's centre (radius 0.5)
            offset = np.abs(now["x"] - tip)  # (s is taken where the node's vertical ray meets it)
            steepest = np.max(offset / np.sqrt(0.25 - offset ** 2))
            assert r <= 0.2 + steepest, (t, r, steepest)
        last = rows[np.isclose(rows["t"], times[-1])]
        behind = (last["x"] > -0.35) & (last["x"] < 0.0)  # scratched, the tip gone
        assert np.all(last["u_normal"][behind] < -0.01), last["u_normal"][behind]
        assert last["slipping"][last["pressure"] > 1e-6].sum() >= 2
    assert (out / "scratch.png").stat().st_size > 500
    xdmf = (out / "scratch.xdmf").read_text()
    assert 'Name="tangential_traction"' in xdmf and 'Name="slipping"' in xdmf
