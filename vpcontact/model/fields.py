# SPDX-License-Identifier: MIT
"""The unknowns of a step: displacement alone, or displacement and pressure (locking-free).

A field layout owns what depends on the choice of unknowns: the stress that enters equilibrium
in terms of them, the forms of the extra equations, and how the unknowns sit in the one PETSc
vector SNES works on. The step solver, the Signorini bounds, the contact frames and the
outputs ask the layout; nothing else needs to know which one it is.

:class:`Displacement` — u ∈ V_h (P_k), the stress σ_q of the constitutive kernels as it is (the
paper's P1/P0 scheme for k = 1).

:class:`DisplacementPressure` — Taylor–Hood: u ∈ P2, p ∈ P1 (the mean stress). Once a von Mises
body flows, the consistent tangent keeps the bulk modulus K while its shear stiffness falls
towards μ*/k: a nearly incompressible response that P1 (and, more slowly, P2) displacements
cannot represent — they *lock*. Here the mean stress is a field of its own:

    σ_h = σ_q + (p − m_q) 1,       m_q = m_0 + K_q (tr ε(u) − tr ε_0),
    β (tr ε(u) − tr ε_0 − (p − m_0)/K, q) = 0   for all q ∈ Q_h,

σ_q the kernels' stress, m_q its mean (exact for an isochoric law: its flow has no volumetric
part, so the kernels' mean stress is elastic, with their bulk modulus K_q), K the material's
bulk modulus (1/K = 0 for ν = 0.5: then the kernels run with a stand-in K_q, see
:meth:`~vpcontact.model.constitutive.Elasticity.kernel_moduli`), m_0 and tr ε_0 the initial
state's. So dev σ_h = dev σ_q and the volumetric stress is p, which the constraint makes the
L2(Q_h)-projection of m_0 + K (tr ε − tr ε_0). A homogeneous state has p = m_q and σ_h = σ_q
exactly. β = 2G/h (G the shear modulus, h the mean cell size) puts the constraint's residual
in the units of the equilibrium residual (forces); with SNES's unknown p/(β s) (s the
displacement scale of :class:`~vpcontact.solver.step_solver.StepSolver`) the Jacobian is
symmetric whenever the kernels' tangent is.

The SNES vector of :class:`DisplacementPressure` is dolfinx's block layout: on each rank its
owned u entries (in V's order), then its owned p entries. u-vectors (bounds, rigid-body modes)
are embedded by :meth:`DisplacementPressure.embed`.
"""

from __future__ import annotations

import math
from typing import Optional, Protocol

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.errors import InputError
from vpcontact.model.locking import FORMULATIONS  # noqa: F401  (re-exported)
from vpcontact.model.quadrature import quadrature_space
from vpcontact.model.tensors import mandel_strain

#: the Schur preconditioner's compliance at a point is at most this many times that of the mean
#: shear stiffness of the cells around each pressure node (see
#: :meth:`DisplacementPressure.schur_preconditioner_form`; at the onset of flow on 44 508
#: unknowns 3 and 10 measured alike, 16 GMRES iterations against 39 uncapped, 30 gave 19)
SCHUR_CONTRAST = 10.0


