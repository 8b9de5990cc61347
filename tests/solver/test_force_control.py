# SPDX-License-Identifier: MIT
"""Obstacles driven by a force: the displacement d of the obstacle along the force is an unknown
of each step, solved with u (vpcontact.solver.variables), so that the contact force balances
F(t).

* Elastic Hertz under force control: a rigid plane pressed by P onto the quarter of a cylinder
  (2-D) and of a sphere (3-D): the contact force is P at every step, and the contact size and
  peak pressure follow Hertz's closed forms for P; a rigid sphere pressed into a block: Hertz's
  contact radius and, the clamped block being a little stiffer than a half-space, an
  indentation depth just below Hertz's δ = (3P/(4E*√R))^(2/3).
* Indentation creep of a Perzyna block: the force is ramped up, then held; the depth keeps
  growing while it is held, and the contact force equals F(t) at every step.
* A block squeezed by two indenters driven by opposite forces (2-D and 3-D): each carries its
  own force, and the clamp carries nothing.
* The same through scene files: ``force = [...]`` in a contact table, the driver column of
  reactions.csv, and the located refusals.
"""

import json
import re

import numpy as np
import pytest
from mpi4py import MPI
from dolfinx import mesh as dmesh

from vpcontact import cli
from vpcontact.model import Elastic, Elasticity, Perzyna, PlaneStrain, Signorini
from vpcontact.solver import Dirichlet, QuasistaticProblem, StepControl, advance, tag_facets
from vpcontact.studies import hertz

from tests.support.mpi_launch import write_shared

E, NU = 1.0, 0.3
E_STAR = E / (1 - NU ** 2)
COMM = MPI.COMM_WORLD


@pytest.mark.slow
def test_plane_pressed_by_a_force_on_a_cylinder_follows_hertz(shared_tmp_path):
    """2-D, plane strain, the quarter x ≥ 0 of a cylinder (R = 1) held at its centre line; a
    rigid plane below it pressed up with P(t) per unit length on the half model."""
    mesh, tags = hertz.read_msh(hertz.cylinder_msh(shared_tmp_path / "cylinder.msh",
                                                   h_contact=0.005), 2)
    P = 0.005  # on the half x ≥ 0
    plane = Signorini(hertz.CONTACT, obstacle=lambda x: x[1], max_distance=10.0,
                      force=lambda t: np.array([0.0, P * t]), force_direction=(0.0, 1.0, 0.0))
    problem = QuasistaticProblem(mesh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", E, NU))),
                                 dirichlet=[Dirichlet.symmetry(hertz.SYMMETRY_X, 2, 0, "axis"),
                                            Dirichlet.clamped(hertz.TOP, 2, "top")],
                                 contact=plane)
    depths = []
    for step in advance(problem, 1.0, StepControl(0.25)):
        _, force = problem.support_forces()
        assert force[1] == pytest.approx(P * step.time, rel=1e-8)  # the plane pushes up
        # from the unloaded state the active set is found in the first step; later steps
        # start from the last one's
        assert step.newton_iterations <= (12 if step.step == 1 else 6), step
        depths.append(problem.driving_displacement())
    assert np.all(np.diff(depths) > 0)  # the plane moves up (+y) as the force grows
    p = hertz.profile(problem, np.zeros(3))
    # (the sum of the nodal normal forces: P up to the faces' turning, cos θ ≈ 1)
    assert p.force == pytest.approx(P, rel=1e-2)
    a, p0 = hertz.cylinder_2d(2 * P, 1.0, E_STAR)
    assert abs(p.half_width - a) <= p.facet, (p.half_width, a, p.facet)
    assert abs(p.pressure.max() / p0 - 1) < 0.03, (p.pressure.max(), p0)


