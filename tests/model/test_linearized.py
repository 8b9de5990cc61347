# SPDX-License-Identifier: MIT
"""The linearized (linearly implicit Euler) scheme: G linearised at the start of each step.

Each step of a body is then one linear problem (with contact, one bound-constrained one): checked
here at the kernel level (the update against its definition, the implicit step and closed forms)
and on the paper's tests (convergence in k, Newton iterations, the scene key)."""

import json
import math
import re

import numpy as np
import pytest
from mpi4py import MPI

from vpcontact import cli, kernels
from vpcontact.errors import InputError
from vpcontact.model import Elasticity, LinearRate, Perzyna
from vpcontact.scene import build, loads_text
from vpcontact.solver import StepControl, advance
from tests.support import flowing_beam
from tests.support.mpi_launch import write_shared
from tests.support.scenes import scene_text

E, NU, SY, MU = 100.0, 0.3, 1.0, 1.0


def _random_step(n, points=40, seed=0, scale=5.0):
    rng = np.random.default_rng(seed)
    so = rng.normal(size=(points, n)) * scale
    eo = rng.normal(size=(points, n)) * 1e-3
    en = eo + rng.normal(size=(points, n)) * 1e-3
    return so, eo, en


@pytest.mark.parametrize("model", ["1d", "plane_stress", "3d"])
def test_linearized_is_the_implicit_step_for_a_linear_law(model):
    n = kernels.mandel_size(model)
    so, eo, en = _random_step(n)
    si, ti = kernels.stress_update_linear_mandel(so, eo, en, dt=0.1, E=E, nu=NU, a=-1.0, b=10.0,
                                                 model=model, scheme="implicit")
    sl, tl = kernels.stress_update_linear_mandel(so, eo, en, dt=0.1, E=E, nu=NU, a=-1.0, b=10.0,
                                                 model=model, scheme="linearized")
    assert np.abs(sl - si).max() <= 1e-13 * np.abs(si).max()
    assert np.abs(tl - ti).max() <= 1e-13 * np.abs(ti).max()


@pytest.mark.parametrize("model", ["1d", "plane_stress", "3d", "3d_standard"])
def test_perzyna_linearized_step_is_its_definition(model):
    """σ_n − σ_{n−1} solves (I − k G'(σ_{n−1}))Δσ = E Δε + k G(σ_{n−1}); the tangent is the
    (exact) derivative of that affine map; points of K take the elastic step."""
    n = kernels.mandel_size(model)
    so, eo, en = _random_step(n)
    so[:5] *= 1e-4  # inside K
    dt = 0.01
    s, t = kernels.stress_update_mandel(so, eo, en, dt=dt, E=E, nu=NU, sigma_y=SY, mu_star=MU,
                                        model=model, scheme="linearized")
    C = kernels.elasticity_matrix(model, E=E, nu=NU)
    assert np.allclose(s[:5], so[:5] + (en[:5] - eo[:5]) @ C.T, rtol=0, atol=1e-14)
    assert np.array_equal(t[:5], np.broadcast_to(C, (5, n, n)))
    # The definition, with G and G' by differences of the explicit step (which adds k G(σ_{n−1})).
    def g(sigma):
        zero = np.zeros_like(sigma)
        out, _ = kernels.stress_update_mandel(sigma, zero, zero, dt=1.0, E=E, nu=NU, sigma_y=SY,
                                              mu_star=MU, model=model, scheme="explicit")
        return out - sigma

    h = 1e-6
    for p in range(5, so.shape[0], 7):
        J = np.column_stack([(g(so[[p]] + h * e) - g(so[[p]] - h * e))[0] / (2 * h)
                             for e in np.eye(n)])
        lhs = (np.eye(n) - dt * J) @ (s[p] - so[p])
        rhs = C @ (en[p] - eo[p]) + dt * g(so[[p]])[0]
        assert np.allclose(lhs, rhs, rtol=1e-6, atol=1e-6 * np.abs(rhs).max())
        # affine in ε_n: the tangent maps a strain change exactly
        d = 1e-3 * np.arange(1, n + 1)
        s2, _ = kernels.stress_update_mandel(so[[p]], eo[[p]], en[[p]] + d, dt=dt, E=E, nu=NU,
                                             sigma_y=SY, mu_star=MU, model=model,
                                             scheme="linearized")
        assert np.allclose(s2[0] - s[p], t[p] @ d, rtol=1e-10, atol=1e-12)