class FieldLayout(Protocol):
    """The unknowns of a step and their place in the SNES vector.

    Attributes:
        u: the displacement (always the first field).
        functions: every unknown field, u first.
        names: their names (for outputs and checkpoints).
    """

    u: fem.Function
    functions: tuple
    names: tuple

    def stress(self, sigma_q):
        """UFL Mandel vector of the stress in equilibrium, from the kernels' σ_q."""

    def tangent(self, tangent_q, du):
        """UFL dσ_h/du · du (Mandel) from the kernels' tangent."""

    def compile(self, residual_u, jacobian_uu) -> None:
        """Add the layout's own terms to the equilibrium forms and compile them."""

    def create_vector(self) -> PETSc.Vec:
        """A vector laid out like SNES's unknown (ghosted)."""

    def create_matrix(self) -> PETSc.Mat:
        """The Jacobian's matrix."""

    def assemble_residual(self, b: PETSc.Vec, x: PETSc.Vec, bcs, extra=None) -> None:
        """b ← F at the physical state ``x`` (which the functions hold), Dirichlet rows x − g."""

    def assemble_jacobian(self, A: PETSc.Mat, bcs) -> None:
        """A ← J (assembled, Dirichlet rows and columns identity)."""

    def column_scales(self, scale: float) -> Optional[PETSc.Vec]:
        """Physical unknown = column scale × SNES unknown (None: ``scale`` for all)."""

    def to_functions(self, x: PETSc.Vec) -> None:
        """Copy the physical vector ``x`` into the fields (ghosts updated)."""

    def from_functions(self, x: PETSc.Vec) -> None:
        """Copy the fields into ``x``."""

    def embed(self, vec_u: PETSc.Vec, fill: float = 0.0) -> PETSc.Vec:
        """A vector of the layout with ``vec_u``'s owned entries in u's place, ``fill`` elsewhere."""

    def field_indices(self) -> dict:
        """Global indices (PETSc IS) of each field in the layout, by name."""

    def saved_functions(self) -> dict:
        """Functions besides u that a checkpoint must hold, by name."""

    def output_functions(self) -> tuple:
        """Functions besides u for the XDMF series (P1 on the mesh)."""

    def stress_correction(self):
        """UFL scalar added to σ_q's normal components to give σ_h (σ33 too), or None."""


