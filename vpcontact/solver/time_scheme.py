# SPDX-License-Identifier: MIT
"""The time scheme a problem integrates its law with, as an object it holds: implicit or explicit
Euler (:class:`EulerScheme`, the paper's) or BDF2 (:class:`Bdf2Scheme`), and the accepted steps'
history that the predictor and the local error estimate read (:class:`StepHistory`).

A scheme answers what a step needs of it, whichever it is:

* :meth:`~EulerScheme.prepare` before the solve (the law's effective step size, on which the
  constant-Jacobian reuse is keyed);
* :meth:`~EulerScheme.update`, the constitutive update at the quadrature points;
* :attr:`~EulerScheme.order`, the order of the step's error estimate;
* :meth:`~EulerScheme.accept` when the step is accepted (before the state commits);
* :meth:`~EulerScheme.arrays`, :meth:`~EulerScheme.scalars` and :meth:`~EulerScheme.restore`
  for checkpoints (their names are those of the files written before: ``bdf2_w_prev``,
  ``bdf2_dt_prev``).
"""

from __future__ import annotations

from typing import Callable, Optional

import numpy as np
from mpi4py import MPI

from vpcontact.solver.bdf2 import Bdf2
from vpcontact.solver.error_estimate import extrapolation_weights, milne_factor, past_nodes

#: (key) -> where the update writes the tangent, or None to skip it (the problem's)
TangentOut = Callable[[object], Optional[np.ndarray]]


def euler_update(law, state, eps: np.ndarray, dt: float, tangent_out: TangentOut) -> None:
    """σ_n from σ_{n−1}, ε_{n−1} and ε_n = ``eps`` over the step ``dt`` (the law's own Euler
    scheme, implicit or explicit)."""
    law.update(state.view(state.stress_old), state.view(state.strain_old), eps, dt,
               state.view(state.stress), tangent_out(("euler", dt)))


class EulerScheme:
    """Implicit or explicit Euler, as the law says (the paper's Problems 2 and 4)."""

    #: the order of every step's error estimate
    order = 1

    def prepare(self, state, dt: float) -> float:
        """Set up the step of size ``dt``; the law's effective step size."""
        return dt

    def update(self, law, state, eps: np.ndarray, dt: float, tangent_out: TangentOut) -> None:
        """The stress update of the step (see :func:`euler_update`)."""
        euler_update(law, state, eps, dt, tangent_out)

    def accept(self, state, dt: float) -> None:
        """The step is accepted (before the state commits): nothing to keep."""

    def arrays(self) -> dict:
        return {}

    def scalars(self) -> dict:
        return {"bdf2_dt_prev": None}

    def restore(self, scalars: dict, arrays: dict) -> None:
        """Nothing to restore."""


class Bdf2Scheme:
    """BDF2 through the implicit-Euler kernel (:class:`~vpcontact.solver.bdf2.Bdf2`); its first
    step is implicit Euler."""

    def __init__(self, law):
        self.bdf2 = Bdf2(law)

    @property
    def order(self) -> int:
        """2 once a step has BDF2's history, 1 for the first step (Euler)."""
        return 2 if self.bdf2.active else 1

    def prepare(self, state, dt: float) -> float:
        return self.bdf2.prepare(state, dt)

    def update(self, law, state, eps: np.ndarray, dt: float, tangent_out: TangentOut) -> None:
        if not self.bdf2.active:
            euler_update(law, state, eps, dt, tangent_out)
            return
        sigma_hist, zero, k = self.bdf2.inputs()
        law.update(sigma_hist, zero, eps, k, state.view(state.stress), tangent_out(("bdf2", k)))

    def accept(self, state, dt: float) -> None:
        """Keep w at t_{n−1} (the committed state: before the commit) and k_n."""
        self.bdf2.accept(state, dt)

    def arrays(self) -> dict:
        return {} if self.bdf2.w_prev is None else {"bdf2_w_prev": self.bdf2.w_prev}

    def scalars(self) -> dict:
        return {"bdf2_dt_prev": self.bdf2.dt_prev}

    def restore(self, scalars: dict, arrays: dict) -> None:
        self.bdf2.w_prev = arrays["bdf2_w_prev"].copy() if "bdf2_w_prev" in arrays else None
        self.bdf2.dt_prev = scalars["bdf2_dt_prev"]


