# SPDX-License-Identifier: MIT
"""Point histories (``[output] probes``): displacement, stress and viscoplastic strain at given
points over time, ``probes.csv``.

Each point is located once, before the run, with dolfinx's point search (a bounding-box tree of
the owned cells, :func:`dolfinx.geometry.compute_collisions`, then
:func:`dolfinx.geometry.compute_colliding_cells`). A point on the boundary between cells collides
with several, possibly on several ranks; the one taken is the colliding cell whose midpoint is
lexicographically smallest, which does not depend on the partition, so serial and parallel runs
read the same cell. Its rank evaluates the point; the values are gathered on rank 0.

Values: u at the point itself (the finite-element function, P1 or P2); the stress, its von Mises
norm, ε_vp and its equivalent as the XDMF series has them, averaged over the point's cell
(:class:`~vpcontact.output.fields.CellStress`, :class:`~vpcontact.output.strains.ViscoplasticStrain`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional, Sequence

import numpy as np
from dolfinx import geometry
from dolfinx import mesh as dmesh
from mpi4py import MPI

from vpcontact.errors import InputError
from vpcontact.output.fields import CellStress, on_rank0

_AXES = "xyz"


def _pairs(dim: int) -> list[tuple[int, int]]:
    """The independent components (i, j) of a symmetric d×d tensor: normal, then shear."""
    return [(i, i) for i in range(dim)] + [(i, j) for i in range(dim) for j in range(i + 1, dim)]


def locate(mesh, points: Sequence[Sequence[float]]) -> np.ndarray:
    """For each point, the local index of the cell that evaluates it on this rank, or −1
    (collective).

    Raises:
        InputError: a point lies in no cell of the mesh (``key``: ``output.probes[i]``; on
            every rank).
    """
    tdim, gdim = mesh.topology.dim, mesh.geometry.dim
    x = np.zeros((len(points), 3))
    for i, p in enumerate(points):
        x[i, :len(p)] = p
    owned = np.arange(mesh.topology.index_map(tdim).size_local, dtype=np.int32)
    tree = geometry.BoundingBoxTree(mesh, tdim, owned)
    colliding = geometry.compute_colliding_cells(mesh, geometry.compute_collisions(tree, x), x)
    midpoints = dmesh.compute_midpoints(mesh, tdim, owned)
    chosen = np.full(len(points), -1, dtype=np.int32)
    keys = []  # per point: this rank's smallest colliding midpoint (None: no cell here)
    for i in range(len(points)):
        cells = colliding.links(i)
        if len(cells):
            order = np.lexsort(midpoints[cells, :gdim].T[::-1])
            chosen[i] = cells[order[0]]
            keys.append(tuple(midpoints[chosen[i], :gdim]))
        else:
            keys.append(None)
    everyone = mesh.comm.allgather(keys)
    for i, point in enumerate(points):
        found = [(k[i], rank) for rank, k in enumerate(everyone) if k[i] is not None]
        if not found:
            where = ", ".join(f"{c:.6g}" for c in point)
            raise InputError(f"the point ({where}) is outside the mesh", key=f"output.probes[{i}]")
        if min(found)[1] != mesh.comm.rank:
            chosen[i] = -1
    return chosen


class ProbeHistory:
    """The values at the probes at every recorded time, gathered on rank 0.

    Args:
        u: the displacement.
        points: the probes (one coordinate per dimension each).
        cells: the cell stress fields, refreshed at each record.
        strain: the viscoplastic strain fields (None: no such columns).
    """

    def __init__(self, u, points: Sequence[Sequence[float]], cells: CellStress, strain=None):
        self.u = u
        self.mesh = u.function_space.mesh
        self.comm = self.mesh.comm
        self.points = np.array([list(p) for p in points], dtype=float).reshape(len(points), -1)
        self.cells, self.strain = cells, strain
        self._cell = locate(self.mesh, points)
        self._mine = np.flatnonzero(self._cell >= 0)
        self._x = np.zeros((len(self._mine), 3))
        self._x[:, :self.points.shape[1]] = self.points[self._mine]
        self.times: list[float] = []
        self.values: list[np.ndarray] = []   # (probes, columns) per recorded time
        self.columns = self._column_names()

    def _column_names(self) -> list[str]:
        dim = self.mesh.geometry.dim
        names = [f"u_{_AXES[i]}" for i in range(dim)]
        names += [f"sigma_{_AXES[i]}{_AXES[j]}" for i, j in _pairs(dim)] + ["von_mises"]
        if self.strain is not None:
            names += [f"eps_vp_{_AXES[i]}{_AXES[j]}" for i, j in _pairs(dim)] + ["eps_vp_eq"]
        return names

    def _local_values(self) -> np.ndarray:
        """The columns at this rank's probes ``(mine, columns)``."""
        dim = self.mesh.geometry.dim
        if not len(self._mine):
            return np.zeros((0, len(self.columns)))
        cells = self._cell[self._mine]
        pairs = [i * dim + j for i, j in _pairs(dim)]

        def at_probes(f):  # (eval returns a flat array for a single point)
            return f.eval(self._x, cells).reshape(len(cells), -1)

        parts = [at_probes(self.u), at_probes(self.cells.stress)[:, pairs],
                 at_probes(self.cells.von_mises)]
        if self.strain is not None:
            parts += [at_probes(self.strain.tensor)[:, pairs], at_probes(self.strain.equivalent)]
        return np.hstack(parts)

    def record(self, t: float) -> None:
        """The values of the current state at ``t`` (collective)."""
        self.cells.update()
        if self.strain is not None:
            self.strain.update()
        gathered = self.comm.gather((self._mine, self._local_values()), root=0)
        if self.comm.rank != 0:
            return
        values = np.full((len(self.points), len(self.columns)), np.nan)
        for index, rows in gathered:
            values[index] = rows
        self.times.append(float(t))
        self.values.append(values)

    def arrays(self) -> dict:
        """The records (rank 0) for a checkpoint."""
        return {"times": np.array(self.times),
                "values": np.array(self.values).reshape(len(self.times), len(self.points),
                                                        len(self.columns))}

    def restore(self, arrays: dict) -> None:
        """The records of a checkpoint (rank 0; none in a checkpoint without probes)."""
        if self.comm.rank != 0 or "times" not in arrays:
            return
        self.times = [float(t) for t in arrays["times"]]
        self.values = list(arrays["values"])

    def write_csv(self, path: str | Path) -> None:
        """Long format, one row per probe and time: t, probe (its index in ``[output]
        probes``), x, y, z, then :attr:`columns`; written by rank 0, on disk when any rank
        returns."""
        def write():
            with open(path, "w") as f:
                f.write("t,probe,x,y,z," + ",".join(self.columns) + "\n")
                for t, values in zip(self.times, self.values):
                    for i, (point, row) in enumerate(zip(self.points, values)):
                        xyz = list(point) + [0.0] * (3 - len(point))
                        f.write(f"{t:.10g},{i}," + ",".join(f"{c:.10g}" for c in xyz) + ","
                                + ",".join(f"{v:.10e}" for v in row) + "\n")
        on_rank0(self.comm, write)


def probe_history(problem, points, cells: CellStress, strain=None) -> Optional[ProbeHistory]:
    """The probes' history of ``problem`` (None without points; collective)."""
    if not points:
        return None
    return ProbeHistory(problem.u, points, cells, strain)
