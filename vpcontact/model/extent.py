# SPDX-License-Identifier: MIT
"""The size of a mesh: the longest side of its bounding box, the same on every rank; and the
coordinates of a space's nodes.

Lengths that scale tolerances and penalty-like stiffnesses (friction's stick stiffness
SNES's unknown scale, search tolerances) are taken relative to it. The
maximum over ranks of each rank's own extent is not it: a rank holding half of a bar sees half
its length, so the stick stiffness (and the answers where a body sticks) depended on the number
of ranks.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI


def mesh_extent(mesh) -> float:
    """max_k (max x_k − min x_k) over the whole mesh (every rank's geometry). Collective."""
    x = mesh.geometry.x
    lower = x.min(axis=0) if len(x) else np.full(x.shape[1], np.inf)
    upper = x.max(axis=0) if len(x) else np.full(x.shape[1], -np.inf)
    lower, upper = np.ascontiguousarray(lower), np.ascontiguousarray(upper)
    mesh.comm.Allreduce(MPI.IN_PLACE, lower, op=MPI.MIN)
    mesh.comm.Allreduce(MPI.IN_PLACE, upper, op=MPI.MAX)
    return float(np.max(upper - lower))


def node_coordinates(V) -> np.ndarray:
    """The coordinates (n, 3) of the nodes (blocks) of the space ``V``, ghosts included. dolfinx
    will not tabulate them for a one-component vector space (a bar's displacement): there they
    come from its collapsed component."""
    if V.num_sub_spaces == 0 or V.dofmap.index_map_bs > 1:
        return V.tabulate_dof_coordinates()
    scalar, to_parent = V.sub(0).collapse()
    index_map = V.dofmap.index_map
    x = np.empty((index_map.size_local + index_map.num_ghosts, 3))
    x[np.asarray(to_parent) // V.dofmap.index_map_bs] = scalar.tabulate_dof_coordinates()
    return x
