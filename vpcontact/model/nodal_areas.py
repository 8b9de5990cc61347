# SPDX-License-Identifier: MIT
"""Each node's share of a boundary part, positive for any Lagrange degree (HRZ lumping), and
the local facet size there.

Nodal laws on a contact face (friction on a Signorini part, :mod:`vpcontact.model.nodal_friction`)
need the area A_i a node stands for. The row sum of the boundary mass matrix, ∫_Γ φ_i da, is the
usual choice and is right for P1, but a P2 vertex function integrates to zero over a triangle
(and to h/6 against 2h/3 at the midpoint of a segment): a 3-D P2 face would have nodes with no
area. Hinton, Rock and Zienkiewicz's lumping (HRZ) scales the diagonal of the mass matrix
instead,

    A_i = M_ii · |Γ| / Σ_j M_jj,     M_ij = ∫_Γ φ_i φ_j da,

which is positive for every degree (M_ii = ∫ φ_i² > 0), sums to |Γ| exactly, and on straight
facets equals the element-by-element HRZ areas (every facet's M^e_jj is |e| times a constant of
the reference facet, so the global ratio is each facet's ratio). For P1 it is the row sum:
on a segment M^e_ii = |e|/3 and Σ_j M^e_jj = 2|e|/3, A_i = Σ_e |e|/2; on a triangle |e|/6 of
|e|/2, A_i = Σ_e |e|/3. For P2 segments it is the row sum too (Simpson: |e|/6 and 2|e|/3);
for P2 triangles it is |e|/19 at vertices and 16|e|/57 at edge midpoints (the row sums: 0 and
|e|/3).

Friction's stick stiffness is a traction per length, STICK_STIFFNESS · G / h_i with h_i the size
of the facets around node i (:func:`facet_sizes`, weighted the same way): a sticking node then
moves by 1e-2 of the elastic displacement a traction causes over one facet, on any mesh, graded
or not, and the stiffness does not change when the body is turned.
"""

from __future__ import annotations

import numpy as np
import ufl
from ufl.geometry import FacetJacobianDeterminant
from dolfinx import fem
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI

from vpcontact.errors import InputError


def _diagonal(scalar: fem.FunctionSpace, ds, weight=1.0) -> fem.Function:
    """diag(∫_Γ weight φ_i φ_j da) as a function of ``scalar`` (ghosts updated). Collective."""
    phi, psi = ufl.TrialFunction(scalar), ufl.TestFunction(scalar)
    matrix = fem.petsc.assemble_matrix(fem.form(weight * phi * psi * ds))
    matrix.assemble()
    diagonal = fem.Function(scalar)
    owned = scalar.dofmap.index_map.size_local
    diagonal.x.array[:owned] = matrix.getDiagonal().getArray(readonly=True)
    diagonal.x.scatter_forward()
    matrix.destroy()
    return diagonal


def at_blocks(V: fem.FunctionSpace, to_parent, values: np.ndarray, nodes) -> np.ndarray:
    """``values`` of V's collapsed scalar space at the block indices ``nodes`` of V."""
    bs = V.dofmap.index_map_bs
    size = V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts
    scalar_of_block = np.full(size, -1, dtype=np.int64)
    scalar_of_block[np.asarray(to_parent) // bs] = np.arange(len(to_parent))
    return values[scalar_of_block[np.asarray(nodes)]]


def lumped_areas(V: fem.FunctionSpace, facet_tags, tag: int, nodes: np.ndarray) -> np.ndarray:
    """HRZ areas A_i (see the module docstring) of the nodes ``nodes`` (block indices of the
    vector space ``V``, owned by this rank) on the facets tagged ``tag``. Collective."""
    mesh = V.mesh
    comm = mesh.comm
    scalar, to_parent = V.sub(0).collapse()
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(tag)
    diagonal = _diagonal(scalar, ds)
    owned = scalar.dofmap.index_map.size_local
    total = comm.allreduce(float(diagonal.x.array[:owned].sum()), op=MPI.SUM)
    area = comm.allreduce(fem.assemble_scalar(fem.form(fem.Constant(mesh, 1.0) * ds)),
                          op=MPI.SUM)
    if not total > 0:
        raise InputError(f"the contact boundary (tag {tag}) has no facets",
                         key="contact.boundary")
    return at_blocks(V, to_parent, diagonal.x.array, nodes) * (area / total)


def facet_size(mesh):
    """A facet's size h_F (UFL): its length in 2-D, the square root of its area in 3-D, 1 for
    the point facets of 1-D."""
    fdim = mesh.topology.dim - 1
    if fdim == 0:
        return fem.Constant(mesh, 1.0)
    if mesh.ufl_domain().is_piecewise_linear_simplex_domain():
        return ufl.FacetArea(mesh) ** (1.0 / fdim)
    # FFCx has no FacetArea on quadrilaterals, hexahedra and curved (second-order) cells: there
    # the facet Jacobian's determinant is the size of a straight edge or of a parallelogram face
    # (the reference facets [0, 1] and [0, 1]² measure 1; a triangle's measures 1/2), pointwise
    # on a curved one
    reference = 0.5 if mesh.ufl_cell().is_simplex() and fdim == 2 else 1.0
    return (reference * abs(FacetJacobianDeterminant(mesh))) ** (1.0 / fdim)


def facet_sizes(V: fem.FunctionSpace, facet_tags, tag: int):
    """The local facet size at the nodes of Γ (the facets tagged ``tag``): the HRZ-weighted
    mean of the sizes h_F of the facets around each node,

        h_i = ∫_Γ h_F φ_i² da / ∫_Γ φ_i² da,

    positive at every node of Γ for any degree (1 elsewhere), h_F at every node of a uniform
    face, and unchanged by a rigid motion of the mesh. Returns ``(h, to_parent)``: a function
    of V's collapsed scalar space and that space's map to V's dofs. Collective."""
    mesh = V.mesh
    scalar, to_parent = V.sub(0).collapse()
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(tag)
    weighted, plain = _diagonal(scalar, ds, facet_size(mesh)), _diagonal(scalar, ds)
    on = plain.x.array > 0
    h = fem.Function(scalar, name="facet_size")
    h.x.array[:] = 1.0
    h.x.array[on] = weighted.x.array[on] / plain.x.array[on]
    return h, to_parent


def nodal_facet_sizes(V: fem.FunctionSpace, facet_tags, tag: int, nodes) -> np.ndarray:
    """:func:`facet_sizes` at the block indices ``nodes`` of V. Collective."""
    h, to_parent = facet_sizes(V, facet_tags, tag)
    return at_blocks(V, to_parent, h.x.array, nodes)
