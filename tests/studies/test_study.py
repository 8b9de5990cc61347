# SPDX-License-Identifier: MIT
"""``vpcontact study convergence|cost``: observed orders fitted here from the CSV the command
writes (not taken from its own summary), the Pareto front's defining property, and clear errors
for what a study cannot do. Small meshes and short final times keep it quick."""

import csv
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli, studies as study

ROOT0 = MPI.COMM_WORLD.rank == 0


def _rows(path: Path) -> list[dict]:
    with open(path) as f:
        return list(csv.DictReader(f))


def _slope(x, y) -> float:
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def _study(tmp_path, *args) -> int:
    return cli.main(["study", *args, "--out", str(tmp_path / "study"), "--quiet"])


def test_paper_1d_first_order_in_h_equal_k(tmp_path):
    """The paper's scheme (P1, explicit Euler, h = k) against the exact solution: order 1 and the
    paper's error constant (measured: slope 1.02, max err/h = 0.0959 over T = 2)."""
    assert _study(tmp_path, "convergence", "normal_compliance_1d", "--cells", "10", "--k", "0.1",
                  "--T", "2", "--levels", "3", "--exact", "paper_1d") == 0
    if ROOT0:
        rows = _rows(tmp_path / "study" / "convergence.csv")
        h = [float(r["h"]) for r in rows]
        err = [float(r["error"]) for r in rows]
        assert [float(r["k"]) for r in rows] == h
        assert 0.9 <= _slope(h, err) <= 1.1, err
        c = max(e / x for e, x in zip(err, h))  # the paper's C = 0.9557e-1 (Fig. 7)
        assert abs(c - 0.09557) <= 0.05 * 0.09557, c
        for name in ("convergence.md", "convergence.png"):
            assert (tmp_path / "study" / name).stat().st_size > 0


def test_bdf2_second_order_in_k(tmp_path):
    """P1 nodal values are exact in space here, so refining k alone isolates the time scheme:
    BDF2 (implicit law) is second order (measured 1.84-1.9 over these k; the kink at contact
    onset costs a little at coarse k)."""
    assert _study(tmp_path, "convergence", "normal_compliance_1d", "--cells", "10", "--k", "0.1",
                  "--T", "2", "--levels", "4", "--refine", "k", "--law-scheme", "implicit",
                  "--time-scheme", "bdf2", "--exact", "paper_1d") == 0
    if ROOT0:
        rows = _rows(tmp_path / "study" / "convergence.csv")
        assert len({r["h"] for r in rows}) == 1
        k = [float(r["k"]) for r in rows]
        assert 1.7 <= _slope(k, [float(r["error"]) for r in rows]) <= 2.2


@pytest.mark.slow
def test_perzyna_2d_first_order_in_k_by_richardson(tmp_path):
    """§4.2.2 (point load, Perzyna, normal compliance) on a 6×3 mesh, refining k from 1/32
    without an exact solution: the order is estimated from successive differences (Richardson):
    implicit Euler is first order once the body flows (measured: 0.94, successive 0.89 and
    1.00). From k = 1/4 the coarse runs cut their steps at the same places and are alike
    (Richardson: 0.71, successive 1.01 and 0.41); the fit against a finer run said 1.16 there."""
    assert _study(tmp_path, "convergence", "normal_compliance_2d", "--cells", "6", "3", "--k",
                  "0.03125", "--T", "1", "--levels", "3", "--refine", "k") == 0
    if ROOT0:
        rows = _rows(tmp_path / "study" / "convergence.csv")
        k = [float(r["k"]) for r in rows]
        assert 0.8 <= _slope(k, [float(r["difference"]) for r in rows]) <= 1.2, rows
        text = (tmp_path / "study" / "convergence.md").read_text()
        assert "Richardson" in text and "P1, implicit Euler with h" in text, text


