# SPDX-License-Identifier: MIT
"""Each node's share of a boundary part: positive for any Lagrange degree (HRZ lumping).

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
"""

from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI

from vpcontact.errors import InputError


def lumped_areas(V: fem.FunctionSpace, facet_tags, tag: int, nodes: np.ndarray) -> np.ndarray:
    """HRZ areas A_i (see the module docstring) of the nodes ``nodes`` (block indices of the
    vector space ``V``, owned by this rank) on the facets tagged ``tag``. Collective."""
    mesh = V.mesh
    comm = mesh.comm
    scalar, to_parent = V.sub(0).collapse()
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(tag)
    phi, psi = ufl.TrialFunction(scalar), ufl.TestFunction(scalar)
    matrix = fem.petsc.assemble_matrix(fem.form(phi * psi * ds))
    matrix.assemble()
    diagonal = fem.Function(scalar)
    owned = scalar.dofmap.index_map.size_local
    diagonal.x.array[:owned] = matrix.getDiagonal().getArray(readonly=True)
    diagonal.x.scatter_forward()
    matrix.destroy()
    total = comm.allreduce(float(diagonal.x.array[:owned].sum()), op=MPI.SUM)
    area = comm.allreduce(fem.assemble_scalar(fem.form(fem.Constant(mesh, 1.0) * ds)),
                          op=MPI.SUM)
    if not total > 0:
        raise InputError(f"the contact boundary (tag {tag}) has no facets",
                         key="contact.boundary")
    bs = V.dofmap.index_map_bs
    size = V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts
    scalar_of_block = np.full(size, -1, dtype=np.int64)
    scalar_of_block[np.asarray(to_parent) // bs] = np.arange(len(to_parent))
    return diagonal.x.array[scalar_of_block[np.asarray(nodes)]] * (area / total)
