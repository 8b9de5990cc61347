# SPDX-License-Identifier: MIT
"""Tests of the constitutive kernels (vpcontact.kernels and the C++ module behind it).

Every kernel is checked against an independent formulation: the printed formulas of the
paper (Sec. 4) evaluated on full tensors in numpy, a bisection for the projection's
multiplier in non-orthonormal Voigt coordinates, the variational inequality and the
KKT conditions of the projection, central finite differences for the tangents, the
discrete equations each scheme must satisfy, and the exact solution of the paper's 1-D
law. The tests are serial (no MPI) and rank-independent.
"""

from __future__ import annotations

import math
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from vpcontact import _cpp
from vpcontact import kernels as K

MODELS = K.MODELS
#: The paper's 2-D/3-D data (Sec. 4.1): E, nu, sigma_Y, mu*.
PAPER = {"E": 1e8, "nu": 0.3, "sigma_y": math.sqrt(10.0)}
MU_STAR = 200.0
EPS = np.finfo(float).eps


# --- independent reference formulas (printed in the paper) ----------------------------


def printed_yield(t: np.ndarray, model: str) -> np.ndarray:
    """Left side of the yield condition, from the printed component formulas."""
    if model == "1d":
        return t[:, 0, 0] ** 2
    if model == "plane_stress":
        a, b, c = t[:, 0, 0], t[:, 1, 1], t[:, 0, 1]
        return a**2 + b**2 - a * b + 3 * c**2
    a, b, c = t[:, 0, 0], t[:, 1, 1], t[:, 2, 2]
    normal = (a - b) ** 2 + (b - c) ** 2 + (c - a) ** 2
    shear = t[:, 0, 1] ** 2 + t[:, 0, 2] ** 2 + t[:, 1, 2] ** 2
    if model == "3d":
        return normal + 6 * shear
    return 0.5 * normal + 3 * shear


def printed_elasticity(t: np.ndarray, model: str, E: float, nu: float) -> np.ndarray:
    """E applied to tensors, from the printed formulas."""
    d = t.shape[-1]
    eye = np.eye(d)
    trace = np.trace(t, axis1=-2, axis2=-1)[..., None, None]
    if model == "1d":
        return E * t
    if model == "plane_stress":
        return E * nu / (1 - nu**2) * trace * eye + E / (1 + nu) * t
    return E * nu / ((1 + nu) * (1 - 2 * nu)) * trace * eye + E / (1 + nu) * t


def energy(a: np.ndarray, b: np.ndarray, model: str, E: float, nu: float) -> np.ndarray:
    """(E a, b) per point."""
    return np.einsum("nij,nij->n", printed_elasticity(a, model, E, nu), b)


def random_symmetric(rng, num: int, d: int, scale: float = 1.0) -> np.ndarray:
    a = rng.normal(size=(num, d, d))
    return scale * 0.5 * (a + a.transpose(0, 2, 1))


def outside(rng, num: int, model: str, sigma_y: float, factor=(1.5, 6.0)) -> np.ndarray:
    """Random stresses with yield value factor^2 sigma_Y^2 (outside K)."""
    d = K.dimension(model)
    t = random_symmetric(rng, num, d)
    f = printed_yield(t, model)
    scale = rng.uniform(*factor, size=num) * sigma_y / np.sqrt(f)
    return t * scale[:, None, None]


def inside(rng, num: int, model: str, sigma_y: float) -> np.ndarray:
    """Random stresses strictly inside K (with a large volumetric part in 3-D)."""
    d = K.dimension(model)
    t = random_symmetric(rng, num, d)
    f = printed_yield(t, model)
    scale = rng.uniform(0.0, 0.999, size=num) * sigma_y / np.sqrt(f)
    t = t * scale[:, None, None]
    if model.startswith("3d"):
        t += rng.normal(size=num)[:, None, None] * 10 * sigma_y * np.eye(3)
    return t


def strain_for_stress(sigma: np.ndarray, model: str, E: float, nu: float) -> np.ndarray:
    """E^{-1} sigma via the Mandel matrix (so sigma_old = 0, eps_old = 0 gives sigma^tr)."""
    C = K.elasticity_matrix(model, E, nu)
    m = K.to_mandel(sigma)
    return K.from_mandel(np.linalg.solve(C, m.T).T, K.dimension(model))


def relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


# --- sizes, Mandel conversions, elasticity and yield matrices ---------------------------


@pytest.mark.parametrize("model", MODELS)
def test_sizes(model):
    d = K.dimension(model)
    assert d == {"1d": 1, "plane_stress": 2, "3d": 3, "3d_standard": 3}[model]
    assert K.mandel_size(model) == d * (d + 1) // 2
    assert _cpp.dimension(model) == d and _cpp.mandel_size(model) == K.mandel_size(model)