def test_convergence_study_runs_the_scenes_own_discretization(tmp_path):
    """A plane-strain Perzyna scene is Taylor–Hood by default (P1 would lock under its
    volume-keeping flow): without --degree the study runs that, not the paper's P1 (which it
    ran before, whatever the scene)."""
    assert _study(tmp_path, "convergence", "indentation_relaxation", "--cells", "10", "5",
                  "--T", "0.2", "--k", "0.1", "--levels", "2", "--refine", "k") == 0
    if ROOT0:
        text = (tmp_path / "study" / "convergence.md").read_text()
        assert "P2, implicit Euler" in text and "P1" not in text, text[:300]


@pytest.mark.slow
def test_cost_study_pareto_front(tmp_path):
    """Every method on a 2 × 2 grid of (h, k); the runs marked Pareto are exactly those no run
    beats in both time and error, and the advice has a sentence per method."""
    assert _study(tmp_path, "cost", "normal_compliance_1d", "--cells", "10", "--k", "0.1",
                  "--T", "1", "--levels", "2", "--exact", "paper_1d") == 0
    if ROOT0:
        rows = _rows(tmp_path / "study" / "cost.csv")
        methods = {r["method"] for r in rows}
        assert methods == {"P1, explicit Euler", "P1, implicit Euler", "P1, BDF2",
                           "P2, explicit Euler", "P2, implicit Euler", "P2, BDF2"}
        assert len(rows) == 6 * 4
        pts = [(float(r["wall_time_s"]), float(r["error"]), r["pareto"] == "1") for r in rows]
        for i, (t, e, on) in enumerate(pts):  # beaten: a faster run at least as accurate
            beaten = any((t2 < t and e2 <= e * (1 + 1e-6)) or (t2 <= t and e2 < e * (1 - 1e-6))
                         for j, (t2, e2, _) in enumerate(pts) if j != i)
            assert on != beaten, (t, e, on)
        text = (tmp_path / "study" / "cost.md").read_text()
        for method in methods:
            assert f"* {method}:" in text
        assert (tmp_path / "study" / "cost.png").stat().st_size > 0


def test_pareto_front_ignores_round_off_ties():
    runs = [study.Run(study.Method(), 0, 0, 1.0, 1.0, wall_time=t, error=e)
            for t, e in ((1.0, 1e-3), (2.0, 1e-3 * (1 - 1e-12)), (3.0, 1e-4), (0.5, 1e-2),
                         (4.0, 1e-4))]
    assert [(r.wall_time, r.error) for r in study.pareto_front(runs)] == [(0.5, 1e-2), (1.0, 1e-3),
                                                                          (3.0, 1e-4)]


@pytest.mark.parametrize("args, message", [
    (["convergence", "normal_compliance_1d", "--k", "0.3"], "must divide T"),
    (["convergence", "normal_compliance_1d", "--cells", "4", "4"], "--cells needs 1"),
    (["convergence", "normal_compliance_1d", "--k", "nan"], "must be positive"),
    (["convergence", "normal_compliance_1d", "--levels", "1"], "levels must be in"),
    (["convergence", "elastic_2d", "--exact", "paper_1d"], "not the paper's"),
    (["convergence", "normal_compliance_1d", "--exact", "fourier"], "unknown exact solution"),
    (["cost", "normal_compliance_1d", "--levels", "9"], "levels must be in"),
])
def test_bad_study_requests_are_clear_errors(tmp_path, capsys, args, message):
    assert _study(tmp_path, *args) == 2
    err = capsys.readouterr().err
    if ROOT0:
        assert message in err and "Traceback" not in err, err
    assert not (tmp_path / "study" / "convergence.csv").exists()


def test_gmsh_scene_cannot_be_refined(tmp_path, capsys):
    from tests.scene.test_gmsh_scene import BOTTOM, _rectangle_msh, _write
    _rectangle_msh(tmp_path / "block.msh")
    assert _study(tmp_path, "convergence", str(_write(tmp_path, BOTTOM))) == 2
    if ROOT0:
        assert "built-in meshes only" in capsys.readouterr().err
