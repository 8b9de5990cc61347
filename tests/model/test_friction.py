# SPDX-License-Identifier: MIT
"""Friction on normal-compliance parts (vpcontact.model.friction): a block pressed onto a
deformable foundation, then dragged along it by its top.

* Coulomb, full slip: the tangential contact force is 𝔣 × the normal one, to 1e-8.
* Tresca, full slip: the tangential force is the threshold × the contact length, to 1e-8.
* Stick below the limit: with 𝔣 large the bottom moves only by the stick's micro-slip |t|/k_t.
* A block pushed up an inclined foundation (NAFEMS's frictional benchmark): the horizontal push
  over the weight is (tan α + 𝔣)/(1 − 𝔣 tan α), to 1e-7.
* Newton iterations per step ≤ 6, pressing, sliding and reversing; the scene keys and their
  located errors.
"""

import json
import re

import numpy as np
import pytest
from mpi4py import MPI
from dolfinx import mesh as dmesh

from vpcontact import cli
from vpcontact.model import Elastic, Elasticity, NormalCompliance, PlaneStrain, Signorini
import ufl

from vpcontact.model.friction import STICK_STIFFNESS, Friction
from vpcontact.solver import (Dirichlet, Loads, QuasistaticProblem, StepControl, advance,
                              tag_facets)

from tests.support.mpi_launch import write_shared
from tests.support.scenes import scene_text


#: The foundation of the dragged block (tests/scenes/dragged.toml) as a rigid plane (a Signorini
#: part's obstacle).
PLANE_FLOOR = 'obstacle = { shape = "plane", point = [0, 0], normal = [0, 1] }\n'


def _signorini_dragged(obstacle: str) -> str:
    """The dragged block with a rigid obstacle (the ``obstacle`` lines, with any motion or force)
    in place of the compliant foundation, and Coulomb friction 𝔣 = 0.3."""
    text = scene_text("dragged", friction='friction = { type = "coulomb", coefficient = 0.3 }')
    return text.replace('type = "normal_compliance"', 'type = "signorini"').replace(
        "mu = 1e-3\n", obstacle)


def _dragged_on(floor: str) -> str:
    """The dragged block with Coulomb friction 𝔣 = 0.3 on a ``"rigid"`` floor (a Signorini plane)
    or on its compliant one."""
    if floor == "rigid":
        return _signorini_dragged(PLANE_FLOOR)
    return scene_text("dragged", friction='friction = { type = "coulomb", coefficient = 0.3 }')


def _forces(out):
    lines = (out / "reactions.csv").read_text().splitlines()
    header = lines[0].split(",")
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    return {name: rows[:, i] for i, name in enumerate(header)}


def _run(tmp, name, friction):
    scene = write_shared(tmp / f"{name}.toml", scene_text("dragged", friction=friction))
    out = tmp / name
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    return _forces(out)


def test_coulomb_full_slip_carries_the_coefficient_times_the_normal_force(shared_tmp_path):
    f = _run(shared_tmp_path, "coulomb", 'friction = { type = "coulomb", coefficient = 0.3 }')
    sliding = f["t"] >= 0.7
    ratio = -f["contact_x"][sliding] / f["contact_y"][sliding]
    assert np.allclose(ratio, 0.3, rtol=1e-8), ratio
    assert f["contact_y"][-1] > 1.0  # pressed
    summary = json.loads((shared_tmp_path / "coulomb" / "summary.json").read_text())
    # every step, pressing and sliding (the pressing steps took 10–14 while the residual and the
    # Jacobian were integrated with different rules)
    assert max(summary["newton_iterations"]) <= 6, summary["newton_iterations"]


def test_a_rigid_floor_given_by_its_gap_carries_friction(shared_tmp_path):
    """A Signorini part given by ``gap = 0`` (no obstacle) is the same rigid floor as the plane
    obstacle: with friction it gives the same forces, the Coulomb ratio while sliding. Its
    friction table was read and then dropped: the block slid frictionless, exit 0."""
    forces = {}
    for name, floor in (("gap_floor", "gap = 0.0\n"), ("plane_floor", PLANE_FLOOR)):
        scene = write_shared(shared_tmp_path / f"{name}.toml", _signorini_dragged(floor))
        out = shared_tmp_path / name
        assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
        forces[name] = _forces(out)
    gap, plane = forces["gap_floor"], forces["plane_floor"]
    sliding = gap["t"] >= 0.7
    assert np.allclose(-gap["contact_x"][sliding] / gap["contact_y"][sliding], 0.3, rtol=1e-8)
    for key in ("contact_x", "contact_y"):
        assert np.allclose(gap[key], plane[key], rtol=1e-10, atol=1e-12), key


def test_reactions_and_contact_forces_balance_with_friction_on_a_held_node(scene_text,
                                                                          shared_tmp_path):
    """A block pushed by its weight sideways onto a compliant wall with Coulomb friction,
    pressed from above by a rigid plane; the wall's bottom node sits on a symmetry plane. The
    supports' and the parts' forces balance the load in every step. The wall's force was its
    friction term assembled after the step, which sees the committed slip history instead of
    the step's: 0.29 N (1 %) out of balance in y."""
    scene = write_shared(shared_tmp_path / "held.toml", scene_text("held_on_a_compliant_face"))
    out = shared_tmp_path / "held"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    f = _forces(out)
    scale = np.abs(f["left_x"]).max()
    load_x = 100.0 * f["t"] * 2.0  # the body force over the block's area
    assert np.allclose(f["left_x"] + f["bottom_x"] + f["contact_x"] + load_x, 0.0,
                       atol=1e-8 * scale)
    assert np.allclose(f["left_y"] + f["bottom_y"] + f["contact_y"], 0.0, atol=1e-8 * scale)
    assert np.abs(f["right_y"]).max() > 1.0  # the wall's friction carries load


def test_tresca_full_slip_carries_the_threshold_times_the_length(shared_tmp_path):
    f = _run(shared_tmp_path, "tresca", 'friction = { type = "tresca", threshold = 2.0 }')
    sliding = f["t"] >= 0.7
    assert np.allclose(-f["contact_x"][sliding], 2.0 * 1.0, rtol=1e-8), f["contact_x"]


def test_below_the_limit_the_block_sticks():
    """𝔣 = 10, pressed, then dragged by 1e-4: the bottom moves only by the stick's micro-slip,
    |t|/k_t, 1e-3 of the drag."""
    comm = MPI.COMM_WORLD
    msh = dmesh.create_rectangle(comm, [np.zeros(2), np.array([1.0, 0.25])], [16, 4])
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[1], 0.25), 2: lambda x: np.isclose(x[1], 0.0)})

    def ux(x, t):
        return np.full(x.shape[1], 2e-4 * max(t - 0.5, 0.0))

    def uy(x, t):
        return np.full(x.shape[1], -0.002 * min(t / 0.5, 1.0))

    law = PlaneStrain(Elastic(Elasticity("3d_standard", 1e3, 0.3)))
    problem = QuasistaticProblem(
        msh, tags, law, dirichlet=[Dirichlet(1, (ux, uy), "top")],
        contact=NormalCompliance(2, mu=1e-3, friction=Friction("coulomb", coefficient=10.0)))
    at_press = None
    for step in advance(problem, 1.0, StepControl(0.1)):
        if abs(step.time - 0.5) < 1e-9:
            at_press = problem.u.x.array.copy()
    part = problem.contacts[0]
    x_dofs = part.nodes.nodes * 2
    moved = comm.allreduce(float(np.max(np.abs(problem.u.x.array[x_dofs] - at_press[x_dofs]),
                                        initial=0.0)), op=MPI.MAX)
    state = part.friction_state()
    micro = comm.allreduce(float(np.max(np.linalg.norm(state["traction"], axis=1)
                                        / part.nodal_stick_stiffness(), initial=0.0)), op=MPI.MAX)
    assert moved <= 1.01 * micro, (moved, micro)
    assert moved < 1e-2 * 1e-4, moved
    assert not comm.allreduce(bool(part.friction_state()["slips"].any()), op=MPI.LOR)
    _, contact = problem.support_forces()
    assert 0 < -contact[0] < 10.0 * contact[1]  # a tangential force, below the limit


