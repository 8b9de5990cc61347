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

Layout: :mod:`~vpcontact.kernels.mandel` (sizes, tensor ↔ Mandel conversions),
:mod:`~vpcontact.kernels.yield_sets` (elasticity, yield functions, projections),
:mod:`~vpcontact.kernels.stress_updates` (stress updates and tangents); argument checking is in
the private ``_checks``. A user's own G is written in C++ (``cpp_kernels/examples/user_law.cpp``).
"""

from vpcontact.kernels._checks import MODELS, SCHEMES, SYMMETRY_RTOL
from vpcontact.kernels.mandel import (dimension, from_mandel, mandel_size, tangent_from_mandel,
                                      to_mandel)
from vpcontact.kernels.stress_updates import (stress_update, stress_update_linear,
                                              stress_update_linear_mandel, stress_update_mandel)
from vpcontact.kernels.yield_sets import elasticity_matrix, project, project_mandel, yield_function

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
