# SPDX-License-Identifier: MIT
"""Constitutive kernels: elasticity, yield sets, projections and stress updates.

The rate-type elastic-viscoplastic law of the paper is

.. math:: \\dot\\sigma = \\mathcal{E}\\dot\\varepsilon + G(\\sigma, \\varepsilon),

with :math:`\\mathcal{E}` isotropic elasticity and either Perzyna's law
:math:`G = -\\frac{1}{\\mu^*}\\mathcal{E}(\\sigma - P_K\\sigma)` (paper eq. (20)) or the
linear law :math:`G = a\\sigma + b\\varepsilon`. The loops over points run in C++
(``vpcontact._cpp``, built from ``cpp_kernels/``); this module holds the defaults, the
validation and the documentation.

Models (the ``model`` argument):

* ``"1d"``: bar, :math:`\\mathcal{E}\\tau = E\\tau`, :math:`K = \\{|\\tau| \\le \\sigma_Y\\}`.
  Tensors are arrays of shape ``(N, 1, 1)``; ``nu`` is ignored.
* ``"plane_stress"``: :math:`(\\mathcal{E}\\tau)_{\\alpha\\beta} = \\frac{E\\nu}{1-\\nu^2}
  (\\tau_{11}+\\tau_{22})\\delta_{\\alpha\\beta} + \\frac{E}{1+\\nu}\\tau_{\\alpha\\beta}`,
  :math:`K = \\{\\tau_{11}^2+\\tau_{22}^2-\\tau_{11}\\tau_{22}+3\\tau_{12}^2 \\le \\sigma_Y^2\\}`.
* ``"3d"``: 3-D isotropic elasticity and the set printed in the paper (Sec. 4.1.2),
  :math:`(\\tau_{11}-\\tau_{22})^2+(\\tau_{22}-\\tau_{33})^2+(\\tau_{33}-\\tau_{11})^2
  +6(\\tau_{12}^2+\\tau_{13}^2+\\tau_{23}^2) \\le \\sigma_Y^2`, i.e. :math:`3\\,s:s \\le
  \\sigma_Y^2` with :math:`s` the deviator. Its left side is **twice** the standard von
  Mises one, so its uniaxial yield stress is :math:`\\sigma_Y/\\sqrt2`.
* ``"3d_standard"``: standard von Mises, :math:`\\tfrac32\\,s:s \\le \\sigma_Y^2`.

Mandel vectors (``*_mandel`` functions) are the orthonormal coordinates
``[t11]``, ``[t11, t22, √2 t12]`` or ``[t11, t22, t33, √2 t23, √2 t13, √2 t12]``; a
Mandel matrix ``C`` acts on them as the fourth-order tensor
:math:`T_{ijkl} = \\sum_{ab} C_{ab} (B_a)_{ij} (B_b)_{kl}` with :math:`B_a` the orthonormal
basis tensors, so :math:`d\\sigma = T : d\\varepsilon`.
"""

from __future__ import annotations

import math
import numbers
from typing import Optional, Tuple

import numpy as np
import numpy.typing as npt

from vpcontact import _cpp

__all__ = [
    "MODELS",
    "SCHEMES",
    "dimension",
    "mandel_size",
    "to_mandel",
    "from_mandel",
    "tangent_from_mandel",
    "elasticity_matrix",
    "yield_function",
    "project",
    "project_mandel",
    "stress_update",
    "stress_update_linear",
    "stress_update_mandel",
    "stress_update_linear_mandel",
]

#: Valid values of ``model``.
MODELS: Tuple[str, ...] = ("1d", "plane_stress", "3d", "3d_standard")
#: Valid values of ``scheme``.
SCHEMES: Tuple[str, ...] = ("explicit", "implicit")
#: Relative tolerance of the symmetry check on tensor inputs.
SYMMETRY_RTOL = 1e-10

_DIMENSION = {"1d": 1, "plane_stress": 2, "3d": 3, "3d_standard": 3}


# --- validation -------------------------------------------------------------------------


def _check_model(model: str) -> str:
    if not isinstance(model, str) or model not in MODELS:
        valid = ", ".join(repr(m) for m in MODELS)
        raise ValueError(f"model: unknown model {model!r}; valid models are {valid}")
    return model


