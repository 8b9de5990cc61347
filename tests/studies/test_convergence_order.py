# SPDX-License-Identifier: MIT
"""The observed order of ``vpcontact study convergence`` on a scene whose exact answer is known:
a 1-D Perzyna bar under a ramped traction (issue 45).

The bar Ω = (0, 1) is clamped at x = 0 and pulled at x = 1 by σ(t) = s t. Statics makes the stress
uniform and equal to the traction, so with ε̇ = σ̇/E + (σ − σ_Y)_+/μ* (Perzyna in 1-D)

    u(x, t) = x (s t/E + s (t − t_Y)_+² / (2 μ*)),     t_Y = σ_Y / s.

P1 is exact in space (u is linear in x); implicit Euler sums the flow rate at the right end of
each step, so with t_Y on the step grid its error is exactly (k/2)(s/μ*)(t − t_Y)_+: order 1.00,
max error 0.5 k here (s = 2, μ* = 1, T − t_Y = 0.5).

Measured against a run one level finer and fitted (what the study did), the same runs gave order
1.29–1.40 (levels 4 and 3): the reference's own error steepens the fit. Now the study estimates
the order from successive differences (Richardson) and says so, or takes an exact solution
given as expressions of x and t (``--exact``)."""

import csv
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli

from tests.support.mpi_launch import write_shared

ROOT0 = MPI.COMM_WORLD.rank == 0

BAR = """\
name = "ramped_bar"

[mesh]
type = "interval"
lower = [0.0]
upper = [1.0]
cells = [4]

[boundary.left]
kind = "clamped"
plane = { axis = "x", value = 0.0 }

[boundary.right]
kind = "traction"
plane = { axis = "x", value = 1.0 }
traction = ["2*t"]

[material]
E = 100.0

[law]
type = "perzyna"
sigma_y = 1.0
mu_star = 1.0
scheme = "implicit"

[time]
T = 1.0
k = 0.1

[output]
xdmf = false
figures = false
"""

#: u(x, t) of the bar (s = 2, E = 100, σ_Y = 1, μ* = 1: t_Y = 0.5, s/(2μ*) = 1).
EXACT = "x[0]*(0.02*t + max(t - 0.5, 0)**2)"


def _rows(path: Path) -> list[dict]:
    with open(path) as f:
        return list(csv.DictReader(f))


def _slope(x, y) -> float:
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)[0])


def _study(path, out, *args) -> int:
    return cli.main(["study", "convergence", str(path), "--refine", "k", "--out", str(out),
                     "--quiet", *args])


@pytest.fixture
def bar(shared_tmp_path):
    return write_shared(shared_tmp_path / "bar.toml", BAR)


@pytest.mark.parametrize("levels", [3, 4])
def test_richardson_order_of_a_first_order_scheme(bar, shared_tmp_path, levels):
    """Without an exact solution the order comes from the differences of successive runs: 1.00
    (it was 1.40 with 3 levels and 1.29 with 4, fitted against the finest run); the report says
    it is a Richardson estimate, and the estimated errors are the true ones (0.5 k)."""
    out = shared_tmp_path / "study"
    assert _study(bar, out, "--levels", str(levels)) == 0
    if ROOT0:
        rows = _rows(out / "convergence.csv")
        k = np.array([float(r["k"]) for r in rows])
        error = np.array([float(r["error"]) for r in rows])
        difference = np.array([float(r["difference"]) for r in rows])
        assert len(rows) == levels
        assert abs(_slope(k, difference) - 1.0) <= 0.1, difference
        assert abs(_slope(k, error) - 1.0) <= 0.1, error
        assert np.allclose(error, 0.5 * k, rtol=0.05), error / k
        text = (out / "convergence.md").read_text()
        assert "Richardson" in text and "No exact solution was given" in text, text
        assert "^1.00" in text, text


def test_exact_solution_as_expressions(bar, shared_tmp_path):
    """``--exact`` with u(x, t) as an expression: the errors are the true ones, 0.5 k (to the
    solver's tolerance), and the fitted order is 1.00."""
    out = shared_tmp_path / "study"
    assert _study(bar, out, "--levels", "3", "--exact", EXACT) == 0
    if ROOT0:
        rows = _rows(out / "convergence.csv")
        k = np.array([float(r["k"]) for r in rows])
        error = np.array([float(r["error"]) for r in rows])
        assert np.allclose(error, 0.5 * k, rtol=1e-6), error / k
        assert abs(_slope(k, error) - 1.0) <= 0.01
        assert all(r["difference"] == "" for r in rows)
        text = (out / "convergence.md").read_text()
        assert f"exact solution {EXACT!r}" in text and "Richardson" not in text, text


@pytest.mark.parametrize("exact, message", [
    ("__import__('os').system('true')", "unknown exact solution"),
    ("x[0]*t; t", "2 expression(s) for the 1 displacement component(s)"),
    ("x[1]*t", "unknown exact solution"),
    ("x[0]*tt", "unknown exact solution"),
])
def test_bad_exact_expressions_are_clear_errors(bar, shared_tmp_path, capsys, exact, message):
    out = shared_tmp_path / "study"
    assert _study(bar, out, "--exact", exact) == 2
    err = capsys.readouterr().err
    if ROOT0:
        assert message in err and "Traceback" not in err, err
    assert not (out / "convergence.csv").exists()
