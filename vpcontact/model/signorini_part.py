# SPDX-License-Identifier: MIT
"""A Signorini contact part at run time: its nodes and bounds, a moving obstacle's gaps, the
nodal pressure and report (:class:`SignoriniPart`), and an obstacle pressed by a force, whose
translation is an unknown (:class:`DrivenSignoriniPart`)."""

from __future__ import annotations

from typing import Optional

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from vpcontact.errors import InputError
from vpcontact.model.contact_monitor import ContactMonitor
from vpcontact.model.contact_nodes import (ContactDofs, ContactReport, contact_dofs, contact_gap,
                                           unrolled)
from vpcontact.model.extent import mesh_extent
from vpcontact.model.friction import OUTPUTS, nodal_values
from vpcontact.model.obstacle import gap_along_normal


class SignoriniPart:
    """A Signorini contact part at run time (a :class:`~vpcontact.model.contact.ContactPart`):
    its nodes and bounded dofs, the gap of a moving obstacle, the nodal pressure and the report.
    Its obstacle stays where it is or moves as prescribed (see :class:`DrivenSignoriniPart`
    for one pressed by a force).

    Args:
        law: the condition.
        u: the displacement.
        facet_tags: the mesh's facet tags (Γ3 is ``law.tag``).
        equilibrium: the UFL form (σ, ε(v)) − (f, v), whose residual gives the pressure.
        name: the boundary part's name.
        exclude: dofs held elsewhere (Dirichlet dofs, the nodes of earlier contact parts).
        rotate: see :func:`contact_dofs`.
    """

    bounded = True
    driven = False
    friction = None  # its NodalFriction, with friction
    obstacle_normals = None  # its ObstacleNormalForce, with normals = "obstacle"
    _time = 0.0  # of the last accepted step

    def __init__(self, law, u: fem.Function, facet_tags, equilibrium, name: str,
                 exclude: np.ndarray, rotate: Optional[bool]):
        V = u.function_space
        self.law, self.name, self.u = law, name, u
        self.comm = V.mesh.comm
        self._nodes = contact_dofs(V, facet_tags, law, exclude=exclude, rotate=rotate)
        self.node_blocks = np.unique(self._nodes.nodes).astype(np.int32)
        self.force_dofs = unrolled(V.dofmap.index_map_bs, self.node_blocks, exclude)
        self.monitor = ContactMonitor(u, self._nodes, equilibrium, facet_tags, law.tag)

    @property
    def nodes(self) -> ContactDofs:
        return self._nodes

    @property
    def moving(self) -> bool:
        return self.law.moving

    def snes_defaults(self, linear_law: bool) -> dict:
        """SNES options this part needs: the VI solver, and with friction what its law asks for
        on a rigid obstacle (the law's ``rigid_snes_defaults``,
        :class:`~vpcontact.model.friction.FrictionLaw`: Coulomb's critical-point line search)."""
        needs = {} if self.friction is None else self.friction.friction.rigid_snes_defaults
        return {"snes_type": "vinewtonrsls", **needs}

    @property
    def splits_force(self) -> bool:
        """With friction the outputs split its force into normal and tangential parts."""
        return self.friction is not None

    @property
    def resists_sliding(self) -> bool:
        """With friction it resists the body's motion along its face where it presses."""
        return self.friction is not None

    #: its force is the residual left at its nodes (the bound's multiplier)
    reports_law_force = False

    def nodal_outputs(self) -> tuple:
        return () if self.friction is None else OUTPUTS

    def nodal_values(self, key: str) -> np.ndarray:
        return nodal_values(self.last_friction, key, len(self._nodes.gap))

    def terms(self, u, du, v, normal, ds):
        return None

    def bind_prescribed(self, prescribed: np.ndarray) -> None:
        """(Nothing: its friction learnt the Dirichlet dofs from the step solver.)"""

    def prescribed_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """(local u dofs, values): the forces of its nodal terms (friction, the obstacle's
        normals) on the body at the tangential dofs of its nodes that a Dirichlet part
        prescribes (:meth:`~vpcontact.model.nodal_friction.NodalFriction.prescribed_forces`);
        none without such terms (a prescribed normal component is no bound: no contact force
        there). A dof may come twice."""
        pieces = [term.prescribed_forces() for term in self.solver_terms()]
        if not pieces:
            return np.zeros(0, np.int32), np.zeros(0)
        return (np.concatenate([dofs for dofs, _ in pieces]),
                np.concatenate([values for _, values in pieces]))

    def update(self, time: float) -> None:
        """The gaps at ``time`` (raises InputError where a ray loses the obstacle)."""
        if self.moving:
            self._nodes.gap = contact_gap(self.law, self._nodes, time,
                                          self.u.function_space.mesh.comm)
            if self.obstacle_normals is not None:
                self.obstacle_normals.refresh(time)
        if self.friction is not None and (self.law.translation is not None
                                          or self.law.rotation is not None):
            # the obstacle's points at the nodes' places at the last step, and where they go
            cd, bs = self._nodes, self.u.function_space.dofmap.index_map_bs
            places = cd.points.copy()
            places[:, :bs] += self.u.x.array[cd.nodes[:, None] * bs + np.arange(bs)]
            self.friction.move(self.law.obstacle_motion(self._time, time, places))

    @property
    def last_friction(self) -> Optional[dict]:
        """The accepted step's friction at the nodes: tangential traction (the nodal force over
        the node's area), slip over the step, whether the node slipped; None without."""
        if self.friction is None or self.friction.last is None:
            return None
        last, areas = self.friction.last, self.areas
        return {"traction": last["force"] / areas[:, None],
                "slip": last["slip"], "slips": last["slips"]}

    def solver_terms(self) -> list:
        """Nodal terms of the step's residual and Jacobian (friction, the obstacle's normals), for
        the step solver."""
        return [t for t in (self.friction, self.obstacle_normals) if t is not None]

    def bound_gaps(self) -> np.ndarray:
        """The right-hand sides of the bounds u_ν ≤ g at the nodes."""
        return self._nodes.gap

    def commit(self, time: float, x=None) -> None:
        """The step to ``time`` is accepted (``x``: SNES's unknowns there, for friction)."""
        self._time = time
        if self.friction is not None and x is not None:
            self.friction.commit(x)

    def state(self) -> dict:
        """What a checkpoint must hold to continue (JSON-able)."""
        return {}

    def arrays(self) -> dict:
        """Arrays (this rank's) a checkpoint must hold to continue: friction's nodal history."""
        return {} if self.friction is None else self.friction.arrays()

    def restore(self, state: dict, time: float, arrays: Optional[dict] = None) -> None:
        """Continue from :meth:`state` (and :meth:`arrays`) at ``time``."""
        self._time = time  # the last accepted step's: the next step's slip is the obstacle's
        self.update(time)  # motion from there (from t = 0 it was, 44 % off in the force)
        if self.friction is not None:
            self.friction.restore(arrays or {})

    @property
    def areas(self) -> np.ndarray:
        """A_i, each node's HRZ-lumped share of Γ3 (its pressure and its friction traction are
        its forces over it)."""
        return self.monitor.areas

    def normal_forces(self) -> np.ndarray:
        """λ_i at the nodes: with friction the accepted step's, which its friction's bound
        took (so |t_i| ≤ 𝔣 λ_i / A_i holds to the last digit), else the monitor's (collective)."""
        if self.friction is not None and self.friction.last is not None:
            return self.friction.last["lam"]
        return self.monitor.normal_forces()

    def pressure(self) -> np.ndarray:
        """σ_ν,i = −λ_i / A_i (:mod:`vpcontact.model.contact_monitor`; collective)."""
        return self.monitor.nodal_pressure(self.normal_forces())

    def report(self) -> "ContactReport":
        return self.monitor.report(normal_forces=self.normal_forces())

    def touching(self, tolerance: float) -> bool:
        cd = self._nodes
        return bool(np.any(cd.normal_displacement(self.u) >= cd.gap - tolerance))

    def driving_displacement(self, time: float) -> Optional[float]:
        if self.law.translation is None:
            return None
        d = np.asarray(self.law.translation(time), dtype=float).ravel()
        return float(d[np.argmax(np.abs(d))]) if d.size else 0.0


