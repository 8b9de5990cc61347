# SPDX-License-Identifier: MIT
"""Signorini contact with a rigid foundation as bounds of a variational inequality.

On a planar Γ3 whose outward normal is a coordinate axis ±e_i, the discrete constraint
u_ν ≤ g on Γ3 is a bound on single displacement dofs: u_i ≤ g(x) where ν = +e_i and
u_i ≥ -g(x) where ν = -e_i. PETSc's SNES VI (``vinewtonrsls``) then solves each time step as
a complementarity problem. Γ3 of any other shape is refused with a clear error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional, Union

import numpy as np
import ufl
from dolfinx import fem
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.errors import InputError
from vpcontact.model.obstacle import LevelSet, gap_along_normal

Gap = Union[float, Callable[[np.ndarray], np.ndarray]]


@dataclass(frozen=True)
class Signorini:
    """Signorini condition u_ν ≤ g, σ_ν ≤ 0, σ_ν (u_ν - g) = 0 on the facets tagged ``tag``.

    Attributes:
        tag: facet tag of Γ3.
        gap: constant gap g ≥ 0 or a function g(x) of points (3, N) -> (N,).
        obstacle: level set φ of a rigid obstacle {φ ≤ 0}; when given, g is the distance to it
            along the outward normal (``gap`` is then ignored).
        max_distance: longest ray searched for the obstacle.
    """

    tag: int
    gap: Gap = 0.0
    obstacle: Optional[LevelSet] = None
    max_distance: float = 1e3

    def __post_init__(self):
        if isinstance(self.gap, (int, float)) and not (math.isfinite(self.gap) and self.gap >= 0):
            raise InputError(f"Signorini gap g must be finite and >= 0, got {self.gap}")


@dataclass
class ContactDofs:
    """Normal displacement dofs of Γ3 (owned by this rank)."""

    axis: int                 # normal = sign * e_axis
    sign: float
    dofs: np.ndarray          # local indices into u.x.array (owned only)
    points: np.ndarray        # (n, 3) coordinates
    gap: np.ndarray           # g at the points

    def normal_displacement(self, u: fem.Function) -> np.ndarray:
        """u_ν at the contact dofs."""
        return self.sign * u.x.array[self.dofs]


def planar_normal(mesh, facet_tags, tag: int, tol: float = 1e-10) -> tuple[int, float]:
    """(axis, sign) with ν = sign · e_axis on the facets ``tag``; InputError if not planar/aligned."""
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(tag)
    n = ufl.FacetNormal(mesh)
    comm = mesh.comm

    def integral(expr):
        return comm.allreduce(fem.assemble_scalar(fem.form(expr * ds)), op=MPI.SUM)

    area = integral(fem.Constant(mesh, 1.0))
    if area <= 0:
        raise InputError(f"the contact boundary (tag {tag}) has no facets")
    dim = mesh.geometry.dim
    mean = np.array([integral(n[i]) for i in range(dim)]) / area
    spread = integral(ufl.dot(n - ufl.as_vector(mean.tolist()), n - ufl.as_vector(mean.tolist()))) / area
    if spread > tol or abs(np.linalg.norm(mean) - 1.0) > tol:
        raise InputError(f"the Signorini contact boundary (tag {tag}) must be planar; its normal "
                         f"varies (mean normal {np.round(mean, 6).tolist()})")
    axis = int(np.argmax(np.abs(mean)))
    if abs(abs(mean[axis]) - 1.0) > 1e-8:
        raise InputError(f"the Signorini contact boundary (tag {tag}) must have an axis-aligned "
                         f"normal; its normal is {np.round(mean, 6).tolist()}")
    return axis, float(np.sign(mean[axis]))


def contact_dofs(V: fem.FunctionSpace, facet_tags, contact: Signorini,
                 exclude: np.ndarray = np.zeros(0, dtype=np.int32)) -> ContactDofs:
    """Locate the normal-component dofs of Γ3 and evaluate the gap there.

    Dofs in ``exclude`` (the Dirichlet dofs: u = 0 there already) are left out, so that clamp
    reactions on the edge shared by Γ1 and Γ3 are not reported as contact forces.
    """
    mesh = V.mesh
    axis, sign = planar_normal(mesh, facet_tags, contact.tag)
    sub = V.sub(axis)
    collapsed, _ = sub.collapse()
    facets = facet_tags.find(contact.tag)
    parent, child = fem.locate_dofs_topological((sub, collapsed), mesh.topology.dim - 1, facets)
    owned = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
    keep = (parent < owned) & ~np.isin(parent, exclude)
    parent, child = parent[keep], child[keep]
    points = collapsed.tabulate_dof_coordinates()[child]
    normal = np.zeros(3)
    normal[axis] = sign
    if contact.obstacle is not None:
        gap = gap_along_normal(contact.obstacle, points, normal, max_distance=contact.max_distance)
    elif callable(contact.gap):
        gap = np.broadcast_to(np.asarray(contact.gap(points.T), dtype=np.float64), (len(points),)).copy()
    else:
        gap = np.full(len(points), float(contact.gap))
    if not np.isfinite(gap).all() or (gap < 0).any():
        raise InputError("the Signorini gap must be finite and >= 0 at every contact point")
    return ContactDofs(axis, sign, parent.astype(np.int32), points, gap)


def variable_bounds(u: fem.Function, cdofs: ContactDofs) -> tuple[PETSc.Vec, PETSc.Vec]:
    """Bounds for SNES VI: -∞ < u < ∞ except u_axis ≤ g (ν = +e) or u_axis ≥ -g (ν = -e) on Γ3."""
    lower = u.vector.duplicate()
    upper = u.vector.duplicate()
    lower.set(PETSc.NINFINITY)
    upper.set(PETSc.INFINITY)
    if cdofs.sign > 0:
        upper.array[cdofs.dofs] = cdofs.gap
    else:
        lower.array[cdofs.dofs] = -cdofs.gap
    for vec in (lower, upper):
        vec.assemble()
    return lower, upper


@dataclass
class ContactReport:
    """Contact state after a step (global over ranks)."""

    active: int                    # contact dofs with u_ν = g
    max_penetration: float         # max (u_ν - g); ≤ 0 up to solver tolerance
    min_pressure: float            # min σ_ν (most compressive)
    max_pressure: float            # max σ_ν; ≤ 0 up to round-off (no adhesion)
    complementarity: float         # max |σ_ν (u_ν - g)|
    normal_force: float            # ∫_Γ3 σ_ν da (sum of nodal normal forces)


class ContactMonitor:
    """Nodal σ_ν on Γ3 from the equilibrium residual R(u) = (σ, ε(v)) - (f, v) at the solution.

    For a Γ3 dof i of the normal component, R_i = ∫_Γ3 σ_ν v_ν da with v_ν = ±φ_i, so the nodal
    contact pressure is σ_ν,i = ν_axis R_i / ∫_Γ3 φ_i da (lumped).
    """

    def __init__(self, u: fem.Function, cdofs: ContactDofs, equilibrium_form, facet_tags, tag: int):
        self.u = u
        self.cdofs = cdofs
        self._form = fem.form(equilibrium_form)
        self._vec = fem.petsc.create_vector(self._form)
        V = u.function_space
        v = ufl.TestFunction(V)
        ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=facet_tags)(tag)
        weights = fem.petsc.assemble_vector(fem.form(v[cdofs.axis] * ds))
        weights.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self.weights = weights.array[cdofs.dofs].copy()
        weights.destroy()
        self.comm = V.mesh.comm

    def nodal_forces(self) -> np.ndarray:
        """ν_axis R_i at the contact dofs (= ∫ σ_ν φ_i da)."""
        with self._vec.localForm() as local:
            local.set(0.0)
        fem.petsc.assemble_vector(self._vec, self._form)
        self._vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return self.cdofs.sign * self._vec.array[self.cdofs.dofs]

    def report(self, active_tol: float = 1e-10) -> ContactReport:
        forces = self.nodal_forces()
        pressure = forces / self.weights
        gap = self.cdofs.normal_displacement(self.u) - self.cdofs.gap
        scale = max(self.comm.allreduce(float(np.max(np.abs(self.cdofs.gap), initial=0.0)), op=MPI.MAX), 1.0)
        active = int(np.count_nonzero(gap >= -active_tol * scale))
        red = self.comm.allreduce
        return ContactReport(
            active=red(active, op=MPI.SUM),
            max_penetration=red(float(np.max(gap, initial=-np.inf)), op=MPI.MAX),
            min_pressure=red(float(np.min(pressure, initial=np.inf)), op=MPI.MIN),
            max_pressure=red(float(np.max(pressure, initial=-np.inf)), op=MPI.MAX),
            complementarity=red(float(np.max(np.abs(pressure * gap), initial=0.0)), op=MPI.MAX),
            normal_force=red(float(np.sum(forces)), op=MPI.SUM))