def _check_scheme(scheme: str) -> str:
    if not isinstance(scheme, str) or scheme not in SCHEMES:
        valid = ", ".join(repr(s) for s in SCHEMES)
        raise ValueError(f"scheme: unknown scheme {scheme!r}; valid schemes are {valid}")
    return scheme


def _real(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name}: expected a real number, got {value!r}")
    return float(value)


def _finite(name: str, value: object) -> float:
    v = _real(name, value)
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {v}")
    return v


def _positive(name: str, value: object) -> float:
    v = _real(name, value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name}: must be positive and finite, got {v}")
    return v


def _yield_stress(sigma_y: object) -> float:
    v = _real("sigma_y", sigma_y)
    if not v > 0.0:  # NaN fails too; +inf means "never yields"
        raise ValueError(f"sigma_y: yield stress must be positive (or +inf), got {v}")
    return v


def _elastic(model: str, E: object, nu: object) -> Tuple[float, float]:
    young = _positive("E", E)
    if model == "1d":
        return young, 0.0
    poisson = _real("nu", nu)
    if not -1.0 < poisson < 0.5:
        raise ValueError(f"nu: Poisson's ratio must lie in (-1, 0.5), got {poisson}")
    return young, poisson


def _real_array(name: str, x: npt.ArrayLike, check_finite: bool = True) -> np.ndarray:
    """``x`` as a C-contiguous float64 array; ``check_finite=False`` for arrays whose kernel
    checks finiteness itself (the stress updates, in the same C++ pass that reads them)."""
    a = np.asarray(x)
    if a.dtype.kind not in "fiu":
        raise ValueError(f"{name}: expected real numbers, got dtype {a.dtype}")
    a = np.ascontiguousarray(a, dtype=np.float64)
    if check_finite and not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains non-finite values")
    return a


def _tensors(name: str, x: npt.ArrayLike, model: str) -> np.ndarray:
    """Validate an (N, d, d) array of symmetric tensors of the model."""
    a = _real_array(name, x)
    d = _DIMENSION[model]
    if a.ndim != 3 or a.shape[1:] != (d, d):
        raise ValueError(
            f"{name}: expected shape (N, {d}, {d}) for model {model!r}, got {a.shape}"
        )
    if d > 1 and a.shape[0] > 0:
        asym = np.abs(a - a.transpose(0, 2, 1)).max(axis=(1, 2))
        scale = np.abs(a).max(axis=(1, 2))
        bad = np.nonzero(asym > SYMMETRY_RTOL * scale)[0]
        if bad.size:
            i = int(bad[0])
            raise ValueError(
                f"{name}: tensors must be symmetric; point {i} has max |t - t^T| = "
                f"{asym[i]:.3g} (relative tolerance {SYMMETRY_RTOL:g})"
            )
    return a


def _mandel(name: str, x: npt.ArrayLike, model: str, num_points: Optional[int] = None,
            check_finite: bool = True):
    a = _real_array(name, x, check_finite)
    n = mandel_size(model)
    if a.ndim != 2 or a.shape[1] != n:
        raise ValueError(f"{name}: expected shape (N, {n}) for model {model!r}, got {a.shape}")
    if num_points is not None and a.shape[0] != num_points:
        raise ValueError(f"{name}: expected {num_points} points like sigma_old, got {a.shape[0]}")
    return a


def _same_points(names: Tuple[str, ...], arrays: Tuple[np.ndarray, ...]) -> None:
    for name, a in zip(names[1:], arrays[1:]):
        if a.shape != arrays[0].shape:
            raise ValueError(
                f"{name}: shape {a.shape} differs from {names[0]} shape {arrays[0].shape}"
            )


def _output(name: str, out: object, shape: Tuple[int, ...]) -> np.ndarray:
    if out is None:
        return np.empty(shape)
    if not isinstance(out, np.ndarray):
        raise ValueError(f"{name}: expected a numpy array, got {type(out).__name__}")
    if out.dtype != np.float64 or not out.flags.c_contiguous or not out.flags.writeable:
        raise ValueError(f"{name}: must be a writeable C-contiguous float64 array")
    if out.shape != shape:
        raise ValueError(f"{name}: expected shape {shape}, got {out.shape}")
    return out


