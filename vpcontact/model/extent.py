# SPDX-License-Identifier: MIT
"""The size of a mesh: the longest side of its bounding box, the same on every rank.

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