def test_perzyna_linearized_step_is_third_order_close_to_the_implicit_one():
    """Where G is smooth (points flowing in the whole step) the two steps differ by
    k G'' Δσ² = O(k³), below either scheme's own local error O(k²)."""
    so, eo, en = _random_step(6)
    rate = (en - eo) / 1e-3
    dts = np.array([1e-3, 5e-4, 2.5e-4, 1.25e-4])  # k E/μ* from 0.1 down
    gaps = []
    for dt in dts:
        en = eo + rate * dt
        si, _ = kernels.stress_update_mandel(so, eo, en, dt=dt, E=E, nu=NU, sigma_y=SY,
                                             mu_star=MU, model="3d", scheme="implicit")
        sl, _ = kernels.stress_update_mandel(so, eo, en, dt=dt, E=E, nu=NU, sigma_y=SY,
                                             mu_star=MU, model="3d", scheme="linearized")
        gaps.append(np.abs(sl - si).max())
    slope = np.polyfit(np.log(dts), np.log(gaps), 1)[0]
    assert 2.7 < slope < 3.3


def _shear_history(scheme, k, T, rate=1.0):
    """A homogeneous 3-D point sheared at a constant rate (von Mises, 2G = E/(1 + ν)): τ = 2G γ̇ t
    until √3 τ = σ_Y, then τ = τ_Y + μ* γ̇ (1 − exp(−2G (t − t_y)/μ*)) (γ̇ = ε̇12)."""
    sigma = np.zeros((1, 6))
    for i in range(round(T / k)):
        eps_old, eps_new = np.zeros((1, 6)), np.zeros((1, 6))
        eps_old[0, 5] = math.sqrt(2) * rate * i * k  # Mandel: √2 ε12
        eps_new[0, 5] = math.sqrt(2) * rate * (i + 1) * k
        sigma, _ = kernels.stress_update_mandel(sigma, eps_old, eps_new, dt=k, E=E, nu=NU,
                                                sigma_y=SY, mu_star=MU, model="3d_standard",
                                                scheme=scheme, tangent=False)
    return sigma[0, 5] / math.sqrt(2)


def test_linearized_converges_at_rate_one_to_the_closed_form_of_a_sheared_point():
    two_g, rate, T = E / (1 + NU), 1.0, 0.05
    tau_y = SY / math.sqrt(3)
    t_y = tau_y / (two_g * rate)
    exact = tau_y + MU * rate * (1 - math.exp(-two_g * (T - t_y) / MU))
    ks = T / np.array([20, 40, 80, 160, 320])
    errors = {s: [abs(_shear_history(s, k, T) - exact) for k in ks]
              for s in ("implicit", "linearized")}
    for scheme, errs in errors.items():
        slope = np.polyfit(np.log(ks), np.log(errs), 1)[0]
        assert 0.85 < slope < 1.2, (scheme, errs)
    # the same order, and a constant within a small factor of the implicit scheme's
    assert max(l / i for l, i in zip(errors["linearized"], errors["implicit"])) < 3.0


def test_linearized_step_stays_bounded_at_huge_contrast():
    """k E/μ* from 1 to 10⁸: the overstress is damped (not amplified) in every step."""
    so, eo, _ = _random_step(6, scale=50.0)
    for contrast in (1.0, 1e2, 1e4, 1e8):
        dt = contrast * MU / E
        s, _ = kernels.stress_update_mandel(so, eo, eo, dt=dt, E=E, nu=NU, sigma_y=SY,
                                            mu_star=MU, model="3d", scheme="linearized")
        over_old = np.linalg.norm(
            so - kernels.project_mandel(so, E=E, nu=NU, sigma_y=SY, model="3d"), axis=1)
        over_new = np.linalg.norm(
            s - kernels.project_mandel(s, E=E, nu=NU, sigma_y=SY, model="3d"), axis=1)
        assert np.all(over_new <= over_old / (1 + 0.5 * contrast) + 1e-12 * np.abs(so).max())
        assert np.all(np.isfinite(s))


