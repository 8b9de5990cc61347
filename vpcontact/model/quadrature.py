# SPDX-License-Identifier: MIT
"""Internal variables at quadrature points.

The stress σ, the strain ε of the last accepted step and the consistent tangent dσ/dε live in
dolfinx "Quadrature" function spaces: one value per quadrature point of the rule that the
equilibrium form is integrated with. The strain of the current iterate is evaluated at those points
by a compiled :class:`dolfinx.fem.Expression`, and the constitutive update runs on the whole array
at once in C++ (see :mod:`vpcontact.kernels`). Nothing loops over points in Python.
"""

from __future__ import annotations

import basix
import numpy as np
import ufl
from dolfinx import fem

from vpcontact.model.tensors import mandel_size, mandel_strain


def quadrature_space(mesh, degree: int, size: int) -> fem.FunctionSpace:
    """Function space holding ``size`` values per quadrature point of the degree-``degree`` rule."""
    cell = mesh.ufl_cell()
    if size == 1:
        element = ufl.FiniteElement("Quadrature", cell, degree, quad_scheme="default")
    else:
        element = ufl.VectorElement("Quadrature", cell, degree, dim=size, quad_scheme="default")
    return fem.FunctionSpace(mesh, element)


def quadrature_points(mesh, degree: int) -> np.ndarray:
    """Reference points of the default rule (the rule FFCx uses for ``quadrature_scheme="default"``)."""
    cell_type = basix.cell.string_to_type(mesh.ufl_cell().cellname())
    points, _ = basix.make_quadrature(basix.QuadratureType.Default, cell_type, degree)
    return points


class QuadratureState:
    """Stress, strain and tangent at the quadrature points of a mesh.

    Arrays are kept in the dof order of the quadrature spaces; :meth:`strain_at_points` maps the
    cell-ordered output of the strain expression to that order once per call.

    Args:
        u: displacement Function whose strain drives the update.
        degree: quadrature degree (1 point per cell for P1 displacements).
    """

    def __init__(self, u: fem.Function, degree: int):
        mesh = u.function_space.mesh
        self.dim = mesh.topology.dim
        self.size = mandel_size(self.dim)
        self.degree = degree
        self.measure = ufl.Measure("dx", domain=mesh, metadata={
            "quadrature_degree": degree, "quadrature_scheme": "default"})
        space = quadrature_space(mesh, degree, self.size)
        self.stress = fem.Function(space, name="stress")
        self.stress_old = fem.Function(space, name="stress_old")
        self.strain_old = fem.Function(space, name="strain_old")
        self.tangent = fem.Function(quadrature_space(mesh, degree, self.size ** 2), name="tangent")

        points = quadrature_points(mesh, degree)
        self._strain_expr = fem.Expression(mandel_strain(u, self.dim), points)
        index_map = mesh.topology.index_map(self.dim)
        self._cells = np.arange(index_map.size_local + index_map.num_ghosts, dtype=np.int32)
        blocks = space.dofmap.list.array.reshape(len(self._cells), -1).ravel()
        self._order = None if np.array_equal(blocks, np.arange(blocks.size)) else blocks
        self.num_points = blocks.size
        self.strain = np.zeros((self.num_points, self.size))

    @property
    def num_cells(self) -> int:
        """Owned plus ghost cells covered by the arrays."""
        return len(self._cells)

    # Views of the Function arrays with one row per quadrature point (no copies).
    def view(self, f: fem.Function) -> np.ndarray:
        """Array view ``(num_points, components)`` of a quadrature Function."""
        return f.x.array.reshape(self.num_points, -1)

    def tangent_view(self) -> np.ndarray:
        """Array view ``(num_points, size, size)`` of the tangent (no copy)."""
        return self.tangent.x.array.reshape(self.num_points, self.size, self.size)

    def strain_at_points(self) -> np.ndarray:
        """Evaluate ε(u) at every quadrature point of owned and ghost cells (Mandel, dof order)."""
        return self.at_points(self._strain_expr, self.strain)

    def expression(self, expr) -> fem.Expression:
        """A compiled UFL expression for :meth:`at_points`, at this rule's points."""
        return fem.Expression(expr, quadrature_points(self.stress.function_space.mesh, self.degree))

    def at_points(self, expression: fem.Expression, out: np.ndarray | None = None) -> np.ndarray:
        """Values of a compiled expression at every quadrature point of owned and ghost cells,
        ``(num_points, components)`` in dof order (into ``out`` when given)."""
        values = expression.eval(self._cells).reshape(self.num_points, -1)
        if out is None:
            out = np.empty_like(values)
        if self._order is None:
            out[:] = values
        else:
            out[self._order] = values
        return out

    def set_stress(self, values: np.ndarray) -> None:
        """Set the current and previous stress from a ``(num_points, size)`` array (e.g. σ0)."""
        self.view(self.stress)[:] = values
        self.view(self.stress_old)[:] = values

    def point_coordinates(self) -> np.ndarray:
        """Physical coordinates ``(num_points, 3)`` of the quadrature points, in dof order."""
        mesh = self.stress.function_space.mesh
        expr = fem.Expression(ufl.SpatialCoordinate(mesh), quadrature_points(mesh, self.degree))
        gdim = mesh.geometry.dim
        values = expr.eval(self._cells).reshape(-1, gdim)
        coords = np.zeros((self.num_points, 3))
        if self._order is None:
            coords[:, :gdim] = values
        else:
            coords[self._order, :gdim] = values
        return coords

    def commit(self) -> None:
        """Accept the step: σ_{n-1} ← σ_n and ε_{n-1} ← ε_n."""
        self.stress_old.x.array[:] = self.stress.x.array
        self.view(self.strain_old)[:] = self.strain

    def rollback(self) -> None:
        """Reject the step: restore σ from σ_{n-1} (ε is recomputed on the next evaluation)."""
        self.stress.x.array[:] = self.stress_old.x.array
