# SPDX-License-Identifier: MIT
"""What SNES evaluates in a step (:class:`StepAssembly`): the residual and the Jacobian at its
unknown x, the loads, and the passage between x and the fields — as dolfinx keeps the forms and
their assembly (``NonlinearProblem``) apart from the Newton solver that calls them.

SNES works on x = u / scale (and the layout's own scale for other fields, see
:meth:`~vpcontact.model.fields.FieldLayout.column_scales`), through a change of variables
u = P x̃ where there is one (:class:`~vpcontact.solver.variables.ChangeOfVariables`: SNES then
solves Pᵀ F(P x̃) = 0 with Jacobian Pᵀ J P); residuals stay in physical units. Before every
evaluation the iterate is loaded into the fields and the refresh hook runs (the quadrature
stresses and tangents, from the C++ kernels), unless it is the iterate loaded last.
"""

from __future__ import annotations

import time as _time
from typing import Callable, Optional, Sequence

import numpy as np
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc


class StepAssembly:
    """SNES's residual and Jacobian of a step, and its vectors (see the module docstring).

    Args:
        fields: the unknowns, their compiled forms and their layout in the SNES vector.
        bcs: Dirichlet conditions.
        refresh: called after the iterate is copied into the fields and before assembling.
        variables: the change of variables u = P x̃, or None.
        nodal_terms: the nodal terms (they add to the residual and the Jacobian at x).
        scale: SNES's displacement scale.
        load: UFL form of the applied loads, or None.
        point_forces: called at each residual evaluation; (dofs, values) of nodal forces.
        timings: the step solver's wall times (``kernel``, ``residual``, ``jacobian``), added to.
    """

    def __init__(self, fields, bcs: Sequence, refresh: Callable[[], None], variables,
                 nodal_terms: Sequence, scale: float, load, point_forces, timings: dict):
        self.fields, self.bcs, self._refresh = fields, bcs, refresh
        self._P, self._nodal, self.scale, self.timings = variables, nodal_terms, scale, timings
        driven = variables is not None and not variables.square
        #: SNES's residual vector
        self.b = variables.create_vector() if driven else fields.create_vector()
        self._xp = fields.physical_vector()  # the physical unknowns (u's own vector for u alone)
        self._columns = fields.column_scales(scale)  # None: every column scaled by scale
        self._load = fem.form(load) if load is not None else None
        self._load_vec = (fields.u.vector.duplicate()
                          if load is not None or point_forces is not None else None)
        self._bc_dofs = np.concatenate([bc.dof_indices()[0] for bc in bcs] or
                                       [np.zeros(0, dtype=np.int32)])
        self._b_free = None  # residual without Dirichlet conditions (the round-off scale)
        self._point_forces = point_forces
        #: SNES's Jacobian
        self.A = fields.create_matrix()
        self._b_phys = self._A_phys = None  # physical residual and Jacobian (with P)
        if variables is not None:
            self._b_phys = fields.create_vector()
            self._A_phys = self.A
            fields.assemble_jacobian(self._A_phys, bcs)  # a pattern for PtAP
            self.A = variables.jacobian(self._A_phys)
        #: SNES's unknown
        self.x = variables.create_vector() if driven else fields.create_vector()
        self._xs = None  # scratch: the physical unknowns in SNES units (with P)
        self._loaded = self.x.duplicate()  # the iterate whose refresh is current
        self.loaded_valid = False
        self.kernel_calls = 0

    def assemble_loads(self) -> float:
        """Assemble the applied loads of the step; return their norm (the force scale)."""
        if self._load_vec is None:
            return 0.0
        with self._load_vec.localForm() as local:
            local.set(0.0)
        if self._load is not None:
            fem_petsc.assemble_vector(self._load_vec, self._load)
        self._load_vec.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if self._point_forces is not None:
            dofs, values = self._point_forces()
            self._load_vec.array[dofs] += values
        fem_petsc.set_bc(self._load_vec, self.bcs, scale=0.0)
        return self._load_vec.norm()

    def initial_guess(self) -> None:
        """x from the fields (scaled, in P's unknowns)."""
        self.fields.from_functions(self._xp)
        xs = self.x
        if self._P is not None:
            if self._xs is None:
                self._xs = self._xp.duplicate()
            self._xp.copy(self._xs)
            xs = self._xs
        else:
            self._xp.copy(xs)
        if self._columns is not None:
            xs.pointwiseDivide(xs, self._columns)
        elif self.scale != 1.0:
            xs.scale(1.0 / self.scale)
        if self._P is not None:
            self._P.to_snes(xs, self.x)

    def load_iterate(self, x: PETSc.Vec) -> None:
        """The fields at x, refreshed (not again for the iterate loaded last)."""
        # SNES may evaluate at vectors other than the solution: always copy x into u first.
        # The Jacobian is usually requested at the iterate whose residual was just computed:
        # then u and the quadrature state are current and the kernel need not run again.
        if self.loaded_valid and x.equal(self._loaded):
            return
        start = _time.perf_counter()
        xp = self._xp
        if self._P is None:
            x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            x.copy(xp)
        else:
            self._P.to_physical(x, xp)
        if self._columns is not None:
            xp.pointwiseMult(xp, self._columns)
        elif self.scale != 1.0:
            xp.scale(self.scale)
        self.fields.to_functions(xp)
        self._refresh()
        self.kernel_calls += 1
        x.copy(self._loaded)
        self.loaded_valid = True
        self.timings["kernel"] += _time.perf_counter() - start

    def free_residual_norm(self) -> float:
        """||F|| at the initial guess with no Dirichlet condition applied: the interior
        imbalance and, in the Dirichlet rows, the support reactions (physical units)."""
        self.load_iterate(self.x)
        if self._b_free is None:
            self._b_free = self.fields.create_vector()
        start = _time.perf_counter()
        self.fields.assemble_residual(self._b_free, self._xp, [], self._free_point_forces())
        self.timings["residual"] += _time.perf_counter() - start
        return self._b_free.norm()

    def _free_point_forces(self):
        """(dofs, values) of the point forces at dofs no Dirichlet condition prescribes, or None."""
        if self._point_forces is None:
            return None
        dofs, values = self._point_forces()
        keep = ~np.isin(dofs, self._bc_dofs)
        return dofs[keep], values[keep]

    def residual(self, snes, x: PETSc.Vec, b_snes: PETSc.Vec) -> None:
        """SNES's residual callback: b = F(x) (Pᵀ F with P; the nodal terms added)."""
        self.load_iterate(x)
        start = _time.perf_counter()
        b = b_snes if self._P is None else self._b_phys
        # physical units: b = u - g on Dirichlet rows
        self.fields.assemble_residual(b, self._xp, self.bcs, self._free_point_forces())
        if self._P is not None:
            self._P.residual(b, b_snes)
        for term in self._nodal:
            term.residual(x, b_snes)
        self.timings["residual"] += _time.perf_counter() - start

    def read_multipliers(self, x: PETSc.Vec) -> None:
        """The residual at x, evaluated for the nodal terms: they read their multipliers λ."""
        scratch = self.b.duplicate()
        self.residual(None, x, scratch)
        scratch.destroy()

    def jacobian(self, x: PETSc.Vec, A_snes: PETSc.Mat, bounds: Optional[tuple]) -> None:
        """Assemble SNES's Jacobian at x (Pᵀ J P with P, stabilized within ``bounds``; the
        nodal terms added)."""
        self.load_iterate(x)
        start = _time.perf_counter()
        for term in self._nodal:
            term.prepare_jacobian(x)
        A = A_snes if self._P is None else self._A_phys
        self.fields.assemble_jacobian(A, self.bcs)
        if self._columns is not None:
            A.diagonalScale(None, self._columns)  # d(residual)/dx = d(residual)/du * scales
        elif self.scale != 1.0:
            A.scale(self.scale)  # d(residual)/dx = d(residual)/du * scale
        if self._P is not None:
            self._P.jacobian(A, A_snes)
            self._P.stabilize(A_snes, x, self.b, bounds)
        if self._nodal and not all(term.current(x) for term in self._nodal):
            # (the line search's last residual was elsewhere: λ must be read at x)
            self.read_multipliers(x)
        for term in self._nodal:
            term.jacobian(x, A_snes)
        self.timings["jacobian"] += _time.perf_counter() - start

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for obj in (self.A, self.b, self.x, self._loaded, self._b_free, self._load_vec,
                    self._A_phys, self._b_phys, self._columns, self._xs):
            if obj is not None:
                obj.destroy()