@pytest.mark.slow
def test_sphere_pressed_into_a_block_by_a_force_follows_hertz(shared_tmp_path):
    """3-D: a rigid sphere (R = 0.5) pressed by P into the quarter of a block (clamped below,
    symmetry planes x = 0 and y = 0): contact radius within 5 % of Hertz's for the force, the
    depth 0–15 % below Hertz's (the clamped block is stiffer than a half-space)."""
    R, P = 0.5, 2e-4  # P on the quarter
    mesh, _ = hertz.read_msh(hertz.block_msh(shared_tmp_path / "block.msh", h_contact=0.015), 3)
    tags = tag_facets(mesh, {
        1: lambda x: np.isclose(x[2], -1.0), 2: lambda x: np.isclose(x[0], 0.0),
        3: lambda x: np.isclose(x[1], 0.0),
        4: lambda x: np.isclose(x[2], 0.0) & (x[0] ** 2 + x[1] ** 2 <= 0.3 ** 2 + 1e-12)})
    parts = [Dirichlet.clamped(1, 3, "bottom"), Dirichlet.symmetry(2, 3, 0, "x = 0"),
             Dirichlet.symmetry(3, 3, 1, "y = 0")]
    sphere = Signorini(4, obstacle=lambda x: np.linalg.norm(x - np.array([[0.0], [0.0], [R]]),
                                                            axis=0) - R,
                       max_distance=10.0, force=lambda t: np.array([0.0, 0.0, -P * t]),
                       force_direction=(0.0, 0.0, -1.0))
    problem = QuasistaticProblem(mesh, tags, Elastic(Elasticity("3d_standard", E, NU)),
                                 dirichlet=parts, contact=sphere)
    for step in advance(problem, 1.0, StepControl(0.5)):
        _, force = problem.support_forces()
        assert force[2] == pytest.approx(-P * step.time, rel=1e-8)
        p = hertz.profile(problem, np.zeros(3))
        a, _ = hertz.sphere_3d(4 * P * step.time, R, E_STAR)
        assert abs(p.half_width / a - 1) < 0.05, (step.time, p.half_width, a)
    depth = -problem.driving_displacement()
    hertz_depth = (3 * 4 * P / (4 * E_STAR * np.sqrt(R))) ** (2 / 3)
    assert 0.85 < depth / hertz_depth < 1.0, (depth, hertz_depth)


def _block(dim: int, top_and_bottom: bool):
    """A block [-1, 1] × [-0.5, 0.5] (× [-0.5, 0.5]) clamped at x = -1; contact faces y = ±0.5."""
    if dim == 2:
        msh = dmesh.create_rectangle(COMM, [np.array([-1.0, -0.5]), np.array([1.0, 0.5])],
                                     [16, 8], cell_type=dmesh.CellType.quadrilateral)
    else:
        msh = dmesh.create_box(COMM, [np.array([-1.0, -0.5, -0.5]), np.array([1.0, 0.5, 0.5])],
                               [8, 4, 4], cell_type=dmesh.CellType.hexahedron)
    facets = {1: lambda x: np.isclose(x[0], -1.0), 2: lambda x: np.isclose(x[1], 0.5)}
    if top_and_bottom:
        facets[3] = lambda x: np.isclose(x[1], -0.5)
    return msh, tag_facets(msh, facets)


def _indenter(tag: int, dim: int, side: float, force):
    """A cylinder (2-D) or sphere (3-D) of radius 2 above (side 1) or below (side -1) the block,
    touching it at x = 0.3, pressed by ``force`` towards it."""
    centre = np.zeros((3, 1))
    centre[0], centre[1] = 0.3, side * 2.5

    def phi(x):
        return np.linalg.norm((x - centre)[:dim], axis=0) - 2.0

    direction = (0.0, -side, 0.0)
    return Signorini(tag, obstacle=phi, max_distance=10.0, force=lambda t: force(t) *
                     np.array(direction[:dim]), force_direction=direction)


@pytest.mark.parametrize("dim", [2, pytest.param(3, marks=pytest.mark.slow)])
def test_two_indenters_driven_by_opposite_forces(dim):
    """The block squeezed between two indenters pressed by 10 t and 6 t: each part's contact
    force is its own, and the clamp holds the difference."""
    msh, tags = _block(dim, True)
    elastic = Elastic(Elasticity("3d_standard", 1e3, 0.3))
    law = PlaneStrain(elastic) if dim == 2 else elastic
    problem = QuasistaticProblem(msh, tags, law, clamped_tag=1, contact={
        "top": _indenter(2, dim, 1.0, lambda t: 10.0 * t),
        "bottom": _indenter(3, dim, -1.0, lambda t: 6.0 * t)})
    for step in advance(problem, 1.0, StepControl(0.5)):
        reactions, parts = problem.support_forces(per_part=True)
        assert parts[0][1] == pytest.approx(-10.0 * step.time, rel=1e-8)
        assert parts[1][1] == pytest.approx(6.0 * step.time, rel=1e-8)
        assert reactions[0][1] == pytest.approx(4.0 * step.time, rel=1e-6)
        assert step.newton_iterations <= 6
    d_top, d_bottom = (p.displacement for p in problem.contacts)
    # the block bends down under the net force, the bottom indenter follows it; the two
    # indenters come closer (they squeeze it)
    assert d_top > 0 and d_top + d_bottom > 0, (d_top, d_bottom)


