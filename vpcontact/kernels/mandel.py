# SPDX-License-Identifier: MIT
"""Sizes of a model's tensors and conversions between tensors and Mandel vectors/matrices."""

from __future__ import annotations

import math
import numbers

import numpy as np
import numpy.typing as npt

from vpcontact import _cpp
from vpcontact.kernels._checks import _DIMENSION, _check_model, _mandel, _real_array, _tensors


#: The Mandel convention, owned here: a symmetric tensor's shear components enter its Mandel
#: vector multiplied by √2 (so that m(a)·m(b) = a:b), in the order 23, 13, 12 (3-D) after the
#: normal ones. The C++ kernels, the UFL forms (:mod:`vpcontact.model.tensors`) and the scene's
#: Voigt input use these.
SHEAR_FACTOR = math.sqrt(2.0)
OFF_DIAGONAL = {1: [], 2: [(0, 1)], 3: [(1, 2), (0, 2), (0, 1)]}


def voigt_to_mandel_factors(d: int) -> list:
    """Factors turning Voigt stresses (s11 | s11 s22 s12 | s11 s22 s33 s23 s13 s12) into Mandel
    components."""
    return [1.0] * d + [SHEAR_FACTOR] * len(OFF_DIAGONAL[d])


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
