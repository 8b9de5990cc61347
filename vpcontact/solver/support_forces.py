# SPDX-License-Identifier: MIT
"""The forces that hold the body at the current state: each Dirichlet part's reaction and each
contact part's force, from the equilibrium residual (σ, ε(v)) − (f, v) − P (P the point loads),
or, for a part that reports its own term's force, from that term
(``reports_law_force`` of :class:`~vpcontact.model.contact.ContactPart`).

At a dof that a Dirichlet part prescribes at a contact node (the corner where a pushed face
meets a frictional face) the residual R_j is the support's reaction and the contact law's force
c_j together: the reaction is R_j − c_j, and c_j is the contact part's
(:meth:`~vpcontact.model.contact.ContactPart.prescribed_forces`). Counted as the support's, a
block pushed between two frictional faces (𝔣 = 0.2 and 0.4 under 10 N) needed 5.897 instead of
6 on 32×16 cells, its two corners' friction.
"""

from __future__ import annotations

from typing import Callable, Optional

import numpy as np
from dolfinx import fem
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.solver.dirichlet import rigid_mode_values


class SupportForces:
    """The support and contact forces of a problem (collective calls).

    Args:
        V: the displacement's space.
        dirichlet: the :class:`~vpcontact.solver.dirichlet.DirichletParts`.
        contacts: the contact parts, in order.
        equilibrium_form: the compiled (σ, ε(v)) − (f, v).
        compliance_forces: part index -> (form of its term, owned dofs, vector), for the parts
            that report their term's force.
        point_forces: () -> (dofs, values) of the point loads at the current time, or None
            without point loads.
        load_form: the compiled (f, v) of the applied loads (tractions, body force), for
            :meth:`nodal_loads`, or None.
    """

    def __init__(self, V, dirichlet, contacts: list, equilibrium_form, compliance_forces: dict,
                 point_forces: Optional[Callable] = None, load_form=None):
        self.V, self.dirichlet, self.contacts = V, dirichlet, contacts
        self.comm = V.mesh.comm
        self._equilibrium_form = equilibrium_form
        self._equilibrium_vec = None
        self._compliance_forces = compliance_forces
        self._point_forces = point_forces
        self._load_form = load_form
        for part in contacts:
            part.bind_prescribed(dirichlet.prescribed)

    def support_forces(self, per_part: bool = False, split: bool = False) -> tuple:
        """See :meth:`~vpcontact.solver.problem.QuasistaticProblem.support_forces`."""
        values = self.equilibrium_values()
        shared = [part.prescribed_forces() for part in self.contacts]
        supports = values.copy()
        for dofs, forces in shared:
            np.subtract.at(supports, dofs, forces)
        reactions = self.dirichlet.reactions(supports)
        dim = self.V.dofmap.index_map_bs
        parts = self.contact_forces(values, shared)
        local = np.array([f.reshape(-1, dim).sum(axis=0) for f in parts]).reshape(-1, dim)
        forces = self.comm.allreduce(local, op=MPI.SUM)
        result = (reactions, forces if per_part else forces.sum(axis=0))
        return result + (self.normal_and_tangential(parts),) if split else result

    def contact_forces(self, values: np.ndarray, shared: list) -> list[np.ndarray]:
        """Each contact part's force on the body at this rank's owned dofs (0 elsewhere), from
        the residual ``values`` of :meth:`equilibrium_values` (bounded parts: the multiplier
        of the bound, applied loads left out) or from the part's compliance term, and at the
        prescribed dofs of its nodes its ``shared`` (dofs, forces) (collective)."""
        forces = []
        for i, (part, (held, force)) in enumerate(zip(self.contacts, shared)):
            f = np.zeros(values.size)
            if i in self._compliance_forces:
                form, dofs, vec = self._compliance_forces[i]
                with vec.localForm() as local:
                    local.set(0.0)
                fem.petsc.assemble_vector(vec, form)
                vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
                f[dofs] = 0.0 - vec.array[dofs]  # (R_c is the body's push on the foundation)
            else:
                f[part.force_dofs] = values[part.force_dofs]
            np.add.at(f, held, force)
            forces.append(f)
        return forces

    def normal_and_tangential(self, parts: list[np.ndarray]) -> np.ndarray:
        """The ``split`` of :meth:`support_forces` from each part's nodal forces ``parts``."""
        dim = self.V.dofmap.index_map_bs
        local = np.zeros((len(self.contacts), 1 + dim))
        for i, part in enumerate(self.contacts):
            nodes = part.nodes
            at = nodes.nodes[:, None] * dim + np.arange(dim)
            f = parts[i][at]
            normal = np.einsum("ij,ij->i", f, nodes.normals)
            local[i, 0] = 0.0 - normal.sum()  # (0, not -0, where nothing touches)
            local[i, 1:] = (f - normal[:, None] * nodes.normals).sum(axis=0)
        total = self.comm.allreduce(local, op=MPI.SUM)
        return np.column_stack([total[:, 0], np.linalg.norm(total[:, 1:], axis=1)])

    def equilibrium_values(self) -> np.ndarray:
        """The equilibrium residual (σ, ε(v)) − (f, v) − P at the current state, P the point
        loads, this rank's owned entries (collective): at a node held by a support or an
        obstacle, the force that holds it (a point load there is an applied force, not a
        reaction)."""
        if self._equilibrium_vec is None:
            self._equilibrium_vec = fem.petsc.create_vector(self._equilibrium_form)
        vec = self._equilibrium_vec
        with vec.localForm() as local:
            local.set(0.0)
        fem.petsc.assemble_vector(vec, self._equilibrium_form)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        values = vec.array
        if self._point_forces is not None:
            values = values.copy()
            dofs, forces = self._point_forces()
            np.add.at(values, dofs, -forces)  # (owned dofs: each load on one rank)
        return values

    def applied_size(self) -> float:
        """Σ |f| over the reactions, the contact forces and the applied loads' nodal forces
        (collective): the scale of the forces on the body."""
        reactions, forces = self.support_forces(per_part=True)
        applied = float(np.abs(forces).sum() + np.abs(reactions).sum())
        return applied + self.comm.allreduce(float(np.abs(self.nodal_loads()).sum()),
                                             op=MPI.SUM)

    def nodal_loads(self) -> np.ndarray:
        """This rank's owned entries of the nodal load vector at the current time (tractions,
        body force, point loads)."""
        loads = fem.Function(self.V)
        if self._load_form is not None:
            fem.petsc.assemble_vector(loads.vector, self._load_form)
            loads.vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if self._point_forces is not None:
            dofs, values = self._point_forces()
            loads.x.array[dofs] += values
        return loads.x.array[:self.V.dofmap.index_map.size_local * self.V.dofmap.index_map_bs]

    def load_along(self, coefficients) -> tuple[float, float]:
        """(generalised force L · m of the applied loads on the rigid motion m (its
        ``coefficients``) at the current time, and its scale Σ |L_i m_i|), L the nodal load
        vector (tractions, body force, point loads)."""
        loads = self.nodal_loads()
        products = loads * rigid_mode_values(self.V, coefficients)[:len(loads)]
        return (self.comm.allreduce(float(products.sum()), op=MPI.SUM),
                self.comm.allreduce(float(np.abs(products).sum()), op=MPI.SUM))

