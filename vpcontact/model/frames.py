# SPDX-License-Identifier: MIT
"""Normals of a contact boundary and local frames in which u_ν ≤ g is a bound on one dof.

Vertex normals. At a node i of Γ3 the outward normal is the normalised vector

    ν_i ∝ ∫_Γ3 φ_i n da,

φ_i the P1 hat function of the node and n the facet normal: an average of the normals of the Γ3
facets around the node, each weighted by ∫ φ_i da over the facet (a third of a triangle's area, half
a segment's length). On a flat part this is the facet normal exactly; on a curved Γ3 meshed with
vertices on the true surface it is a second-order approximation of the true normal at the vertex
(the weights are symmetric about the vertex on a uniform mesh, so the first-order errors of the
two sides cancel); it is what the standard weak form of u_ν ≤ g tests with. It is one assembled
vector, so a node shared by several ranks gets the same normal on each. Only Γ3 facets count: at
the rim of Γ3, where it meets Γ1 or Γ2, the normal is that of the adjacent Γ3 facets (the
neighbouring part's facets do not bend it).

Frames. At each contact node the displacement is written in an orthonormal frame
(t_1, …, ν, …) stored as the columns of a d×d block Q_i; globally ũ = Rᵀu with R block-diagonal
and orthogonal (the identity away from Γ3). The normal takes the *slot* (component index) where
|ν| is largest, with the sign s = sign(ν_slot) that makes s ν close to +e_slot, so
ũ_slot = s u·ν and u_ν ≤ g becomes the bound ũ_slot ≤ g (s > 0) or ũ_slot ≥ −g (s < 0). When ν
is ±e_slot exactly, Q_i is the identity: an axis-aligned Γ3 gives R = I.

Dirichlet components. A component already prescribed at a contact node (a symmetry plane u_x = 0
through the node, say) keeps its own axis as a frame column in its own slot: ν is first projected
onto the complement of the prescribed axes (on a symmetry plane the true normal lies in the plane;
the one-sided average above does not) and the frame is completed in that complement. Prescribed
rows and columns of the Jacobian then stay untouched by RᵀJR. A node whose every component is
prescribed is not a contact node.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.errors import InputError


def vertex_normals(V: fem.FunctionSpace, facet_tags, tag: int) -> np.ndarray:
    """∫_Γ3 φ_i n da for every node of ``V`` (shape (num_owned + num_ghosts, dim)), summed over
    ranks and scattered to ghosts; zero off Γ3.

    For P_k, k > 1, the P1 vectors are interpolated into V (a node on an edge gets the mean of
    its end vertices' vectors): P2's own vertex functions integrate to zero over a triangle, so
    ∫ φ_i n da would give no normal at the vertices of a 3-D face."""
    bs = V.dofmap.index_map_bs
    V1 = V
    if V.ufl_element().degree() != 1:
        V1 = fem.VectorFunctionSpace(V.mesh, ("Lagrange", 1), dim=bs)
    v = ufl.TestFunction(V1)
    ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=facet_tags)(tag)
    vec = fem.petsc.assemble_vector(fem.form(ufl.dot(ufl.FacetNormal(V.mesh), v) * ds))
    vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    vec.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    if V1 is not V:
        weighted = fem.Function(V1)
        vec.copy(weighted.vector)
        weighted.x.scatter_forward()
        interpolated = fem.Function(V)
        interpolated.interpolate(weighted)
        interpolated.x.scatter_forward()
        vec.destroy()
        return interpolated.x.array.reshape(-1, bs).copy()
    with vec.localForm() as local:
        values = local.array.copy()
    vec.destroy()
    return values.reshape(-1, bs)


@dataclass
class Frames:
    """Local frames at contact nodes.

    Attributes:
        nodes: node (block) indices, local to this rank.
        normals: (n, dim) unit outward normals ν.
        slots: the component index holding ν in each frame.
        signs: s with column ``slots`` of the frame = s ν.
        blocks: (n, dim, dim) orthogonal Q with ũ = Qᵀu at the node.
    """

    nodes: np.ndarray
    normals: np.ndarray
    slots: np.ndarray
    signs: np.ndarray
    blocks: np.ndarray

    @property
    def identity(self) -> bool:
        """Every block is the identity (an axis-aligned Γ3: no rotation needed), on this rank."""
        return bool(np.all(self.blocks == np.eye(self.blocks.shape[-1])))


def frames(nodes: np.ndarray, normals: np.ndarray, prescribed: np.ndarray) -> Frames:
    """Frames at ``nodes`` with outward normals ``normals`` (n, dim) and prescribed components
    ``prescribed`` (n, dim) bools (rows with every component prescribed must be left out)."""
    n, dim = normals.shape
    free = ~prescribed
    projected = np.where(free, normals, 0.0)
    length = np.linalg.norm(projected, axis=1)
    if np.any(length <= 1e-8 * np.linalg.norm(normals, axis=1)):
        i = int(np.argmax(length <= 1e-8 * np.linalg.norm(normals, axis=1)))
        raise InputError(f"contact node {i}: its normal {normals[i].round(6).tolist()} lies along "
                         "components prescribed by a Dirichlet part: no normal direction is free",
                             key="boundary")
    nu = projected / length[:, None]
    slots = np.argmax(np.where(free, np.abs(nu), -1.0), axis=1)
    signs = np.where(nu[np.arange(n), slots] >= 0.0, 1.0, -1.0)
    blocks = np.zeros((n, dim, dim))
    for i in range(n):
        blocks[i] = _frame(nu[i], int(slots[i]), float(signs[i]), free[i])
    return Frames(np.asarray(nodes, dtype=np.int32), nu, slots.astype(np.int32), signs, blocks)


def _frame(nu: np.ndarray, slot: int, sign: float, free: np.ndarray) -> np.ndarray:
    """Orthogonal Q with column ``slot`` = sign ν, prescribed axes e_k in their own columns, and
    the other free columns completed by Gram–Schmidt from their own axes (so ν = ±e_slot gives
    Q = I)."""
    dim = len(nu)
    Q = np.eye(dim)
    Q[:, slot] = sign * nu
    done = [slot] + [k for k in range(dim) if not free[k]]
    for k in range(dim):
        if k in done:
            continue
        q = np.eye(dim)[k]
        for j in done:
            q = q - (Q[:, j] @ q) * Q[:, j]
        Q[:, k] = q / np.linalg.norm(q)
        done.append(k)
    return Q


def rotation_matrix(V: fem.FunctionSpace, fr: Frames, fields=None) -> PETSc.Mat:
    """R (AIJ, laid out like the PETSc vectors of V, or like the SNES vector of ``fields``, a
    :class:`~vpcontact.model.fields.FieldLayout` whose owned u entries come first): the identity
    except the blocks Q_i of the owned contact nodes ``fr.nodes``; ũ = Rᵀu. Identity rows store
    one entry, frame rows d."""
    imap = V.dofmap.index_map
    bs = V.dofmap.index_map_bs
    owned = imap.size_local
    start = imap.local_range[0] * bs
    size = owned * bs
    if fields is not None:
        layout = fields.create_vector()
        start, end = layout.getOwnershipRange()
        size = end - start
        layout.destroy()
    keep = fr.nodes < owned
    nodes, blocks = fr.nodes[keep], fr.blocks[keep]
    counts = np.ones(size, dtype=np.int32)
    rows_of = (nodes[:, None] * bs + np.arange(bs)).ravel()
    counts[rows_of] = bs
    indptr = np.zeros(size + 1, dtype=np.int32)
    np.cumsum(counts, out=indptr[1:])
    cols = np.empty(indptr[-1], dtype=np.int32)
    vals = np.empty(indptr[-1])
    identity_rows = np.ones(size, dtype=bool)
    identity_rows[rows_of] = False
    cols[indptr[:-1][identity_rows]] = start + np.flatnonzero(identity_rows)
    vals[indptr[:-1][identity_rows]] = 1.0
    for node, Q in zip(nodes, blocks):
        for i in range(bs):
            r = node * bs + i
            cols[indptr[r]:indptr[r + 1]] = start + node * bs + np.arange(bs)
            vals[indptr[r]:indptr[r + 1]] = Q[i, :]
    R = PETSc.Mat().createAIJWithArrays(((size, None), (size, None)),
                                        (indptr, cols, vals), comm=V.mesh.comm)
    R.assemble()
    return R


def any_rank(comm, flag: bool) -> bool:
    """``flag`` on any rank."""
    return comm.allreduce(bool(flag), op=MPI.LOR)
