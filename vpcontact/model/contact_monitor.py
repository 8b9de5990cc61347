# SPDX-License-Identifier: MIT
"""The nodal contact pressure σ_ν of a Signorini part, from the equilibrium residual at the
solution, and the part's :class:`~vpcontact.model.contact_nodes.ContactReport`."""

from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
import dolfinx.fem.petsc  # noqa: F401  (fem.petsc)
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.model.contact_nodes import ContactDofs, ContactReport
from vpcontact.model.frames import vertex_normals


class ContactMonitor:
    """Nodal σ_ν on Γ3 from the equilibrium residual R(u) = (σ, ε(v)) - (f, v) at the solution.

    At a contact node i, ν_i · R_i = ∫_Γ3 σ_ν φ_i da (R_i the block of the node's components),
    so the nodal contact pressure is σ_ν,i = ν_i · R_i / ∫_Γ3 φ_i da (lumped). A point load P
    at a contact node is an applied force like f: R − P is the obstacle's force there
    (:meth:`set_point_loads`).

    For P2 the lumped weights fail: a vertex function of P2 integrates to zero over a triangle.
    The residual is then also tested with the P1 hat functions (each one a combination of P2
    functions, so ν_a · R¹_a = ∫ σ_ν φ¹_a da exactly), σ_ν is lumped at the vertices as for P1,
    and a node on an edge gets the mean of its end vertices (the P1 interpolant).
    """

    def __init__(self, u: fem.Function, cdofs: ContactDofs, equilibrium_form, facet_tags, tag: int):
        self.u = u
        self.cdofs = cdofs
        self._form = fem.form(equilibrium_form)
        self._vec = fem.petsc.create_vector(self._form)
        V = u.function_space
        v = ufl.TestFunction(V)
        ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=facet_tags)(tag)
        axis = cdofs.axis if cdofs.axis is not None else 0
        weights = fem.petsc.assemble_vector(fem.form(v[axis] * ds))
        weights.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        at = cdofs.dofs if cdofs.axis is not None else cdofs.nodes * V.dofmap.index_map_bs
        self.weights = weights.array[at].copy()
        weights.destroy()
        self.comm = V.mesh.comm
        self._vertices = None
        if V.ufl_element().degree() > 1:
            self._vertices = _VertexPressure(V, equilibrium_form, facet_tags, tag, cdofs)
        self._points = None  # (PointDofs, time Constant): the point loads, subtracted from R

    def set_point_loads(self, loads, time: fem.Constant) -> None:
        """Subtract the point loads ``loads`` (the problem's located
        :class:`~vpcontact.solver.loads.PointDofs`, F at ``time``) from the residual: they
        are applied forces, not the obstacle's (collective)."""
        self._points = (loads, time)
        if self._vertices is not None:
            self._vertices.set_point_loads(self.u.function_space, loads, time)

    def _subtract_point_loads(self, vec: PETSc.Vec) -> None:
        """R − P on this rank's owned entries of the assembled (ghost-updated) ``vec``."""
        if self._points is None:
            return
        loads, time = self._points
        t = float(time.value)
        array = vec.array
        for load in loads:
            array[load.dofs] -= load.values(t)

    def nodal_pressure(self) -> np.ndarray:
        """σ_ν at the contact nodes (lumped; P2: through the vertices, see the class docstring)."""
        if self._vertices is not None:
            return self._vertices.pressure()
        return self.nodal_forces() / self.weights

    def nodal_forces(self) -> np.ndarray:
        """ν_i · R_i at the contact nodes (= ∫ σ_ν φ_i da)."""
        with self._vec.localForm() as local:
            local.set(0.0)
        fem.petsc.assemble_vector(self._vec, self._form)
        self._vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self._subtract_point_loads(self._vec)
        return self.cdofs.normal_component(self._vec.array)

    def report(self, active_tol: float = 1e-10) -> ContactReport:
        forces = self.nodal_forces()
        pressure = self.nodal_pressure()
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


