# SPDX-License-Identifier: MIT
"""The C++ kernels agree with tests/reference/numpy_reference.py, an independent numpy
implementation of the same formulas (projection, explicit and implicit updates with the
consistent tangent) — the agreement bench/kernel_throughput.py relies on, checked in CI on random
inputs of both branches."""

import numpy as np
import pytest

from vpcontact import kernels

from tests.reference import numpy_reference as ref

E, NU, SIGMA_Y, MU_STAR = 1e8, 0.3, np.sqrt(10.0), 200.0


@pytest.mark.parametrize("model", kernels.MODELS)
def test_kernels_match_the_numpy_formulas(model):
    rng = np.random.default_rng(7)
    d, n = kernels.dimension(model), kernels.mandel_size(model)
    Emat = kernels.elasticity_matrix(model, E, NU)
    Y = ref.yield_matrix(lambda m: kernels.yield_function(kernels.from_mandel(m, d), model=model), n)
    sigma_old = rng.normal(size=(400, n)) * 4.0  # about half the points outside K
    eps_old = rng.normal(size=(400, n)) * 1e-8
    eps_new = eps_old + rng.normal(size=(400, n)) * 3e-8

    def close(a, b):
        return np.abs(a - b).max() <= 1e-12 * np.abs(b).max()

    assert close(kernels.project_mandel(sigma_old, E=E, nu=NU, sigma_y=SIGMA_Y, model=model),
                 ref.project(sigma_old, Emat, Y, SIGMA_Y))
    for dt, scheme in ((1e-7, "explicit"), (0.01, "implicit"), (10.0, "implicit")):
        sigma, tangent = kernels.stress_update_mandel(
            sigma_old, eps_old, eps_new, dt=dt, E=E, nu=NU, sigma_y=SIGMA_Y, mu_star=MU_STAR,
            model=model, scheme=scheme)
        if scheme == "explicit":
            assert close(sigma, ref.explicit_update(sigma_old, eps_old, eps_new, Emat, Y, SIGMA_Y,
                                                    dt / MU_STAR))
        else:
            want_sigma, want_tangent = ref.implicit_update(sigma_old, eps_old, eps_new, Emat, Y,
                                                           SIGMA_Y, dt / MU_STAR)
            assert close(sigma, want_sigma) and close(tangent, want_tangent), (model, dt)