def test_a_block_pushed_up_an_inclined_foundation():
    """Plane strain: a block [0, 1] × [0, 0.25] on a foundation inclined at α = 20° (the whole
    problem turned), its weight W vertical, pushed horizontally on the upper part of its back
    face (not at the contact corner) until it slides up: P/W = (tan α + 𝔣)/(1 − 𝔣 tan α)."""
    comm = MPI.COMM_WORLD
    alpha, f, W = np.radians(20.0), 0.3, 5.0
    Q = np.array([[np.cos(alpha), -np.sin(alpha)], [np.sin(alpha), np.cos(alpha)]])
    msh = dmesh.create_rectangle(comm, [np.zeros(2), np.array([1.0, 0.25])], [16, 4])
    msh.geometry.x[:, :2] = msh.geometry.x[:, :2] @ Q.T

    def ref(p):
        return Q.T @ p[:2]

    tags = tag_facets(msh, {1: lambda p: np.isclose(ref(p)[0], 0.0) & (ref(p)[1] > 1e-9),
                            2: lambda p: np.isclose(ref(p)[1], 0.0)})
    loads = Loads(body_force=lambda X, t: ufl.as_vector(
        [0.0, -W / 0.25 * ufl.min_value(2 * t, 1.0)]))

    def push(x, t):
        return np.full(x.shape[1], 0.1 * max(t - 0.5, 0.0))

    problem = QuasistaticProblem(
        msh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", 1e3, 0.3))), loads=loads,
        dirichlet=[Dirichlet(1, (push, None), "back")],
        contact=NormalCompliance(2, mu=1e-3, friction=Friction("coulomb", coefficient=f)))
    expected = (np.tan(alpha) + f) / (1 - f * np.tan(alpha))
    for step in advance(problem, 1.0, StepControl(0.1)):
        reactions, _ = problem.support_forces()
        if step.time >= 0.7 - 1e-9:
            assert abs(reactions[0][0] / W / expected - 1) < 1e-7, (reactions, expected)
            assert step.newton_iterations <= 6


@pytest.mark.parametrize("friction, key, message", [
    ('friction = { type = "coulomb", coefficient = -0.1 }', r"contact\.friction\.coefficient",
     "must be >= 0"),
    ('friction = { type = "coulomb", coefficient = 0.1, threshold = 1 }',
     r"contact\.friction\.threshold", "only for type = 'tresca'"),
    ('friction = { type = "tresca", threshold = -1 }', r"contact\.friction\.threshold",
     "must be >= 0"),
    ('friction = { type = "viscous" }', r"contact\.friction\.type", ""),
])
def test_friction_errors_are_located(shared_tmp_path, capsys, friction, key, message):
    scene = write_shared(shared_tmp_path / "bad.toml", scene_text("dragged", friction=friction))
    assert cli.main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(rf"bad\.toml:\d+: {key}: .*{message}", err), err


def _block_on_a_driven_floor(angle: float, coefficient: float):
    """The block held by its top; under it a rigid floor pushed by a force 2t along
    e = (sin α, cos α): into the block and, for α > 0, sideways along it. The floor's d along e
    is an unknown of each step (force control)."""
    comm = MPI.COMM_WORLD
    msh = dmesh.create_rectangle(comm, [np.zeros(2), np.array([1.0, 0.25])], [16, 4])
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[1], 0.25), 2: lambda x: np.isclose(x[1], 0.0)})
    e = np.array([np.sin(angle), np.cos(angle), 0.0])
    floor = Signorini(2, obstacle=lambda x: x[1], max_distance=1.0,
                      force=lambda t: 2.0 * t * e[:2], force_direction=tuple(e),
                      friction=Friction("coulomb", coefficient=coefficient))
    zero = lambda x, t: np.zeros(x.shape[1])  # noqa: E731
    problem = QuasistaticProblem(msh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", 1e3, 0.3))),
                                 dirichlet=[Dirichlet(1, (zero, zero), "top")], contact=floor)
    return problem, e[:2]


def test_a_floor_pushed_obliquely_by_a_force_slides_with_the_coulomb_ratio():
    """Pushed at 60° from the normal, the floor slides along the block's bottom: at every step
    every contact node slips, the tangential force is 𝔣 × the normal one (1e-8), and the
    floor's own equation holds with friction in it — the contact force along e is the applied
    force, C · e = F (1e-8), so N = F/(cos α + 𝔣 sin α). (Without friction in the floor's
    equation: C · e = 1.52 F, in 13 Newton iterations per step.) At most 6 Newton iterations
    per step (measured 5, then 2–3)."""
    problem, e = _block_on_a_driven_floor(np.pi / 3, 0.3)
    comm = MPI.COMM_WORLD
    for step in advance(problem, 1.0, StepControl(0.1)):
        assert step.newton_iterations <= 6, step
        _, force = problem.support_forces()
        assert force[:2] @ e == pytest.approx(2.0 * step.time, rel=1e-8), force
        assert force[0] == pytest.approx(0.3 * force[1], rel=1e-8), force
        last = problem.contacts[0].friction.last
        touching = last["lam"] > 0
        assert comm.allreduce(bool(np.all(last["slips"][touching])), op=MPI.LAND)
    assert force[1] == pytest.approx(2.0 / (0.5 + 0.3 * np.sqrt(3) / 2), rel=1e-8)


def test_a_floor_pushed_almost_normally_by_a_force_carries_the_nodes_that_stick():
    """Pushed at 10° from the normal, the floor drags the block's bottom but below the limit in
    the middle: the nodes that stick move, between steps, as the floor's tangential motion
    Δd sin α (d the floor's solved displacement along e), up to the stick's micro-slip
    |Δf|/k (at most 1.1e-2 of Δd sin α, next to the slipping rim); C · e = F throughout."""
    angle = np.pi / 18
    problem, e = _block_on_a_driven_floor(angle, 0.3)
    part = problem.contacts[0]
    friction = part.friction
    rows = part.nodes.nodes * 2  # the x components of the contact nodes
    history = []
    for step in advance(problem, 1.0, StepControl(0.1)):
        _, force = problem.support_forces()
        assert force[:2] @ e == pytest.approx(2.0 * step.time, rel=1e-8), force
        history.append((problem.u.x.array[rows].copy(), part.displacement,
                        friction.last["force"][:, 0].copy(), friction.last["slips"].copy(),
                        friction.last["lam"] > 0))
    comm = MPI.COMM_WORLD
    checked = 0
    for (u0, d0, f0, _, on0), (u1, d1, f1, slips, on1) in zip(history[4:], history[5:]):
        stuck = on0 & on1 & ~slips
        expected = (d1 - d0) * np.sin(angle)
        micro = np.abs(f1 - f0)[stuck] / friction.stiffness[stuck]
        assert np.all(np.abs((u1 - u0)[stuck] - expected) <= 1.01 * micro + 1e-14), (
            (u1 - u0)[stuck], expected, micro)
        assert np.all(micro < 0.05 * abs(expected))  # (the floor's motion is what moves them)
        checked += comm.allreduce(int(stuck.sum()))
    assert checked >= 20


def test_friction_on_a_force_driven_obstacle_runs_from_a_scene(shared_tmp_path):
    """A scene with friction on an obstacle driven by a force validates and runs (it used to be
    refused)."""
    text = _signorini_dragged(PLANE_FLOOR + 'force = ["0.5*t", "t"]\n').replace(
        'displacement = ["0.02*max(t - 0.5, 0)", "-0.002*min(t/0.5, 1)"]', 'displacement = [0, 0]')
    scene = write_shared(shared_tmp_path / "driven.toml", text)
    assert cli.main(["validate", str(scene)]) == 0
    out = shared_tmp_path / "driven"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    assert json.loads((out / "summary.json").read_text())


def _signorini_block(friction, floor_motion=None, drag=0.02, drag_path=None, cells=(16, 4),
                     **discretization):
    """The dragged block on a rigid floor (Signorini) with friction; or held by its top while
    the floor slides under it (``floor_motion``). ``discretization``: ``degree`` and
    ``formulation`` of the problem (default: P1 displacements)."""
    comm = MPI.COMM_WORLD
    msh = dmesh.create_rectangle(comm, [np.zeros(2), np.array([1.0, 0.25])], list(cells))
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[1], 0.25), 2: lambda x: np.isclose(x[1], 0.0)})

    def ux(x, t):
        if drag_path is not None:
            return np.full(x.shape[1], drag_path(t))
        return np.full(x.shape[1], 0.0 if floor_motion else drag * max(t - 0.5, 0.0))

    def uy(x, t):
        return np.full(x.shape[1], -0.002 * min(t / 0.5, 1.0))

    floor = Signorini(2, obstacle=lambda x: x[1], max_distance=1.0, friction=friction,
                      translation=floor_motion)
    return QuasistaticProblem(msh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", 1e3, 0.3))),
                              dirichlet=[Dirichlet(1, (ux, uy), "top")], contact=floor,
                              **discretization)


