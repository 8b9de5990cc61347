# SPDX-License-Identifier: MIT
"""Argument checking shared by the kernel wrappers: models, schemes, material parameters and
arrays (shape, dtype, finiteness, symmetry, preallocated outputs). Every check raises
``ValueError`` naming the argument."""

from __future__ import annotations

import math
import numbers
from typing import Optional, Tuple

import numpy as np
import numpy.typing as npt

#: Valid values of ``model``.
MODELS: Tuple[str, ...] = ("1d", "plane_stress", "3d", "3d_standard")
#: Valid values of ``scheme``.
SCHEMES: Tuple[str, ...] = ("explicit", "implicit", "linearized")
#: Relative tolerance of the symmetry check on tensor inputs.
SYMMETRY_RTOL = 1e-10

_DIMENSION = {"1d": 1, "plane_stress": 2, "3d": 3, "3d_standard": 3}


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
    d = _DIMENSION[_check_model(model)]
    n = d * (d + 1) // 2
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