@pytest.mark.slow
def test_indentation_creep_of_a_perzyna_block():
    """Plane strain, a Perzyna block pressed by a cylinder: F ramps to 20 over t ≤ 0.2, then
    holds. While it is held the indenter keeps sinking (the block flows) at a falling rate, and
    the contact force is F(t) at every step."""
    msh, tags = _block(2, False)
    law = PlaneStrain(Perzyna(Elasticity("3d_standard", 1e3, 0.3), 20.0, 50.0))
    force = lambda t: 20.0 * min(t, 0.2) / 0.2  # noqa: E731
    problem = QuasistaticProblem(msh, tags, law, clamped_tag=1,
                                 contact=_indenter(2, 2, 1.0, force), formulation="mixed")
    times, depths = [], []
    for step in advance(problem, 1.0, StepControl(0.05)):
        _, contact = problem.support_forces()
        assert contact[1] == pytest.approx(-force(step.time), rel=1e-7)
        times.append(step.time)
        depths.append(problem.contacts[0].displacement)
    held = np.array(times) >= 0.2
    creep = np.diff(np.array(depths)[held])
    assert np.all(creep > 0), creep           # still sinking under a constant force
    assert creep[-1] < 0.5 * creep[0], creep  # more and more slowly


def test_a_force_driven_indenter_from_a_scene(scene_text, shared_tmp_path):
    scene = write_shared(shared_tmp_path / "pressed.toml", scene_text("pressed_by_force"))
    out = shared_tmp_path / "out"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    text = (out / "reactions.csv").read_text().splitlines()
    header = text[0].split(",")
    rows = np.array([[float(v) for v in line.split(",")] for line in text[1:]])
    col = {name: i for i, name in enumerate(header)}
    assert np.allclose(rows[:, col["contact_y"]], -10.0 * rows[:, col["t"]], atol=1e-7)
    d = rows[:, col["displacement"]]
    assert d[0] == 0.0 or d[0] < 0  # the indenter starts touching (it was placed so)
    assert np.all(np.diff(d) < 0), d  # signed: it moves down
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] and max(summary["newton_iterations"]) <= 6


@pytest.mark.parametrize("edit, key, message", [
    (lambda s: s.replace('force = [0, "-10*t"]', 'force = [0, "-10*t"]\nmotion = [0, "-t"]'),
     r"contact\.motion", "an obstacle driven by a force moves along the force"),
    (lambda s: s.replace('force = [0, "-10*t"]', 'force = ["t*t", "-10*t"]'),
     r"contact\.force", "the force turns"),
    (lambda s: s.replace('force = [0, "-10*t"]', 'force = [0, "10*t"]'),
     r"contact\.force", "moves the obstacle away from the contact part"),
    (lambda s: s.replace('force = [0, "-10*t"]', 'force = [0, "-10*max(t - 0.5, 0)"]'),
     r"contact\.force", "the force is zero at t = 0.25"),
    (lambda s: s.replace('force = [0, "-10*t"]', 'force = ["-10*t"]'), r"contact\.force", ""),
    (lambda s: s.replace('type = "signorini"', 'type = "normal_compliance"\nmu = 1.0'),
     r"contact\.force", "a foundation surface stays where it is"),
])
def test_force_control_errors_are_located(scene_text, shared_tmp_path, capsys, edit, key, message):
    scene = write_shared(shared_tmp_path / "bad.toml", edit(scene_text("pressed_by_force")))
    out = shared_tmp_path / "bad"
    assert cli.main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(rf"bad\.toml:\d+: {key}: .*{message}", err), err
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    assert not out.exists()


def test_show_writes_the_force_back(scene_text, shared_tmp_path):
    from vpcontact.scene import loads_text
    scene = loads_text(scene_text("pressed_by_force"))
    again = loads_text(scene.to_toml())
    assert again == scene and again.contact.force is not None