@pytest.mark.parametrize("kind", ["coulomb", "tresca"])
def test_signorini_full_slip(kind):
    """The block pressed onto a rigid floor (Signorini, nodal friction in the contact frames),
    then dragged: tangential force = 0.3 × normal force (Coulomb) or = 2 × the contact length
    (Tresca) to 1e-8 while it slides; at most 6 Newton iterations per step. With Coulomb, the
    pressing steps after the first and the steady sliding ones are linear (the stick/slip
    pattern no longer changes): the extrapolated guess solves them, with no Newton iteration
    (measured 4, 0, 0, 0, 0, 5, 4, 3, 0, 0; from a sticking guess they took 3 each)."""
    friction = (Friction("coulomb", coefficient=0.3) if kind == "coulomb"
                else Friction("tresca", threshold=2.0))
    problem = _signorini_block(friction)
    for step in advance(problem, 1.0, StepControl(0.1)):
        assert step.newton_iterations <= 6, step
        steady = (0.2 - 1e-9 < step.time < 0.5 + 1e-9) or step.time > 0.9 - 1e-9
        if kind == "coulomb" and steady:
            assert step.newton_iterations == 0, step
        if step.time >= 0.7 - 1e-9:
            _, force = problem.support_forces()
            expected = 0.3 * force[1] if kind == "coulomb" else 2.0 * 1.0
            assert -force[0] == pytest.approx(expected, rel=1e-8), force
    assert problem.contact_monitor.report().active > 10


def _count_predictor_runs(monkeypatch) -> list:
    """A list that grows by one entry each time a step goes through the Tresca predictor."""
    from vpcontact.solver import retries

    predicted = []
    original = retries.Predictor.run

    def counted(solver, terms):
        predicted.append(True)
        return original(solver, terms)

    monkeypatch.setattr(retries.Predictor, "run", counted)
    return predicted


@pytest.mark.slow
def test_a_slip_zone_spreading_over_a_fine_face_converges_from_the_sticking_guess(monkeypatch):
    """The dragged block on a rigid floor on 256×64 cells, k = 0.05 (bench/friction_step.py
    --floor rigid). In the second dragging step the slip zone spreads over the whole face; from
    the sticking guess Newton with Coulomb's thresholds, which move with every iterate, grew it
    by about one node per iteration: 35 iterations (25 / 12 on 64×16 / 128×32 cells; 36 and
    three cut steps on 512×128). After 10 iterations that step started again with the
    Tresca predictor (every pressed node stuck, then the thresholds fixed at that iterate's,
    then Coulomb: NodalFriction.freeze): 22 iterations in all (19 / 21 on the coarser meshes,
    27 and no cut on 512×128). Now that second try also stops once 3 iterations have not
    halved its residual (retries.CRAWL_ITERATIONS): 16 (13 / 15, and 21 on 512×128). Most
    of the crawl was three nodes at the face's trailing end, whose cones had shrunk under their
    old forces, thrown across their stick intervals one way and back; linearised on the stick
    branch while that brings them nearer their cones (NodalFriction._unloading), the step
    converges from the sticking guess in 10 (7 / 8, and 12 on 512×128 with SECOND_TRY = 15),
    no other step moving. The block slides with the Coulomb ratio."""
    predicted = _count_predictor_runs(monkeypatch)
    problem = _signorini_block(Friction("coulomb", coefficient=0.3), cells=(256, 64))
    its = [step.newton_iterations for step in advance(problem, 1.0, StepControl(0.05))]
    assert len(its) == 20 and problem.solver.total_iterations == sum(its), its  # no step cut
    assert max(its) <= 11 and not predicted, (its, len(predicted))
    _, force = problem.support_forces()
    assert -force[0] == pytest.approx(0.3 * force[1], rel=1e-8), force


def _on_displacement_unknowns_only(problem) -> bool:
    """Whether every unknown the nodal friction touches (its tangential rows and the normal
    rows it reads λ from) is a displacement unknown of SNES's vector (on every rank)."""
    friction = problem.contacts[0].friction
    probe = problem.fields.create_vector()
    start = probe.getOwnershipRange()[0]
    probe.destroy()
    indices = problem.fields.field_indices()
    u_rows = indices["displacement"].getIndices() - start
    used = np.concatenate([friction.tangential.ravel(), friction.slots])
    inside = bool(np.isin(used, u_rows).all())
    if "pressure" in indices:
        inside &= not np.isin(used, indices["pressure"].getIndices() - start).any()
    return MPI.COMM_WORLD.allreduce(inside, op=MPI.LAND)


@pytest.mark.parametrize("discretization", [{"degree": 2}, {"formulation": "mixed"}],
                         ids=["P2", "mixed"])
def test_signorini_full_slip_beyond_p1(discretization):
    """Coulomb on a rigid floor with P2 displacements, and with the mixed (Taylor–Hood u, p)
    formulation: while the block slides the tangential force is 0.3 × the normal one to 1e-8
    (measured 1e-15 with both); the HRZ areas of the bottom's nodes add up to its length;
    friction touches displacement unknowns only; Newton iterations per step ≤ 6 (measured
    5, 0, 0, 0, 0, 6, 3, 4, 0, 0 and 4, 0, 0, 0, 0, 5, 3, 4, 0, 0)."""
    problem = _signorini_block(Friction("coulomb", coefficient=0.3), **discretization)
    assert problem.formulation == discretization.get("formulation", "displacement")
    assert problem.V.ufl_element().degree() == 2
    sliding = 0
    for step in advance(problem, 1.0, StepControl(0.1)):
        assert step.newton_iterations <= 6, step
        if step.time >= 0.7 - 1e-9:
            _, force = problem.support_forces()
            assert -force[0] == pytest.approx(0.3 * force[1], rel=1e-8), force
            sliding += 1
    assert sliding == 4
    friction = problem.contacts[0].friction
    comm = MPI.COMM_WORLD
    assert comm.allreduce(float(friction.areas.sum())) == pytest.approx(1.0, rel=1e-12)
    assert comm.allreduce(float(friction.areas.min(initial=np.inf)), op=MPI.MIN) > 0
    assert _on_displacement_unknowns_only(problem)
    assert problem.contact_monitor.report().active > 20  # 2 × 16 + 1 nodes on the bottom
    assert comm.allreduce(bool(friction.last["slips"].any()), op=MPI.LOR)


def test_signorini_sticks_below_the_limit():
    problem = _signorini_block(Friction("coulomb", coefficient=10.0), drag=2e-4)
    for _ in advance(problem, 1.0, StepControl(0.1)):
        pass
    part = problem.contacts[0]
    assert part.friction.last is not None
    assert not MPI.COMM_WORLD.allreduce(bool(part.friction.last["slips"].any()), op=MPI.LOR)
    _, force = problem.support_forces()
    assert 0 < -force[0] < 10.0 * force[1]


def test_signorini_sticks_below_the_limit_with_the_mixed_formulation():
    """The mixed formulation, 𝔣 = 10, dragged by 1e-4 once pressed: no node slips, the bottom
    moves by less than 1e-2 of the drag (the stick's micro-slip; measured 4.8e-3),
    and the tangential force is below the limit."""
    problem = _signorini_block(Friction("coulomb", coefficient=10.0), drag=2e-4,
                               formulation="mixed")
    x_dofs = problem.contacts[0].nodes.nodes * 2
    at_press = None
    for step in advance(problem, 1.0, StepControl(0.1)):
        if abs(step.time - 0.5) < 1e-9:
            at_press = problem.u.x.array[x_dofs].copy()
    friction, comm = problem.contacts[0].friction, MPI.COMM_WORLD
    # k_i = STICK_STIFFNESS G/h_i A_i with h_i = 1/16 the bottom's facets, on any number of
    # ranks (a length taken from each rank's own part of the mesh once made the stick answers
    # change with the ranks)
    shear = 1e3 / (2 * 1.3)
    assert np.allclose(friction.sizes, 1.0 / 16, rtol=1e-12)
    assert np.allclose(friction.stiffness, STICK_STIFFNESS * shear * 16 * friction.areas,
                       rtol=1e-12)
    assert not comm.allreduce(bool(friction.last["slips"].any()), op=MPI.LOR)
    moved = comm.allreduce(float(np.max(np.abs(problem.u.x.array[x_dofs] - at_press),
                                        initial=0.0)), op=MPI.MAX)
    assert moved < 1e-2 * 1e-4, moved
    _, force = problem.support_forces()
    assert 0 < -force[0] < 10.0 * force[1]