def _outputs(out, num_points: int, n: int,
             tangent: bool) -> Tuple[np.ndarray, Optional[np.ndarray]]:
    if out is None:
        out = (None, None)
    if not isinstance(out, (tuple, list)) or len(out) != 2:
        raise ValueError("out: expected a pair (sigma_new, tangent) of arrays or None")
    if not isinstance(tangent, bool):
        raise ValueError(f"tangent: expected True or False, got {tangent!r}")
    if not tangent and out[1] is not None:
        raise ValueError("out[1]: a tangent array was given with tangent=False")
    return (
        _output("out[0]", out[0], (num_points, n)),
        _output("out[1]", out[1], (num_points, n, n)) if tangent else None,
    )


# --- sizes and conversions --------------------------------------------------------------


def dimension(model: str) -> int:
    """Spatial dimension d of the stress tensors of a model (1, 2 or 3).

    Args:
        model: One of :data:`MODELS`.
    """
    return _DIMENSION[_check_model(model)]


def mandel_size(model: str) -> int:
    """Number :math:`n = d(d+1)/2` of Mandel components of a model (1, 3 or 6).

    Args:
        model: One of :data:`MODELS`.
    """
    d = dimension(model)
    return d * (d + 1) // 2


def _model_of_dimension(d: int) -> str:
    return {1: "1d", 2: "plane_stress", 3: "3d"}[d]


def to_mandel(t: npt.ArrayLike) -> np.ndarray:
    """Convert symmetric tensors to Mandel vectors.

    Args:
        t: Symmetric tensors, shape ``(N, d, d)`` with ``d`` in 1, 2, 3.

    Returns:
        Mandel vectors, shape ``(N, d(d+1)/2)``: ``[t11]``, ``[t11, t22, √2 t12]`` or
        ``[t11, t22, t33, √2 t23, √2 t13, √2 t12]``.

    Raises:
        ValueError: if ``t`` has the wrong shape, non-finite or non-real entries, or is
            not symmetric.
    """
    a = _real_array("t", t)
    if a.ndim != 3 or a.shape[1] != a.shape[2] or a.shape[1] not in (1, 2, 3):
        raise ValueError(f"t: expected shape (N, d, d) with d in 1, 2, 3, got {a.shape}")
    return _convert_to_mandel(_tensors("t", a, _model_of_dimension(a.shape[1])))


