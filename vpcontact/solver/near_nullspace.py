# SPDX-License-Identifier: MIT
"""The rigid-body modes of a displacement space: the near null space of algebraic multigrid
(GAMG on the displacement formulation, on the P1 level of the p-multigrid cycle, inside SNES VI's
lagged multigrid)."""

from __future__ import annotations

import numpy as np
from petsc4py import PETSc


def rigid_body_modes(V, variables=None, layout=None) -> PETSc.NullSpace:
    """Orthonormal rigid-body modes (translations and rotations) of a vector P_k space, in the
    layout of its PETSc vectors (owned entries): GAMG's near null space for elasticity. With
    ``layout`` (a :class:`~vpcontact.model.fields.FieldLayout`), in the layout of its SNES
    vector (zero in fields other than u). With ``variables`` (a :class:`~vpcontact.solver.
    variables.ChangeOfVariables` whose P is a rotation R: unknowns ũ = Rᵀu in local frames),
    the modes are written in those frames."""
    bs = V.dofmap.index_map_bs
    owned = V.dofmap.index_map.size_local
    # (a bar's one-component space cannot tabulate its coordinates; its one mode is a translation)
    x = V.tabulate_dof_coordinates()[:owned] if bs > 1 else None
    fields = [np.eye(bs)[i] * np.ones((owned, 1)) for i in range(bs)]  # translations
    if bs == 2:
        fields.append(np.column_stack([-x[:, 1], x[:, 0]]))
    elif bs == 3:
        fields += [np.column_stack([-x[:, 1], x[:, 0], 0 * x[:, 0]]),
                   np.column_stack([0 * x[:, 0], -x[:, 2], x[:, 1]]),
                   np.column_stack([x[:, 2], 0 * x[:, 0], -x[:, 0]])]
    comm = V.mesh.comm
    vectors = []
    for field in fields:
        vec = PETSc.Vec().createMPI((owned * bs, None), comm=comm)
        vec.array[:] = field.ravel()
        if layout is not None:
            full = layout.embed(vec, 0.0)
            if full.handle != vec.handle:
                vec.destroy()
                vec = PETSc.Vec().createMPI((full.getLocalSize(), None), comm=comm)
                vec.array[:] = full.getArray(readonly=True)
                full.destroy()
        if variables is not None:
            physical = vec.copy()
            variables.to_snes(physical, vec)
            physical.destroy()
        vectors.append(vec)
    for i, vec in enumerate(vectors):
        for prev in vectors[:i]:
            vec.axpy(-vec.dot(prev), prev)
        vec.normalize()
    return PETSc.NullSpace().create(vectors=vectors, comm=comm)
