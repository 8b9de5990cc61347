# SPDX-License-Identifier: MIT
"""BDF2 (second-order backward differentiation) for the constitutive law, through the implicit
Euler kernel."""

from __future__ import annotations

from typing import Optional

import numpy as np

from vpcontact.errors import InputError


def check_time_scheme(time_scheme: str, law) -> str:
    """The time scheme the law is integrated with: ``time_scheme``, except that an elastic law
    (no rate: G = 0) is exact in either and takes Euler's."""
    if time_scheme not in ("euler", "bdf2"):
        raise InputError(f"time_scheme must be 'euler' or 'bdf2', got {time_scheme!r}",
                         key="time.scheme")
    if time_scheme == "bdf2" and getattr(law, "rate_free", False):
        return "euler"
    if time_scheme == "bdf2" and (getattr(law, "scheme", None) != "implicit"
                                  or not hasattr(law, "elasticity")):
        raise InputError("time scheme 'bdf2' needs an implicit law ([law] scheme = "
                         f"\"implicit\"); this one's scheme is "
                         f"{getattr(law, 'scheme', None)!r}", key="time.scheme")
    return time_scheme


class Bdf2:
    """BDF2 for σ̇ = E ε̇ + G(σ, ε) through the implicit-Euler kernel.

    With w = σ − E ε, ω = k_n/k_{n−1} and variable-step BDF2 coefficients,

        w_n = a1 w_{n−1} + a2 w_{n−2} + b k_n G(σ_n, ε_n),
        a1 = (1+ω)²/(1+2ω), a2 = −ω²/(1+2ω), b = (1+ω)/(1+2ω)

    (4/3, −1/3, 2/3 for constant steps). The implicit-Euler kernel computes
    σ = σ_old + E(ε − ε_old) + dt G(σ, ε); given σ_old = a1 w_{n−1} + a2 w_{n−2}, ε_old = 0 and
    dt = b k_n it returns exactly the BDF2 σ_n, with its consistent tangent.
    """

    def __init__(self, law):
        self.E = law.elasticity.matrix()
        # a law whose state hides components (plane strain's σ33) gives its full arrays
        self._full_history = getattr(law, "full_history", None)
        self.w_prev: Optional[np.ndarray] = None  # w_{n−2}: w before the last accepted step
        self.dt_prev = 0.0
        self.active = False
        self._inputs = None

    def prepare(self, state, dt: float) -> float:
        """Set up the step of size dt; return the kernel's effective step."""
        self.active = self.w_prev is not None
        if not self.active:
            return dt
        omega = dt / self.dt_prev
        a1, a2 = (1 + omega) ** 2 / (1 + 2 * omega), -omega**2 / (1 + 2 * omega)
        w_now = self._w(state)
        history = a1 * w_now + a2 * self.w_prev
        self._inputs = (history, np.zeros_like(history), (1 + omega) / (1 + 2 * omega) * dt)
        return self._inputs[2]

    def inputs(self):
        return self._inputs

    def accept(self, state, dt: float) -> None:
        """Keep w_{n−1} (the committed state before this step) and k_n for the next step."""
        self.w_prev = self._w(state)
        self.dt_prev = dt

    def _w(self, state) -> np.ndarray:
        """w = σ − E ε of the committed state, in the law's own (full) components."""
        stress, strain = state.view(state.stress_old), state.view(state.strain_old)
        if self._full_history is not None:
            stress, strain = self._full_history(stress, strain)
        return stress - strain @ self.E