class Displacement:
    """u alone: the displacement formulation (σ_h = σ_q)."""

    names = ("displacement",)

    def __init__(self, u: fem.Function):
        self.u = u
        self.functions = (u,)
        self.F = self.J = None

    def stress(self, sigma_q):
        return sigma_q

    def tangent(self, tangent_q, du):
        dim = self.u.function_space.mesh.topology.dim
        return ufl.dot(tangent_q, mandel_strain(du, dim))

    def compile(self, residual_u, jacobian_uu) -> None:
        self.F = fem.form(residual_u)
        self.J = fem.form(jacobian_uu)

    def create_vector(self) -> PETSc.Vec:
        return fem_petsc.create_vector(self.F)

    def create_matrix(self) -> PETSc.Mat:
        return fem_petsc.create_matrix(self.J)

    def assemble_residual(self, b, x, bcs, extra=None) -> None:
        with b.localForm() as local:
            local.set(0.0)
        fem_petsc.assemble_vector(b, self.F)
        fem_petsc.apply_lifting(b, [self.J], bcs=[bcs], x0=[x], scale=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if extra is not None:
            dofs, values = extra
            b.array[dofs] -= values
        fem_petsc.set_bc(b, bcs, x, -1.0)

    def assemble_jacobian(self, A, bcs) -> None:
        A.zeroEntries()
        fem_petsc.assemble_matrix(A, self.J, bcs=bcs)
        A.assemble()

    def column_scales(self, scale: float) -> Optional[PETSc.Vec]:
        return None

    def physical_vector(self) -> PETSc.Vec:
        """The vector whose values are the physical unknowns: u's own (no copies)."""
        return self.u.vector

    def to_functions(self, x) -> None:
        if x.handle != self.u.vector.handle:
            x.copy(self.u.vector)
        self.u.vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    def from_functions(self, x) -> None:
        if x.handle != self.u.vector.handle:
            self.u.vector.copy(x)

    def embed(self, vec_u, fill: float = 0.0) -> PETSc.Vec:
        return vec_u

    def field_indices(self) -> dict:
        start, end = self.u.vector.getOwnershipRange()
        comm = self.u.function_space.mesh.comm
        return {"displacement": PETSc.IS().createStride(end - start, start, 1, comm=comm)}

    def saved_functions(self) -> dict:
        return {}

    def output_functions(self) -> tuple:
        return ()

    def stress_correction(self):
        return None


class DisplacementPressure:
    """Taylor–Hood P2–P1: displacement and the mean stress p (see the module docstring).

    Args:
        u: the displacement, in a P2 vector space.
        law: the constitutive law; its flow must be isochoric (``law.isochoric``).
        state: the quadrature state (the constraint is integrated with the stress's rule).
    """

    names = ("displacement", "pressure")

    def __init__(self, u: fem.Function, law, state):
        V = u.function_space
        mesh = V.mesh
        if V.ufl_element().degree() != 2:
            raise InputError("the mixed formulation is Taylor–Hood: P2 displacements "
                             f"(degree = 2), got degree {V.ufl_element().degree()}",
                             key="discretization.degree")
        if not getattr(law, "isochoric", False):
            raise InputError("the mixed formulation needs a law whose flow keeps the volume "
                             "(elastic, or Perzyna in 3-D or plane strain); this law's mean "
                             "stress is not K tr ε: use formulation = \"displacement\"",
                             key="discretization.formulation")
        el = law.elasticity
        self.u = u
        self.dim = mesh.topology.dim
        family = "Q" if mesh.ufl_cell().cellname() in ("quadrilateral", "hexahedron") else "Lagrange"
        self.Q = fem.FunctionSpace(mesh, (family, 1))
        self.p = fem.Function(self.Q, name="pressure")
        self.functions = (u, self.p)
        self.measure = state.measure  # the stress quadrature's dx
        self.bulk = el.bulk_modulus
        self.kernel_bulk = el.kernel_bulk_modulus()
        cells = mesh.topology.index_map(self.dim)
        volume = mesh.comm.allreduce(
            fem.assemble_scalar(fem.form(fem.Constant(mesh, 1.0) * ufl.dx(domain=mesh))),
            op=MPI.SUM)
        h = (volume / cells.size_global) ** (1.0 / self.dim)
        self.beta = 2.0 * el.shear_modulus / h
        #: 1/K (0 for incompressible elasticity), UFL
        self.inverse_bulk = fem.Constant(mesh, 0.0 if math.isinf(self.bulk) else 1.0 / self.bulk)
        self._beta = fem.Constant(mesh, self.beta)
        self._Kq = fem.Constant(mesh, self.kernel_bulk)
        # Initial state: m_0 and tr ε_0 per quadrature point (zero unless set).
        space = quadrature_space(mesh, state.degree, 1)
        self.mean_stress_0 = fem.Function(space, name="mean_stress_0")
        self.trace_strain_0 = fem.Function(space, name="trace_strain_0")
        self.F = self.J = None
        self._patch_stiffness: Optional[fem.Function] = None  # 2Ḡ (schur_preconditioner_form)
        self._maps = [(V.dofmap.index_map, V.dofmap.index_map_bs),
                      (self.Q.dofmap.index_map, 1)]
        self._owned = [m.size_local * bs for m, bs in self._maps]

    # -- the stress and the constraint ------------------------------------------------------
    def identity(self):
        """The identity as a Mandel vector (in-plane in 2-D)."""
        size = self.dim * (self.dim + 1) // 2
        return ufl.as_vector([1.0 if i < self.dim else 0.0 for i in range(size)])

    def _trace(self, w):
        return ufl.tr(ufl.sym(ufl.grad(w)))

    def correction(self):
        """p − m_q: what σ_h adds to each normal stress of σ_q (UFL scalar)."""
        m_q = self.mean_stress_0 + self._Kq * (self._trace(self.u) - self.trace_strain_0)
        return self.p - m_q

    def stress(self, sigma_q):
        return sigma_q + self.correction() * self.identity()

    def tangent(self, tangent_q, du):
        self._tangent_q = tangent_q  # for the Schur preconditioner's weight
        e = self.identity()
        return ufl.dot(tangent_q, mandel_strain(du, self.dim)) - self._Kq * self._trace(du) * e

    def compile(self, residual_u, jacobian_uu) -> None:
        dx = self.measure
        v = residual_u.arguments()[0]
        q, dp = ufl.TestFunction(self.Q), ufl.TrialFunction(self.Q)
        du = jacobian_uu.arguments()[1]
        e = self.identity()
        residual_p = self._beta * (self._trace(self.u) - self.trace_strain_0
                                   - (self.p - self.mean_stress_0) * self.inverse_bulk) * q * dx
        j_up = dp * ufl.dot(e, mandel_strain(v, self.dim)) * dx
        j_pu = self._beta * self._trace(du) * q * dx
        j_pp = -self._beta * self.inverse_bulk * dp * q * dx
        self.F = [fem.form(residual_u), fem.form(residual_p)]
        self.J = [[fem.form(jacobian_uu), fem.form(j_up)], [fem.form(j_pu), fem.form(j_pp)]]

    def capture_initial_state(self, state) -> None:
        """m_0 and tr ε_0 from the committed state (σ_{n−1}, ε_{n−1}) before the first step."""
        d = self.dim
        stress, strain = state.view(state.stress_old), state.view(state.strain_old)
        self.mean_stress_0.x.array[:] = stress[:, :d].sum(axis=1) / 3.0
        self.trace_strain_0.x.array[:] = strain[:, :d].sum(axis=1)

    # -- layout -----------------------------------------------------------------------------
    def create_vector(self) -> PETSc.Vec:
        return fem_petsc.create_vector_block(self.F)

    def create_matrix(self) -> PETSc.Mat:
        return fem_petsc.create_matrix_block(self.J)

    def physical_vector(self) -> PETSc.Vec:
        """A block vector for the physical unknowns (the fields are copies of it)."""
        return self.create_vector()

    def assemble_residual(self, b, x, bcs, extra=None) -> None:
        with b.localForm() as local:
            local.set(0.0)
        # Point forces act on free dofs only (the owner filters Dirichlet dofs out), so adding
        # them after the boundary rows are set leaves those rows alone.
        fem_petsc.assemble_vector_block(b, self.F, self.J, bcs=bcs, x0=x, scale=-1.0)
        if extra is not None:
            dofs, values = extra
            b.array[dofs] -= values

    def assemble_jacobian(self, A, bcs) -> None:
        A.zeroEntries()
        fem_petsc.assemble_matrix_block(A, self.J, bcs=bcs)
        A.assemble()

    def column_scales(self, scale: float) -> PETSc.Vec:
        vec = self.create_vector()
        vec.array[:self._owned[0]] = scale
        vec.array[self._owned[0]:] = self.beta * scale
        return vec

    def to_functions(self, x) -> None:
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        owned = x.getArray(readonly=True)
        offset = 0
        for f, n in zip(self.functions, self._owned):
            f.vector.array[:] = owned[offset:offset + n]
            f.vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            offset += n

    def from_functions(self, x) -> None:
        offset = 0
        array = x.getArray()
        for f, n in zip(self.functions, self._owned):
            array[offset:offset + n] = f.vector.getArray(readonly=True)
            offset += n
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    def embed(self, vec_u, fill: float = 0.0) -> PETSc.Vec:
        vec = self.create_vector()
        vec.array[:self._owned[0]] = vec_u.getArray(readonly=True)[:self._owned[0]]
        vec.array[self._owned[0]:] = fill
        return vec

    def field_indices(self) -> dict:
        comm = self.u.function_space.mesh.comm
        start = comm.scan(sum(self._owned)) - sum(self._owned)
        n_u, n_p = self._owned
        return {"displacement": PETSc.IS().createStride(n_u, start, 1, comm=comm),
                "pressure": PETSc.IS().createStride(n_p, start + n_u, 1, comm=comm)}

    def saved_functions(self) -> dict:
        return {"pressure": self.p, "mean_stress_0": self.mean_stress_0,
                "trace_strain_0": self.trace_strain_0}

    def output_functions(self) -> tuple:
        return (self.p,)

    def stress_correction(self):
        return self.correction()

    # -- the Schur complement's preconditioner ---------------------------------------------
    def shear_stiffness(self):
        """2G_eff of the kernels' tangent C (UFL): its trace on the complement of the identity
        1, per dimension there — 2G for isotropic elasticity, ~μ*/k where a Perzyna point
        flows."""
        C, e = self._tangent_q, self.identity()
        size = len(e)
        trace = sum(C[i, i] for i in range(size))
        return (trace - ufl.dot(e, ufl.dot(C, e)) / ufl.dot(e, e)) / (size - 1)

    def schur_preconditioner_form(self, scale: float):
        """S_p = −β² s ∫ (w + 1/K) dp q dx: the pressure mass matrix weighted like the Schur
        complement −β² s (B A⁻¹ Bᵀ + M/K) of the Jacobian in SNES's units (the analogue of the
        inverse-viscosity mass matrix of variable-viscosity Stokes), with the compliance
        w = min(1/(2G_eff), c/(2Ḡ)): each point's own, but at most :data:`SCHUR_CONTRAST`
        times that of 2Ḡ, the shear stiffness averaged over the cells of each pressure node
        (:meth:`update_schur_weight`, which must run before each assembly; the forms this
        returns share that one field).

        Why the cap: a pressure unknown loads the displacement unknowns of its node's cells, and
        those are held by every cell around them. Where a thin zone flows (the contact edge at
        the onset of flow: 2G_eff ~ μ*/k, thousands of times below 2G) the points' own
        compliance made S_p thousands of times too compliant there — the exact Schur complement
        lay 25 times below it — and GMRES paid about one iteration per such node; inside a wide
        flowing region the points and their patches agree and the cap does not act (where it
        did, with the patch mean alone, GMRES took 40 % more iterations:
        bench/results/field_split_parts_*.json, from a script that also built the uncapped
        matrix; git history keeps it)."""
        q, dp = ufl.TestFunction(self.Q), ufl.TrialFunction(self.Q)
        if self._patch_stiffness is None:
            self._patch_stiffness = fem.Function(self.Q, name="patch_shear_stiffness")
            self._patch_stiffness.x.array[:] = np.nan  # (until update_schur_weight)
            self._stiffness_moment = fem.form(self.shear_stiffness() * q * self.measure)
            volume = fem_petsc.assemble_vector(fem.form(q * self.measure))
            volume.ghostUpdate(PETSc.InsertMode.ADD, PETSc.ScatterMode.REVERSE)
            self._patch_volume = volume.array.copy()
            volume.destroy()
        compliance = ufl.min_value(1.0 / self.shear_stiffness(),
                                   SCHUR_CONTRAST / self._patch_stiffness)
        factor = -(self.beta ** 2 * scale)
        return fem.form(factor * (compliance + self.inverse_bulk) * dp * q * self.measure)

    def update_schur_weight(self) -> None:
        """2Ḡ at each pressure node: ∫ 2G_eff φ_i dx / ∫ φ_i dx of the current tangent (the
        mean over the node's cells, weighted by its shape function)."""
        moment = fem_petsc.assemble_vector(self._stiffness_moment)
        moment.ghostUpdate(PETSc.InsertMode.ADD, PETSc.ScatterMode.REVERSE)
        self._patch_stiffness.vector.array[:] = moment.array / self._patch_volume
        moment.destroy()
        self._patch_stiffness.x.scatter_forward()

    def split(self, vectors: list) -> list:
        """The u part (owned entries) of vectors in the layout, as u-sized vectors."""
        comm = self.u.function_space.mesh.comm
        parts = []
        for vec in vectors:
            part = PETSc.Vec().createMPI((self._owned[0], None), comm=comm)
            part.array[:] = vec.getArray(readonly=True)[:self._owned[0]]
            parts.append(part)
        return parts
