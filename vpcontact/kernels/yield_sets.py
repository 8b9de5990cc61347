# SPDX-License-Identifier: MIT
"""Elasticity matrices, yield functions and the energy-norm projection P_K onto the yield set."""

from __future__ import annotations

from typing import Optional

import numpy as np
import numpy.typing as npt

from vpcontact import _cpp
from vpcontact.kernels._checks import (_check_model, _elastic, _mandel, _output, _tensors,
                                       _yield_stress)
from vpcontact.kernels.mandel import _convert_to_mandel, dimension, from_mandel


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