def _convert_to_mandel(a: np.ndarray) -> np.ndarray:
    """to_mandel() of an already validated (N, d, d) float64 array."""
    d = a.shape[1]
    out = np.empty((a.shape[0], d * (d + 1) // 2))
    _cpp.to_mandel(d, a, out)
    return out


def from_mandel(m: npt.ArrayLike, d: int) -> np.ndarray:
    """Convert Mandel vectors to symmetric tensors (inverse of :func:`to_mandel`).

    Args:
        m: Mandel vectors, shape ``(N, d(d+1)/2)``.
        d: Spatial dimension, 1, 2 or 3.

    Returns:
        Symmetric tensors, shape ``(N, d, d)``.
    """
    if isinstance(d, bool) or not isinstance(d, numbers.Integral) or d not in (1, 2, 3):
        raise ValueError(f"d: dimension must be 1, 2 or 3, got {d!r}")
    a = _mandel("m", m, _model_of_dimension(int(d)))
    out = np.empty((a.shape[0], d, d))
    _cpp.from_mandel(int(d), a, out)
    return out


def tangent_from_mandel(C: npt.ArrayLike, d: int) -> np.ndarray:
    """Convert Mandel matrices to fourth-order tensors with minor symmetries.

    :math:`T_{ijkl} = \\sum_{ab} C_{ab} (B_a)_{ij} (B_b)_{kl}`, so that
    :math:`T : d\\varepsilon` is the tensor of :math:`C\\,m(d\\varepsilon)` for symmetric
    :math:`d\\varepsilon`.

    Args:
        C: Mandel matrices, shape ``(N, n, n)`` with ``n = d(d+1)/2``.
        d: Spatial dimension, 1, 2 or 3.

    Returns:
        Tensors, shape ``(N, d, d, d, d)``.
    """
    if isinstance(d, bool) or not isinstance(d, numbers.Integral) or d not in (1, 2, 3):
        raise ValueError(f"d: dimension must be 1, 2 or 3, got {d!r}")
    d = int(d)
    n = d * (d + 1) // 2
    a = _real_array("C", C)
    if a.ndim != 3 or a.shape[1:] != (n, n):
        raise ValueError(f"C: expected shape (N, {n}, {n}), got {a.shape}")
    out = np.empty((a.shape[0], d, d, d, d))
    _cpp.matrix_from_mandel(d, a, out)
    return out


# --- elasticity and yield sets ----------------------------------------------------------


def elasticity_matrix(model: str, E: float, nu: float = 0.0) -> np.ndarray:
    """Mandel matrix of the isotropic elasticity tensor :math:`\\mathcal{E}` of a model.

    Args:
        model: One of :data:`MODELS`.
        E: Young's modulus, > 0.
        nu: Poisson's ratio in (-1, 0.5); ignored for ``"1d"``.

    Returns:
        Symmetric positive definite matrix, shape ``(n, n)``.
    """
    model = _check_model(model)
    young, poisson = _elastic(model, E, nu)
    return _cpp.elasticity_matrix(model, young, poisson)


def yield_function(sigma: npt.ArrayLike, *, model: str) -> np.ndarray:
    """Values :math:`\\tau\\cdot Y\\tau` of the yield function (compare with
    :math:`\\sigma_Y^2`).

    Args:
        sigma: Symmetric tensors, shape ``(N, d, d)``.
        model: One of :data:`MODELS`.

    Returns:
        Shape ``(N,)``.
    """
    model = _check_model(model)
    m = _convert_to_mandel(_tensors("sigma", sigma, model))
    out = np.empty(m.shape[0])
    _cpp.yield_function(model, m, out)
    return out


def project_mandel(
    sigma: npt.ArrayLike,
    *,
    E: float,
    nu: float = 0.0,
    sigma_y: float,
    model: str,
    out: Optional[np.ndarray] = None,
) -> np.ndarray:
    """Energy-norm projection onto K, on Mandel vectors (see :func:`project`).

    Args:
        sigma: Mandel vectors, shape ``(N, n)``.
        E: Young's modulus, > 0.
        nu: Poisson's ratio in (-1, 0.5); ignored for ``"1d"``.
        sigma_y: Yield stress, > 0; ``inf`` means K is the whole space.
        model: One of :data:`MODELS`.
        out: Optional preallocated float64 C-contiguous output of shape ``(N, n)``
            (may be ``sigma`` itself).

    Returns:
        :math:`P_K\\sigma`, shape ``(N, n)``.
    """
    model = _check_model(model)
    young, poisson = _elastic(model, E, nu)
    sy = _yield_stress(sigma_y)
    s = _mandel("sigma", sigma, model)
    result = _output("out", out, s.shape)
    _cpp.project(model, young, poisson, sy, s, result)
    return result


def project(
    sigma: npt.ArrayLike, *, E: float, nu: float = 0.0, sigma_y: float, model: str
) -> np.ndarray:
    """Project stresses onto the yield set in the energy norm.

    Computes :math:`P_K\\sigma = \\arg\\min_{\\tau\\in K} (\\mathcal{E}(\\tau-\\sigma),
    \\tau-\\sigma)` with :math:`K = \\{\\tau : \\tau\\cdot Y\\tau \\le \\sigma_Y^2\\}`.
    Points inside K are returned unchanged. Otherwise, in the common eigenbasis of
    :math:`\\mathcal{E}` (eigenvalues :math:`e_i`) and :math:`Y` (:math:`y_i`),
    :math:`\\tau_i = \\sigma_i/(1+\\lambda y_i/e_i)` with :math:`\\lambda > 0` the root of
    :math:`\\sum_i y_i\\tau_i(\\lambda)^2 = \\sigma_Y^2`, found to machine precision by a
    monotone Newton iteration. The result lies in K up to a relative :math:`10^{-14}`.

    Args:
        sigma: Symmetric tensors, shape ``(N, d, d)`` (``(N, 1, 1)`` for ``"1d"``).
        E: Young's modulus, > 0.
        nu: Poisson's ratio in (-1, 0.5); ignored for ``"1d"``.
        sigma_y: Yield stress, > 0; ``inf`` means K is the whole space.
        model: One of :data:`MODELS`.

    Returns:
        :math:`P_K\\sigma`, shape ``(N, d, d)``.

    Raises:
        ValueError: on invalid parameters or arrays (the message names the argument).
    """
    model = _check_model(model)
    s = _convert_to_mandel(_tensors("sigma", sigma, model))
    return from_mandel(
        project_mandel(s, E=E, nu=nu, sigma_y=sigma_y, model=model), dimension(model)
    )


# --- stress updates ---------------------------------------------------------------------


def _step_inputs(model, sigma_old, eps_old, eps_new):
    names = ("sigma_old", "eps_old", "eps_new")
    # Finiteness is checked by the C++ update (std::invalid_argument -> ValueError).
    arrays = tuple(_mandel(nm, a, model, check_finite=False)
                   for nm, a in zip(names, (sigma_old, eps_old, eps_new)))
    _same_points(names, arrays)
    return arrays


def stress_update_mandel(
    sigma_old: npt.ArrayLike,
    eps_old: npt.ArrayLike,
    eps_new: npt.ArrayLike,
    *,
    dt: float,
    E: float,
    nu: float = 0.0,
    sigma_y: float,
    mu_star: float,
    model: str,
    scheme: str = "implicit",
    out: Optional[Tuple[np.ndarray, np.ndarray]] = None,
    tangent: bool = True,
) -> Tuple[np.ndarray, Optional[np.ndarray]]:
    """One Perzyna time step on Mandel arrays (the FE solver's hot loop).

    See :func:`stress_update` for the mathematics.

    Args:
        sigma_old: :math:`\\sigma_{n-1}`, shape ``(N, n)``.
        eps_old: :math:`\\varepsilon_{n-1}`, shape ``(N, n)``.
        eps_new: :math:`\\varepsilon_n`, shape ``(N, n)``.
        dt: Time step :math:`k > 0`.
        E: Young's modulus, > 0.
        nu: Poisson's ratio in (-1, 0.5); ignored for ``"1d"``.
        sigma_y: Yield stress, > 0 (``inf``: purely elastic).
        mu_star: Viscosity :math:`\\mu^* > 0`.
        model: One of :data:`MODELS`.
        scheme: ``"implicit"`` (default) or ``"explicit"``.
        out: Optional pair of preallocated float64 C-contiguous arrays of shapes
            ``(N, n)`` and ``(N, n, n)``, written in place (they may alias the inputs);
            with ``tangent=False`` the second must be None.
        tangent: False skips the tangent: it is neither computed nor written, and None is
            returned in its place (for callers whose tangent is constant and already known,
            e.g. the explicit scheme's E).

    Returns:
        ``(sigma_new, tangent)``: :math:`\\sigma_n`, shape ``(N, n)``, and the Mandel
        matrix of :math:`d\\sigma_n/d\\varepsilon_n`, shape ``(N, n, n)`` (or None).
    """
    model = _check_model(model)
    scheme = _check_scheme(scheme)
    k = _positive("dt", dt)
    young, poisson = _elastic(model, E, nu)
    sy = _yield_stress(sigma_y)
    mu = _positive("mu_star", mu_star)
    so, eo, en = _step_inputs(model, sigma_old, eps_old, eps_new)
    s_out, t_out = _outputs(out, so.shape[0], mandel_size(model), tangent)
    _cpp.perzyna_update(scheme, model, young, poisson, sy, mu, k, so, eo, en, s_out, t_out)
    return s_out, t_out


def stress_update_linear_mandel(
    sigma_old: npt.ArrayLike,
    eps_old: npt.ArrayLike,
    eps_new: npt.ArrayLike,
    *,
    dt: float,
    E: float,
    nu: float = 0.0,
    a: float,
    b: float,
    model: str,
    scheme: str = "explicit",
    out: Optional[Tuple[np.ndarray, np.ndarray]] = None,
    tangent: bool = True,
) -> Tuple[np.ndarray, Optional[np.ndarray]]:
    """One time step with :math:`G = a\\sigma + b\\varepsilon` on Mandel arrays.

    See :func:`stress_update_linear` for the mathematics; arguments as in
    :func:`stress_update_mandel` with ``a``, ``b`` (finite) instead of ``sigma_y``,
    ``mu_star``.

    Returns:
        ``(sigma_new, tangent)`` with shapes ``(N, n)`` and ``(N, n, n)`` (tangent None with
        ``tangent=False``).
    """
    model = _check_model(model)
    scheme = _check_scheme(scheme)
    k = _positive("dt", dt)
    young, poisson = _elastic(model, E, nu)
    ca, cb = _finite("a", a), _finite("b", b)
    if scheme == "implicit" and not 1.0 - k * ca > 0.0:
        raise ValueError(
            f"dt: the implicit step of G = a sigma + b eps needs 1 - dt*a > 0, got dt*a = {k * ca}"
        )
    so, eo, en = _step_inputs(model, sigma_old, eps_old, eps_new)
    s_out, t_out = _outputs(out, so.shape[0], mandel_size(model), tangent)
    _cpp.linear_update(scheme, model, young, poisson, ca, cb, k, so, eo, en, s_out, t_out)
    return s_out, t_out


def _tensor_step_inputs(model, sigma_old, eps_old, eps_new):
    names = ("sigma_old", "eps_old", "eps_new")
    arrays = tuple(_tensors(nm, a, model) for nm, a in zip(names, (sigma_old, eps_old, eps_new)))
    _same_points(names, arrays)
    return tuple(_convert_to_mandel(a) for a in arrays)


def _to_tensors(model: str, sigma: np.ndarray, tangent: np.ndarray):
    d = dimension(model)
    return from_mandel(sigma, d), tangent_from_mandel(tangent, d)


def stress_update(
    sigma_old: npt.ArrayLike,
    eps_old: npt.ArrayLike,
    eps_new: npt.ArrayLike,
    *,
    dt: float,
    E: float,
    nu: float = 0.0,
    sigma_y: float,
    mu_star: float,
    model: str,
    scheme: str = "implicit",
) -> Tuple[np.ndarray, np.ndarray]:
    """One time step of the Perzyna law at every point, with its tangent.

    With :math:`k` = ``dt``, :math:`\\beta = k/\\mu^*` and the trial stress
    :math:`\\sigma^{tr} = \\sigma_{n-1} + \\mathcal{E}(\\varepsilon_n-\\varepsilon_{n-1})`:

    * explicit: :math:`\\sigma_n = \\sigma^{tr} - \\beta\\mathcal{E}(\\sigma_{n-1} -
      P_K\\sigma_{n-1})`; tangent :math:`\\mathcal{E}`.
    * implicit: :math:`\\sigma_n = \\sigma^{tr} - \\beta\\mathcal{E}(\\sigma_n - P_K\\sigma_n)`.
      If :math:`\\sigma^{tr}\\in K`, :math:`\\sigma_n = \\sigma^{tr}`. Otherwise, in the
      eigenbasis, :math:`p = P_K\\sigma_n` has :math:`p_i = \\sigma^{tr}_i/(1+\\lambda s_i)`,
      :math:`s_i = y_i(1/e_i + \\beta)`, :math:`\\sum_i y_i p_i^2 = \\sigma_Y^2`, and
      :math:`\\sigma_{n,i} = p_i(1+\\lambda y_i/e_i)`. The consistent tangent follows by
      implicit differentiation and stays bounded as :math:`kE/\\mu^*\\to\\infty`. In that
      rate-independent limit :math:`\\sigma^{tr}-\\sigma_n` lies in the normal cone of K,
      i.e. :math:`\\sigma_n` tends to the point of K closest to :math:`\\sigma^{tr}` in the
      Frobenius norm. That is :math:`P_K\\sigma^{tr}` (a radial return) for ``"1d"`` and
      the 3-D models, but not for ``"plane_stress"``, where :math:`\\mathcal{E}` has two
      different eigenvalues on the constrained components.

    Args:
        sigma_old: :math:`\\sigma_{n-1}`, shape ``(N, d, d)`` (``(N, 1, 1)`` for ``"1d"``).
        eps_old: :math:`\\varepsilon_{n-1}`, same shape.
        eps_new: :math:`\\varepsilon_n`, same shape.
        dt: Time step :math:`k > 0`.
        E: Young's modulus, > 0.
        nu: Poisson's ratio in (-1, 0.5); ignored for ``"1d"``.
        sigma_y: Yield stress, > 0 (``inf``: purely elastic).
        mu_star: Viscosity :math:`\\mu^* > 0`.
        model: One of :data:`MODELS`.
        scheme: ``"implicit"`` (default) or ``"explicit"``.

    Returns:
        ``(sigma_new, tangent)``: shapes ``(N, d, d)`` and ``(N, d, d, d, d)``, with
        :math:`d\\sigma_n = T : d\\varepsilon_n` for symmetric :math:`d\\varepsilon_n`
        (:math:`T` has both minor symmetries; it is not major-symmetric in general).

    Raises:
        ValueError: on invalid parameters or arrays (the message names the argument).
    """
    model = _check_model(model)
    so, eo, en = _tensor_step_inputs(model, sigma_old, eps_old, eps_new)
    s, t = stress_update_mandel(
        so, eo, en, dt=dt, E=E, nu=nu, sigma_y=sigma_y, mu_star=mu_star, model=model,
        scheme=scheme,
    )
    return _to_tensors(model, s, t)


def stress_update_linear(
    sigma_old: npt.ArrayLike,
    eps_old: npt.ArrayLike,
    eps_new: npt.ArrayLike,
    *,
    dt: float,
    E: float,
    nu: float = 0.0,
    a: float,
    b: float,
    model: str,
    scheme: str = "explicit",
) -> Tuple[np.ndarray, np.ndarray]:
    """One time step with the linear law :math:`G(\\sigma,\\varepsilon) = a\\sigma +
    b\\varepsilon` (the paper's 1-D example, Sec. 4.2.1, is ``a=-1, b=10``).

    * explicit: :math:`\\sigma_n = \\sigma_{n-1} + \\mathcal{E}(\\varepsilon_n -
      \\varepsilon_{n-1}) + k(a\\sigma_{n-1} + b\\varepsilon_{n-1})`; tangent
      :math:`\\mathcal{E}`.
    * implicit: :math:`\\sigma_n = (\\sigma^{tr} + kb\\varepsilon_n)/(1-ka)`; tangent
      :math:`(\\mathcal{E} + kb\\,I)/(1-ka)`. Requires :math:`1 - ka > 0`.

    Args:
        sigma_old: :math:`\\sigma_{n-1}`, shape ``(N, d, d)`` (``(N, 1, 1)`` for ``"1d"``).
        eps_old: :math:`\\varepsilon_{n-1}`, same shape.
        eps_new: :math:`\\varepsilon_n`, same shape.
        dt: Time step :math:`k > 0`.
        E: Young's modulus, > 0.
        nu: Poisson's ratio in (-1, 0.5); ignored for ``"1d"``.
        a: Coefficient of :math:`\\sigma` (finite).
        b: Coefficient of :math:`\\varepsilon` (finite).
        model: One of :data:`MODELS`.
        scheme: ``"explicit"`` (default) or ``"implicit"``.

    Returns:
        ``(sigma_new, tangent)``: shapes ``(N, d, d)`` and ``(N, d, d, d, d)``.

    Raises:
        ValueError: on invalid parameters or arrays (the message names the argument).
    """
    model = _check_model(model)
    so, eo, en = _tensor_step_inputs(model, sigma_old, eps_old, eps_new)
    s, t = stress_update_linear_mandel(
        so, eo, en, dt=dt, E=E, nu=nu, a=a, b=b, model=model, scheme=scheme
    )
    return _to_tensors(model, s, t)