@pytest.mark.parametrize("d", [1, 2, 3])
def test_mandel_round_trip_and_isometry(d):
    rng = np.random.default_rng(10 + d)
    t = random_symmetric(rng, 50, d)
    m = K.to_mandel(t)
    assert m.shape == (50, d * (d + 1) // 2)
    np.testing.assert_allclose(K.from_mandel(m, d), t, rtol=0, atol=4 * EPS)
    np.testing.assert_allclose(K.to_mandel(K.from_mandel(m, d)), m, rtol=0, atol=4 * EPS)
    s = random_symmetric(rng, 50, d)
    np.testing.assert_allclose(
        np.einsum("na,na->n", m, K.to_mandel(s)), np.einsum("nij,nij->n", t, s), atol=1e-13
    )
    if d == 3:  # the documented layout
        np.testing.assert_allclose(
            m[:, 3:], math.sqrt(2) * np.stack([t[:, 1, 2], t[:, 0, 2], t[:, 0, 1]], axis=1)
        )


@pytest.mark.parametrize("model", MODELS)
def test_elasticity_matrix_matches_printed_formula(model):
    rng = np.random.default_rng(1)
    d = K.dimension(model)
    C = K.elasticity_matrix(model, 2.5e3, 0.27)
    np.testing.assert_allclose(C, C.T, rtol=0, atol=1e-12 * np.abs(C).max())
    assert np.all(np.linalg.eigvalsh(C) > 0)
    t = random_symmetric(rng, 20, d)
    expected = printed_elasticity(t, model, 2.5e3, 0.27)
    got = K.from_mandel(K.to_mandel(t) @ C.T, d)
    np.testing.assert_allclose(got, expected, rtol=1e-13, atol=1e-13 * np.abs(expected).max())
    # Tensor form of the same matrix: T : t = E t, with both minor symmetries.
    T = K.tangent_from_mandel(np.broadcast_to(C, (20,) + C.shape), d)
    np.testing.assert_allclose(T, T.transpose(0, 2, 1, 3, 4), atol=0)
    np.testing.assert_allclose(T, T.transpose(0, 1, 2, 4, 3), atol=0)
    np.testing.assert_allclose(
        np.einsum("nijkl,nkl->nij", T, t), expected, atol=1e-12 * np.abs(expected).max()
    )


@pytest.mark.parametrize("model", MODELS)
def test_yield_function_matches_printed_formula(model):
    rng = np.random.default_rng(2)
    t = random_symmetric(rng, 30, K.dimension(model), scale=3.0)
    np.testing.assert_allclose(
        K.yield_function(t, model=model), printed_yield(t, model), rtol=1e-13
    )


def test_printed_3d_set_is_twice_the_standard_one():
    rng = np.random.default_rng(3)
    t = random_symmetric(rng, 10, 3)
    np.testing.assert_allclose(
        K.yield_function(t, model="3d"), 2 * K.yield_function(t, model="3d_standard"), rtol=1e-14
    )
    # Uniaxial stress s e1 (x) e1: printed 2 s^2, standard s^2.
    u = np.zeros((1, 3, 3))
    u[0, 0, 0] = 1.0
    assert K.yield_function(u, model="3d")[0] == pytest.approx(2.0)
    assert K.yield_function(u, model="3d_standard")[0] == pytest.approx(1.0)


# --- projection ---------------------------------------------------------------------------


@pytest.mark.parametrize("model", MODELS)
def test_points_inside_are_unchanged(model):
    rng = np.random.default_rng(4)
    t = inside(rng, 200, model, PAPER["sigma_y"])
    m = K.to_mandel(t)
    p = K.project_mandel(m, model=model, **PAPER)
    assert np.array_equal(p, m), "Mandel projection must return points of K bit for bit"
    np.testing.assert_allclose(
        K.project(t, model=model, **PAPER), t, rtol=0, atol=4 * EPS * np.abs(t).max()
    )


@pytest.mark.parametrize("model", MODELS)
def test_projection_lands_on_boundary_and_is_idempotent(model):
    rng = np.random.default_rng(5)
    sy = PAPER["sigma_y"]
    t = outside(rng, 500, model, sy)
    p = K.project(t, model=model, **PAPER)
    f = printed_yield(p, model) / sy**2
    assert np.max(np.abs(f - 1.0)) <= 1e-12, f"|f(P sigma)/sigma_Y^2 - 1| = {np.max(np.abs(f - 1))}"
    # Inside K up to rounding of the tensor-coordinate evaluation (relative to |P sigma|/sigma_Y).
    size = np.abs(p).max(axis=(1, 2)) / sy
    assert np.all(f <= 1.0 + 1e-14 * np.maximum(1.0, size))
    pp = K.project(p, model=model, **PAPER)
    np.testing.assert_allclose(pp, p, rtol=0, atol=1e-14 * np.abs(p).max())


@pytest.mark.parametrize("sigma_y", [1e-150, 1e-140, math.sqrt(10.0), 1e150, 1e300])
@pytest.mark.parametrize("model", MODELS)
def test_projection_across_the_fast_inside_test(model, sigma_y):
    """Points of K are first tested without the scaled split (tau . Y tau <= (1 - 16 eps)
    sigma_Y^2 when sigma_Y^2 is a normal number); points in the layer around that bound and
    around the boundary, at any magnitude of sigma_Y, still come back unchanged when inside,
    land on the boundary when outside, and project to themselves afterwards (bit for bit)."""
    rng = np.random.default_rng(7)
    data = dict(E=PAPER["E"], nu=PAPER["nu"], sigma_y=sigma_y)
    direction = K.to_mandel(random_symmetric(rng, 400, K.dimension(model)))
    unit = direction / np.sqrt(K.yield_function(K.from_mandel(direction, K.dimension(model)),
                                                model=model))[:, None]
    ulps = rng.integers(-80, 80, size=400)  # yield value within ~80 eps of sigma_Y^2
    m = np.ascontiguousarray(unit * sigma_y * (1.0 + ulps * EPS / 2)[:, None])
    scale = 2.0 ** math.frexp(sigma_y)[1]  # exact rescaling: sigma_Y^2 may overflow

    def yield_ratio(x):
        return K.yield_function(K.from_mandel(x / scale, K.dimension(model)),
                                model=model) / (sigma_y / scale) ** 2

    f = yield_ratio(m)
    p = K.project_mandel(m, model=model, **data)
    inside_k = f <= 1.0 - 4 * EPS * K.mandel_size(model)  # inside whatever the evaluation order
    assert inside_k.sum() > 50 and (~inside_k).sum() > 50
    assert np.array_equal(p[inside_k], m[inside_k])
    fp = yield_ratio(p)
    assert np.all(fp <= 1.0 + 1e-14) and np.all(fp >= 1.0 - 1e-13)
    assert np.array_equal(K.project_mandel(p, model=model, **data), p)


@pytest.mark.parametrize("model", MODELS)
def test_projection_variational_inequality(model):
    """(E(sigma - P sigma), tau - P sigma) <= 0 for every tau in K."""
    rng = np.random.default_rng(6)
    E, nu, sy = PAPER["E"], PAPER["nu"], PAPER["sigma_y"]
    sigma = outside(rng, 40, model, sy)
    p = K.project(sigma, model=model, **PAPER)
    for i in range(sigma.shape[0]):
        tau = np.concatenate([inside(rng, 500, model, sy), outside(rng, 500, model, sy, (1, 1))])
        tau = np.concatenate([tau, p[i] + 1e-3 * (tau[:100] - p[i])])  # near P sigma
        tau = tau[printed_yield(tau, model) <= sy**2]
        diff = np.broadcast_to(sigma[i] - p[i], tau.shape)
        value = energy(diff, tau - p[i], model, E, nu)
        # Relative tolerance, plus the rounding of P sigma itself (|E diff| eps |P sigma|).
        Ediff = printed_elasticity(diff[:1], model, E, nu)
        rounding = 1e-14 * np.linalg.norm(Ediff) * np.linalg.norm(p[i])
        bound = 1e-10 * np.sqrt(energy(diff, diff, model, E, nu)) * np.sqrt(
            energy(tau - p[i], tau - p[i], model, E, nu)
        ) + rounding
        assert np.all(value <= bound), f"point {i}: max violation {np.max(value - bound):.3g}"


def brute_force_projection(
    sigma: np.ndarray, model: str, E: float, nu: float, sigma_y: float, metric: str = "energy"
):
    """Minimise (E(tau - sigma), tau - sigma) on K by bisection on the KKT multiplier.

    Independent of the module: non-orthonormal Voigt coordinates v (tau = sum v_a S_a,
    S_a = e_k e_l^T + e_l e_k^T), energy and yield quadratic forms assembled from the
    printed formulas, tau(lambda) = (A + lambda B)^{-1} A s, and plain bisection on
    v(lambda)^T B v(lambda) = sigma_Y^2. With metric="frobenius", A is the Gram matrix
    S_a : S_b instead (the closest point of K in the Frobenius norm).
    """
    d = K.dimension(model)
    basis = []
    for k in range(d):
        for l in range(k, d):
            S = np.zeros((d, d))
            S[k, l] = S[l, k] = 1.0
            basis.append(S)
    S = np.array(basis)
    n = len(S)
    ES = printed_elasticity(S, model, E, nu) if metric == "energy" else S
    A = np.einsum("aij,bij->ab", ES, S)

    def f(t):
        return printed_yield(t, model)

    def polar(a, b):  # the bilinear form of the quadratic f
        return 0.5 * (f((S[a] + S[b])[None])[0] - f(S[a][None])[0] - f(S[b][None])[0])

    B = np.array([[polar(a, b) for b in range(n)] for a in range(n)])
    s = np.array([sigma[k, l] for k in range(d) for l in range(k, d)])
    if s @ B @ s <= sigma_y**2:
        return sigma.copy(), 0.0

    def v(lam):
        return np.linalg.solve(A + lam * B, A @ s)

    lo, hi = 0.0, 1.0 / A.max()
    while v(hi) @ B @ v(hi) > sigma_y**2:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if v(mid) @ B @ v(mid) > sigma_y**2:
            lo = mid
        else:
            hi = mid
    return sum(c * Sa for c, Sa in zip(v(hi), S)), hi


@pytest.mark.parametrize("model", MODELS)
def test_projection_matches_brute_force_and_kkt(model):
    rng = np.random.default_rng(7)
    E, nu, sy = PAPER["E"], PAPER["nu"], PAPER["sigma_y"]
    sigma = np.concatenate(
        [outside(rng, 20, model, sy), outside(rng, 5, model, sy, (1.0001, 1.001))]
    )
    p = K.project(sigma, model=model, **PAPER)
    for i in range(sigma.shape[0]):
        ref, lam = brute_force_projection(sigma[i], model, E, nu, sy)
        np.testing.assert_allclose(p[i], ref, rtol=0, atol=1e-10 * np.abs(ref).max())
        # KKT: E(sigma - P sigma) = lambda Y P sigma with lambda > 0 (Y from the printed form).
        lhs = printed_elasticity(sigma[i][None] - p[i][None], model, E, nu)[0]
        m = K.to_mandel(p[i][None])[0]
        rhs = K.from_mandel((_cpp.yield_matrix(model) @ m)[None], K.dimension(model))[0]
        np.testing.assert_allclose(lhs, lam * rhs, rtol=0, atol=1e-8 * np.abs(lhs).max())


@pytest.mark.parametrize("model, c", [("3d", 3.0), ("3d_standard", 1.5)])
def test_radial_return_closed_form(model, c):
    rng = np.random.default_rng(8)
    pressure = rng.normal(size=100)[:, None, None] * np.eye(3)
    sigma = outside(rng, 100, model, PAPER["sigma_y"]) + pressure
    mean = np.trace(sigma, axis1=1, axis2=2)[:, None, None] / 3 * np.eye(3)
    s = sigma - mean
    norm = np.sqrt(c * np.einsum("nij,nij->n", s, s))[:, None, None]
    expected = mean + s * PAPER["sigma_y"] / norm
    np.testing.assert_allclose(
        K.project(sigma, model=model, **PAPER), expected, rtol=0, atol=1e-14 * np.abs(sigma).max()
    )


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("magnitude", [1e-300, 1e-150, 1.0, 1e150, 1e300])
def test_projection_extreme_magnitudes_scale_covariant(model, magnitude):
    """P_K is positively homogeneous: P(a sigma; a sigma_Y) = a P(sigma; sigma_Y)."""
    rng = np.random.default_rng(9)
    sigma = outside(rng, 20, model, 1.0, (1.5, 1e3))
    ref = K.project(sigma, E=7.0, nu=0.2, sigma_y=1.0, model=model)
    got = K.project(sigma * magnitude, E=7.0, nu=0.2, sigma_y=magnitude, model=model)
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got / magnitude, ref, rtol=0, atol=1e-13 * np.abs(ref).max())