class DrivenSignoriniPart(SignoriniPart):
    """A rigid obstacle pressed on the body by a force F(t) = F(t) e: it translates by d along
    e, an unknown of each step solved with u (see :mod:`vpcontact.solver.variables`), so that
    the contact force on it balances F(t).

    Over a step the gaps are linear in the unknown δ = d − d_p (:attr:`increment`; d_p the d
    predicted from the last two steps): g_i(d) ≈ g_i(d_p) + (e · ν_i) δ, g_i(d_p) by ray
    casting. The coefficient e · ν_i makes the obstacle's own equation the balance of the
    contact forces along e, Σ σ_ν,i ν_i · e = F(t) · e, exactly (to solver tolerance). It is
    the gap's exact sensitivity ∂g_i/∂d where the contact face is normal to e (any obstacle);
    where the face turns by θ from that (a curved body on a plane) the linearization is off by
    |δ| O(θ²) per step. The obstacle starts touching the body: at set-up it is moved along e
    until the first node's gap closes (a force on an obstacle in free flight has no
    equilibrium).
    """

    driven = True

    def __init__(self, law, u, facet_tags, equilibrium, name: str, exclude, rotate):
        super().__init__(law, u, facet_tags, equilibrium, name, exclude, rotate)
        e = np.zeros(3)
        e[:len(law.force_direction)] = law.force_direction
        self._e = e / np.linalg.norm(e)
        V = u.function_space
        self._bs = V.dofmap.index_map_bs
        cd = self._nodes
        self._slopes = cd.normals @ self._e[:cd.normals.shape[1]]  # e · ν_i
        if cd.unreachable is not None:
            self._slopes[cd.unreachable] = 0.0  # (no contact there)
        self._delta = 1e-6 * mesh_extent(V.mesh)
        self._time = 0.0
        self.increment = 0.0
        self._predicted = self._touching_displacement()
        self._committed = [(0.0, self._predicted)]  # the last two accepted (t, d)
        self._linearize(self._predicted)

    @property
    def direction(self) -> np.ndarray:
        """e, the unit vector the obstacle moves along (3 components)."""
        return self._e

    @property
    def displacement(self) -> float:
        """d = d_p + δ at the current iterate."""
        return self._predicted + self.increment

    # -- the gaps as functions of d ---------------------------------------------------------
    def _gaps_at(self, d: float) -> np.ndarray:
        cd = self._nodes
        normals = np.zeros((len(cd.points), 3))
        normals[:, :cd.normals.shape[1]] = cd.normals
        phi = self.law.obstacle
        shifted = lambda x: phi(np.asarray(x, dtype=np.float64) - d * self._e[:, None])  # noqa: E731
        return gap_along_normal(shifted, cd.points, normals, max_distance=self.law.max_distance,
                                signed=True, check_side=False, may_miss=cd.unreachable)

    def _gaps_in_run(self, d: float, timed: bool = True) -> np.ndarray:
        """:meth:`_gaps_at` once the run has started (collective): a ray that met the obstacle
        at t = 0 and misses it now means that the force has pushed it through the body (the
        message gives the time if ``timed``; :func:`~vpcontact.model.contact.moved_parts` adds
        it itself)."""
        error = None
        try:
            gaps = self._gaps_at(d)
        except InputError as err:
            error = err
        if self.comm.allreduce(error is not None, op=MPI.LOR):
            when = f"at t = {self._time:.6g} " if timed else ""
            raise InputError(
                f"{when}the obstacle pressed by the force has passed through "
                f"the body: the force moved it {abs(d):.4g} along "
                f"{self._e[:self._bs].round(12).tolist()}, past contact nodes whose normal rays "
                "met it at t = 0 (the body does not carry this force: it yields or is too thin "
                "or soft for it). A smaller force, a stiffer or stronger body, or smaller steps "
                "([time] k) if it is only the step's prediction that overshoots",
                key="contact.force", part=self.name)
        return gaps

    def _touching_displacement(self) -> float:
        """The d at which the obstacle, moved along e, first touches a node (collective)."""
        d = 0.0
        for _ in range(60):
            gaps = self._gaps_at(d)
            reach = ~self._nodes.unreachable if self._nodes.unreachable is not None else None
            local = gaps[reach] if reach is not None else gaps
            i = int(np.argmin(local)) if len(local) else -1
            g = float(local[i]) if len(local) else np.inf
            slope = 0.0
            if len(local):
                ahead, behind = (self._gaps_at(d + self._delta), self._gaps_at(d - self._delta))
                rows = np.flatnonzero(reach) if reach is not None else np.arange(len(gaps))
                slope = float(ahead[rows[i]] - behind[rows[i]]) / (2 * self._delta)
            g_min, slope = min(self.comm.allgather((g, slope)))
            if g_min <= 1e-12 * max(1.0, abs(d), self._delta * 1e6):
                return d
            if not slope < 0:
                raise InputError(f"the force's direction {self._e[:self._bs].round(12).tolist()} "
                                 "moves the obstacle away from the contact part (the force must "
                                 "press it on the body)", key="contact.force")
            d -= g_min / slope
        raise InputError("the obstacle cannot be brought into contact along the force's "
                         "direction", key="contact.force")

    def _linearize(self, d: float, timed: bool = True) -> None:
        """The gaps at d = d_p (the bounds: u_ν − (e · ν) δ ≤ g(d_p))."""
        self._predicted, self.increment = d, 0.0
        self._nodes.gap = self._gaps_in_run(d, timed)
        self._bound = self._nodes.gap.copy()

    # -- the part's protocol ----------------------------------------------------------------
    def update(self, time: float) -> None:
        """Predict d at ``time`` from the last two accepted steps and linearize about it."""
        (t1, d1), (t0, d0) = self._committed[-1], self._committed[0]
        d = d1 if t1 == t0 else d1 + (time - t1) / (t1 - t0) * (d1 - d0)
        self._time = time
        self._linearize(d, timed=False)

    def bound_gaps(self) -> np.ndarray:
        return self._bound

    def column(self) -> tuple[np.ndarray, np.ndarray]:
        """(owned unrolled dofs, values): u changes by (e · ν_i) ν_i per unit of δ at node i."""
        cd = self._nodes
        if cd.axis is not None:
            return cd.dofs, self._slopes * cd.sign
        dofs = (cd.nodes[:, None] * self._bs + np.arange(self._bs)).ravel().astype(np.int32)
        return dofs, (self._slopes[:, None] * cd.normals).ravel()

    def bounded_dofs(self) -> np.ndarray:
        """The bounded entries (w̃'s normal slots) of this rank's nodes."""
        return self._nodes.dofs

    def refit(self, tolerance: float) -> bool:
        """After a solve: if the linearized gaps g(d_p) + (e · ν) δ differ from the ray-cast gaps
        at the solved d by more than ``tolerance`` (a length) at some node in contact or within
        that difference of contact, linearize about d
        (the step is then solved again from where it is; the difference shrinks by about θ²
        per round, θ the face's turn from the normal to e). Collective; True if it did."""
        gaps = self._gaps_in_run(self.displacement)
        linear = self._bound + self._slopes * self.increment
        error = np.abs(gaps - linear)
        # the nodes whose contact the error could decide: in contact, or within it of contact
        clearance = np.minimum(gaps, linear) - self._nodes.normal_displacement(self.u)
        near = clearance <= error + tolerance
        if self._nodes.unreachable is not None:
            near &= ~self._nodes.unreachable
        local = float(np.max(error[near], initial=0.0))
        if self.comm.allreduce(local, op=MPI.MAX) <= tolerance:
            return False
        self._linearize(self.displacement)
        return True

    def applied_force(self) -> float:
        """F(t) · e at the step's time."""
        force = np.zeros(3)
        value = np.asarray(self.law.force(self._time), dtype=np.float64).ravel()
        force[:len(value)] = value
        return float(force @ self._e)

    def commit(self, time: float, x=None) -> None:
        self._committed = (self._committed + [(time, self.displacement)])[-2:]
        self._nodes.gap = self._gaps_in_run(self.displacement)  # where the obstacle is now
        if self.friction is not None and x is not None:
            self.friction.commit(x)

    def state(self) -> dict:
        return {"committed": [list(c) for c in self._committed]}

    def restore(self, state: dict, time: float, arrays: Optional[dict] = None) -> None:
        self._committed = [tuple(c) for c in state["committed"]]
        self._time = time
        self._linearize(self._committed[-1][1])
        if self.friction is not None:
            self.friction.restore(arrays or {})

    def driving_displacement(self, time: float) -> Optional[float]:
        d = self.displacement * self._e
        return float(d[np.argmax(np.abs(d))])
