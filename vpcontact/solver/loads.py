# SPDX-License-Identifier: MIT
"""Applied loads (body force, surface tractions, point loads) and facet tags from predicates."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np
import ufl
from dolfinx import fem, mesh as dmesh
from mpi4py import MPI

from vpcontact.model.extent import mesh_extent, node_coordinates
from vpcontact.errors import InputError

#: A load is a function (x, t) -> UFL expression, x the spatial coordinate, t a time Constant.
Load = Callable[[ufl.SpatialCoordinate, fem.Constant], ufl.core.expr.Expr]


@dataclass(frozen=True)
class PointLoad:
    """A concentrated force F(t) [N] at a mesh vertex ``at``."""

    at: Sequence[float]
    force: Callable[[float], Sequence[float]]


@dataclass
class Loads:
    """Body force f_0, surface tractions f_2 (by facet tag) and point loads."""

    body_force: Optional[Load] = None
    tractions: Dict[int, Load] = field(default_factory=dict)
    points: List[PointLoad] = field(default_factory=list)


class PointDofs:
    """The owned dofs of the vertex where a point load acts (on one rank only)."""

    def __init__(self, V, load: PointLoad):
        mesh = V.mesh
        dim = mesh.topology.dim
        at = np.zeros(3)
        at[:dim] = np.asarray(load.at, dtype=np.float64)[:dim]
        extent = mesh_extent(mesh)
        tol = 1e-8 * extent
        blocks = np.flatnonzero(np.linalg.norm(node_coordinates(V) - at, axis=1) <= tol)
        owned = blocks[blocks < V.dofmap.index_map.size_local]
        found = mesh.comm.allreduce(len(owned), op=MPI.SUM)
        if found == 0:
            raise InputError(f"point load at {list(load.at)} is not at a mesh vertex (tolerance {tol:.3g})",
                             key="loads.point")
        # A vertex shared by ranks is owned by one of them: exactly one rank applies the load.
        bs = V.dofmap.index_map_bs
        self.dofs = (owned[:1, None] * bs + np.arange(bs)[None, :]).ravel().astype(np.int32)
        self.force = load.force
        self.dim = dim

    def values(self, t: float) -> np.ndarray:
        if len(self.dofs) == 0:
            return np.zeros(0)
        f = np.asarray(self.force(t), dtype=np.float64).reshape(-1)
        if f.shape != (self.dim,):
            raise InputError(f"point load force must have {self.dim} components, got {f.shape[0]}",
                             key="loads.point")
        return f


def as_vector(expr, dim: int):
    """Accept scalar loads in 1-D."""
    if dim == 1 and ufl.shape(expr) == ():
        return ufl.as_vector([expr])
    return ufl.as_vector(expr) if isinstance(expr, (list, tuple)) else expr


def tag_facets(mesh, markers: Dict[int, Callable[[np.ndarray], np.ndarray]]):
    """Facet meshtags from geometric predicates {tag: f(x) -> bool array} on the boundary."""
    fdim = mesh.topology.dim - 1
    indices, values = [], []
    for tag, predicate in markers.items():
        facets = dmesh.locate_entities_boundary(mesh, fdim, predicate)
        indices.append(facets)
        values.append(np.full(len(facets), tag, dtype=np.int32))
    indices = np.concatenate(indices) if indices else np.zeros(0, dtype=np.int32)
    values = np.concatenate(values) if values else np.zeros(0, dtype=np.int32)
    unique, counts = np.unique(indices, return_counts=True)
    shared = set(values[np.isin(indices, unique[counts > 1])].tolist())
    shared = sorted(set().union(*mesh.comm.allgather(shared)))  # raise on all ranks together
    if shared:
        raise InputError(f"boundary parts {shared} overlap: a facet may belong to one part only",
                         key="boundary")
    order = np.argsort(indices)
    return dmesh.meshtags(mesh, fdim, indices[order].astype(np.int32), values[order])