@pytest.mark.parametrize("model", MODELS)
def test_projection_far_outside_and_tiny_yield_stress(model):
    """sigma_Y/|sigma| down to the smallest subnormal: finite, on the boundary.

    In 3-D the stresses are exactly deviatoric: P_K keeps the volumetric part, and even a
    rounding-size one would dominate a deviator of size 1e-200 in the tensor components.
    """
    rng = np.random.default_rng(11)
    sigma = outside(rng, 10, model, 1.0, (2.0, 3.0))
    if model.startswith("3d"):  # exactly traceless
        sigma[:, 2, 2] = -(sigma[:, 0, 0] + sigma[:, 1, 1])
    for sy in (1e-200, 1e-300, 5e-324):
        p = K.project(sigma, E=3.0, nu=0.1, sigma_y=sy, model=model)
        assert np.all(np.isfinite(p))
        if sy > 1e-200 / 2:
            f = printed_yield(p / sy, model)
            np.testing.assert_allclose(f, 1.0, rtol=1e-12)


@pytest.mark.parametrize("model", MODELS)
def test_infinite_yield_stress_is_elastic(model):
    rng = np.random.default_rng(12)
    t = outside(rng, 10, model, 1.0, (10, 1e6))
    assert np.array_equal(
        K.project_mandel(K.to_mandel(t), E=1.0, sigma_y=math.inf, model=model), K.to_mandel(t)
    )
    z = np.zeros_like(t)
    eps = strain_for_stress(t, model, 5.0, 0.25)
    s, T = K.stress_update(
        z, z, eps, dt=1.0, E=5.0, nu=0.25, sigma_y=math.inf, mu_star=1.0, model=model
    )
    np.testing.assert_allclose(s, t, rtol=1e-13, atol=1e-13 * np.abs(t).max())


