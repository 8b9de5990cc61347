# SPDX-License-Identifier: MIT
"""UFL helpers for symmetric tensors stored as Mandel vectors.

A symmetric d x d tensor τ is stored as the vector of its orthonormal (Mandel) components

* d = 1: ``[τ11]``
* d = 2: ``[τ11, τ22, √2 τ12]``
* d = 3: ``[τ11, τ22, τ33, √2 τ23, √2 τ13, √2 τ12]``

so that the Euclidean dot product of two Mandel vectors equals σ : τ. The C++ kernels use the
same layout, which lets quadrature-point stresses and tangents enter UFL forms directly.
"""

from __future__ import annotations

import ufl

from vpcontact.kernels.mandel import OFF_DIAGONAL as _OFF_DIAGONAL
from vpcontact.kernels.mandel import SHEAR_FACTOR as _SQRT2


def mandel_size(dim: int) -> int:
    """Number of Mandel components of a symmetric tensor in ``dim`` dimensions."""
    return dim * (dim + 1) // 2


def strain(u):
    """Small-strain tensor ε(u) = ½(∇u + ∇uᵀ)."""
    return ufl.sym(ufl.grad(u))


def mandel_vector(tensor, dim: int):
    """Mandel vector (UFL) of a symmetric UFL tensor."""
    comps = [tensor[i, i] for i in range(dim)]
    comps += [_SQRT2 * tensor[i, j] for i, j in _OFF_DIAGONAL.get(dim, [])]
    return ufl.as_vector(comps)


def mandel_strain(u, dim: int):
    """Mandel vector of ε(u)."""
    return mandel_vector(strain(u), dim)


def mandel_tensor(vec, dim: int):
    """Symmetric UFL tensor from a Mandel vector (a UFL vector, or a scalar when dim == 1)."""
    if dim == 1:
        return ufl.as_matrix([[component(vec, 0, 1)]])
    t = [[None] * dim for _ in range(dim)]
    for i in range(dim):
        t[i][i] = vec[i]
    for k, (i, j) in enumerate(_OFF_DIAGONAL[dim]):
        t[i][j] = t[j][i] = vec[dim + k] / _SQRT2
    return ufl.as_matrix(t)


def component(f, i: int, size: int):
    """Component ``i`` of a quadrature coefficient that is scalar when ``size == 1``."""
    return f if size == 1 else f[i]


def as_mandel_vector(f, size: int):
    """UFL vector view of a Mandel-vector coefficient (scalar-valued when ``size == 1``)."""
    return ufl.as_vector([component(f, i, size) for i in range(size)])


def as_mandel_matrix(f, size: int):
    """UFL ``size x size`` matrix view of a tangent coefficient stored row-major."""
    return ufl.as_matrix([[component(f, i * size + j, size * size) for j in range(size)]
                          for i in range(size)])


def von_mises(sigma_vec, dim: int):
    """Von Mises equivalent stress √(3/2 s:s) of a Mandel stress vector (plane stress: σ33 = 0)."""
    sig = mandel_tensor(sigma_vec, dim)
    if dim == 2:  # plane stress: embed with σ33 = 0
        sig = ufl.as_matrix([[sig[0, 0], sig[0, 1], 0], [sig[1, 0], sig[1, 1], 0], [0, 0, 0]])
    s = ufl.dev(sig)
    return ufl.sqrt(1.5 * ufl.inner(s, s))
