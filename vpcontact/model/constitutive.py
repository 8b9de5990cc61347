# SPDX-License-Identifier: MIT
"""Constitutive laws σ̇ = E ε(u̇) + G(σ, ε(u)) and their time-discrete updates.

Each law advances the stress at all quadrature points at once through the C++ kernels:

* :class:`Elastic`: G = 0 (the update is exact and linear in ε).
* :class:`LinearRate`: G(σ, ε) = aσ + bε (the paper's 1-D test uses a = -1, b = 10).
* :class:`Perzyna`: G(σ, ε) = -(1/μ*) E(σ - P_K σ), P_K the projection onto the yield set K in
  the energy norm ‖τ‖² = (Eτ, τ).

``scheme="explicit"`` evaluates G at the previous step (the paper's Problem 4);
``scheme="implicit"`` at the new one (Problem 2), which the kernels solve locally and
differentiate exactly for the Newton tangent; ``scheme="linearized"`` (linearly implicit
Euler) takes G at the new step through its linearisation at the previous one, so that the
update is affine in ε_n and a step is one linear (or contact) problem, with a tangent that is
fixed within the step but changes from step to step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vpcontact import kernels
from vpcontact.errors import InputError

SCHEMES = ("explicit", "implicit", "linearized")
#: Poisson's ratio of the kernels' stand-in for an incompressible material (see
#: :meth:`Elasticity.kernel_moduli`).
INCOMPRESSIBLE_SURROGATE_NU = 0.3


#: Young's moduli a run can hold in double precision, in any units (steel in Pa is 2e11; E = 1e308
#: passed validation and overflowed in the first stress update)
MIN_MODULUS, MAX_MODULUS = 1e-100, 1e100


@dataclass(frozen=True)
class Elasticity:
    """Isotropic elasticity tensor E of a model.

    Attributes:
        model: ``"1d"``, ``"plane_stress"``, ``"3d"`` or ``"3d_standard"`` (the last two differ
            only in the yield set used by :class:`Perzyna`).
        E: Young's modulus (> 0).
        nu: Poisson's ratio in (-1, 0.5]; ignored in 1-D. ν = 0.5 (incompressible, K = ∞) is a
            3-D model for the mixed formulation only (:mod:`vpcontact.model.fields`): the
            kernels then see :meth:`kernel_moduli`, a material with the same shear modulus and
            a finite bulk modulus, whose volumetric part the mixed formulation replaces.
    """

    model: str
    E: float
    nu: float = 0.0

    def __post_init__(self):
        if self.model not in kernels.MODELS:
            raise InputError(f"unknown model {self.model!r}; expected one of {kernels.MODELS}",
                             key="law")
        if not (math.isfinite(self.E) and self.E > 0):
            raise InputError(f"Young's modulus E must be finite and > 0, got {self.E}",
                             key="material.E")
        if not MIN_MODULUS <= self.E <= MAX_MODULUS:
            raise InputError(f"Young's modulus E = {self.E:g} lies outside [{MIN_MODULUS:g}, "
                             f"{MAX_MODULUS:g}]: the stresses (E times the strains) and their "
                             "squares would leave double precision; choose other units",
                             key="material.E")
        if self.model != "1d" and not -1.0 < self.nu <= 0.5:
            raise InputError(f"Poisson's ratio nu must lie in (-1, 0.5], got {self.nu}",
                             key="material.nu")
        if self.incompressible and self.model not in ("3d", "3d_standard"):
            raise InputError("Poisson's ratio nu = 0.5 (incompressible) needs a 3-D or "
                             f"plane-strain model, got {self.model!r}", key="material.nu")

    @property
    def incompressible(self) -> bool:
        """ν = 0.5: the bulk modulus is infinite."""
        return self.model != "1d" and self.nu == 0.5

    @property
    def shear_modulus(self) -> float:
        """G = E / (2(1 + ν)) (E in 1-D)."""
        return self.E if self.model == "1d" else self.E / (2.0 * (1.0 + self.nu))

    @property
    def bulk_modulus(self) -> float:
        """K = E / (3(1 − 2ν)) (inf for ν = 0.5)."""
        return math.inf if self.incompressible else self.E / (3.0 * (1.0 - 2.0 * self.nu))

    def kernel_moduli(self) -> tuple[float, float]:
        """(E, ν) the C++ kernels work with: the material's own, except for ν = 0.5, where they
        get ν = :data:`INCOMPRESSIBLE_SURROGATE_NU` and the E that keeps G (the deviatoric
        response, all an isochoric law's flow sees, is then exact; the finite volumetric part
        is replaced by the mixed formulation's pressure)."""
        if not self.incompressible:
            return self.E, self.nu
        nu = INCOMPRESSIBLE_SURROGATE_NU
        return 2.0 * self.shear_modulus * (1.0 + nu), nu

    def kernel_bulk_modulus(self) -> float:
        """The bulk modulus of :meth:`kernel_moduli` (the volumetric stiffness in σ_q)."""
        E, nu = self.kernel_moduli()
        return E / (3.0 * (1.0 - 2.0 * nu))

    def matrix(self) -> np.ndarray:
        """E as a Mandel matrix (of :meth:`kernel_moduli`)."""
        E, nu = self.kernel_moduli()
        return kernels.elasticity_matrix(self.model, E=E, nu=nu)


def _check_scheme(scheme: str) -> None:
    if scheme not in SCHEMES:
        raise InputError(f"unknown time scheme {scheme!r}; expected one of {SCHEMES}",
                         key="law.scheme")


@dataclass(frozen=True)
class LinearRate:
    """G(σ, ε) = a σ + b ε, integrated with the given scheme."""

    elasticity: Elasticity
    a: float
    b: float
    scheme: str = "explicit"

    def __post_init__(self):
        _check_scheme(self.scheme)

    @property
    def linear_in_strain(self) -> bool:
        """The update is affine in ε_n, so Newton needs one iteration without contact."""
        return True

    @property
    def constant_tangent(self) -> bool:
        """dσ_n/dε_n depends on the step size only (not on the state)."""
        return True

    @property
    def plastic(self) -> bool:
        """No yield set: G is linear."""
        return False

    @property
    def isochoric(self) -> bool:
        """G has no volumetric part, so the mean stress stays K tr ε (elasticity: a = b = 0)."""
        return self.a == 0.0 and self.b == 0.0

    @property
    def rate_free(self) -> bool:
        """G = 0 (elasticity): every time scheme gives σ = σ_0 + E(ε − ε_0) exactly."""
        return self.a == 0.0 and self.b == 0.0

    def explicit_step_limit(self) -> float:
        """Largest stable explicit step: σ is multiplied by (1 + k a) per step, so k < 2/|a|
        for a < 0 (inf for the implicit scheme or a ≥ 0, where nothing oscillates)."""
        if self.scheme != "explicit" or self.a >= 0:
            return math.inf
        return 2.0 / abs(self.a)

    def update(self, stress_old, strain_old, strain_new, dt, stress_out, tangent_out) -> None:
        """Write σ_n and dσ_n/dε_n for all points into the output arrays (Mandel layout);
        ``tangent_out=None`` skips the tangent."""
        el = self.elasticity
        E, nu = el.kernel_moduli()
        kernels.stress_update_linear_mandel(
            stress_old, strain_old, strain_new, dt=dt, E=E, nu=nu, a=self.a, b=self.b,
            model=el.model, scheme=self.scheme, out=(stress_out, tangent_out),
            tangent=tangent_out is not None)


def Elastic(elasticity: Elasticity) -> LinearRate:
    """Linear elasticity: G = 0."""
    return LinearRate(elasticity, a=0.0, b=0.0, scheme="explicit")


@dataclass(frozen=True)
class Perzyna:
    """Perzyna viscoplasticity G = -(1/μ*) E(σ - P_K σ) with yield stress σ_Y and viscosity μ*."""

    elasticity: Elasticity
    sigma_y: float
    mu_star: float
    scheme: str = "implicit"

    def __post_init__(self):
        _check_scheme(self.scheme)
        if not self.sigma_y > 0 or math.isnan(self.sigma_y):
            raise InputError(f"yield stress sigma_y must be > 0, got {self.sigma_y}",
                             key="law.sigma_y")
        if not (math.isfinite(self.mu_star) and self.mu_star > 0):
            raise InputError(f"viscosity mu_star must be finite and > 0, got {self.mu_star}",
                             key="law.mu_star")

    @property
    def linear_in_strain(self) -> bool:
        """The update is affine in ε_n (explicit and linearized schemes)."""
        return self.scheme != "implicit"

    @property
    def constant_tangent(self) -> bool:
        """dσ_n/dε_n depends on the step size only: E (explicit scheme). The linearized
        scheme's tangent depends on σ_{n−1}, the implicit one's on σ_n."""
        return self.scheme == "explicit"

    @property
    def plastic(self) -> bool:
        """The body flows once its stress leaves the yield set."""
        return True

    @property
    def isochoric(self) -> bool:
        """The 3-D yield sets bound the deviatoric stress only (von Mises; the paper's set is
        von Mises with another radius) and E is isotropic, so σ − P_K σ is deviatoric and the
        flow keeps the volume: the mean stress stays K tr ε (3-D models; the 1-D and plane-stress
        sets are not of that kind)."""
        return self.elasticity.model in ("3d", "3d_standard")

    def explicit_step_limit(self) -> float:
        """Largest stable step of the explicit scheme, 2 μ* / λ_max(E) (inf for the implicit
        and linearized schemes).

        Inside K the update is elastic; outside it, σ - P_K σ is damped by (I - (k/μ*) E)
        per step in the energy norm, which stays a contraction only for k < 2μ*/λ_max(E).
        """
        if self.scheme != "explicit":
            return math.inf
        return 2.0 * self.mu_star / float(np.linalg.eigvalsh(self.elasticity.matrix()).max())

    def update(self, stress_old, strain_old, strain_new, dt, stress_out, tangent_out) -> None:
        """Write σ_n and dσ_n/dε_n for all points into the output arrays (Mandel layout);
        ``tangent_out=None`` skips the tangent."""
        el = self.elasticity
        E, nu = el.kernel_moduli()
        kernels.stress_update_mandel(
            stress_old, strain_old, strain_new, dt=dt, E=E, nu=nu, sigma_y=self.sigma_y,
            mu_star=self.mu_star, model=el.model, scheme=self.scheme, out=(stress_out, tangent_out),
            tangent=tangent_out is not None)


class PlaneStrain:
    """A 3-D law on a 2-D mesh in plane strain: ε33 = ε13 = ε23 = 0, σ33 free.

    Each update embeds the in-plane Mandel strains [ε11, ε22, √2ε12] into 3-D, advances the 3-D
    law (with its own yield set, e.g. 3-D von Mises), and returns the in-plane stress and the
    in-plane block of the tangent; σ13 = σ23 = 0 stay zero because they decouple. σ33 is an
    internal variable per point, kept here and committed with the step
    (:meth:`commit`); it starts at zero.

    Args:
        law: a law whose elasticity model is ``"3d"`` or ``"3d_standard"``.
    """

    _IN_PLANE = np.array([0, 1, 5])  # 3-D Mandel slots of σ11, σ22, √2 σ12

    def __init__(self, law):
        if law.elasticity.model not in ("3d", "3d_standard"):
            raise InputError(f"plane strain needs a 3-D law, got model {law.elasticity.model!r}",
                             key="material.plane")
        self.law = law
        self.elasticity = law.elasticity
        self.scheme = law.scheme
        self._s33_old = np.zeros(0)
        self._s33 = np.zeros(0)

    @property
    def linear_in_strain(self) -> bool:
        return self.law.linear_in_strain

    @property
    def constant_tangent(self) -> bool:
        return self.law.constant_tangent

    @property
    def isochoric(self) -> bool:
        return self.law.isochoric

    @property
    def plastic(self) -> bool:
        return self.law.plastic

    @property
    def rate_free(self) -> bool:
        return getattr(self.law, "rate_free", False)

    def explicit_step_limit(self) -> float:
        """The 3-D law's limit (its stiffest mode, the hydrostatic one, exists in plane strain)."""
        return self.law.explicit_step_limit()

    def full_history(self, stress: np.ndarray, strain: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The committed in-plane (N, 3) stress and strain as the 3-D law's (N, 6) arrays: σ33
        from this wrapper's committed state, ε33 = 0. A history built from the state (BDF2's
        w = σ − E ε, :mod:`vpcontact.solver.bdf2`) needs σ33 too: (E ε)33 = λ tr ε ≠ 0."""
        n = stress.shape[0]
        if self._s33_old.shape != (n,):
            self._s33_old, self._s33 = np.zeros(n), np.zeros(n)
        ip = self._IN_PLANE
        s, e = np.zeros((n, 6)), np.zeros((n, 6))
        s[:, ip], s[:, 2] = stress, self._s33_old
        e[:, ip] = strain
        return s, e

    def update(self, stress_old, strain_old, strain_new, dt, stress_out, tangent_out) -> None:
        """As the 3-D law's update, for in-plane (N, 3) Mandel arrays. The old stress and strain
        may instead be (N, 6) 3-D arrays (a history from :meth:`full_history`); σ33_old is then
        theirs, not the committed one."""
        n = stress_old.shape[0]
        if self._s33_old.shape != (n,):
            self._s33_old, self._s33 = np.zeros(n), np.zeros(n)
        ip = self._IN_PLANE
        if stress_old.shape[1] == 6:
            s_old, e_old = stress_old, strain_old
        else:
            s_old, e_old = self.full_history(stress_old, strain_old)
        e_new = np.zeros((n, 6))
        e_new[:, ip] = strain_new
        s_new = np.empty((n, 6))
        t_new = None if tangent_out is None else np.empty((n, 6, 6))
        self.law.update(s_old, e_old, e_new, dt, s_new, t_new)
        stress_out[:] = s_new[:, ip]
        if tangent_out is not None:
            tangent_out[:] = t_new[:, ip][:, :, ip]
        self._s33[:] = s_new[:, 2]

    def commit(self) -> None:
        """Accept the step: σ33 of the new state becomes the old one."""
        self._s33_old[:] = self._s33

    def internal_state(self) -> dict:
        """σ33 at the quadrature points (committed and current), for checkpoints."""
        return {"s33_old": self._s33_old.copy(), "s33": self._s33.copy()}

    def set_internal_state(self, arrays: dict) -> None:
        """Restore what :meth:`internal_state` returned."""
        self._s33_old = np.array(arrays["s33_old"], dtype=np.float64)
        self._s33 = np.array(arrays["s33"], dtype=np.float64)

    def out_of_plane_stress(self) -> np.ndarray:
        """σ33 at the points of the last update (same order as the stress arrays)."""
        return self._s33