def test_a_restored_checkpoint_keeps_the_stick_forces():
    """The block dragged until it slides, then pulled back a little: its nodes stick again with
    forces that depend on the history (the return mapping's f_{n−1}). A run restored from a
    checkpoint taken then ends where an uninterrupted one does (Tresca; Coulomb's reversal:
    the next test)."""
    friction = Friction("tresca", threshold=2.0)

    def path(t):  # forward to t = 0.8, then back by 1e-5 (the block unloads elastically)
        return 0.02 * max(min(t, 0.8) - 0.5, 0.0) - 1e-5 * max(t - 0.8, 0.0) / 0.2

    first = _signorini_block(friction, drag_path=path)
    for _ in advance(first, 0.9, StepControl(0.1)):
        pass
    scalars, arrays = first.checkpoint()
    for _ in advance(first, 1.0, StepControl(0.1)):  # on, uninterrupted
        pass
    second = _signorini_block(friction, drag_path=path)
    second.restore(scalars, arrays)
    for _ in advance(second, 1.0, StepControl(0.1)):
        pass
    expected = first.support_forces()[1]
    assert abs(expected[0]) < 2.0 * (1 - 1e-3)  # below the slip force: sticking again
    assert np.allclose(second.support_forces()[1], expected, rtol=1e-9, atol=0.0)


@pytest.mark.parametrize("back", [1e-5, 1e-4, 1e-3])
def test_a_reversed_drag_sticks_again_within_six_newton_iterations(back):
    """Coulomb: the block dragged until it slides, then pulled back by ``back`` within one step:
    every node sticks again, in at most 6 Newton iterations, with no step cut. (The nodes
    start the step on the cone's edge with no slip yet; linearised there on the slip branch,
    whose 2-D tangent is zero, Newton jumped them across the stick interval and cycled: 8, 29
    and 23 iterations for these pull-backs.)"""
    def path(t):
        return 0.02 * max(min(t, 0.8) - 0.5, 0.0) - back * max(t - 0.8, 0.0) / 0.2

    problem = _signorini_block(Friction("coulomb", coefficient=0.3), drag_path=path)
    friction, comm = problem.contacts[0].friction, MPI.COMM_WORLD
    its = []
    for step in advance(problem, 1.0, StepControl(0.1)):
        its.append(step.newton_iterations)
        if abs(step.time - 0.8) < 1e-9:  # sliding before the reversal
            assert comm.allreduce(int(friction.last["slips"].sum()), op=MPI.SUM) > 10
    assert len(its) == 10 and problem.solver.total_iterations == sum(its), its  # no step cut
    assert max(its) <= 6, its
    assert not comm.allreduce(bool(friction.last["slips"].any()), op=MPI.LOR)


@pytest.mark.parametrize("back", [1e-5, 1e-4, 1e-3])
def test_on_a_compliant_floor_a_reversed_drag_sticks_again_within_six_newton_iterations(back):
    """The same reversal on a deformable foundation (normal compliance, μ = 1e-3): at most 6
    Newton iterations in every step, no step cut, and the block sticks again in the reversing
    step (pulled back further, by 1e-3, it then slides back). From the extrapolated guess alone
    the reversal took 34, 32 and 22 iterations and, for 1e-3, a step cut: SNES now starts again
    from a sticking guess after 5 (friction.StickingGuess), which takes 1."""
    comm = MPI.COMM_WORLD
    msh = dmesh.create_rectangle(comm, [np.zeros(2), np.array([1.0, 0.25])], [16, 4])
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[1], 0.25), 2: lambda x: np.isclose(x[1], 0.0)})

    def ux(x, t):
        return np.full(x.shape[1], 0.02 * max(min(t, 0.8) - 0.5, 0.0) - back * max(t - 0.8, 0.0) / 0.2)

    def uy(x, t):
        return np.full(x.shape[1], -0.002 * min(t / 0.5, 1.0))

    problem = QuasistaticProblem(
        msh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", 1e3, 0.3))),
        dirichlet=[Dirichlet(1, (ux, uy), "top")],
        contact=NormalCompliance(2, mu=1e-3, friction=Friction("coulomb", coefficient=0.3)))
    part = problem.contacts[0]
    its = []
    for step in advance(problem, 1.0, StepControl(0.1)):
        its.append(step.newton_iterations)
        slipping = comm.allreduce(int(part.last_friction["slips"].sum()), op=MPI.SUM)
        if abs(step.time - 0.8) < 1e-9:  # sliding before the reversal
            assert slipping > 10
        if abs(step.time - 0.9) < 1e-9:  # the reversing step: every node sticks
            assert slipping == 0
    assert len(its) == 10 and problem.solver.total_iterations == sum(its), its  # no step cut
    assert max(its) <= 6, its


def _clamped_block(contact: dict, dirichlet=()):
    """An elastic block [0, 1] × [0, 0.25] (plane strain, 32×8 cells) clamped at its left end
    (tag 1), with ``contact`` parts on its bottom (tag 2) and top (tag 3) and further Dirichlet
    parts."""
    msh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.zeros(2), np.array([1.0, 0.25])], [32, 8])
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[0], 0.0), 2: lambda x: np.isclose(x[1], 0.0),
                            3: lambda x: np.isclose(x[1], 0.25)})
    clamp = Dirichlet(1, (_zero, _zero), "left")
    return QuasistaticProblem(msh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", 1e3, 0.3))),
                              dirichlet=[clamp, *dirichlet], contact=contact)


def _zero(x, t):
    return np.zeros(x.shape[1])


def _pressed_down(t):
    """The top's descent: 0.004 over t ≤ 0.5, then held."""
    return 0.004 * min(t / 0.5, 1.0)


@pytest.mark.parametrize("press", ["prescribed", "rigid plane"])
def test_a_clamped_block_pressed_onto_a_compliant_floor_with_friction(press):
    """A block clamped at its left end and pressed down by its top — a prescribed displacement,
    or a frictionless rigid plane (Signorini) — onto a compliant floor with Coulomb friction
    until t = 0.5, then held. From the extrapolated guess, the onset step's Newton iteration
    cycled between two iterates (the far end's nodes slipping one way, then the other, across
    the stick interval) at every step size, so the run could not start; at the onset the
    sticking guess now starts from the first try's pressed nodes
    (friction.StickingGuess.fallback). Where the rigid plane stops, full Newton steps cycled
    again and the step was cut 10 times; the compliant part's friction now takes the ``l2`` line
    search. Every step converges with no cut (measured 16, 1, 1, 1, 1, 2, 2, 1, 1, 1 and 21, 1,
    1, 1, 1, 20, 1, 1, 1, 1), and every node's traction is within its cone, some nodes slipping
    and some sticking."""
    comm = MPI.COMM_WORLD
    floor = NormalCompliance(2, mu=1e-3, friction=Friction("coulomb", coefficient=0.3))
    dirichlet, contact = [], {"floor": floor}
    if press == "prescribed":
        down = Dirichlet(3, (_zero, lambda x, t: np.full(x.shape[1], -_pressed_down(t))), "top")
        dirichlet.append(down)
    else:
        contact["top"] = Signorini(3, obstacle=lambda x: 0.25 - x[1], max_distance=1.0,
                                   translation=lambda t: np.array([0.0, -_pressed_down(t), 0.0]))
    problem = _clamped_block(contact, dirichlet)
    its = [step.newton_iterations for step in advance(problem, 1.0, StepControl(0.1))]
    assert len(its) == 10 and problem.solver.total_iterations == sum(its), its  # no step cut
    assert max(its) <= 25, its
    part = problem.contacts[0]
    state = part.last_friction
    pressure = -part.law.normal_stress(part.nodes.normal_displacement(part.u) - part.nodes.gap)
    size = np.linalg.norm(state["traction"], axis=1)
    assert np.all(size <= 0.3 * pressure * (1 + 1e-9) + 1e-14), (size, pressure)
    slipping = comm.allreduce(int(state["slips"].sum()), op=MPI.SUM)
    pressed = comm.allreduce(int((pressure > 0).sum()), op=MPI.SUM)
    assert 0 < slipping < pressed, (slipping, pressed)


def test_friction_on_a_rigid_and_on_a_compliant_part_of_one_scene():
    """A block clamped at its left end, pressed by a rigid plane with Coulomb friction
    (Signorini, nodal friction) onto a compliant floor with Coulomb friction, then dragged by
    the plane: the run completes; the parts ask for different line searches (``cp`` for the
    rigid part's friction, ``l2`` for the compliant part's) and the problem takes ``cp``. With
    the Tresca predictor of the rigid part's Coulomb friction (NodalFriction.freeze; its last
    stage with the rescue line search ``l2``), 109 Newton iterations in all and no step cut
    (308 and 12 steps for 10 with ``cp`` in that stage); before it, 860 and 22 steps for 10
    (680 without the rescue tries, 1 145 with ``l2``)."""
    def motion(t):
        return np.array([0.01 * max(t - 0.5, 0.0), -_pressed_down(t), 0.0])

    top = Signorini(3, obstacle=lambda x: 0.25 - x[1], max_distance=1.0, translation=motion,
                    friction=Friction("coulomb", coefficient=0.3))
    floor = NormalCompliance(2, mu=1e-3, friction=Friction("coulomb", coefficient=0.3))
    problem = _clamped_block({"top": top, "floor": floor})
    steps = list(advance(problem, 1.0, StepControl(0.1)))
    assert steps[-1].time == pytest.approx(1.0)
    its = [step.newton_iterations for step in steps]
    assert len(steps) == 10 and problem.solver.total_iterations == sum(its), its  # no step cut
    assert problem.solver.total_iterations <= 200, its


