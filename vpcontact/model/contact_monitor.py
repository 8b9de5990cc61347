# SPDX-License-Identifier: MIT
"""The nodal normal forces and contact pressures σ_ν of a Signorini part, from the equilibrium
residual at the solution, and the part's :class:`~vpcontact.model.contact_nodes.ContactReport`.

What a node reports (contact.csv's ``pressure``, the XDMF field ``contact_pressure``) is its
normal force over its share of Γ3,

    σ_ν,i = −λ_i / A_i,   λ_i = −ν_i · R_i where node i is on its bound, 0 where it is not,

R_i the residual (σ, ε(v)) − (f, v) at the node (its block of components; point loads there are
applied forces and are left out), λ_i the variational inequality's multiplier of the node's
bound u_ν,i ≤ g_i, and A_i the node's HRZ-lumped share of Γ3
(:func:`~vpcontact.model.nodal_areas.lumped_areas`: positive at every node of every degree, the
row sum ∫_Γ3 φ_i da for P1 and for 2-D P2). Friction divides its nodal force by the same A_i, so
node by node a node off its bound carries no pressure, |t_i| = 𝔣 p_i where it slips and
|t_i| ≤ 𝔣 p_i where it sticks, and Σ_i A_i σ_ν,i is the part's normal force.

For P1 this is the lumped pressure. For P2 it is the mean pressure a node's force stands for:
on a 2-D face a uniform pressure gives that pressure at every node (Simpson's weights), but on a
3-D face the vertex functions integrate to zero over a triangle, so a smooth pressure puts
almost all of the force on the edge midpoints: the vertices report little, the midpoints about
57/48 of the pressure (their forces over HRZ areas of 16/57 of a triangle's each share against
its 1/3). A smooth pressure field on such a face is the total over a region, not a node's value.
(The column was once the P1 interpolant of pressures lumped at the vertices: smooth, but open
edge midpoints next to the contact reported up to 34 % (2-D) and 100 % (3-D) of the peak, and
|t|/p at slipping nodes ranged over 0.002–0.61 for 𝔣 = 0.3: tests/model/
test_nodal_contact_output.py.)
"""

from __future__ import annotations

import numpy as np
from dolfinx import fem
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.model.contact_nodes import ContactDofs, ContactReport
from vpcontact.model.extent import mesh_extent
from vpcontact.model.nodal_areas import lumped_areas

#: A node is on its bound where its clearance g − u_ν is at most this times the mesh's extent
#: (above the round-off of u_ν in a rotated frame and the gaps' linearisation of an obstacle
#: driven by a force, 1e-10 of the extent; far below any clearance a load opens).
ON_BOUND = 1e-9


class ContactMonitor:
    """Nodal normal forces and σ_ν on Γ3 from the equilibrium residual R(u) = (σ, ε(v)) − (f, v)
    at the solution (see the module docstring).

    At a contact node i, ν_i · R_i = ∫_Γ3 σ_ν φ_i da (R_i the block of the node's components):
    the node's normal force is λ_i = −ν_i · R_i where it is on its bound. A point load P at a
    contact node is an applied force like f: R − P is the obstacle's force there
    (:meth:`set_point_loads`).
    """

    def __init__(self, u: fem.Function, cdofs: ContactDofs, equilibrium_form, facet_tags, tag: int):
        self.u = u
        self.cdofs = cdofs
        self._form = fem.form(equilibrium_form)
        self._vec = fem.petsc.create_vector(self._form)
        V = u.function_space
        self.comm = V.mesh.comm
        #: A_i, each node's HRZ-lumped share of Γ3
        self.areas = lumped_areas(V, facet_tags, tag, cdofs.nodes)
        self._tolerance = ON_BOUND * mesh_extent(V.mesh)
        self._points = None  # (PointDofs, time Constant): the point loads, subtracted from R

    def set_point_loads(self, loads, time: fem.Constant) -> None:
        """Subtract the point loads ``loads`` (the problem's located
        :class:`~vpcontact.solver.loads.PointDofs`, F at ``time``) from the residual: they
        are applied forces, not the obstacle's."""
        self._points = (loads, time)

    def _subtract_point_loads(self, vec) -> None:
        """R − P on this rank's owned entries of the assembled (ghost-updated) ``vec``."""
        if self._points is None:
            return
        loads, time = self._points
        t = float(time.value)
        array = vec.array
        for load in loads:
            array[load.dofs] -= load.values(t)

    def on_bound(self) -> np.ndarray:
        """Which nodes are on their bound: clearance g − u_ν ≤ :data:`ON_BOUND` × the extent."""
        cd = self.cdofs
        return cd.gap - cd.normal_displacement(self.u) <= self._tolerance

    def normal_forces(self) -> np.ndarray:
        """λ_i = −ν_i · R_i at the nodes on their bound, 0 at the others (collective)."""
        return np.where(self.on_bound(), -self.nodal_forces(), 0.0)

    def nodal_pressure(self, normal_forces=None) -> np.ndarray:
        """σ_ν,i = −λ_i / A_i at the contact nodes, λ the ``normal_forces`` (default:
        :meth:`normal_forces`; collective then)."""
        lam = self.normal_forces() if normal_forces is None else normal_forces
        return 0.0 - lam / self.areas

    def nodal_forces(self) -> np.ndarray:
        """ν_i · R_i at the contact nodes (= ∫ σ_ν φ_i da; collective)."""
        with self._vec.localForm() as local:
            local.set(0.0)
        fem.petsc.assemble_vector(self._vec, self._form)
        self._vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self._subtract_point_loads(self._vec)
        return self.cdofs.normal_component(self._vec.array)

    def report(self, active_tol: float = 1e-10, normal_forces=None) -> ContactReport:
        """The contact state (collective); ``normal_forces``: the λ_i its pressures are
        reported from (default: :meth:`normal_forces`)."""
        forces = self.nodal_forces()
        lam = np.where(self.on_bound(), -forces, 0.0) if normal_forces is None else normal_forces
        pressure = self.nodal_pressure(lam)
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
