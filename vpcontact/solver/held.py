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
∫ ε (u − u_{n−1}) · m dx — and reported (summary.json). Above :data:`NO_EQUILIBRIUM` of the
forces on the body the body is not held (it lifts off, or is pushed along a frictionless face or
beyond its friction) and the step is refused.

Those forces are measured by a scale that does not vanish when the body is unloaded:

    F_ref = max(F_n, F_{n−1}, UNLOADED · max_m F_m, ROUND_OFF_STRAIN · G L^{d−1}),

F the sum of |f| over the loads, reactions and contact forces at a step (:meth:`~vpcontact.solver.
support_forces.SupportForces.applied_size`). The step's displacement change, on which the spring
acts, is caused by the change from F_{n−1} to F_n; so a body unloaded to exactly zero (or through
zero), whose spring carries about STIFFNESS of the forces it had a step before while its
contacts carry the same (F_n is then the spring's own footprint: the ratio F_spring/F_n was 1,
and the run stopped), is in equilibrium. A body pulled off, or pushed along a frictionless face,
has its spring carry the net load (a share of F_n near 1) and is refused as before. A body whose
forces fall below UNLOADED of the largest they have been is unloaded: nothing presses it onto the
contacts that hold it, so they no longer fix its rigid motions; it is kept where it is (the
spring), and the run says so once (:attr:`HeldByContacts.warnings`, summary.json).

Before the run, a scene whose loads push the body along a free motion that no contact part can
resist (every contact normal perpendicular to it, and no friction) is refused outright
(:func:`check_held`).
"""

from __future__ import annotations

from typing import Optional, Sequence

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
#: After a step that did not converge, the body counts as not held only when the spring carries
#: this share of the forces (it drifts off on it): a smaller share on an iterate that is not a
#: solution says nothing, and the step is cut (two frictional faces swapping their load after an
#: exact unloading failed to converge and were reported as "no equilibrium" at 0.025).
DRIFTING = 0.5
#: The body counts as unloaded when the forces on it fall below this share of the largest they
#: have been (the spring's own footprint, about STIFFNESS of them, included).
UNLOADED = 1e-6
#: The force scale's floor: the elastic force of this strain over the body (G L^{d−1}), below
#: which forces are round-off (a body never loaded yet).
ROUND_OFF_STRAIN = 1e-12


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
        self.floor = ROUND_OFF_STRAIN * shear_modulus * extent ** (mesh.topology.dim - 1)
        self.largest_ratio = 0.0
        self.largest_force = 0.0
        self.last_applied = 0.0     # F at the last accepted step
        self.largest_applied = 0.0  # the largest F of the accepted steps
        self.unloaded_at: Optional[float] = None  # the first time the body was unloaded
        self._pending: Optional[tuple[float, float]] = None  # (F, t) of the step being checked

    def terms(self, v, du):
        """(residual, Jacobian) UFL terms of the spring."""
        return (self._eps * ufl.dot(self.u - self.held, v) * ufl.dx,
                self._eps * ufl.dot(du, v) * ufl.dx)

    def carried(self) -> np.ndarray:
        """The spring's generalised force along each free motion (collective)."""
        return np.array([self.comm.allreduce(fem.assemble_scalar(f), op=MPI.SUM)
                         for f in self._forces])

    def reference(self, applied: float) -> float:
        """F_ref of the module docstring for the forces ``applied`` on the body now."""
        return max(applied, self.last_applied, UNLOADED * self.largest_applied, self.floor)

    def check_step(self, applied: float, time: float, share: float = NO_EQUILIBRIUM) -> None:
        """After a converged step: refuse it if the spring carries more than ``share`` of
        F_ref (:meth:`reference`; ``applied``: the size of the loads, reactions and contact
        forces now) along a free motion (collective); after a failed one, ``share`` is
        :data:`DRIFTING`.

        Raises:
            InputError: at ``boundary``: nothing holds the body along that motion.
        """
        forces = np.abs(self.carried())
        carried = float(forces.max(initial=0.0))
        scale = self.reference(applied)
        self._pending = (applied, time)
        if carried > share * scale:
            which = self.names[int(np.argmax(forces))]
            raise InputError(
                f"no equilibrium at t = {time:.6g}: nothing holds the body along its {which} "
                f"(no Dirichlet part removes it, and the contacts do not resist it: the body "
                f"lifts off, or is pushed along a face that cannot hold it, frictionless or "
                f"beyond its friction; the stabilising spring carries {carried / scale:.2g} of "
                f"the forces on the body). Hold it with a "
                "Dirichlet part (clamped, a prescribed displacement or a symmetry plane)",
                key="boundary")
        self.largest_ratio = max(self.largest_ratio, carried / scale)
        self.largest_force = max(self.largest_force, carried)

    def commit(self) -> None:
        """The step is accepted: the spring now ties the body to where it is; its forces are
        the last step's (and the first time they are below UNLOADED of the largest so far,
        the body is unloaded)."""
        self.held.x.array[:] = self.u.x.array
        if self._pending is None:
            return
        applied, time = self._pending
        self._pending = None
        if (self.unloaded_at is None and self.largest_applied > self.floor
                and applied <= UNLOADED * self.largest_applied):
            self.unloaded_at = time
        self.last_applied = applied
        self.largest_applied = max(self.largest_applied, applied)

    @property
    def warnings(self) -> list[str]:
        """What the run should say at its end: that the body was unloaded and then free."""
        if self.unloaded_at is None:
            return []
        return [f"at t = {self.unloaded_at:.6g} the body was unloaded (its forces fell below "
                f"{UNLOADED:g} of their largest): nothing pressed it onto the contacts that hold "
                f"it along its {', '.join(self.names)}, so it was kept where it was until a load "
                "pressed it again"]

    def state(self) -> dict:
        """For a checkpoint (with the held position, :attr:`held`)."""
        return {"last_applied": self.last_applied, "largest_applied": self.largest_applied,
                "unloaded_at": self.unloaded_at}

    def restore(self, state: dict, position: np.ndarray) -> None:
        """Continue from :meth:`state` and the held position of a checkpoint."""
        self.held.x.array[:] = position
        self.last_applied = float(state.get("last_applied", 0.0))
        self.largest_applied = float(state.get("largest_applied", 0.0))
        self.unloaded_at = state.get("unloaded_at")

    def report(self) -> dict:
        """For summary.json."""
        return {"free_rigid_motions": self.names, "coefficient": self.coefficient,
                "largest_force": self.largest_force, "largest_share_of_applied": self.largest_ratio,
                "unloaded_at": self.unloaded_at}