# --- stress updates: schemes against their defining equations ---------------------------


def perzyna_case(rng, model, num=30, factor=(1.5, 5.0)):
    """sigma_old in and out of K, strain increments driving points out of K."""
    E, nu, sy = PAPER["E"], PAPER["nu"], PAPER["sigma_y"]
    d = K.dimension(model)
    sigma_old = np.concatenate(
        [inside(rng, num // 2, model, sy), outside(rng, num - num // 2, model, sy)]
    )
    eps_old = random_symmetric(rng, num, d, 1e-7)
    target = outside(rng, num, model, sy, factor)
    eps_new = eps_old + strain_for_stress(target - sigma_old, model, E, nu)
    return sigma_old, eps_old, eps_new


@pytest.mark.parametrize("scheme", ["explicit", "implicit"])
@pytest.mark.parametrize("model", MODELS)
def test_update_of_many_points_is_the_update_of_each(model, scheme):
    """The updates pick a branch per point with hints from the previous point (the implicit one
    skips the cheap inside test after a plastic point): runs of elastic, plastic and boundary
    points in any order give bit for bit the results of updating each point alone."""
    rng = np.random.default_rng(42)
    n, d = K.mandel_size(model), K.dimension(model)
    sy = PAPER["sigma_y"]
    sigma_old = K.to_mandel(np.concatenate([inside(rng, 40, model, sy),
                                            outside(rng, 40, model, sy, (1.0, 1.0 + 1e-15)),
                                            outside(rng, 40, model, sy)]))
    order = np.concatenate([np.arange(30), 30 + rng.permutation(90)])  # runs, then a mix
    so = np.ascontiguousarray(sigma_old[order])
    eo, en = np.zeros_like(so), np.zeros_like(so)  # trial stress = sigma_old: the branch is set
    en[::7] = K.to_mandel(random_symmetric(rng, len(en[::7]), d, 1e-8))
    kw = dict(dt=1e-4, mu_star=MU_STAR, model=model, scheme=scheme, **PAPER)
    s, t = K.stress_update_mandel(so, eo, en, **kw)
    for i in range(len(so)):
        si, ti = K.stress_update_mandel(so[i:i + 1], eo[i:i + 1], en[i:i + 1], **kw)
        assert np.array_equal(si[0], s[i]) and np.array_equal(ti[0], t[i]), i
    assert s.shape == (120, n)


@pytest.mark.parametrize("model", MODELS)
def test_explicit_perzyna_matches_closed_form(model):
    rng = np.random.default_rng(20)
    E, nu = PAPER["E"], PAPER["nu"]
    so, eo, en = perzyna_case(rng, model)
    dt = 3e-6
    s, T = K.stress_update(
        so, eo, en, dt=dt, mu_star=MU_STAR, model=model, scheme="explicit", **PAPER
    )
    p_old = K.project(so, model=model, **PAPER)
    viscoplastic = dt / MU_STAR * printed_elasticity(so - p_old, model, E, nu)
    expected = so + printed_elasticity(en - eo, model, E, nu) - viscoplastic
    np.testing.assert_allclose(s, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    C = K.tangent_from_mandel(K.elasticity_matrix(model, E, nu)[None], K.dimension(model))
    np.testing.assert_allclose(T, np.broadcast_to(C, T.shape), rtol=1e-14)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("ratio", [0.1, 1.0, 10.0, 100.0])
def test_implicit_perzyna_solves_its_equation(model, ratio):
    """sigma_n = sigma_{n-1} + E deps - (k/mu*) E (sigma_n - P_K sigma_n), P_K from project."""
    rng = np.random.default_rng(21)
    E, nu = PAPER["E"], PAPER["nu"]
    so, eo, en = perzyna_case(rng, model)
    dt = ratio * MU_STAR / E
    s, _ = K.stress_update(so, eo, en, dt=dt, mu_star=MU_STAR, model=model, **PAPER)
    p = K.project(s, model=model, **PAPER)
    trial = so + printed_elasticity(en - eo, model, E, nu)
    residual = s - trial + dt / MU_STAR * printed_elasticity(s - p, model, E, nu)
    scale = np.abs(trial).max(axis=(1, 2))
    worst = np.max(np.abs(residual).max(axis=(1, 2)) / scale)
    assert worst <= 1e-12 * max(1.0, ratio), f"relative residual {worst:.3g}"


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("ratio", [1.0, 1e4, 1e8])
def test_implicit_perzyna_bounded_and_rate_independent_limit(model, ratio):
    rng = np.random.default_rng(22)
    E, nu, sy = PAPER["E"], PAPER["nu"], PAPER["sigma_y"]
    so, eo, en = perzyna_case(rng, model, factor=(2.0, 100.0) if ratio < 1e8 else (1.5, 5.0))
    dt = ratio * MU_STAR / E
    s, T = K.stress_update(so, eo, en, dt=dt, mu_star=MU_STAR, model=model, **PAPER)
    assert np.all(np.isfinite(s)) and np.all(np.isfinite(T))
    trial = so + printed_elasticity(en - eo, model, E, nu)
    # |sigma_n|_E <= |sigma^tr|_E and the tangent is bounded by E.
    assert np.all(energy(s, s, model, E, nu) <= energy(trial, trial, model, E, nu) * (1 + 1e-12))
    d = K.dimension(model)
    Tm = np.abs(T.reshape(-1, d * d, d * d)).max()
    Cm = np.abs(K.tangent_from_mandel(K.elasticity_matrix(model, E, nu)[None], d)).max()
    assert Tm <= 1.5 * Cm
    if ratio == 1e8:
        # sqrt(f(sigma_n))/sigma_Y - 1 = (overshoot of the trial stress) * O(mu*/(k E)).
        excess = np.sqrt(printed_yield(s, model)) / sy - 1
        overshoot = np.sqrt(printed_yield(trial, model)) / sy
        assert np.all(excess <= 2e-8 * overshoot), f"max excess {np.max(excess / overshoot):.3g}"
        # The limit of sigma_n + beta E (sigma_n - P_K sigma_n) = sigma^tr as beta -> inf
        # is sigma^tr - sigma_n in the (Euclidean) normal cone of K: the closest point of K
        # in the Frobenius norm. It equals P_K sigma^tr in 1-D and 3-D (radial return),
        # not in plane stress, where E has two different eigenvalues on the active part.
        closest = np.array(
            [brute_force_projection(t, model, E, nu, sy, "frobenius")[0] for t in trial]
        )
        np.testing.assert_allclose(s, closest, rtol=0, atol=2e-8 * np.abs(trial).max())
        if model != "plane_stress":
            p_trial = K.project(trial, model=model, **PAPER)
            np.testing.assert_allclose(s, p_trial, rtol=0, atol=2e-8 * np.abs(trial).max())


@pytest.mark.parametrize("model", MODELS)
def test_implicit_tends_to_explicit_for_small_steps(model):
    rng = np.random.default_rng(23)
    E = PAPER["E"]
    so = outside(rng, 20, model, PAPER["sigma_y"], (2, 5))
    eo = en = np.zeros_like(so)  # sigma^tr = sigma_old: only the viscoplastic term acts
    for ratio in (1e-4, 1e-6):
        dt = ratio * MU_STAR / E
        si, _ = K.stress_update(so, eo, en, dt=dt, mu_star=MU_STAR, model=model, **PAPER)
        se, _ = K.stress_update(
            so, eo, en, dt=dt, mu_star=MU_STAR, model=model, scheme="explicit", **PAPER
        )
        change = np.abs(se - so).max()
        assert change > 0
        assert np.abs(si - se).max() <= 10 * ratio * change, (ratio, np.abs(si - se).max() / change)


@pytest.mark.parametrize("model", MODELS)
def test_generic_newton_agrees_with_exact_perzyna(model):
    """The user-G path (Newton with dG/dsigma, continuation) reproduces the exact kernel."""
    rng = np.random.default_rng(24)
    so, eo, en = (K.to_mandel(a) for a in perzyna_case(rng, model, num=20))
    E, nu, sy = PAPER["E"], PAPER["nu"], PAPER["sigma_y"]
    for ratio in (1.0, 1e4):
        dt = ratio * MU_STAR / E
        s1, t1 = K.stress_update_mandel(so, eo, en, dt=dt, mu_star=MU_STAR, model=model, **PAPER)
        s2, t2 = np.empty_like(s1), np.empty_like(t1)
        _cpp.perzyna_update_newton(model, E, nu, sy, MU_STAR, dt, so, eo, en, s2, t2)
        np.testing.assert_allclose(s2, s1, rtol=0, atol=1e-14 * ratio * np.abs(s1).max())
        np.testing.assert_allclose(t2, t1, rtol=0, atol=1e-14 * ratio * np.abs(t1).max())


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("scheme", K.SCHEMES)
def test_linear_law_solves_its_equation(model, scheme):
    rng = np.random.default_rng(25)
    d = K.dimension(model)
    E, nu, a, b, dt = 10.0, 0.2, -1.0, 10.0, 0.05
    so, eo, en = (random_symmetric(rng, 15, d) for _ in range(3))
    s, T = K.stress_update_linear(
        so, eo, en, dt=dt, E=E, nu=nu, a=a, b=b, model=model, scheme=scheme
    )
    Edeps = printed_elasticity(en - eo, model, E, nu)
    if scheme == "explicit":
        expected = so + Edeps + dt * (a * so + b * eo)
        np.testing.assert_allclose(s, expected, rtol=0, atol=1e-13 * np.abs(expected).max())
    else:
        residual = s - so - Edeps - dt * (a * s + b * en)
        assert np.abs(residual).max() <= 1e-13 * np.abs(s).max()
        m = (K.to_mandel(a_) for a_ in (so, eo, en))
        s2, t2 = np.empty((15, K.mandel_size(model))), np.empty((15,) + (K.mandel_size(model),) * 2)
        _cpp.linear_update_newton(model, E, nu, a, b, dt, *m, s2, t2)
        np.testing.assert_allclose(K.from_mandel(s2, d), s, rtol=0, atol=1e-13 * np.abs(s).max())
        np.testing.assert_allclose(
            K.tangent_from_mandel(t2, d), T, rtol=0, atol=1e-13 * np.abs(T).max()
        )


# --- tangents against central finite differences ----------------------------------------


def check_tangent(update, so, eo, en, model, rtol=1e-6, samples=4, seed=30):
    rng = np.random.default_rng(seed)
    d = K.dimension(model)
    s, T = update(so, eo, en)
    h = 1e-6 * np.abs(s).max() / np.abs(T).max()  # changes the stress by ~1e-6 relative
    for _ in range(samples):
        delta = random_symmetric(rng, so.shape[0], d)
        plus, _ = update(so, eo, en + h * delta)
        minus, _ = update(so, eo, en - h * delta)
        fd = (plus - minus) / (2 * h)
        predicted = np.einsum("nijkl,nkl->nij", T, delta)
        scale = (np.abs(T).max(axis=(1, 2, 3, 4)) * np.abs(delta).max(axis=(1, 2)))[:, None, None]
        np.testing.assert_allclose(fd / scale, predicted / scale, rtol=0, atol=rtol)
    return s, T


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("ratio", [1.0, 1e3])
def test_implicit_perzyna_tangent_finite_differences(model, ratio):
    rng = np.random.default_rng(31)
    E, sy = PAPER["E"], PAPER["sigma_y"]
    so, eo, en = perzyna_case(rng, model, num=20, factor=(2.0, 5.0))
    dt = ratio * MU_STAR / E

    def update(a, b, c):
        return K.stress_update(a, b, c, dt=dt, mu_star=MU_STAR, model=model, **PAPER)

    s, _ = check_tangent(update, so, eo, en, model)
    trial = so + printed_elasticity(en - eo, model, E, PAPER["nu"])
    assert np.all(printed_yield(trial, model) > sy**2), "plastic branch expected"
    # Elastic branch: tangent E.
    small = eo + 1e-3 * (en - eo)
    so_in = inside(rng, 20, model, 0.5 * sy)
    check_tangent(update, so_in, eo, small, model)
    _, T = update(so_in, eo, small)
    C = K.tangent_from_mandel(K.elasticity_matrix(model, E, PAPER["nu"])[None], K.dimension(model))
    np.testing.assert_allclose(T, np.broadcast_to(C, T.shape), rtol=0, atol=1e-14 * np.abs(C).max())


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("scheme", K.SCHEMES)
def test_linear_law_tangent_finite_differences(model, scheme):
    rng = np.random.default_rng(32)
    d = K.dimension(model)
    so, eo, en = (random_symmetric(rng, 10, d) for _ in range(3))

    def update(a, b, c):
        return K.stress_update_linear(
            a, b, c, dt=0.1, E=10.0, nu=0.3, a=-1.0, b=10.0, model=model, scheme=scheme
        )

    check_tangent(update, so, eo, en, model)


@pytest.mark.parametrize("model", MODELS)
def test_explicit_perzyna_tangent_finite_differences(model):
    rng = np.random.default_rng(33)
    so, eo, en = perzyna_case(rng, model, num=10)

    def update(a, b, c):
        return K.stress_update(
            a, b, c, dt=1e-6, mu_star=MU_STAR, model=model, scheme="explicit", **PAPER
        )

    check_tangent(update, so, eo, en, model)


# --- the paper's 1-D law G = -sigma + 10 eps (Sec. 4.2.1) -------------------------------


@pytest.mark.parametrize("scheme", K.SCHEMES)
def test_paper_1d_law_first_order_convergence(scheme):
    """Relaxation sigma' = -sigma + 10 eps at fixed eps: sigma(t) = 10 eps + (s0 - 10 eps) e^-t.

    Also the paper's no-contact phase: with eps(t, x) = (1 - e^-t)(1 - x) the stress stays
    sigma = 10 - 10x (exact solution (21)).
    """
    x = np.array([0.0, 0.25, 0.5, 1.0])
    s0 = (10 - 10 * x)[:, None, None]
    eps_fixed = np.full_like(s0, 0.3)
    law = dict(E=10.0, a=-1.0, b=10.0, model="1d", scheme=scheme)
    steps = [1e-1 / 2**i for i in range(5)]
    errors = {"no contact": [], "relaxation": []}
    for k in steps:
        s, e_old = s0.copy(), np.zeros_like(s0)
        s_fix = s0.copy()
        for n in range(round(1.0 / k)):
            e_new = ((1 - np.exp(-(n + 1) * k)) * (1 - x))[:, None, None]
            s, _ = K.stress_update_linear(s, e_old, e_new, dt=k, **law)
            s_fix, _ = K.stress_update_linear(s_fix, eps_fixed, eps_fixed, dt=k, **law)
            e_old = e_new
        exact_fix = 10 * eps_fixed + (s0 - 10 * eps_fixed) * np.exp(-1.0)
        errors["no contact"].append(np.abs(s - s0).max())
        errors["relaxation"].append(np.abs(s_fix - exact_fix).max())
    for name, err in errors.items():
        rate = np.polyfit(np.log(steps), np.log(err), 1)[0]
        assert 0.9 <= rate <= 1.1, f"{name}: rate {rate:.3f}, errors {err}"
        assert err[-1] < 0.05, (name, err)


# --- in-place outputs ------------------------------------------------------------------


@pytest.mark.parametrize("model", MODELS)
def test_mandel_update_writes_preallocated_outputs_in_place(model):
    rng = np.random.default_rng(40)
    so, eo, en = (np.ascontiguousarray(K.to_mandel(a)) for a in perzyna_case(rng, model, num=12))
    kw = dict(dt=1e-6, mu_star=MU_STAR, model=model, **PAPER)
    s_ref, t_ref = K.stress_update_mandel(so, eo, en, **kw)
    n = K.mandel_size(model)
    out = (np.full((12, n), np.nan), np.full((12, n, n), np.nan))
    s, t = K.stress_update_mandel(so, eo, en, out=out, **kw)
    assert s is out[0] and t is out[1]
    assert np.array_equal(s, s_ref) and np.array_equal(t, t_ref)
    alias = so.copy()  # sigma_new may alias sigma_old
    K.stress_update_mandel(alias, eo, en, out=(alias, out[1]), **kw)
    assert np.array_equal(alias, s_ref)
    s_lin, _ = K.stress_update_linear_mandel(
        so, eo, en, dt=0.1, E=1.0, a=-1.0, b=1.0, model=model, out=out
    )
    assert s_lin is out[0]


@pytest.mark.parametrize("scheme", ["explicit", "implicit"])
@pytest.mark.parametrize("model", MODELS)
def test_update_without_tangent_gives_the_same_stress(model, scheme):
    rng = np.random.default_rng(41)
    so, eo, en = (np.ascontiguousarray(K.to_mandel(a)) for a in perzyna_case(rng, model, num=12))
    kw = dict(dt=1e-6, mu_star=MU_STAR, model=model, scheme=scheme, **PAPER)
    s_ref, _ = K.stress_update_mandel(so, eo, en, **kw)
    s, t = K.stress_update_mandel(so, eo, en, tangent=False, **kw)
    assert t is None and np.array_equal(s, s_ref)
    lin = dict(dt=0.1, E=1.0, a=-1.0, b=1.0, model=model, scheme=scheme)
    s_ref, _ = K.stress_update_linear_mandel(so, eo, en, **lin)
    s, t = K.stress_update_linear_mandel(so, eo, en, tangent=False, **lin)
    assert t is None and np.array_equal(s, s_ref)
    n = K.mandel_size(model)
    with pytest.raises(ValueError, match=r"out\[1\]: a tangent array was given with tangent=False"):
        K.stress_update_mandel(so, eo, en, tangent=False, out=(None, np.empty((12, n, n))), **kw)
    with pytest.raises(ValueError, match="tangent: expected True or False"):
        K.stress_update_mandel(so, eo, en, tangent=1, **kw)


# --- validation --------------------------------------------------------------------------


def _tensors(model="3d", num=2):
    d = K.dimension(model)
    return np.zeros((num, d, d))


def _perzyna(sigma_old=None, eps_old=None, eps_new=None, **over):
    z = _tensors()
    kw = dict(dt=0.1, E=1.0, nu=0.3, sigma_y=1.0, mu_star=1.0, model="3d")
    kw.update(over)
    arrays = [z if a is None else a for a in (sigma_old, eps_old, eps_new)]
    return lambda: K.stress_update(*arrays, **kw)


def _perzyna_mandel(sigma_old=None, **over):
    z = np.zeros((2, 6))
    kw = dict(dt=1.0, E=1.0, sigma_y=1.0, mu_star=1.0, model="3d")
    kw.update(over)
    return lambda: K.stress_update_mandel(z if sigma_old is None else sigma_old, z, z, **kw)


def _linear(**over):
    z = _tensors()
    kw = dict(dt=0.1, E=1.0, nu=0.3, a=-1.0, b=1.0, model="3d")
    kw.update(over)
    return lambda: K.stress_update_linear(z, z, z, **kw)


def _project(sigma=None, **over):
    kw = dict(E=1.0, nu=0.3, sigma_y=1.0, model="3d")
    kw.update(over)
    return lambda: K.project(_tensors() if sigma is None else sigma, **kw)


_asym = np.zeros((1, 3, 3))
_asym[0, 0, 1] = 1.0
_nan = np.zeros((1, 3, 3))
_nan[0, 1, 1] = np.nan
_huge = 1e308 * np.eye(3)[None]
_dev = np.diag([1e300, -1e300, 0.0])[None]
_z1 = _tensors(num=1)

INVALID = [
    (
        _project(model="2d"),
        r"model: unknown model '2d'; valid models are '1d', 'plane_stress', '3d', '3d_standard'",
    ),
    (_perzyna(model=3), r"model: unknown model 3"),
    (
        _perzyna(scheme="crank"),
        r"scheme: unknown scheme 'crank'; valid schemes are 'explicit', 'implicit'",
    ),
    (_project(sigma_y=0.0), r"sigma_y: yield stress must be positive"),
    (_project(sigma_y=-1.0), r"sigma_y: yield stress must be positive"),
    (_project(sigma_y=math.nan), r"sigma_y: yield stress must be positive"),
    (_project(sigma_y="1"), r"sigma_y: expected a real number"),
    (_perzyna(mu_star=0.0), r"mu_star: must be positive and finite"),
    (_perzyna(mu_star=math.inf), r"mu_star: must be positive and finite"),
    (_perzyna(dt=0.0), r"dt: must be positive and finite"),
    (_perzyna(dt=-1e-3), r"dt: must be positive and finite"),
    (_linear(dt=math.nan), r"dt: must be positive and finite"),
    (_project(E=0.0), r"E: must be positive and finite"),
    (_project(E=math.inf), r"E: must be positive and finite"),
    (_project(E=True), r"E: expected a real number"),
    (_project(nu=0.5), r"nu: Poisson's ratio must lie in \(-1, 0.5\)"),
    (_project(nu=-1.0), r"nu: Poisson's ratio must lie in \(-1, 0.5\)"),
    (_project(nu=math.nan, model="plane_stress", sigma=_tensors("plane_stress")), r"nu: Poisson"),
    (_linear(a=math.inf), r"a: must be finite"),
    (_linear(b=math.nan), r"b: must be finite"),
    (
        _linear(a=20.0, scheme="implicit"),
        r"dt: the implicit step of G = a sigma \+ b eps needs 1 - dt\*a > 0",
    ),
    (
        _project(sigma=np.zeros((2, 2, 2))),
        r"sigma: expected shape \(N, 3, 3\) for model '3d', got \(2, 2, 2\)",
    ),
    (_project(sigma=np.zeros((3, 3))), r"sigma: expected shape \(N, 3, 3\)"),
    (_project(sigma=_asym), r"sigma: tensors must be symmetric; point 0"),
    (_project(sigma=_nan), r"sigma: contains non-finite values"),
    (
        _project(sigma=np.zeros((1, 3, 3), dtype=complex)),
        r"sigma: expected real numbers, got dtype complex128",
    ),
    (_project(sigma=np.full((1, 3, 3), "a")), r"sigma: expected real numbers"),
    (_project(sigma=np.zeros((1, 3, 3), dtype=bool)), r"sigma: expected real numbers"),
    (
        _perzyna(eps_old=_tensors(num=3)),
        r"eps_old: shape \(3, 3, 3\) differs from sigma_old shape \(2, 3, 3\)",
    ),
    (
        _perzyna_mandel(np.zeros((2, 3))),
        r"sigma_old: expected shape \(N, 6\) for model '3d', got \(2, 3\)",
    ),
    (
        _perzyna_mandel(out=(np.zeros((2, 6), dtype=np.float32), np.zeros((2, 6, 6)))),
        r"out\[0\]: must be a writeable C-contiguous float64 array",
    ),
    (
        _perzyna_mandel(out=(np.zeros((2, 6)), np.zeros((2, 36)))),
        r"out\[1\]: expected shape \(2, 6, 6\), got \(2, 36\)",
    ),
    (_perzyna_mandel(out=np.zeros((2, 6))), r"out: expected a pair \(sigma_new, tangent\)"),
    (lambda: K.from_mandel(np.zeros((2, 6)), 4), r"d: dimension must be 1, 2 or 3, got 4"),
    (lambda: K.from_mandel(np.zeros((2, 6)), 2), r"m: expected shape \(N, 3\)"),
    (lambda: K.to_mandel(np.zeros((2, 4, 4))), r"t: expected shape \(N, d, d\) with d in 1, 2, 3"),
    (lambda: K.tangent_from_mandel(np.zeros((2, 6, 5)), 3), r"C: expected shape \(N, 6, 6\)"),
    (
        lambda: K.elasticity_matrix("3d", 1.0, 0.7),
        r"nu: Poisson's ratio must lie in \(-1, 0.5\), got 0.7",
    ),
    (
        lambda: K.yield_function(np.zeros((1, 2, 2)), model="1d"),
        r"sigma: expected shape \(N, 1, 1\) for model '1d'",
    ),
    (
        _perzyna(_huge, _z1, 1e300 * np.eye(3)[None], E=1e10),
        r"trial stress sigma_old \+ E \(eps_new - eps_old\) is not finite at point 0",
    ),
    (
        _perzyna(_dev, _z1, _z1, dt=1.0, E=1e10, scheme="explicit"),
        r"explicit_update: sigma_new is not finite at point 0",
    ),
]


@pytest.mark.parametrize("call, match", INVALID, ids=[m[:40] for _, m in INVALID])
def test_invalid_input_raises_value_error(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_1d_ignores_poisson_ratio_and_accepts_n11_arrays():
    z = np.zeros((3, 1, 1))
    s, T = K.stress_update(
        z, z, z + 1e-3, dt=1.0, E=2.0, nu=0.9, sigma_y=1.0, mu_star=1.0, model="1d"
    )
    assert s.shape == (3, 1, 1) and T.shape == (3, 1, 1, 1, 1)
    np.testing.assert_allclose(s, 2e-3)


def test_cpp_errors_surface_as_value_errors():
    """The private module raises too (std::invalid_argument -> ValueError), never crashes."""
    z = np.zeros((2, 6))
    with pytest.raises(ValueError, match=r"model: unknown model 'x'"):
        _cpp.project("x", 1.0, 0.3, 1.0, z, z)
    with pytest.raises(ValueError, match=r"sigma_y: yield stress must be positive"):
        _cpp.project("3d", 1.0, 0.3, -1.0, z, z)
    with pytest.raises(ValueError, match=r"out: expected shape \(2, 6\)"):
        _cpp.project("3d", 1.0, 0.3, 1.0, z, np.zeros((3, 6)))
    with pytest.raises(ValueError, match=r"tangent: expected shape"):
        _cpp.perzyna_update("implicit", "3d", 1.0, 0.3, 1.0, 1.0, 1.0, z, z, z, z, np.zeros((2, 6)))
    with pytest.raises(TypeError):  # outputs are never silently converted
        _cpp.project("3d", 1.0, 0.3, 1.0, z, np.zeros((2, 6), dtype=np.float32))


# --- pure C++ use of the headers with a user-defined law --------------------------------

EXAMPLE = Path(__file__).resolve().parents[2] / "cpp_kernels" / "examples" / "user_law.cpp"


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("g++") is None, reason="needs g++")
def test_cpp_user_law_example(tmp_path):
    """The headers compile without Python, warning-free, and a user law runs through them."""
    exe = tmp_path / "user_law"
    include = EXAMPLE.parents[1] / "include"
    flags = ["-std=c++17", "-O1", "-Wall", "-Wextra", "-Wpedantic", "-Werror"]
    subprocess.run(["g++", *flags, f"-I{include}", str(EXAMPLE), "-o", str(exe)], check=True)
    result = subprocess.run([str(exe)], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr


@pytest.mark.parametrize("scheme", ["implicit", "explicit"])
@pytest.mark.parametrize("model", ["1d", "plane_stress", "3d"])
@pytest.mark.parametrize("which", ["sigma_old", "eps_old", "eps_new"])
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_stress_updates_name_the_first_non_finite_input(which, model, scheme, bad):
    """The C++ updates check their inputs (the Python wrapper no longer does): a non-finite
    entry is reported with its array and point, before anything is written."""
    n = K.mandel_size(model)
    arrays = {name: np.zeros((1030, n)) for name in ("sigma_old", "eps_old", "eps_new")}
    arrays[which][1027, n - 1] = bad  # past the first block of the scan, in its tail
    arrays[which][1029, 0] = bad
    out = (np.full((1030, n), 7.0), np.full((1030, n, n), 7.0))
    common = dict(dt=0.1, E=1.0, model=model, out=out)
    calls = [lambda: K.stress_update_mandel(*arrays.values(), sigma_y=1.0, mu_star=1.0,
                                            scheme=scheme, **common),
             lambda: K.stress_update_linear_mandel(*arrays.values(), a=-1.0, b=1.0,
                                                   scheme=scheme, **common)]
    for call in calls:
        with pytest.raises(ValueError, match=rf"{which}: contains non-finite values "
                                             r"\(first at point 1027\)"):
            call()
        assert np.all(out[0] == 7.0) and np.all(out[1] == 7.0)
