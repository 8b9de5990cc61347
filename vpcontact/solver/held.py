# SPDX-License-Identifier: MIT
"""Bodies held by their contacts rather than by Dirichlet parts.

A block pressed onto a foundation, or squeezed between two indenters, may have rigid motions that
no Dirichlet part removes: the contacts hold it along their normals, and nothing at all holds it
along a frictionless foundation. Its Jacobian is then singular whenever those motions are free
(before contact closes, and for ever along a frictionless face), although the problem has
solutions. They are found with a weak spring that ties the body to its last accepted position,

    ε ∫_Ω (u − u_{n−1}) · v dx,     ε = STIFFNESS · G / L²

(G the shear modulus, L the mesh's extent): far too weak to change an answer (its force is about
1e-8 of the elastic forces of the same displacement) but enough to remove the singularity. What
it carries is measured after every step — along each free rigid motion m, the generalised force
∫ ε (u − u_{n−1}) · m dx against the loads and contact forces — and reported (summary.json);
above :data:`NO_EQUILIBRIUM` of the applied forces the body is not held (it lifts off, or is
pushed along a frictionless face) and the step is refused.

Before the run, a scene whose loads push the body along a free motion that no contact part can
resist (every contact normal perpendicular to it) is refused outright (:meth:`check`).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from vpcontact.errors import InputError
from vpcontact.solver.dirichlet import rigid_mode_expressions

#: ε relative to G / L².
STIFFNESS = 1e-8
#: Share of the applied forces the spring may carry along a free rigid motion before the body
#: counts as not held.
NO_EQUILIBRIUM = 1e-4


class HeldByContacts:
    """The weak spring on a body with free rigid motions (see the module docstring).

    Args:
        u: the displacement.
        free: the free rigid motions, as (name, coefficients) over the rigid modes of
            :func:`~vpcontact.solver.dirichlet.rigid_mode_expressions`.
        shear_modulus: G of the material.
    """

    def __init__(self, u: fem.Function, free: Sequence[tuple[str, np.ndarray]],
                 shear_modulus: float):
        V = u.function_space
        mesh = V.mesh
        self.u = u
        self.comm = mesh.comm
        x = mesh.geometry.x
        lo = np.min(self.comm.allgather(x.min(axis=0)), axis=0)
        hi = np.max(self.comm.allgather(x.max(axis=0)), axis=0)
        extent = float(np.max(hi - lo))
        self.coefficient = STIFFNESS * shear_modulus / extent ** 2
        self.held = fem.Function(V, name="held_position")  # u_{n−1}
        self._eps = fem.Constant(mesh, self.coefficient)
        modes = rigid_mode_expressions(mesh, 0.5 * (lo + hi), extent)
        self.names = [name for name, _ in free]
        self.modes = [sum(float(c) * m for c, m in zip(coefficients, modes))
                      for _, coefficients in free]
        self._forces = [fem.form(ufl.dot(self._eps * (u - self.held), m) * ufl.dx)
                        for m in self.modes]
        self.largest_ratio = 0.0
        self.largest_force = 0.0

    def terms(self, v, du):
        """(residual, Jacobian) UFL terms of the spring."""
        return (self._eps * ufl.dot(self.u - self.held, v) * ufl.dx,
                self._eps * ufl.dot(du, v) * ufl.dx)

    def carried(self) -> np.ndarray:
        """The spring's generalised force along each free motion (collective)."""
        return np.array([self.comm.allreduce(fem.assemble_scalar(f), op=MPI.SUM)
                         for f in self._forces])

    def check_step(self, applied: float, time: float) -> None:
        """After a converged step: refuse it if the spring carries more than NO_EQUILIBRIUM of
        ``applied`` (the size of the applied and contact forces) along a free motion."""
        forces = np.abs(self.carried())
        ratio = float(forces.max(initial=0.0)) / max(applied, np.finfo(float).tiny)
        if applied == 0.0 and forces.max(initial=0.0) == 0.0:
            ratio = 0.0
        if ratio > NO_EQUILIBRIUM:
            which = self.names[int(np.argmax(forces))]
            raise InputError(
                f"no equilibrium at t = {time:.6g}: nothing holds the body along its {which} "
                f"(no Dirichlet part removes it, and the contacts do not resist it: the body "
                f"lifts off or is pushed along a frictionless face; the stabilising spring "
                f"carries {ratio:.2g} of the applied forces). Hold it with a Dirichlet part "
                "(clamped, a prescribed displacement or a symmetry plane)", key="boundary")
        self.largest_ratio = max(self.largest_ratio, ratio)
        self.largest_force = max(self.largest_force, float(forces.max(initial=0.0)))

    def commit(self) -> None:
        """The step is accepted: the spring now ties the body to where it is."""
        self.held.x.array[:] = self.u.x.array

    def report(self) -> dict:
        """For summary.json."""
        return {"free_rigid_motions": self.names, "coefficient": self.coefficient,
                "largest_force": self.largest_force, "largest_share_of_applied": self.largest_ratio}


def check_held(mesh, free: Sequence[tuple[str, np.ndarray]], loads_along, contacts,
               facet_tags) -> None:
    """Refuse (InputError at ``boundary``) a free rigid motion along which the loads push
    (``loads_along(coefficients)``: (their generalised force on the motion, its scale)) while
    no contact part can resist it (m · ν = 0 on every contact face)."""
    comm = mesh.comm
    x = mesh.geometry.x
    lo = np.min(comm.allgather(x.min(axis=0)), axis=0)
    hi = np.max(comm.allgather(x.max(axis=0)), axis=0)
    extent = float(np.max(hi - lo))
    modes = rigid_mode_expressions(mesh, 0.5 * (lo + hi), extent)
    n = ufl.FacetNormal(mesh)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    for name, coefficients in free:
        m = sum(float(c) * mode for c, mode in zip(coefficients, modes))
        resisted = 0.0
        area = 0.0
        for part in contacts:
            tag = part.law.tag
            resisted += comm.allreduce(fem.assemble_scalar(fem.form(ufl.dot(m, n) ** 2
                                                                    * ds(tag))), op=MPI.SUM)
            area += comm.allreduce(fem.assemble_scalar(fem.form(ufl.dot(m, m) * ds(tag))),
                                   op=MPI.SUM)
        pushed, scale = loads_along(coefficients)
        if resisted <= 1e-12 * max(area, np.finfo(float).tiny) and abs(pushed) > 1e-9 * scale:
            raise InputError(
                f"the body is not held along its {name}: no Dirichlet part removes that motion, "
                "the loads push the body along it, and no contact part can resist it (every "
                "contact face is parallel to it: contact is frictionless). Hold the body with a "
                "Dirichlet part (clamped, a prescribed displacement or a symmetry plane)",
                key="boundary")