def test_law_properties():
    law = Perzyna(Elasticity("3d", 1e8, 0.3), 1.0, 200.0, scheme="linearized")
    assert law.linear_in_strain and not law.constant_tangent
    assert law.explicit_step_limit() == math.inf
    assert not Perzyna(Elasticity("3d", 1e8, 0.3), 1.0, 200.0).linear_in_strain
    assert Perzyna(Elasticity("3d", 1e8, 0.3), 1.0, 200.0, scheme="explicit").constant_tangent
    assert LinearRate(Elasticity("1d", 10.0), -1.0, 10.0, scheme="linearized").constant_tangent
    assert LinearRate(Elasticity("1d", 10.0), -30.0, 10.0,
                      scheme="linearized").explicit_step_limit() == math.inf
    with pytest.raises(InputError, match="unknown time scheme"):
        Perzyna(Elasticity("3d", 1e8, 0.3), 1.0, 200.0, scheme="rosenbrock")


def test_a_scene_runs_with_the_linearized_scheme_and_show_writes_it_back(shared_tmp_path):
    scene = loads_text(scene_text("plate", time=""))
    assert scene.law.scheme == "linearized"
    assert loads_text(scene.to_toml()) == scene
    path = write_shared(shared_tmp_path / "plate.toml", scene_text("plate", time=""))
    out = shared_tmp_path / "plate"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] and not summary["rejected_steps"]
    assert max(summary["newton_iterations"]) <= 6, summary["newton_iterations"]


def test_a_large_linearized_step_is_one_newton_iteration():
    """The bundled cantilever with Perzyna's law (σ_Y far above its stresses) integrated by the
    linearized scheme, its end load ×100: each step is one linear problem, solved in one
    Newton iteration, and the deflection (1.6 % of the length) is the elastic law's. bt, the
    scheme's line search, used to cut every Newton step longer than 1e-4 of the extent (PETSc's
    maxstep, 1e8 in SNES's scaled unknowns): 50 iterations and DIVERGED_MAX_IT."""
    from vpcontact import scene as scenes

    text = scenes.bundled()["elastic_2d"].read_text()
    text = re.sub(r'(?m)^traction = .*$', 'traction = [0.0, "-100*t"]', text)
    elastic = build(loads_text(text)).problem
    viscoplastic = build(loads_text(text.replace('type = "elastic"', (
        'type = "perzyna"\nsigma_y = 1e4\nmu_star = 1.0\nscheme = "linearized"'))))
    problem = viscoplastic.problem
    reports = list(advance(problem, 1.0, StepControl(0.25)))
    list(advance(elastic, 1.0, StepControl(0.25)))
    assert [r.newton_iterations for r in reports] == [1, 1, 1, 1]
    deflection = MPI.COMM_WORLD.allreduce(float(np.abs(elastic.u.x.array).max(initial=0.0)),
                                          op=MPI.MAX)
    assert deflection > 1e-2 * 4.0
    assert np.abs(problem.u.x.array - elastic.u.x.array).max() <= 1e-8 * deflection


def test_bdf2_refuses_the_linearized_scheme(shared_tmp_path, capsys):
    path = write_shared(shared_tmp_path / "bdf.toml", scene_text("plate", time='scheme = "bdf2"'))
    assert cli.main(["run", str(path), "--out", str(shared_tmp_path / "bdf"), "--quiet"]) == 2
    err = capsys.readouterr().err
    if MPI.COMM_WORLD.rank == 0:
        assert re.search(r"time\.scheme.*needs an implicit law", err), err
    assert not (shared_tmp_path / "bdf" / "summary.json").exists()


def _plate_problem(scheme, T):
    """The problem of the plate (tests/scenes/plate.toml: plane strain, mixed formulation,
    pressed onto a rigid floor while it flows) with the given law scheme and final time."""
    text = scene_text("plate", time="").replace('scheme = "linearized"', f'scheme = "{scheme}"')
    return build(loads_text(text.replace("T = 0.2", f"T = {T}"))).problem


def _plate(scheme, k, T=0.5):
    """The plate run to T with steps k (cut where SNES fails): (u, Newton iterations, steps)."""
    problem = _plate_problem(scheme, T)
    steps = len(list(advance(problem, T, StepControl(k))))
    return problem.u, problem.solver.total_iterations, steps


