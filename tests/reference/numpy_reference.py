# SPDX-License-Identifier: MIT
"""The Perzyna kernels' mathematics in vectorised numpy (the kernel tests' oracle and
the baseline of bench/kernel_throughput.py).

Mandel vectors, one row per point. E is the elasticity matrix, Y the quadratic form of the yield
set K = {τ : τ·Yτ ≤ σ_Y²}; the two commute (isotropic E, von Mises-type Y), so one orthonormal
basis Q (rows) diagonalises both: E = Qᵀ diag(e) Q, Y = Qᵀ diag(y) Q. In the coordinates
z = Q τ:

* Energy-norm projection P_K τ: p_i = z_i / (1 + λ y_i/e_i) with λ ≥ 0 the root of
  φ(λ) = Σ y_i p_i(λ)² − σ_Y² (λ = 0 when τ ∈ K). φ is convex and decreasing, so Newton's method
  from λ = 0 increases monotonically to the root.
* Explicit step: σ_n = σ_{n−1} + E(ε_n − ε_{n−1}) − β E(σ_{n−1} − P_K σ_{n−1}), β = k/μ*.
* Implicit step: with σ^tr = σ_{n−1} + E(ε_n − ε_{n−1}) and z = Q σ^tr: σ_n = σ^tr inside K;
  otherwise s_i = y_i (1/e_i + β), λ the root of Σ y_i (z_i/(1 + λ s_i))² = σ_Y², and
  σ_n,i = z_i m_i with m_i = (1 + λ y_i/e_i)/(1 + λ s_i). Tangent (implicit differentiation,
  q_i = 1/(1 + λ s_i)): dσ_n/dε = Qᵀ (diag(m) + (z∘m') (∂λ/∂z)ᵀ) diag(e) Q with
  m_i' = −β y_i q_i², ∂λ/∂z_j = y_j z_j q_j² / Σ_k y_k s_k z_k² q_k³; inside K it is E.

Written from these formulas, not from the C++ (which works per eigenspace in scaled variables).
"""

from __future__ import annotations

import numpy as np


def common_basis(E: np.ndarray, Y: np.ndarray):
    """(Q, e, y): rows of Q an orthonormal basis diagonalising both E and Y."""
    mix = E / np.linalg.norm(E) + np.pi * Y / max(np.linalg.norm(Y), 1e-300)  # generic combination
    _, vectors = np.linalg.eigh(mix)
    Q = vectors.T
    e = np.einsum("ij,jk,ik->i", Q, E, Q)
    y = np.einsum("ij,jk,ik->i", Q, Y, Q)
    return Q, e, y


def yield_matrix(yield_function, n: int) -> np.ndarray:
    """The symmetric matrix Y of a quadratic yield function f(τ) = τ·Yτ, by polarisation."""
    basis = np.eye(n)
    diag = yield_function(basis)
    Y = np.diag(diag)
    for i in range(n):
        for j in range(i + 1, n):
            Y[i, j] = Y[j, i] = 0.5 * (yield_function((basis[i] + basis[j])[None])[0]
                                       - diag[i] - diag[j])
    return Y


def _multiplier(z2y: np.ndarray, s: np.ndarray, sigma_y: float, iterations: int = 200):
    """λ ≥ 0 with Σ_i z2y_i/(1 + λ s_i)² = σ_Y² per row (0 where the left side at 0 is ≤ σ_Y²)."""
    lam = np.zeros(z2y.shape[0])
    active = z2y.sum(axis=1) > sigma_y**2
    for _ in range(iterations):
        if not active.any():
            break
        q = 1.0 / (1.0 + lam[active, None] * s)
        phi = (z2y[active] * q**2).sum(axis=1) - sigma_y**2
        dphi = -2.0 * (z2y[active] * s * q**3).sum(axis=1)
        step = -phi / dphi
        lam[active] += step
        done = np.abs(step) <= 1e-15 * np.abs(lam[active])
        idx = np.flatnonzero(active)
        active[idx[done]] = False
    return lam


def project(tau: np.ndarray, E: np.ndarray, Y: np.ndarray, sigma_y: float) -> np.ndarray:
    """P_K τ in the energy norm, rows of tau."""
    Q, e, y = common_basis(E, Y)
    z = tau @ Q.T
    lam = _multiplier(y * z**2, y / e, sigma_y)
    return (z / (1.0 + lam[:, None] * (y / e))) @ Q


def explicit_update(sigma_old, eps_old, eps_new, E, Y, sigma_y, beta):
    """σ_n of the explicit step."""
    return sigma_old + (eps_new - eps_old) @ E - beta * (sigma_old - project(sigma_old, E, Y, sigma_y)) @ E


def implicit_update(sigma_old, eps_old, eps_new, E, Y, sigma_y, beta):
    """(σ_n, dσ_n/dε_n) of the implicit step, tangents of shape (N, n, n)."""
    Q, e, y = common_basis(E, Y)
    z = (sigma_old + (eps_new - eps_old) @ E) @ Q.T
    s = y * (1.0 / e + beta)
    lam = _multiplier(y * z**2, s, sigma_y)
    q = 1.0 / (1.0 + lam[:, None] * s)
    m = (1.0 + lam[:, None] * (y / e)) * q
    sigma = (z * m) @ Q
    dm = -beta * y * q**2
    dlam = y * z * q**2 / np.maximum((y * s * z**2 * q**3).sum(axis=1), 1e-300)[:, None]
    dlam[lam == 0.0] = 0.0  # inside K: elastic
    inner = np.einsum("pi,ij->pij", m, np.eye(len(e))) + (z * dm)[:, :, None] * dlam[:, None, :]
    tangent = np.einsum("ik,pij,j,jl->pkl", Q, inner, e, Q, optimize=True)
    return sigma, tangent