def time_scheme(name: str, law):
    """The scheme object for ``name`` ("euler" or "bdf2", as the problem was asked for: an
    elastic law's "bdf2", which :func:`~vpcontact.solver.bdf2.check_time_scheme` reports as
    "euler" since it is exact either way, runs BDF2's update, as it always has)."""
    return Bdf2Scheme(law) if name == "bdf2" else EulerScheme()


class StepHistory:
    """The displacements (and the other fields) of the last accepted steps and their sizes: the
    predictor extrapolates from them, the error estimate compares with them."""

    def __init__(self):
        self.u_prev: Optional[np.ndarray] = None   # u_{n-1}, for the predictor
        self.others_prev: list = []  # the other fields at t_{n-1} (the mixed formulation's p)
        self.dt_prev = 0.0
        self.u_prev2: Optional[np.ndarray] = None  # u_{n-2}, for the BDF2 error estimate
        self.dt_prev2 = 0.0

    def predict(self, u, others, u_old: np.ndarray, others_old: list, dt: float) -> None:
        """u_n + k_n/k_{n-1} (u_n − u_{n-1}) into ``u`` (and the same for the ``others``
        fields), where there is a last step."""
        if self.u_prev is None:
            return
        # Ghost entries are extrapolated from ghost entries: consistent without a scatter.
        u.x.array[:] += (dt / self.dt_prev) * (u_old - self.u_prev)
        for f, old, prev in zip(others, others_old, self.others_prev):
            f.x.array[:] += (dt / self.dt_prev) * (old - prev)

    def push(self, u_old: np.ndarray, others_old: list, dt: float) -> None:
        """The step from u_old over ``dt`` is accepted."""
        self.u_prev2, self.dt_prev2 = self.u_prev, self.dt_prev
        self.u_prev, self.dt_prev = u_old, dt
        self.others_prev = others_old

    def error_ratio(self, u: np.ndarray, u_old: np.ndarray, dt: float, order: int,
                    tolerance: float, comm):
        """(local error estimate of the step to ``u`` / (tolerance · max|u_n|), order), at the
        scheme's ``order`` or lower where the history is too short; (None, 1) without history
        (see :mod:`vpcontact.solver.error_estimate`; collective)."""
        history = [u_old] + [v for v in (self.u_prev, self.u_prev2) if v is not None]
        order = min(order, len(history) - 1)
        if order < 1:
            return None, 1
        steps = [dt, self.dt_prev, self.dt_prev2][: order + 1]
        weights = extrapolation_weights(past_nodes(steps, order), 0.0)
        predicted = sum(w * v for w, v in zip(weights, history))
        difference = comm.allreduce(float(np.max(np.abs(u - predicted), initial=0.0)), op=MPI.MAX)
        size = comm.allreduce(float(np.max(np.abs(u), initial=0.0)), op=MPI.MAX)
        estimate = abs(milne_factor(order, steps)) * difference
        if estimate == 0.0:
            return 0.0, order
        return estimate / (tolerance * max(size, np.finfo(float).tiny)), order

    def arrays(self) -> dict:
        """Checkpoint arrays (``_u_prev``, ``_u_prev2``, ``_others_prev<i>``)."""
        arrays = {f"_others_prev{i}": prev for i, prev in enumerate(self.others_prev)}
        for name in ("u_prev", "u_prev2"):
            if getattr(self, name) is not None:
                arrays[f"_{name}"] = getattr(self, name)
        return arrays

    def scalars(self) -> dict:
        return {"dt_prev": self.dt_prev, "dt_prev2": self.dt_prev2}

    def restore(self, scalars: dict, arrays: dict, others: int) -> None:
        """From :meth:`arrays` and :meth:`scalars` (``others``: the fields besides u)."""
        self.u_prev = arrays["_u_prev"].copy() if "_u_prev" in arrays else None
        self.others_prev = [arrays[f"_others_prev{i}"].copy() for i in range(others)
                            if f"_others_prev{i}" in arrays]
        self.u_prev2 = arrays["_u_prev2"].copy() if "_u_prev2" in arrays else None
        self.dt_prev, self.dt_prev2 = scalars["dt_prev"], scalars["dt_prev2"]
