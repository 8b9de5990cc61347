# SPDX-License-Identifier: MIT
"""Vertex-star smoothing for the P2 displacement block of the mixed formulation.

Where a Perzyna body flows, its tangent is k E/μ* times softer (5 000 with the paper's data)
along each point's deviatoric stress direction, and the flow the P2 mesh can represent is
nearly volume-keeping. Such modes are smooth, so point smoothers (Jacobi, Chebyshev–Jacobi)
barely touch them, and the P1 coarse space of the p-multigrid cycle cannot represent them
either (P1 locks under volume-keeping flow): the Krylov count of the field split grew with the
mesh as the body flowed. Solving small patches exactly reaches them: the unknowns of a vertex's
star (the vertex and the midpoints of its edges, for P2) carry the local volume-keeping
motions, as in the patch smoothers of robust multigrid for nearly incompressible elasticity
(Schöberl; Farrell et al.'s augmented-Lagrangian preconditioners).

One sweep solves every star exactly for the same residual and adds the corrections, damped:
y = ω Σ_p R_pᵀ A_pp⁻¹ R_p b, with ω = 1/2 (an edge midpoint lies in two stars, a vertex in
one; undamped, the Krylov solves of the flowing beam diverged, and with ω = 1/2 each sweep
lowers the error's energy on an elasticity matrix: ``tests/solver/test_star_smoother.py``). The blocks
A_pp are factorized (dense LU) in C++ (``cpp_kernels/include/vpcontact/patch_smoother.hpp``)
whenever the matrix changes. On several processes each one smooths its own rows: a star keeps
the unknowns this process owns, and couplings to other processes' unknowns are left out of its
blocks. Measured, and not kept: the multiplicative sweep (each star in turn for the residual its
predecessors left, forward before the coarse correction and backward after it): more Krylov
iterations in the time loop (176.7 against 169.7 per step at 44 508 unknowns) at 1.7× the cost.
"""

from __future__ import annotations

from typing import Optional

import basix
import numpy as np
from dolfinx import fem
from petsc4py import PETSc

from vpcontact import _cpp

#: Damping of the sweep.
DAMPING = 0.5


def vertex_stars(V: fem.FunctionSpace) -> tuple[np.ndarray, np.ndarray]:
    """The vertex stars of a Lagrange vector space as patches of this process's rows.

    For each vertex of this process's cells (its own and its ghosts): the unknowns on the mesh
    entities that contain it (for P2, the vertex and the midpoints of its edges) that this
    process owns, as local indices of V's unrolled unknowns (node × block size + component),
    over the cells this process holds; stars with no such unknown are left out. So every
    unknown this process owns lies in a star.

    Returns:
        (offsets, indices): star p holds indices[offsets[p]:offsets[p + 1]], sorted.
    """
    mesh = V.mesh
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim, 0)
    cell_vertices = mesh.topology.connectivity(tdim, 0).array.reshape(-1, tdim + 1)
    layout = V.dofmap.dof_layout
    topology = basix.topology(basix.cell.string_to_type(mesh.ufl_cell().cellname()))
    cell_nodes = V.dofmap.list.array.reshape(cell_vertices.shape[0], -1)
    vertices, nodes = [], []
    for j in range(tdim + 1):  # the cell's nodes on the entities that contain local vertex j
        star = [dof for d in range(tdim + 1) for e, entity in enumerate(topology[d])
                if j in entity for dof in layout.entity_dofs(d, e)]
        vertices.append(np.repeat(cell_vertices[:, j], len(star)))
        nodes.append(cell_nodes[:, star].ravel())
    vertices = np.concatenate(vertices).astype(np.int64)
    nodes = np.concatenate(nodes).astype(np.int64)
    keep = nodes < V.dofmap.index_map.size_local  # (every vertex's star, ghosts' too: an
    # owned midpoint between two other processes' vertices lies in theirs only)
    width = int(nodes.max(initial=0)) + 1
    vertices, nodes = np.divmod(np.unique(vertices[keep] * width + nodes[keep]), width)
    bs = V.dofmap.index_map_bs
    indices = (nodes[:, None] * bs + np.arange(bs)).ravel()
    starts = np.flatnonzero(np.diff(vertices, prepend=-1)) * bs
    offsets = np.append(starts, indices.size).astype(np.int64)
    return offsets, indices.astype(np.int64)


class StarSmoother:
    """One vertex-star Schwarz sweep on the rows this process owns of a matrix laid out like V's
    unknowns (the displacement block, in SNES's frames where it has them: a star is a set of
    nodes, whatever their components' frame).

    Args:
        stars: (offsets, indices) from :func:`vertex_stars`.
        num_rows: the number of rows this process owns.
    """

    def __init__(self, stars: tuple[np.ndarray, np.ndarray], num_rows: int):
        self._patches = _cpp.PatchSmoother(stars[0], stars[1], num_rows)
        self._indices = stars[1]
        self._owner = np.repeat(np.arange(len(stars[0]) - 1), np.diff(stars[0]))  # per index

    @property
    def singular(self) -> int:
        """The stars whose block was singular at the last :meth:`set_operator` (each is
        smoothed by its diagonal)."""
        return self._patches.singular

    def set_operator(self, A: PETSc.Mat, csr=None, stars: Optional[np.ndarray] = None) -> None:
        """Factorize the stars' blocks of A (its owned rows; other processes' columns left out):
        all of them, or only ``stars`` (:meth:`stars_of`) where A differs from the last matrix
        only in those stars' rows and columns. ``csr``: A's local rows, if already fetched."""
        row_start, columns, values = csr if csr is not None else A.getValuesCSR()
        self._patches.factorize(row_start, columns, values, A.getOwnershipRange()[0], stars)

    def stars_of(self, rows: np.ndarray) -> np.ndarray:
        """The stars that hold any of the local ``rows``."""
        return np.unique(self._owner[np.isin(self._indices, rows)])

    def schur_sum(self, row_start, columns, values, stars: Optional[np.ndarray] = None):
        """Σ_s B_s A_s⁻¹ B_sᵀ over the stars as coordinates (rows, columns, values, starts),
        from the local rows of Bᵀ (CSR, global columns) and the factors of the last
        :meth:`set_operator`; star s's entries are values[starts[s]:starts[s + 1]]. With
        ``stars``, theirs only, in that order (and ``starts`` over them)."""
        return self._patches.schur_sum(row_start, columns, values, stars)

    def solve(self, b: PETSc.Vec, y: PETSc.Vec) -> None:
        """y ← one sweep on A y = b from y = 0."""
        self._patches.apply(b.array_r, y.array, DAMPING)
