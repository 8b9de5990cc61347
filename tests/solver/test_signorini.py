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
from vpcontact.model import Signorini, gap_along_normal, rotation_matrix
from vpcontact.model.obstacle import shape_level_set
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


def test_a_thin_obstacle_is_not_stepped_over():
    """A blade 0.04 thick, 0.30 above the face, and a circle met along short chords: the rays
    marched by doubling steps from max_distance / 2²⁰ sampled 0.256 and 0.512 and missed the
    blade (a block lifted into it went straight through, exit 0), and reported rays through the
    circle's edge as out of reach. Closed forms: the blade's underside, the circle's lower arc."""
    x = np.linspace(-0.4, 0.4, 9)
    points = np.c_[x, np.ones_like(x), np.zeros_like(x)]
    up = np.array([0.0, 1.0, 0.0])
    blade = lambda p: np.sqrt(p[0] ** 2 / 0.25 + (p[1] - 1.32) ** 2 / 0.0004) - 1.0  # noqa: E731
    gap = gap_along_normal(blade, points, up, max_distance=1e3)
    np.testing.assert_allclose(gap, 0.32 - 0.02 * np.sqrt(1.0 - x ** 2 / 0.25), rtol=1e-10)
    circle = lambda p: np.hypot(p[0] - 0.27, p[1] - 1.644) - 0.5  # noqa: E731
    x = np.array([0.75, 0.76])  # 0.48 and 0.49 from the centre: short chords
    points = np.c_[x, np.ones_like(x), np.zeros_like(x)]
    gap = gap_along_normal(circle, points, up, max_distance=1e3)
    np.testing.assert_allclose(gap, 0.644 - np.sqrt(0.25 - (x - 0.27) ** 2), rtol=1e-10)


def test_rotation_matrix_is_the_turn_about_its_axis():
    q = rotation_matrix([1.0, 1.0, 1.0], 2.0 * np.pi / 3.0)  # a third of a turn about (1,1,1)
    np.testing.assert_allclose(q, np.roll(np.eye(3), 1, axis=0), atol=1e-15)  # x → y → z → x
    q = rotation_matrix([0.2, -0.7, 0.4], 1.1)
    np.testing.assert_allclose(q.T @ q, np.eye(3), atol=1e-15)
    assert np.linalg.det(q) == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_allclose(q @ [0.2, -0.7, 0.4], [0.2, -0.7, 0.4], atol=1e-15)


def test_turned_obstacle_in_3d_is_the_turned_shape():
    """An ellipsoid turned by a quarter turn about the z axis through its centre is the ellipsoid
    with its x and y semi-axes swapped; turned about an axis through another point, its centre
    moves as that point's rotation says. Gaps along the normal agree to round-off."""
    rng = np.random.default_rng(3)
    points = np.c_[rng.uniform(-0.15, 0.35, 40), rng.uniform(-0.25, 0.25, 40), np.zeros(40)]
    up = np.array([0.0, 0.0, 1.0])
    ellipsoid = {"center": (0.1, 0.0, 0.6), "semi_axes": (0.3, 0.5, 0.4)}
    phi = shape_level_set("ellipsoid", ellipsoid, 3)
    about_centre = Signorini(1, obstacle=phi, rotation_center=(0.1, 0.0, 0.6),
                             rotation=lambda t: rotation_matrix([0.0, 0.0, 1.0], t * np.pi / 2))
    swapped = shape_level_set("ellipsoid", {"center": (0.1, 0.0, 0.6),
                                            "semi_axes": (0.5, 0.3, 0.4)}, 3)
    expected = gap_along_normal(swapped, points, up, max_distance=5.0)
    got = gap_along_normal(about_centre.obstacle_at(1.0), points, up, max_distance=5.0)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-14)
    # a half turn about the x axis through (0.1, 0, 1): the centre goes to (0.1, 0, 1.4), and
    # an ellipsoid is symmetric under that half turn about its own centre
    about_x = Signorini(1, obstacle=phi, rotation_center=(0.1, 0.0, 1.0),
                        rotation=lambda t: rotation_matrix([1.0, 0.0, 0.0], t * np.pi),
                        translation=lambda t: np.array([0.0, 0.0, -0.3 * t]))
    raised = shape_level_set("ellipsoid", {"center": (0.1, 0.0, 1.1),
                                           "semi_axes": (0.3, 0.5, 0.4)}, 3)
    expected = gap_along_normal(raised, points, up, max_distance=5.0)
    got = gap_along_normal(about_x.obstacle_at(1.0), points, up, max_distance=5.0)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-14)
    assert about_x.moving and not Signorini(1, obstacle=phi).moving


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
                                    options=runner.RunOptions(verbose=False))
    assert record.completed and history is not None
    assert (shared_tmp_path / "contact_history.csv").exists()
    assert 1.0 <= record.output_time <= record.wall_time
