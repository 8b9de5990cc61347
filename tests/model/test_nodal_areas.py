# SPDX-License-Identifier: MIT
"""HRZ-lumped nodal areas of a boundary part (vpcontact.model.nodal_areas), checked against
independent numbers: the row sums ∫ φ_i da for P1 (which they must equal), and for P2 on a
triangulated face the reference-facet ratios 1/19 (vertices) and 16/57 (edge midpoints) of each
facet's area, where the row sums are 0 at the vertices."""

import numpy as np
import pytest
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.model.nodal_areas import lumped_areas
from vpcontact.solver import tag_facets


def _face_nodes(V, tags, tag):
    nodes = fem.locate_dofs_topological(V, V.mesh.topology.dim - 1, tags.find(tag))
    return nodes[nodes < V.dofmap.index_map.size_local]


def _row_sums(V, tags, tag, nodes):
    ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=tags)(tag)
    vec = fem_petsc.assemble_vector(fem.form(ufl.TestFunction(V)[0] * ds))
    vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    return vec.array[nodes * V.dofmap.index_map_bs].copy()


@pytest.mark.parametrize("dim", [2, 3])
def test_p1_areas_are_the_row_sums(dim):
    """On a graded mesh (unequal facets) P1's HRZ areas are ∫ φ_i da to round-off: the P1
    friction answers do not move."""
    comm = MPI.COMM_WORLD
    if dim == 2:
        msh = dmesh.create_rectangle(comm, [np.zeros(2), np.ones(2)], [9, 3])
    else:
        msh = dmesh.create_box(comm, [np.zeros(3), np.ones(3)], [5, 4, 2])
    msh.geometry.x[:, 0] = msh.geometry.x[:, 0] ** 2  # graded along x
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[dim - 1], 0.0)})
    V = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
    nodes = _face_nodes(V, tags, 1)
    areas = lumped_areas(V, tags, 1, nodes)
    expected = _row_sums(V, tags, 1, nodes)
    assert np.allclose(areas, expected, rtol=1e-12, atol=0), np.abs(areas - expected).max()
    assert comm.allreduce(float(areas.sum())) == pytest.approx(1.0, rel=1e-12)


def test_p2_areas_on_triangles_are_positive_and_add_up():
    """3-D P2 on the face z = 0 of a box: every node's area is positive where a vertex's row
    sum is 0, and they add up to the face's area. Per facet e HRZ gives a vertex |e|/19 and an
    edge midpoint 16|e|/57, i.e. 3/19 of the vertex's P1 row sum (Σ |e|/3) and 16/19 of the
    midpoint's P2 row sum (also Σ |e|/3)."""
    comm = MPI.COMM_WORLD
    msh = dmesh.create_box(comm, [np.zeros(3), np.ones(3)], [4, 3, 2])
    msh.geometry.x[:, 1] = msh.geometry.x[:, 1] ** 2  # unequal facets
    tags = tag_facets(msh, {1: lambda x: np.isclose(x[2], 0.0)})
    V = fem.VectorFunctionSpace(msh, ("Lagrange", 2))
    nodes = _face_nodes(V, tags, 1)
    areas = lumped_areas(V, tags, 1, nodes)
    assert comm.allreduce(float(areas.min(initial=np.inf)), op=MPI.MIN) > 0
    assert comm.allreduce(float(areas.sum())) == pytest.approx(1.0, rel=1e-12)
    row_sums = _row_sums(V, tags, 1, nodes)
    V1 = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
    p1 = fem.Function(V1)
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)(1)
    fem_petsc.assemble_vector(p1.vector, fem.form(ufl.TestFunction(V1)[0] * ds))
    p1.vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    p1.x.scatter_forward()
    at_p2 = fem.Function(V)
    at_p2.interpolate(p1)  # the P1 row sum at the vertices (and means elsewhere)
    vertex = np.abs(row_sums) < 1e-14
    assert 0 < vertex.sum() < len(nodes) or len(nodes) == 0
    expected = np.where(vertex, 3 / 19 * at_p2.x.array[nodes * 3], 16 / 19 * row_sums)
    assert np.allclose(areas, expected, rtol=1e-12), np.abs(areas - expected).max()