def test_a_clamped_block_squeezed_onto_a_rigid_floor_with_friction_is_rescued():
    """A block clamped at its left end and squeezed by a frictionless rigid plane onto a rigid
    floor with Coulomb friction, then held. With the critical-point line search that Coulomb
    friction on a Signorini part uses, the first step stalled near 0.2 of its first residual at
    every step size (the whole face slipping one way, then the other, while the plane's contact
    set changed): the run could not start. A failed step was then tried once more with the
    part's rescue line search (``l2``) before it was cut: 50 + 7 Newton iterations in the first
    step. Now the Tresca predictor (NodalFriction.freeze) takes over after 10 iterations (now
    15: nodal_friction.SECOND_TRY) from the sticking guess: 19 in the first step (23 in the run), none cut; 15 (19) since that try
    also stops where it crawls (retries.CRAWL_ITERATIONS); both faces pressed, the forces
    in balance."""
    floor = Signorini(2, obstacle=lambda x: x[1], max_distance=1.0,
                      friction=Friction("coulomb", coefficient=0.3))
    plane = Signorini(3, obstacle=lambda x: 0.25 - x[1], max_distance=1.0,
                      translation=lambda t: np.array([0.0, -_pressed_down(t), 0.0]))
    problem = _clamped_block({"floor": floor, "plane": plane})
    its = [step.newton_iterations for step in advance(problem, 1.0, StepControl(0.1))]
    assert len(its) == 10 and problem.solver.total_iterations == sum(its), its  # no step cut
    assert its[0] <= 17 and max(its[1:]) <= 6, its
    reactions, parts = problem.support_forces(per_part=True)
    floor_force, plane_force = parts
    assert floor_force[1] > 1.0 and plane_force[1] < -1.0, parts  # both faces pressed
    total = reactions.sum(axis=0) + floor_force + plane_force
    assert np.allclose(total, 0.0, atol=1e-8 * abs(plane_force[1])), (reactions, parts)


def _turned_block(friction, angle: float):
    """The dragged block of :func:`_signorini_block` (Coulomb, pressed then dragged) with the
    mesh, the floor and the top's motion turned by ``angle`` about the origin."""
    comm = MPI.COMM_WORLD
    c, s = np.cos(angle), np.sin(angle)
    Q = np.array([[c, -s], [s, c]])
    msh = dmesh.create_rectangle(comm, [np.zeros(2), np.array([1.0, 0.25])], [16, 4])
    msh.geometry.x[:, :2] = msh.geometry.x[:, :2] @ Q.T

    def height(x):  # the reference y of a turned point
        return -s * x[0] + c * x[1]

    tags = tag_facets(msh, {1: lambda x: np.isclose(height(x), 0.25),
                            2: lambda x: np.isclose(height(x), 0.0)})

    def motion(t):
        return Q @ np.array([0.02 * max(t - 0.5, 0.0), -0.002 * min(t / 0.5, 1.0)])

    def ux(x, t):
        return np.full(x.shape[1], motion(t)[0])

    def uy(x, t):
        return np.full(x.shape[1], motion(t)[1])

    floor = Signorini(2, obstacle=height, max_distance=1.0, friction=friction)
    problem = QuasistaticProblem(msh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", 1e3, 0.3))),
                                 dirichlet=[Dirichlet(1, (ux, uy), "top")], contact=floor)
    return problem, Q


@pytest.mark.parametrize("kind", ["coulomb", "tresca"])
def test_a_turned_problem_gives_the_turned_forces_and_the_same_slips(kind):
    """Rotation invariance: the pressed and dragged block turned by 30° (mesh, floor, motion)
    carries the turned contact force of the upright one at every step, and its contact nodes
    slip by the same amounts, to 1e-12 of the force (measured 5e-15 at most): the stick stiffness
    STICK_STIFFNESS G/h_i takes h_i from the facets around each node, which turn with the body
    (it once took the mesh's bounding box, 0.9 % shorter for the turned block: 4e-6 apart while
    the nodes stuck)."""
    friction = (Friction("coulomb", coefficient=0.3) if kind == "coulomb"
                else Friction("tresca", threshold=2.0))
    upright, _ = _turned_block(friction, 0.0)
    turned, Q = _turned_block(friction, np.pi / 6)
    sliding = 0
    for a, b in zip(advance(upright, 1.0, StepControl(0.1)), advance(turned, 1.0, StepControl(0.1))):
        assert a.time == pytest.approx(b.time, abs=1e-12)
        expected, force = Q @ upright.support_forces()[1], turned.support_forces()[1]
        slips = upright.contacts[0].last_friction["slips"]
        everywhere = MPI.COMM_WORLD.allreduce(bool(np.all(slips)), op=MPI.LAND)
        sliding += everywhere
        error = np.abs(force - expected).max() / np.abs(expected).max()
        assert error <= 1e-12, (a.time, force, expected)
    assert sliding >= 3
    assert abs(expected @ Q[:, 0]) > 0.1  # it was dragged along the floor
    slips = []  # the last step's, as multisets (the node numbering differs)
    for problem in (upright, turned):
        local = np.abs(problem.contacts[0].last_friction["slip"]).ravel()
        slips.append(np.sort(np.concatenate(MPI.COMM_WORLD.allgather(local))))
    assert slips[0].size >= 17 and slips[0].max() > 1e-6
    assert np.allclose(slips[1], slips[0], rtol=0.0, atol=1e-8 * slips[0].max())


def test_a_rigid_floor_sliding_under_a_held_block_drags_it():
    """The slip is relative to the obstacle: the floor translates by 0.02 (t − 0.5) under the
    block, which its top holds; the friction force on the block is +𝔣 × normal (along the
    floor's motion)."""
    problem = _signorini_block(Friction("coulomb", coefficient=0.3),
                               floor_motion=lambda t: np.array([0.02 * max(t - 0.5, 0.0), 0.0, 0.0]))
    for step in advance(problem, 1.0, StepControl(0.1)):
        if step.time >= 0.7 - 1e-9:
            _, force = problem.support_forces()
            assert force[0] == pytest.approx(0.3 * force[1], rel=1e-8), force


def test_show_writes_friction_back():
    from vpcontact.scene import loads_text
    for friction in ('friction = { type = "coulomb", coefficient = 0.3 }',
                     'friction = { type = "tresca", threshold = "1 + x[0]" }'):
        scene = loads_text(scene_text("dragged", friction=friction))
        assert loads_text(scene.to_toml()) == scene and scene.contact.friction is not None


def test_contact_csv_holds_the_friction_state(shared_tmp_path):
    """With friction contact.csv adds |t|, the step's slip, the accumulated slip and whether the
    node slipped: sliding, every node of the bottom slips with |t| = 𝔣 p, and the slips add up."""
    scene = write_shared(shared_tmp_path / "csv.toml", scene_text(
        "dragged", friction='friction = { type = "coulomb", coefficient = 0.3 }'))
    out = shared_tmp_path / "csv"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    lines = (out / "contact.csv").read_text().splitlines()
    header = lines[0].split(",")
    assert header[-4:] == ["tangential_traction", "slip_increment", "slip", "slipping"], header
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    col = {name: i for i, name in enumerate(header)}
    last = rows[np.isclose(rows[:, 0], 1.0)]
    inside = last[:, col["pressure"]] > 0
    assert inside.sum() >= 10 and np.all(last[inside, col["slipping"]] == 1)
    assert np.allclose(last[inside, col["tangential_traction"]],
                       0.3 * last[inside, col["pressure"]], rtol=1e-8)
    for x in np.unique(rows[:, 1]):  # the accumulated slip is the sum of the increments
        node = rows[rows[:, 1] == x]
        assert np.allclose(np.cumsum(node[:, col["slip_increment"]]), node[:, col["slip"]])


