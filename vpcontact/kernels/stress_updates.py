# SPDX-License-Identifier: MIT
"""Time-discrete stress updates (explicit, implicit and linearly implicit Euler, BDF2 factors)
of Perzyna's law and of the linear law G = aσ + bε, with their consistent tangents."""

from __future__ import annotations

from typing import Optional, Tuple

import numpy as np
import numpy.typing as npt

from vpcontact import _cpp
from vpcontact.kernels._checks import (_check_model, _check_scheme, _elastic, _finite, _mandel,
                                       _outputs, _positive, _same_points, _tensors, _yield_stress)
from vpcontact.kernels.mandel import (_convert_to_mandel, dimension, from_mandel, mandel_size,
                                      tangent_from_mandel)


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
        scheme: ``"implicit"`` (default), ``"explicit"`` or ``"linearized"``.
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
    if scheme != "explicit" and not 1.0 - k * ca > 0.0:
        raise ValueError(
            f"dt: the {scheme} step of G = a sigma + b eps needs 1 - dt*a > 0, got dt*a = {k * ca}"
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
    * linearized (linearly implicit Euler): G linearised at :math:`\\sigma_{n-1}`,
      :math:`(I - kG'(\\sigma_{n-1}))(\\sigma_n - \\sigma_{n-1}) = \\mathcal{E}(\\varepsilon_n -
      \\varepsilon_{n-1}) + kG(\\sigma_{n-1})`: affine in :math:`\\varepsilon_n`, elastic at
      points whose :math:`\\sigma_{n-1}` lies in K.

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
        scheme: ``"implicit"`` (default), ``"explicit"`` or ``"linearized"``.

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
        scheme: ``"explicit"`` (default), ``"implicit"`` or ``"linearized"``.

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
