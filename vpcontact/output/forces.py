# SPDX-License-Identifier: MIT
"""Support reactions and the contact force over a run: ``reactions.csv`` and ``reactions.png``.

At every recorded time: the force each Dirichlet part exerts on the body (its reaction, summed
component by component over the part's prescribed dofs) and the force of each contact part's
obstacle or foundation, from the equilibrium residual less the applied loads (point loads
included; a normal-compliance part's from its law: see :meth:`~vpcontact.solver.problem.
QuasistaticProblem.support_forces`).
With the applied loads they balance: Σ reactions + Σ contact forces + ∫f_0 + ∫f_2 + point loads
= 0. ``reactions.csv`` has a column per Dirichlet part and component (``<part>_x`` …), the total
contact force (``contact_x`` …) and, when the scene has several contact parts, each part's
(``<part>_x`` …, named after its boundary part). When some part asks for it (friction: its
``splits_force``), each part's normal force and the magnitude of its tangential force follow (``<part>_normal``,
``<part>_tangential``: the ``split`` of :meth:`~vpcontact.solver.problem.QuasistaticProblem.
support_forces`).
When a prescribed displacement or an obstacle's translation drives the run, its size is recorded
too (the "displacement" column), so that force–displacement curves can be plotted as indentation
and forming tests are.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np

from vpcontact.output.fields import on_rank0


class ForceHistory:
    """Reactions per Dirichlet part and the contact force of ``problem``, recorded over time."""

    def __init__(self, problem):
        self.problem = problem
        self.comm = problem.mesh.comm
        self.names = [part.name or f"part{i}" for i, part in enumerate(problem.dirichlet.parts)]
        self.contact_names = list(problem.contact_names)
        self.dim = problem.V.dofmap.index_map_bs
        self.times: list[float] = []
        self.reactions: list[np.ndarray] = []   # (parts, dim) per time
        self.parts: list[np.ndarray] = []       # (contact parts, dim) per time
        self.driver: list[Optional[float]] = []  # the driving displacement, if any
        #: when some part asks for it (friction): each contact part's (normal force,
        #: |tangential force|) per time
        self.split = any(p.splits_force for p in problem.contacts)
        self.components: list[np.ndarray] = []  # (contact parts, 2) per time

    def record(self, t: float) -> None:
        """Add the forces of the current state (collective)."""
        reactions, contact, *split = self.problem.support_forces(per_part=True,
                                                                 split=self.split)
        self.times.append(float(t))
        self.reactions.append(reactions)
        self.parts.append(contact)
        self.driver.append(self.problem.driving_displacement())
        self.components += split

    def restore(self, arrays: dict) -> None:
        """The records of a checkpoint (:mod:`vpcontact.output.checkpoint`)."""
        self.times = [float(t) for t in arrays["times"]]
        self.reactions = list(arrays["reactions"])
        self.parts = list(arrays["contact"])
        self.driver = [float(d) if driven else None
                       for d, driven in zip(arrays["driver"], arrays["driven"])]
        if self.split:  # (a checkpoint written before these were recorded: unknown)
            missing = np.full((len(self.times), len(self.contact_names), 2), np.nan)
            self.components = list(arrays.get("components", missing))

    @property
    def contact(self) -> list[np.ndarray]:
        """The total contact force (dim,) per recorded time."""
        return [p.sum(axis=0) if len(p) else np.zeros(self.dim) for p in self.parts]

    @property
    def per_part(self) -> bool:
        """Whether the outputs list the contact parts one by one (several parts)."""
        return len(self.contact_names) > 1

    def _columns(self) -> list[str]:
        axes = "xyz"[:self.dim]
        cols = ["t"] + ([] if self.driver and self.driver[0] is None else ["displacement"])
        cols += [f"{name}_{a}" for name in self.names for a in axes]
        cols += [f"contact_{a}" for a in axes]
        if self.per_part:
            cols += [f"{name}_{a}" for name in self.contact_names for a in axes]
        if self.split:
            cols += [f"{name}_{kind}" for name in self.contact_names
                     for kind in ("normal", "tangential")]
        return cols

    def write_csv(self, path: str | Path) -> None:
        """One row per recorded time, written by rank 0; on disk when any rank returns."""
        def write():
            with open(path, "w") as f:
                f.write(",".join(self._columns()) + "\n")
                split = self.components if self.split else [None] * len(self.times)
                for t, d, r, c, p, nt in zip(self.times, self.driver, self.reactions,
                                             self.contact, self.parts, split):
                    values = [f"{t:.10g}"] + ([] if d is None else [f"{d:.10e}"])
                    columns = [r.ravel(), c] + ([p.ravel()] if self.per_part else [])
                    columns += [] if nt is None else [nt.ravel()]
                    values += [f"{v:.10e}" for v in np.concatenate(columns)]
                    f.write(",".join(values) + "\n")
        on_rank0(self.comm, write)

    def summary(self) -> dict:
        """The final reactions and contact force, and their histories, for summary.json."""
        return {
            "parts": self.names,
            "final": {name: self.reactions[-1][i].tolist() for i, name in enumerate(self.names)}
            if self.reactions else {},
            "contact_force_final": self.contact[-1].tolist() if self.contact else None,
            "contact_force": [c.tolist() for c in self.contact],
            "contact_parts": {name: {"final": self.parts[-1][i].tolist() if self.parts else None,
                                     "history": [p[i].tolist() for p in self.parts],
                                     **(self._split_summary(i) if self.split else {})}
                              for i, name in enumerate(self.contact_names)},
        }

    def _split_summary(self, i: int) -> dict:
        """Contact part i's normal and tangential force, final and over time."""
        history = np.array([c[i] for c in self.components]).reshape(-1, 2)
        return {f"{kind}_force": {"final": float(history[-1, k]) if len(history) else None,
                                  "history": history[:, k].tolist()}
                for k, kind in enumerate(("normal", "tangential"))}