@pytest.mark.slow
def test_linearized_and_implicit_plates_converge_together_and_linearized_is_cheaper():
    """Both Euler schemes are first order; their difference falls as k → 0 (measured 4.1 %,
    1.4 %, 0.71 %, 0.11 % of max |u|), and the linearized one takes 2–3× fewer Newton
    iterations in all (cut steps included: 114 against 295 at k = 0.05)."""
    comm = MPI.COMM_WORLD
    ks = 0.5 / np.array([10, 20, 40, 80])
    gaps = []
    for k in ks:
        ui, its_i, _ = _plate("implicit", k)
        ul, its_l, _ = _plate("linearized", k)
        diff = comm.allreduce(float(np.abs(ui.x.array - ul.x.array).max()), op=MPI.MAX)
        size = comm.allreduce(float(np.abs(ui.x.array).max()), op=MPI.MAX)
        gaps.append(diff / size)
        assert its_l <= 0.6 * its_i, (k, its_l, its_i)
    slope = np.polyfit(np.log(ks), np.log(gaps), 1)[0]
    assert slope > 0.8, gaps
    assert gaps[-1] < 5e-3, gaps


@pytest.mark.slow
def test_the_jacobian_is_assembled_once_per_step_and_changes_nothing():
    """The linearized step's Jacobian is constant within the step: assembled once per step (and
    its factors or preconditioner kept), with the answers of assembling it at every iteration."""
    runs = []
    for per_step in (True, False):
        problem = _plate_problem("linearized", 0.3)
        assert problem.solver.jacobian_per_step
        problem.solver.jacobian_per_step = per_step
        reports = list(advance(problem, 0.3, StepControl(0.03)))
        runs.append((problem.u.x.array.copy(), problem.solver.jacobian_assemblies,
                     problem.solver.total_iterations, len(reports)))
    (u1, assemblies1, its1, steps1), (u2, assemblies2, its2, steps2) = runs
    # (the kept factors solve the VI's reduced systems by GMRES to 1e-9: the same path up to
    # an iteration)
    assert steps1 == steps2 and abs(its1 - its2) <= 2, (its1, its2)
    # once per attempted step (cut ones too: 28 for 19 steps) against once per iteration (80)
    assert its2 <= assemblies2 and assemblies1 < 0.5 * assemblies2, (assemblies1, assemblies2)
    comm = MPI.COMM_WORLD
    diff = comm.allreduce(float(np.abs(u1 - u2).max()), op=MPI.MAX)
    assert diff <= 1e-7 * comm.allreduce(float(np.abs(u2).max()), op=MPI.MAX)


@pytest.mark.slow
def test_the_implicit_plate_recovers_from_a_diverged_large_step():
    """At k = T/5 the implicit plate's step from t = 0.15 diverges (k E/μ* = 5e4) and is cut;
    the cut steps must then converge, and the run end near a fine-step one. They did not: MUMPS
    had run out of the work arrays its analysis sized (INFOG(1) = −9, more delayed pivots in
    the flowing saddle point than foreseen), and every later refactorization reusing that
    analysis failed too, giving each cut step an infinite Newton direction (DIVERGED_LINE_SEARCH
    at t = 0.150024). The lagged direct solver now redoes the analysis with more room."""
    u, _, steps = _plate("implicit", 0.1)
    assert steps > 5, "the large steps should have been cut"
    fine, _, _ = _plate("implicit", 0.0125)
    comm = MPI.COMM_WORLD
    diff = comm.allreduce(float(np.abs(u.x.array - fine.x.array).max()), op=MPI.MAX)
    size = comm.allreduce(float(np.abs(fine.x.array).max()), op=MPI.MAX)
    assert diff <= 0.03 * size, diff / size  # (measured 1.1 %: the last steps were cut to 1/8)


def test_step_rtol_aims_at_the_step_target():
    """A fixed-Jacobian step's Krylov tolerance: loose at the first Newton iteration, then what
    takes ||F|| below SNES's target, within [STEP_RTOL_FLOOR, ITERATIVE_RTOL]."""
    from vpcontact.solver import linear

    assert linear.step_rtol(0, 1.0, 1e-10) == linear.STEP_FIRST_RTOL
    assert linear.step_rtol(1, 1e-3, 1e-10) == pytest.approx(linear.STEP_RTOL_SAFETY * 1e-7)
    assert linear.step_rtol(1, 1.0, 1e-30) == linear.STEP_RTOL_FLOOR
    assert linear.step_rtol(2, 1e-9, 1e-10) == linear.ITERATIVE_RTOL  # never looser than that