def check_held(mesh, free: Sequence[tuple[str, np.ndarray]], loads_along, contacts,
               facet_tags) -> None:
    """Refuse (InputError at ``boundary``) a free rigid motion along which the loads push
    (``loads_along(coefficients)``: (their generalised force on the motion, its scale)) while
    no contact part can resist it (m · ν = 0 on every contact face, and none resists sliding:
    a frictional face pressed by the loads holds the body along itself)."""
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
            # the normal part of m, and with friction (a part that resists sliding) all of it
            along = ufl.dot(m, m) if part.resists_sliding else ufl.dot(m, n) ** 2
            resisted += comm.allreduce(fem.assemble_scalar(fem.form(along * ds(tag))),
                                       op=MPI.SUM)
            area += comm.allreduce(fem.assemble_scalar(fem.form(ufl.dot(m, m) * ds(tag))),
                                   op=MPI.SUM)
        pushed, scale = loads_along(coefficients)
        if resisted <= 1e-12 * max(area, np.finfo(float).tiny) and abs(pushed) > 1e-9 * scale:
            raise InputError(
                f"the body is not held along its {name}: no Dirichlet part removes that motion, "
                "the loads push the body along it, and no contact part can resist it (every "
                "contact face is parallel to it and frictionless). Hold the body with a "
                "Dirichlet part (clamped, a prescribed displacement or a symmetry plane)",
                key="boundary")