class _VertexPressure:
    """σ_ν lumped at the vertices of Γ3 from the residual tested with P1 hat functions, then
    interpolated to the nodes of the P_k contact dofs (see :class:`ContactMonitor`)."""

    def __init__(self, V, equilibrium_form, facet_tags, tag: int, cdofs: ContactDofs):
        mesh = V.mesh
        bs = V.dofmap.index_map_bs
        V1 = fem.VectorFunctionSpace(mesh, ("Lagrange", 1), dim=bs)
        v = equilibrium_form.arguments()[0]
        v1 = ufl.TestFunction(V1)
        self._form = fem.form(ufl.replace(equilibrium_form, {v: v1}))
        self._vec = fem.petsc.create_vector(self._form)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(tag)
        weights = fem.petsc.assemble_vector(fem.form(v1[0] * ds))
        weights.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        facets = facet_tags.find(tag)
        vertices = fem.locate_dofs_topological(V1, mesh.topology.dim - 1, facets)
        vertices = vertices[vertices < V1.dofmap.index_map.size_local]
        # only the vertices that are contact nodes (not those every Dirichlet part holds, whose
        # residual is a support reaction)
        contact_points = {tuple(x) for x in np.round(cdofs.points, 12)}
        at_vertices = V1.tabulate_dof_coordinates()[vertices]
        keep = np.array([tuple(x) in contact_points for x in np.round(at_vertices, 12)], dtype=bool)
        self._vertices = vertices[keep] if len(vertices) else vertices
        self._weights = weights.array[self._vertices * bs].copy()
        weights.destroy()
        if cdofs.axis is not None:
            normals = np.zeros((len(self._vertices), bs))
            normals[:, cdofs.axis] = cdofs.sign
        else:
            normals = vertex_normals(V1, facet_tags, tag)[self._vertices]
            normals /= np.linalg.norm(normals, axis=1)[:, None]
        self._normals = normals
        self._bs = bs
        self._p1 = fem.Function(fem.FunctionSpace(mesh, ("Lagrange", 1)))
        V0, to_parent = V.sub(0).collapse()
        self._pk = fem.Function(V0)
        # a node on an edge with one end not a contact node takes the other end's value:
        # σ_ν = I(p¹) / I(1 at the contact vertices), I the interpolation into P_k
        self._p1.x.array[self._vertices] = 1.0
        self._p1.x.scatter_forward()
        self._pk.interpolate(self._p1)
        self._share = self._pk.x.array.copy()
        scalar_of_block = np.empty(V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts,
                                   dtype=np.int32)
        scalar_of_block[np.asarray(to_parent) // bs] = np.arange(len(to_parent), dtype=np.int32)
        self._at = scalar_of_block[cdofs.nodes]
        self._V1 = V1
        self._points = None  # (local V1 dofs incl. ghosts, (n, bs) weights, loads, time)

    def set_point_loads(self, V, loads, time: fem.Constant) -> None:
        """The point loads (located :class:`~vpcontact.solver.loads.PointDofs`) tested with the
        P1 hat functions: a load F at a node x_p of V gives φ¹_a(x_p) F at the vertices a of a
        cell around x_p (F at a vertex, F/2 at the ends of an edge whose midpoint it is, …);
        found by the rank that owns the node."""
        V1, bs = self._V1, self._bs
        mesh = V.mesh
        tdim = mesh.topology.dim
        num_cells = mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
        dofmap = V.dofmap.list.array.reshape(num_cells, -1)
        dofmap1 = V1.dofmap.list.array.reshape(num_cells, -1)
        coordinates = V.tabulate_dof_coordinates()
        hat = fem.Function(fem.FunctionSpace(mesh, ("Lagrange", 1)))
        rows, weights, loads = [], [], []
        for load in loads:
            if len(load.dofs) == 0:
                continue
            block = load.dofs[0] // bs
            cell = int(np.flatnonzero((dofmap == block).any(axis=1))[0])
            x = coordinates[block].reshape(1, 3)
            for a in dofmap1[cell]:
                hat.x.array[:] = 0.0
                hat.x.array[a] = 1.0
                w = float(hat.eval(x, np.array([cell], dtype=np.int32))[0])
                if abs(w) > 1e-12:
                    rows.append(a)
                    weights.append(w)
                    loads.append(load)
        self._points = (np.array(rows, dtype=np.int32), np.array(weights), loads, time)

    def pressure(self) -> np.ndarray:
        vec = self._vec
        with vec.localForm() as local:
            local.set(0.0)
        fem.petsc.assemble_vector(vec, self._form)
        if self._points is not None:  # R − P, tested with the P1 hats (before the ghosts add)
            rows, weights, loads, time = self._points
            t = float(time.value)
            with vec.localForm() as local:
                array = local.array
                for a, w, load in zip(rows, weights, loads):
                    array[a * self._bs:(a + 1) * self._bs] -= w * load.values(t)
        vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        blocks = vec.array.reshape(-1, self._bs)[self._vertices]
        self._p1.x.array[:] = 0.0
        self._p1.x.array[self._vertices] = np.einsum("ij,ij->i", blocks, self._normals) / self._weights
        self._p1.x.scatter_forward()
        self._pk.interpolate(self._p1)
        share = self._share[self._at]
        return np.where(share > 0, self._pk.x.array[self._at] / np.where(share > 0, share, 1.0),
                        0.0)