def _flowing_beam(linear: str, krylov_iterations: int | None = None):
    """The tests' flowing beam (:mod:`flowing_beam`): (problem, Newton iterations per step)."""
    problem, reports = flowing_beam.run(linear, krylov_iterations=krylov_iterations)
    return problem, [r.newton_iterations for r in reports]


def _assert_same_answers(problem, reference):
    comm = MPI.COMM_WORLD
    diff = comm.allreduce(float(np.abs(problem.u.x.array - reference.u.x.array).max()),
                          op=MPI.MAX)
    size = comm.allreduce(float(np.abs(reference.u.x.array).max()), op=MPI.MAX)
    assert diff <= 1e-7 * size, diff / size


def test_aimed_krylov_solves_save_newton_iterations_and_keep_the_answers(monkeypatch):
    """With the block preconditioner inside SNES VI, the linearized step's Krylov solves are
    aimed (vpcontact.solver.linear.step_rtol): the direct solver's answers, in fewer Newton
    iterations (and multigrid set-ups) than with every solve at ITERATIVE_RTOL."""
    from vpcontact.solver import linear

    direct, _ = _flowing_beam("direct")
    aimed, aimed_its = _flowing_beam("iterative")
    assert aimed.solver.test.aimed
    _assert_same_answers(aimed, direct)
    monkeypatch.setattr(linear, "step_rtol", lambda it, fnorm, target: linear.ITERATIVE_RTOL)
    fixed, fixed_its = _flowing_beam("iterative")
    _assert_same_answers(fixed, direct)
    assert len(aimed_its) == len(fixed_its)
    assert sum(aimed_its) < sum(fixed_its), (aimed_its, fixed_its)
    setups = aimed.solver.lagged_lu.counters()["multigrid_setups"]
    assert setups < fixed.solver.lagged_lu.counters()["multigrid_setups"]


def test_a_solve_aimed_beyond_reach_is_accepted_within_the_newton_tolerance(monkeypatch):
    """A solve asked for more than the Krylov method reaches in its iterations stops short; within
    ITERATIVE_RTOL it is still a Newton direction and is accepted (the steps converge to the
    direct solver's answers), not a failed linear solve that cuts the step."""
    from vpcontact.solver import linear, vi_linear

    monkeypatch.setattr(linear, "STEP_RTOL_FLOOR", 1e-30)
    monkeypatch.setattr(linear, "STEP_RTOL_SAFETY", 1e-20)  # beyond any solve's reach
    accepted = []
    close_enough = vi_linear.LaggedMultigrid._close_enough

    def recording(self, b):
        ok = close_enough(self, b)
        accepted.append(ok)
        return ok

    monkeypatch.setattr(vi_linear.LaggedMultigrid, "_close_enough", recording)
    direct, direct_its = _flowing_beam("direct")
    aimed, aimed_its = _flowing_beam("iterative", krylov_iterations=40)
    assert any(accepted), "no solve stopped short of its tolerance"
    assert len(aimed_its) == len(direct_its)  # no step cut
    _assert_same_answers(aimed, direct)


def test_solves_that_stop_at_the_probe_still_reach_the_answers(monkeypatch):
    """An aimed solve is probed at STEP_FIRST_RTOL and ends there when its direction takes an
    inactive entry across its bound. Made to end there every time, the steps still converge to
    the direct solver's answers (the loose directions cost Newton iterations, not accuracy)."""
    from vpcontact.solver import vi_linear

    monkeypatch.setattr(vi_linear.LaggedMultigrid, "_crosses_bounds", lambda self, y: True)
    direct, direct_its = _flowing_beam("direct")
    probed, probed_its = _flowing_beam("iterative")
    assert probed.solver.lagged_lu.counters()["probe_stops"] > 0
    assert len(probed_its) == len(direct_its)
    _assert_same_answers(probed, direct)
