# SPDX-License-Identifier: MIT
"""Signorini contact through SNES VI: invariants at every step, gaps, bad boundary input."""

import time

import numpy as np
import pytest
from dolfinx import mesh as dmesh
from mpi4py import MPI

from vpcontact.paper import signorini as paper
from vpcontact.output import runner
from vpcontact.errors import InputError
from vpcontact.model import gap_along_normal
from vpcontact.solver import tag_facets


@pytest.fixture(scope="module")
def beam_history():
    problem = paper.signorini_3d(9, 3, 3)
    reports = []
    for _ in range(4):
        step = problem.step(0.25)
        reports.append((step, problem.contact_monitor.report()))
    return reports


def test_signorini_conditions_hold_every_step(beam_history):
    for step, rep in beam_history:
        scale = abs(rep.min_pressure)
        assert rep.active > 0, f"step {step.step}: the beam must press on the foundation"
        assert rep.max_penetration <= 1e-10, f"step {step.step}: penetration {rep.max_penetration}"
        assert rep.max_pressure <= 1e-8 * scale, f"step {step.step}: tensile contact {rep.max_pressure}"
        assert rep.complementarity <= 1e-12 * scale, f"step {step.step}: {rep.complementarity}"


def test_contact_force_and_newton_effort(beam_history):
    # The foundation carries the end load 10 t (plus the lever reaction of the clamp).
    for step, rep in beam_history:
        assert 1.0 * 10 * step.time < -rep.normal_force < 1.2 * 10 * step.time, (step.time, rep)
        assert step.newton_iterations <= 20, f"step {step.step}: {step.newton_iterations} Newton its"


def test_obstacle_gap_matches_closed_form():
    x1 = np.linspace(0.0, 1.0, 11)
    points = np.c_[x1, np.zeros_like(x1), np.zeros_like(x1)]
    gap = gap_along_normal(paper.obstacle_2d, points, np.array([0.0, -1.0, 0.0]), max_distance=10.0)
    exact = 3.0 - 3.0 * np.sqrt(1.0 - (x1 - 3.0) ** 2 / 900.0)
    np.testing.assert_allclose(gap, exact, rtol=1e-12, atol=1e-15)


def test_missed_obstacle_and_initial_penetration_are_reported():
    points = np.array([[0.5, 0.0, 0.0]])
    with pytest.raises(InputError, match="misses the obstacle"):
        gap_along_normal(paper.obstacle_2d, points, np.array([0.0, 1.0, 0.0]), max_distance=5.0)
    with pytest.raises(InputError, match="starts inside the obstacle"):
        gap_along_normal(paper.obstacle_2d, np.array([[3.0, -1.0, 0.0]]),
                         np.array([0.0, -1.0, 0.0]), max_distance=5.0)


def test_overlapping_boundary_parts_are_rejected():
    mesh = dmesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    with pytest.raises(InputError, match="overlap"):
        tag_facets(mesh, {1: lambda x: np.isclose(x[1], 0.0), 3: lambda x: x[1] < 0.5})


def test_elastic_limit_needs_one_newton_step_once_contact_settles():
    # σ_Y = ∞: Perzyna reduces to elasticity; with a fixed active set each step is linear.
    problem = paper.signorini_3d(9, 3, 3, sigma_y=float("inf"))
    its = [problem.step(0.25).newton_iterations for _ in range(4)]
    assert max(its[1:]) <= 2, its
    assert np.isfinite(problem.u.x.array).all()


def test_run_wall_time_covers_its_outputs(shared_tmp_path, monkeypatch):
    # output_time counts creating and closing the XDMF series and writing the contact CSV;
    # wall_time is the whole run, so it cannot be smaller (a slow CSV write makes the output
    # time longer than the steps themselves)
    write_csv = runner.ContactHistory.write_csv

    def slow_write_csv(self, path):
        time.sleep(1.0)
        write_csv(self, path)

    monkeypatch.setattr(runner.ContactHistory, "write_csv", slow_write_csv)
    record, history, _ = runner.run(paper.signorini_2d(4), 0.04, 0.02, out=shared_tmp_path,
                                    verbose=False)
    assert record.completed and history is not None
    assert (shared_tmp_path / "contact_history.csv").exists()
    assert 1.0 <= record.output_time <= record.wall_time