def _dragged_diagonally_3d(contact, **discretization):
    """A 3-D elastic block [0, 1]² × [0, 0.25] pressed by its top onto the plane z = 0 (``contact``
    on its bottom) over t ≤ 0.5, then dragged along e = (1, 2, 0)/√5; returns (problem, e)."""
    comm = MPI.COMM_WORLD
    msh = dmesh.create_box(comm, [np.zeros(3), np.array([1.0, 1.0, 0.25])], [4, 4, 2])
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[2], 0.25), 2: lambda x: np.isclose(x[2], 0.0)})
    e = np.array([1.0, 2.0]) / np.sqrt(5.0)

    def drag(i):
        return lambda x, t: np.full(x.shape[1], 0.02 * e[i] * max(t - 0.5, 0.0))

    def press(x, t):
        return np.full(x.shape[1], -0.002 * min(t / 0.5, 1.0))

    problem = QuasistaticProblem(
        msh, tags, Elastic(Elasticity("3d_standard", 1e3, 0.3)),
        dirichlet=[Dirichlet(1, (drag(0), drag(1), press), "top")], contact=contact,
        **discretization)
    return problem, e


def test_3d_block_dragged_diagonally_slides_against_the_drag():
    """3-D: the Coulomb cone is isotropic — a block dragged along (1, 2, 0)/√5 over the
    foundation z = 0 feels a tangential force 𝔣 × the normal one, along −(1, 2, 0)/√5."""
    problem, e = _dragged_diagonally_3d(
        NormalCompliance(2, mu=1e-3, friction=Friction("coulomb", coefficient=0.4)))
    errors = []
    for step in advance(problem, 1.0, StepControl(0.1)):
        if step.time >= 0.6 - 1e-9:
            _, force = problem.support_forces()
            tangential = force[:2]
            errors.append((abs(np.linalg.norm(tangential) / (0.4 * force[2]) - 1),
                           np.abs(tangential / np.linalg.norm(tangential) + e).max()))
            assert step.newton_iterations <= 6
    # The press left the traction turned outwards (Poisson); sliding turns it against the drag
    # geometrically (measured: its direction's error falls about 5-fold per step, 1.8e-3 to
    # 3e-6, and the magnitude's like its square, to 6e-11).
    errors = np.array(errors)
    assert np.all(np.diff(np.log(errors[:, 1])) < -1.3), errors
    assert np.all(np.diff(np.log(errors[:, 0])) < -2.6), errors
    assert errors[-1, 0] < 1e-9 and errors[-1, 1] < 1e-5, errors


def test_contact_csv_holds_a_signorini_part_s_friction(shared_tmp_path):
    text = _signorini_dragged(PLANE_FLOOR)
    scene = write_shared(shared_tmp_path / "sig.toml", text)
    out = shared_tmp_path / "sig"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    lines = (out / "contact.csv").read_text().splitlines()
    header = lines[0].split(",")
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    col = {name: i for i, name in enumerate(header)}
    last = rows[np.isclose(rows[:, 0], 1.0)]
    inside = last[:, col["pressure"]] > 1e-9
    assert inside.sum() >= 10 and np.all(last[inside, col["slipping"]] == 1)
    # nodal: |t| = 0.3 λ_i / A_i, λ_i / A_i the lumped pressure
    assert np.allclose(last[inside, col["tangential_traction"]],
                       0.3 * last[inside, col["pressure"]], rtol=1e-6)


@pytest.mark.parametrize("floor", ["rigid", "compliant"])
def test_reactions_split_each_part_s_force_into_normal_and_tangential(shared_tmp_path, floor):
    """With friction reactions.csv and summary.json add each contact part's normal force and
    the magnitude of its tangential force. On the flat floor they are the contact force's
    components (N = F_y, |T| = |F_x| to round-off), |T| = 𝔣 N while the block slides, and a
    run resumed from its last checkpoint writes the same file."""
    text = _dragged_on(floor).replace("figures = false\n",
                                      "figures = false\ncheckpoint_every = 4\n")
    scene = write_shared(shared_tmp_path / f"split_{floor}.toml", text)
    out = shared_tmp_path / f"split_{floor}"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    f = _forces(out)
    scale = np.abs(f["contact_y"]).max()
    assert np.allclose(f["bottom_normal"], f["contact_y"], rtol=0, atol=1e-12 * scale)
    assert np.allclose(f["bottom_tangential"], np.abs(f["contact_x"]), rtol=0,
                       atol=1e-12 * scale)
    sliding = f["t"] >= 0.7
    assert np.allclose(f["bottom_tangential"][sliding], 0.3 * f["bottom_normal"][sliding],
                       rtol=1e-6)
    part = json.loads((out / "summary.json").read_text())["reactions"]["contact_parts"]["bottom"]
    assert part["normal_force"]["final"] == pytest.approx(f["bottom_normal"][-1], rel=1e-9)
    assert np.allclose(part["tangential_force"]["history"], f["bottom_tangential"], rtol=1e-9)
    written = (out / "reactions.csv").read_bytes()
    assert cli.main(["run", str(scene), "--out", str(out), "--resume", "--quiet"]) == 0
    assert (out / "reactions.csv").read_bytes() == written


ROLLER_RADIUS, ROLLER_CENTRE = 20.0, np.array([0.5, -20.0, 0.0])


def _block_on_a_roller(friction, angle):
    """The block pressed by its top onto a roller (a circle of radius 20 under its middle) that
    turns about its own centre by ``angle(t)``: its surface slides under the block, its shape
    stays — the gaps do not change, only friction sees the rotation."""
    from vpcontact.model.obstacle import rotation_matrix
    comm = MPI.COMM_WORLD
    msh = dmesh.create_rectangle(comm, [np.zeros(2), np.array([1.0, 0.25])], [32, 4])
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[1], 0.25), 2: lambda x: np.isclose(x[1], 0.0)})
    centre = ROLLER_CENTRE[:2, None]
    roller = Signorini(2, obstacle=lambda x: np.linalg.norm(x[:2] - centre, axis=0) - ROLLER_RADIUS,
                       max_distance=1.0, friction=friction,
                       rotation=lambda t: rotation_matrix((0, 0, 1), angle(t)),
                       rotation_center=tuple(ROLLER_CENTRE))
    return QuasistaticProblem(
        msh, tags, PlaneStrain(Elastic(Elasticity("3d_standard", 1e3, 0.3))),
        dirichlet=[Dirichlet(1, (lambda x, t: np.zeros(x.shape[1]),
                                 lambda x, t: np.full(x.shape[1], -0.004 * min(t / 0.5, 1.0))),
                             "top")], contact=roller)


def _roller_motion(part):
    """The direction the roller's surface moves in for a positive turn, at the contact nodes:
    e_z × (x − c), normalised (N, 2)."""
    r = part.nodes.points[:, :2] - ROLLER_CENTRE[:2]
    along = np.column_stack([-r[:, 1], r[:, 0]])
    return along / np.linalg.norm(along, axis=1)[:, None]


@pytest.mark.parametrize("turn", [1.0, -1.0], ids=["anticlockwise", "clockwise"])
def test_a_turning_roller_drags_the_block_along_its_surface(turn):
    """A roller turning under a block held by its top drags the block's bottom along its
    surface: every node in contact slips with |f_i| = 𝔣 λ_i (1e-8), and f_i points along the
    roller's surface motion at the node, reversed when the roller turns the other way. (Before
    the rotation was subtracted from the slip, friction did not see the roller turn.)"""
    problem = _block_on_a_roller(Friction("coulomb", coefficient=0.3),
                                 lambda t: turn * 1e-3 * max(t - 0.5, 0.0))
    part = problem.contacts[0]
    for _ in advance(problem, 1.0, StepControl(0.1)):
        pass
    last, comm = part.friction.last, MPI.COMM_WORLD
    touching = last["lam"] > 0
    assert comm.allreduce(int(touching.sum())) >= 9
    assert np.all(last["slips"][touching])
    # the nodal force as a vector: its one tangential component along the frame's tangent
    tangent = part.friction.frame_tangents[touching][:, :2, 0]
    vector = last["force"][touching][:, :1] * tangent
    lam = last["lam"][touching]
    assert np.allclose(np.linalg.norm(vector, axis=1), 0.3 * lam, rtol=1e-8)
    along = np.einsum("ij,ij->i", vector, _roller_motion(part)[touching])
    assert np.all(turn * along > 0.999 * 0.3 * lam), (along, lam)


