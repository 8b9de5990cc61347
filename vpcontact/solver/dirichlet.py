# SPDX-License-Identifier: MIT
"""Dirichlet parts of the boundary: clamped, prescribed displacement, symmetry (roller) planes.

A part prescribes some or all displacement components on its facets,

    u_i = u_D,i(x, t)   for the listed components i,

with the others free: a clamped part prescribes every component to 0; a prescribed-displacement
part any of them by expressions of x and t (``free`` leaves one out); a symmetry or roller plane
x_a = c the normal component u_a = 0 only. Time-dependent values are interpolated at every step
before the solve. The parts must remove every rigid motion of the body between them
(:meth:`DirichletParts.check_rigid_motions`), since the contact condition alone does not.

Reactions: at a prescribed dof the assembled residual R(u) = (σ, ε(v)) − (f, v) + (contact
terms) is the force the support exerts on the body; a part's reaction is the sum of its dofs'
entries, component by component. A dof shared by two parts (an edge where they meet) belongs to
the first part that prescribes it, in the order the parts are given: its value comes from that
part (a dof constrained twice would get a doubled diagonal in the assembled Jacobian) and so does
its reaction, so the reactions of all parts add up to the total support force.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional, Sequence, Union

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from vpcontact.errors import InputError
from vpcontact.model.extent import node_coordinates

#: A prescribed component: a number, or a function (x: (3, N) points, t) -> (N,) values.
Value = Union[float, Callable[[np.ndarray, float], np.ndarray]]


@dataclass(frozen=True)
class Dirichlet:
    """u_i = values[i] on the facets tagged ``tag`` for the components whose value is not None."""

    tag: int
    values: tuple[Optional[Value], ...]
    name: str = ""

    @staticmethod
    def clamped(tag: int, dim: int, name: str = "clamped") -> "Dirichlet":
        """u = 0."""
        return Dirichlet(tag, (0.0,) * dim, name)

    @staticmethod
    def symmetry(tag: int, dim: int, axis: int, name: str = "symmetry") -> "Dirichlet":
        """u_axis = 0, the other components free (a symmetry plane x_axis = c)."""
        return Dirichlet(tag, tuple(0.0 if i == axis else None for i in range(dim)), name)

    @property
    def all_zero(self) -> bool:
        return all(isinstance(v, (int, float)) and v == 0.0 for v in self.values)


class _Component:
    """One prescribed component of one part: its dofs in V (less ``taken``) and its values."""

    def __init__(self, V, facets, i: int, value: Value, taken: np.ndarray):
        sub = V.sub(i)
        self.space, _ = sub.collapse()
        parent, child = fem.locate_dofs_topological((sub, self.space), V.mesh.topology.dim - 1,
                                                    facets)
        free = ~np.isin(parent, taken)
        self.dofs = [parent[free], child[free]]
        self.function = fem.Function(self.space)
        self.value = value
        self.moving = callable(value)
        if not self.moving:
            self.function.x.array[:] = float(value)
        self.bc = fem.dirichletbc(self.function, self.dofs, sub)

    def update(self, t: float) -> None:
        if self.moving:
            value = self.value
            self.function.interpolate(lambda x: np.broadcast_to(
                np.asarray(value(x, t), dtype=np.float64), x.shape[1:]))


class DirichletParts:
    """The Dirichlet conditions of a problem, their dofs and their reactions."""

    def __init__(self, V: fem.FunctionSpace, facet_tags, parts: Sequence[Dirichlet]):
        mesh = V.mesh
        dim = V.dofmap.index_map_bs
        self.V = V
        self.parts = list(parts)
        self.bcs = []
        self._components: list[_Component] = []
        self.part_dofs: list[np.ndarray] = []  # unrolled local dofs each part prescribes
        fdim = mesh.topology.dim - 1
        for part in self.parts:
            if len(part.values) != dim:
                raise InputError(f"Dirichlet part '{part.name}': {len(part.values)} values for "
                                 f"{dim} displacement components", key=f"boundary.{part.name}")
            facets = facet_tags.find(part.tag)
            if mesh.comm.allreduce(len(facets), op=MPI.SUM) == 0:
                raise InputError(f"the Dirichlet part '{part.name}' (tag {part.tag}) has no facets",
                                 key=f"boundary.{part.name}")
            taken = (np.concatenate(self.part_dofs) if self.part_dofs
                     else np.zeros(0, np.int32))
            blocks = fem.locate_dofs_topological(V, fdim, facets)
            overlap = mesh.comm.allreduce(  # (collective: the branches below differ in MPI calls)
                bool(np.isin(blocks[:, None] * dim + np.arange(dim), taken).any()), op=MPI.LOR)
            if part.all_zero and not overlap:
                # All components zero: one blocked condition (the clamped Γ1 of the paper).
                self.bcs.append(fem.dirichletbc(np.zeros(dim, dtype=np.float64), blocks, V))
                self.part_dofs.append(self.bcs[-1].dof_indices()[0].astype(np.int32))
                continue
            dofs = []
            for i, value in enumerate(part.values):
                if value is None:
                    continue
                component = _Component(V, facets, i, value, taken)
                self._components.append(component)
                self.bcs.append(component.bc)
                dofs.append(component.dofs[0])
            self.part_dofs.append(np.concatenate(dofs).astype(np.int32) if dofs
                                  else np.zeros(0, np.int32))
        self.moving = any(c.moving for c in self._components)
        self.prescribed = (np.unique(np.concatenate(self.part_dofs)).astype(np.int32)
                           if self.part_dofs else np.zeros(0, np.int32))
        owned = V.dofmap.index_map.size_local * dim
        self._reaction_dofs = [np.unique(dofs[dofs < owned]) for dofs in self.part_dofs]

    def update(self, t: float) -> None:
        """Interpolate the time-dependent values at ``t``."""
        for component in self._components:
            component.update(t)

    def mean_moving_value(self) -> Optional[float]:
        """Mean u_D (signed) over the dofs of the first time-dependent component (collective),
        or None without one."""
        moving = [c for c in self._components if c.moving]
        if not moving:
            return None
        c = moving[0]
        owned = c.space.dofmap.index_map.size_local
        values = c.function.x.array[c.dofs[1][c.dofs[1] < owned]]
        comm = self.V.mesh.comm
        total = comm.allreduce(float(np.sum(values)), op=MPI.SUM)
        count = comm.allreduce(len(values), op=MPI.SUM)
        return total / max(count, 1)

    def reactions(self, residual: np.ndarray) -> np.ndarray:
        """(parts, dim) support forces from the assembled residual's owned entries, summed over
        ranks (collective)."""
        dim = self.V.dofmap.index_map_bs
        local = np.zeros((len(self.parts), dim))
        for k, dofs in enumerate(self._reaction_dofs):
            np.add.at(local[k], dofs % dim, residual[dofs])
        return self.V.mesh.comm.allreduce(local, op=MPI.SUM)

    def check_rigid_motions(self) -> None:
        """Raise InputError naming the free rigid motions if the parts do not remove all of
        them (see :meth:`free_rigid_motions`)."""
        free = self.free_rigid_motions()
        if not free:
            return
        raise InputError(
            "the Dirichlet parts do not hold the body: the rigid motion(s) "
            + "; ".join(name for name, _ in free) + " remain free (and there is no contact "
            "part to hold it). Clamp a part (kind = \"clamped\"), prescribe more displacement "
            "components or add symmetry planes", key="boundary")

    def free_rigid_motions(self) -> list[tuple[str, np.ndarray]]:
        """The rigid motions the parts leave free, as (description, coefficients over the modes
        of :func:`rigid_mode_expressions`), orthonormal (collective).

        A rigid motion w(x) = a + b × x is removed when no such w other than 0 vanishes at all
        prescribed dofs, i.e. when the Gram matrix of the rigid modes restricted to those dofs
        is nonsingular (checked relative to its largest eigenvalue, on coordinates centred and
        scaled by the mesh size so that translations and rotations weigh alike).
        """
        V, mesh = self.V, self.V.mesh
        comm = mesh.comm
        dim = V.dofmap.index_map_bs
        names, modes = _rigid_modes(dim)
        owned = V.dofmap.index_map.size_local * dim
        dofs = self.prescribed[self.prescribed < owned]
        x = node_coordinates(V)[dofs // dim]
        lo = np.min(comm.allgather(mesh.geometry.x.min(axis=0)), axis=0)
        hi = np.max(comm.allgather(mesh.geometry.x.max(axis=0)), axis=0)
        size = max(float(np.max(hi - lo)), np.finfo(float).tiny)
        x = (x - 0.5 * (lo + hi)) / size
        values = np.stack([m(x)[np.arange(len(dofs)), dofs % dim] for m in modes], axis=1)
        gram = comm.allreduce(values.T @ values, op=MPI.SUM)
        eigenvalues, vectors = np.linalg.eigh(gram)
        free = eigenvalues <= 1e-10 * max(eigenvalues[-1], np.finfo(float).tiny)
        result = []
        for v in vectors[:, free].T:
            weights = np.abs(v) / np.abs(v).max()
            result.append((" + ".join(n for n, w in zip(names, weights) if w > 1e-6), v))
        return result


def rigid_mode_values(V, coefficients: np.ndarray) -> np.ndarray:
    """The rigid motion Σ c_k w_k (modes of :func:`_rigid_modes` on the centred, scaled
    coordinates of :meth:`DirichletParts.free_rigid_motions`) at V's dofs, unrolled (local
    dofs, ghosts included; collective)."""
    mesh, comm = V.mesh, V.mesh.comm
    dim = V.dofmap.index_map_bs
    lo = np.min(comm.allgather(mesh.geometry.x.min(axis=0)), axis=0)
    hi = np.max(comm.allgather(mesh.geometry.x.max(axis=0)), axis=0)
    size = max(float(np.max(hi - lo)), np.finfo(float).tiny)
    x = (node_coordinates(V) - 0.5 * (lo + hi)) / size
    _, modes = _rigid_modes(dim)
    return sum(float(c) * np.asarray(m(x), dtype=np.float64)
               for c, m in zip(coefficients, modes)).ravel()


def rigid_mode_expressions(mesh, centre: np.ndarray, size: float) -> list:
    """The rigid modes of :func:`_rigid_modes` as UFL vectors of x, on coordinates centred at
    ``centre`` and scaled by ``size`` (as :meth:`DirichletParts.free_rigid_motions` uses)."""
    dim = mesh.geometry.dim
    x = ufl.SpatialCoordinate(mesh)
    y = [(x[i] - float(centre[i])) / size for i in range(dim)]
    e = [ufl.as_vector([1.0 if j == i else 0.0 for j in range(dim)]) for i in range(dim)]
    if dim == 2:
        return e + [ufl.as_vector([-y[1], y[0]])]
    if dim == 3:
        return e + [ufl.as_vector([0.0 * y[0], -y[2], y[1]]), ufl.as_vector([y[2], 0.0 * y[0], -y[0]]),
                    ufl.as_vector([-y[1], y[0], 0.0 * y[0]])]
    return e


def _rigid_modes(dim: int):
    """Names and functions x (n, 3) -> (n, dim) of the rigid motions in ``dim`` dimensions."""
    e = np.eye(dim)
    names = [f"translation along {'xyz'[i]}" for i in range(dim)]
    modes = [lambda x, i=i: np.broadcast_to(e[i], (len(x), dim)) for i in range(dim)]
    if dim == 2:
        names.append("rotation about z")
        modes.append(lambda x: np.column_stack([-x[:, 1], x[:, 0]]))
    elif dim == 3:
        names += ["rotation about x", "rotation about y", "rotation about z"]
        modes += [lambda x: np.column_stack([0 * x[:, 0], -x[:, 2], x[:, 1]]),
                  lambda x: np.column_stack([x[:, 2], 0 * x[:, 0], -x[:, 0]]),
                  lambda x: np.column_stack([-x[:, 1], x[:, 0], 0 * x[:, 0]])]
    return names, modes