def test_a_block_stuck_on_a_turning_roller_moves_with_its_surface():
    """𝔣 = 10 and a small turn θ: the block's bottom sticks and is carried by the roller — each
    contact node's displacement since the pressing, along its frame's tangent, is that of the
    roller's point under it (y_i turned by θ about c, minus y_i; about R θ) up to the stick's
    micro-slip over the turn, |Δf_i|/k_i (measured: 1.3e-3 of R θ)."""
    theta = 2e-6  # R θ = 4e-5: the block shears, far below the friction limit
    problem = _block_on_a_roller(Friction("coulomb", coefficient=10.0),
                                 lambda t: theta * max(t - 0.5, 0.0) / 0.5)
    part = problem.contacts[0]
    rows = part.nodes.nodes[:, None] * 2 + np.arange(2)
    pressed = force = None
    for step in advance(problem, 1.0, StepControl(0.1)):
        if abs(step.time - 0.5) < 1e-9:
            pressed, force = problem.u.x.array[rows].copy(), part.friction.last["force"].copy()
    last = part.friction.last
    touching = last["lam"] > 0
    assert MPI.COMM_WORLD.allreduce(int(touching.sum())) >= 9
    assert not np.any(last["slips"][touching])
    tangent = part.friction.frame_tangents[touching][:, :2, 0]
    moved = problem.u.x.array[rows][touching] - pressed[touching]
    carried = np.einsum("ij,ij->i", moved, tangent)
    y = part.nodes.points[touching, :2] + pressed[touching] - ROLLER_CENTRE[:2]
    turned = y @ np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]]).T
    expected = np.einsum("ij,ij->i", turned - y, tangent)
    assert np.all(np.abs(expected) > 0.99 * ROLLER_RADIUS * theta)
    micro = (np.linalg.norm(last["force"][touching] - force[touching], axis=1)
             / part.friction.stiffness[touching])
    assert np.all(np.abs(carried - expected) <= 1.01 * micro + 1e-13), (carried, expected, micro)
    assert np.all(micro < 1e-2 * ROLLER_RADIUS * theta)


def test_friction_on_a_turning_obstacle_runs_from_a_scene(shared_tmp_path):
    """A scene with friction on a turning obstacle validates and runs (it used to be refused)."""
    text = _signorini_dragged(PLANE_FLOOR + 'rotation = { center = [0.5, -10], angle = "1e-4*t" }\n')
    scene = write_shared(shared_tmp_path / "turn.toml", text)
    assert cli.main(["validate", str(scene)]) == 0
    out = shared_tmp_path / "turn"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary


def test_a_floor_sliding_from_the_start_drags_the_block_it_is_pressed_onto():
    """The floor slides from t = 0 while the block is pressed onto it: at the first step every
    node touches with no normal force yet (a Coulomb bound 𝔣 λ of almost nothing), and Newton
    from the extrapolated guess cycled between slipping either way (50 iterations, every step
    cut to 2e-5: no run). Started sticking (``NodalFriction.predict``), it converges; once the
    block is pressed on, the floor drags it with 𝔣 × its normal force."""
    problem = _signorini_block(Friction("coulomb", coefficient=0.3),
                               floor_motion=lambda t: np.array([-0.02 * t, 0.0, 0.0]))
    for step in advance(problem, 1.0, StepControl(0.1)):
        assert step.newton_iterations <= 6, step  # (measured 3, 0, 0, …, 3, 0, …)
        if step.time >= 0.5 - 1e-9:
            _, force = problem.support_forces()
            assert -force[0] == pytest.approx(0.3 * force[1], rel=1e-8), force


def test_friction_on_a_deforming_obstacle_is_refused(shared_tmp_path, capsys):
    """An obstacle given as a level set of x and t has no material points for the body to slip
    against: refused with a located error, exit 2, nothing written."""
    text = _signorini_dragged('obstacle = "x[1] + 1e-3*t"\n')
    scene = write_shared(shared_tmp_path / "deform.toml", text)
    out = shared_tmp_path / "deform"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(r"deform\.toml:\d+: contact\.friction: .*deforming obstacle", err), err
    assert not out.exists()


@pytest.mark.parametrize("discretization", [{}, {"formulation": "mixed"}], ids=["P1", "mixed"])
def test_3d_block_dragged_diagonally_on_a_rigid_floor_slides_against_the_drag(discretization):
    """3-D on a rigid floor (Signorini, nodal friction with two tangential unknowns per node): a
    block dragged along (1, 2, 0)/√5 slides with every contact node slipping, and its tangential
    force tends to 𝔣 × the normal one along −(1, 2, 0)/√5 (below); at most 6 Newton iterations
    per step (measured 5, 0, 0, 0, 0, 5, 5, … with P1 and 6, 0, 0, 0, 0, 6, 6, … mixed)."""
    comm = MPI.COMM_WORLD
    floor = Signorini(2, obstacle=lambda x: x[2], max_distance=1.0,
                      friction=Friction("coulomb", coefficient=0.4))
    problem, e = _dragged_diagonally_3d(floor, **discretization)
    errors = []
    for step in advance(problem, 1.0, StepControl(0.1)):
        assert step.newton_iterations <= 6, step
        last = problem.contacts[0].friction.last
        touching = last["lam"] > 0
        if step.time > 0.5 + 1e-9 and comm.allreduce(bool(np.all(last["slips"][touching])),
                                                     op=MPI.LAND):
            _, force = problem.support_forces()
            tangential = force[:2]
            errors.append((abs(np.linalg.norm(tangential) / (0.4 * force[2]) - 1),
                           np.abs(tangential / np.linalg.norm(tangential) + e).max()))
    # Every node slips with |f_i| = 𝔣 λ_i along its own slip; the press left the directions
    # turned outwards (Poisson), and sliding turns them against the drag step by step
    # (measured: |T|/𝔣N − 1 from 1.5e-2 to 8e-5 over four steps, about 5-fold per step; the
    # direction within 7e-4 of −e throughout)
    errors = np.array(errors)
    assert len(errors) >= 3
    assert np.all(np.diff(np.log(errors[:, 0])) < -1.0), errors
    assert errors[-1, 0] < 2e-4 and np.all(errors[:, 1] < 1e-3), errors


@pytest.mark.parametrize("discretization", [{}, pytest.param({"formulation": "mixed", "degree": 2},
                                                              marks=pytest.mark.slow)],
                         ids=["P1", "mixed"])
def test_the_tresca_predictor_ends_at_the_coulomb_solution(discretization, monkeypatch):
    """The Tresca predictor (NodalFriction.freeze) is only a way to the step's solution: with no
    second try from the sticking guess, every step that needs Newton iterations goes through it
    (stick, fixed thresholds, Coulomb), and the 3-D diagonal drag ends where the usual path ends
    — forces and displacements equal to round-off (measured 2e−14 and 6e−13; P1 8 iterations in
    such steps against 5, mixed 9–28 against 6), with no step cut."""
    from vpcontact.model import nodal_friction

    def run():
        floor = Signorini(2, obstacle=lambda x: x[2], max_distance=1.0,
                          friction=Friction("coulomb", coefficient=0.4))
        problem, _ = _dragged_diagonally_3d(floor, **discretization)
        its = [step.newton_iterations for step in advance(problem, 1.0, StepControl(0.1))]
        _, force = problem.support_forces()
        return its, force, problem.u.x.array.copy()

    usual = run()
    predicted = _count_predictor_runs(monkeypatch)
    monkeypatch.setattr(nodal_friction, "SECOND_TRY", 0)
    through = run()
    assert len(predicted) >= 5 and len(through[0]) == 10, through[0]
    assert np.allclose(through[1], usual[1], rtol=0, atol=1e-9 * np.abs(usual[1]).max())
    assert np.allclose(through[2], usual[2], rtol=0, atol=1e-9 * np.abs(usual[2]).max())


def test_friction_in_1d_is_refused(shared_tmp_path, capsys):
    """A bar has no tangential direction: friction on its contact is a located error (it was
    accepted and ignored)."""
    from vpcontact.scene.files import bundled
    text = bundled()["normal_compliance_1d"].read_text().replace(
        "[contact]\n", '[contact]\nfriction = { type = "coulomb", coefficient = 0.3 }\n', 1)
    scene = write_shared(shared_tmp_path / "bar.toml", text)
    assert cli.main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(r"bar\.toml:\d+: contact\.friction: .*1-D", err), err


@pytest.mark.slow
def test_a_vi_step_stuck_at_round_off_is_accepted():
    """The scratch scene's indentation (40×10 cells, k = 0.025): SNES VI reached ||F|| = 3.1e-11
    where rtol ||F_0|| was 2.6e-11, and its steps, projected back onto the bounds, left the
    iterate where it was — the same ||F|| to the last bit for 47 iterations, then a cut step
    (twice to t = 0.2). The round-off stop now takes a residual repeated three times at round-off
    as converged: no step is cut, and every step takes at most 8 Newton iterations."""
    from vpcontact import scene as scenes
    from vpcontact.scene import build
    problem = build(scenes.load_bundled("scratch", (40, 10), 0.025)).problem
    steps = list(advance(problem, 0.2, StepControl(0.025, max_cuts=4)))
    assert len(steps) == 8, [s.time for s in steps]  # no step was cut
    assert max(s.newton_iterations for s in steps) <= 8, [s.newton_iterations for s in steps]
    assert problem.solver.total_iterations == sum(s.newton_iterations for s in steps)


def _cylinder_on_a_block(name, lower, upper, cells, box, motion, coefficient, time,
                         plane_strain=False) -> str:
    """An elastic block clamped at its bottom, a rigid cylinder (radius 0.5, centre (0, 0.5))
    moved by ``motion`` onto the part ``box`` of its top, Coulomb friction ``coefficient``;
    ``time`` holds the [time] entries (and any table after them)."""
    bottom = lower.strip("[]").split(",")[1].strip()
    plane = 'plane = "strain"\n' if plane_strain else 'plane = "stress"\n'
    return f"""
name = "{name}"
[mesh]
type = "rectangle"
lower = {lower}
upper = {upper}
cells = {cells}
[boundary.bottom]
kind = "clamped"
plane = {{ axis = "y", value = {bottom} }}
[boundary.top]
kind = "contact"
box = {{ lower = {box} }}
[material]
E = 1000.0
nu = 0.3
{plane}[law]
type = "elastic"
[contact]
type = "signorini"
boundary = "top"
obstacle = {{ shape = "cylinder", center = [0.0, 0.5], radius = 0.5 }}
motion = {motion}
friction = {{ type = "coulomb", coefficient = {coefficient} }}
[time]
{time}"""


def test_friction_on_a_part_that_some_processes_do_not_hold(shared_tmp_path):
    """A cylinder pressed onto a small contact part at the block's corner and moved along it,
    with Coulomb friction: on 2 ranks the part lies on one process only. The other one built its nodal
    friction's frames from no nodes with the wrong shape, raised in the first step's obstacle
    motion and left the first waiting in a collective call: the run hung. Serially it runs as
    before; on 2 ranks it must too, with a process that holds none of the part's nodes."""
    from vpcontact import scene as scenes
    from vpcontact.scene import build

    text = _cylinder_on_a_block("corner_friction", "[0.0, -1.0]", "[1.0, 0.0]", "[8, 8]",
                                "[0.0, 0.0], upper = [0.2, 0.0]", '["0.01*t", "-0.02*t"]',
                                0.3, "T = 0.2\nk = 0.05\n")
    path = write_shared(shared_tmp_path / "corner_friction.toml", text)
    problem = build(scenes.load(path)).problem
    held = len(problem.contacts[0].nodes.nodes)
    comm = MPI.COMM_WORLD
    if comm.size > 1:
        assert comm.allreduce(int(held == 0), op=MPI.SUM) >= 1, "a process must hold none"
    for _ in advance(problem, 0.2, StepControl(0.05)):
        pass
    force = problem.support_forces(per_part=True)[1][0]
    assert np.all(np.isfinite(force)) and abs(force[1]) > 0.0, force


def test_a_run_resumed_on_a_moving_obstacle_slips_from_where_it_stopped(shared_tmp_path):
    """A cylinder pressed into the block and then moved along it, 𝔣 = 1 (the nodes under it
    partly stick), checkpointed at t = 0.4: the run resumed there gives the uninterrupted
    run's forces and slips. The restored part had forgotten the time of its last step, and
    the first resumed step took the cylinder's whole motion since t = 0 as slip: the
    tangential force 44 % off at the end."""
    text = _cylinder_on_a_block(
        "moving_cylinder", "[-1.0, -0.5]", "[1.0, 0.0]", "[16, 4]",
        "[-0.95, 0.0], upper = [0.95, 0.0]", '["0.02*max(t - 0.2, 0)", "-0.01*min(t/0.2, 1)"]',
        1.0, "T = 0.6\nk = 0.05\n[output]\nxdmf = false\nfigures = false\ncheckpoint_every = 8\n",
        plane_strain=True)
    scene = write_shared(shared_tmp_path / "moving_cylinder.toml", text)
    out = shared_tmp_path / "moving_cylinder"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    reference = _forces(out)
    contact = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1)
    assert np.abs(reference["contact_x"][-1]) > 0.1 * np.abs(reference["contact_y"][-1])
    assert cli.main(["run", str(scene), "--out", str(out), "--resume", "--quiet"]) == 0
    resumed = _forces(out)
    assert json.loads((out / "summary.json").read_text())["resumed_from"]["time"] == \
        pytest.approx(0.4)
    for key in ("contact_x", "contact_y"):
        scale = np.abs(reference[key]).max()
        assert np.allclose(resumed[key], reference[key], rtol=0, atol=1e-9 * scale), key
    again = np.loadtxt(out / "contact.csv", delimiter=",", skiprows=1)
    assert np.allclose(again, contact, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("floor", ["rigid", "compliant"])
def test_the_dragged_block_on_quadrilaterals_slides_with_the_coulomb_ratio(shared_tmp_path,
                                                                            floor):
    """The dragged block meshed by quadrilaterals: the stick stiffness's facet size comes from
    the facet Jacobian there (FFCx has no FacetArea on them: the run stopped with an internal
    error), and while the block slides its tangential force is 0.3 × the normal one."""
    text = _dragged_on(floor).replace("cells = [16, 4]\n",
                                      'cells = [16, 4]\ncell_type = "quadrilateral"\n')
    scene = write_shared(shared_tmp_path / f"quads_{floor}.toml", text)
    out = shared_tmp_path / f"quads_{floor}"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    f = _forces(out)
    sliding = f["t"] >= 0.7
    ratio = -f["contact_x"][sliding] / f["contact_y"][sliding]
    assert np.allclose(ratio, 0.3, rtol=1e-8), ratio


def test_facet_sizes_on_quadrilaterals_and_hexahedra():
    """h_F from the facet Jacobian where FacetArea is missing: the edge's length, the square
    root of the face's area, on boxes of unequal spacing (∫ h_F over a face = area × h_F)."""
    from dolfinx import fem
    from vpcontact.model.nodal_areas import facet_size
    comm = MPI.COMM_WORLD
    square = dmesh.create_rectangle(comm, [np.zeros(2), np.array([2.0, 1.0])], [4, 5],
                                    dmesh.CellType.quadrilateral)
    cube = dmesh.create_box(comm, [np.zeros(3), np.array([2.0, 1.0, 1.0])], [4, 2, 5],
                            dmesh.CellType.hexahedron)
    # (faces: measure × facet size; spacings 0.5 × 0.2 and 0.5 × 0.5 × 0.2)
    for msh, expected in ((square, 2 * 2.0 * 0.5 + 2 * 1.0 * 0.2),
                          (cube, 2 * 1.0 * np.sqrt(0.5 * 0.2) + 2 * 2.0 * np.sqrt(0.5 * 0.2)
                           + 2 * 2.0 * np.sqrt(0.5 * 0.5))):
        value = comm.allreduce(fem.assemble_scalar(fem.form(facet_size(msh) * ufl.ds(domain=msh))),
                               op=MPI.SUM)
        assert value == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("formulation,degree", [("mixed", 2), ("displacement", 2)])
def test_the_paper_s_beam_on_a_compliant_foundation_with_tresca_friction_cuts_no_step(
        shared_tmp_path, formulation, degree):
    """The bundled 3-D beam (the paper's data: E = 1e8, μ = 1e-6) with Tresca friction on its
    compliant foundation, 6×2×2 cells, k = 0.02 to t = 0.2. With P2 displacements the sticking
    guess (the contact nodes back where the last step left them) starts 10–100 times above
    the extrapolation and Newton wandered from it for 50 iterations: 17 steps cut with the
    mixed formulation (24.5 s), 1 with P2. Now a first try still converging fast goes on, and
    a sticking try that gets below neither its start nor the first try's last ||F|| in 5
    iterations hands back to the first try's iterate: no step is cut."""
    from vpcontact import scene as scenes

    text = scenes.bundled()["normal_compliance_3d"].read_text()
    text = re.sub(r"(?m)^cells = .*$", "cells = [6, 2, 2]", text)
    text = re.sub(r"(?m)^T = .*$", "T = 0.2", text)
    text = re.sub(r"(?m)^k = .*$", "k = 0.02", text)
    text = text.replace("alpha = 1.0\n", 'alpha = 1.0\nfriction = { type = "tresca", threshold = 1e-3 }\n')
    text += (f'\n[discretization]\nformulation = "{formulation}"\ndegree = {degree}\n'
             "\n[output]\nxdmf = false\nfigures = false\n")
    scene = write_shared(shared_tmp_path / f"beam_tresca_{formulation}.toml", text)
    out = shared_tmp_path / f"beam_tresca_{formulation}"
    assert cli.main(["run", str(scene), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 10 and not summary["rejected_steps"], summary["rejected_steps"]
    assert sum(summary["newton_iterations"]) <= 110, summary["newton_iterations"]
