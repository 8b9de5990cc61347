# SPDX-License-Identifier: MIT
"""Coulomb and Tresca friction on a Signorini part: nodal, in the contact frames, beside SNES VI.

Frictionless Signorini is a bound on one unknown per contact node, ũ_ν ≤ g (in the node's
frame, :mod:`vpcontact.model.frames`). Its normal force λ_i ≥ 0 is the variational
inequality's multiplier: at the solution it is what the residual of that unknown asks of the
obstacle, λ_i = −s_i F̃_ν,i (s_i the frame's sign), and 0 where the node is free. At every
iterate λ_i is read so only where the node is on its bound (within SNES VI's tolerance), and is 0
elsewhere: off the bound −s_i F̃_ν,i is an iterate's imbalance, not a contact force, and a
threshold from it gave nodes not yet in contact friction (a rigid cylinder pressed into a
block, whose contact grows: Newton stalled for 50 iterations in steps cut 16-fold; now 3–5
per step). At a solution the two agree (F̃_ν = 0 off the bound). Friction acts on
the node's other (tangential) unknowns as a nodal force with the same return mapping as on a
deformable foundation (:mod:`vpcontact.model.friction`):

    f_trial = f_{n−1} − k_i Δũ_τ,i,   f = f_trial if |f_trial| ≤ b_i, else b_i f_trial/|f_trial|,
    b_i = 𝔣 λ_i (Coulomb) or g_T(x_i) A_i where λ_i > 0 (Tresca),

Δũ_τ,i the node's tangential slip over the step relative to the obstacle (the motion of the
obstacle's point at the node subtracted: its translation, and its rotation about its centre), k_i = STICK_STIFFNESS · G/h_i · A_i, h_i the size of the facets around the node and
A_i its share of Γ3: HRZ-lumped (:mod:`vpcontact.model.nodal_areas`), positive for any degree and
the row sum ∫_Γ3 φ_i da for P1.
The residual of the tangential unknowns gains −f; their Jacobian rows gain −∂f/∂x̃ — in slip this
includes 𝔣 f̂ ∂λ_i/∂x̃ = −𝔣 s_i f̂ (the normal unknown's Jacobian row), whose columns are the
node's neighbours, already in the pattern (with the mixed formulation they include the pressure
unknowns the normal residual depends on). So each step is still one SNES VI solve, semi-smooth
Newton with the exact generalised Jacobian (LU: it is not symmetric).

A node that lands on the obstacle within a step (its gap open at the step's start) slips in
that step by the obstacle's tangential motion only: its own motion in the step is taken as the
approach (it happened, mostly, before it touched), the obstacle's as what moves past it after
it landed. A slider's tip sweeping over the nodes ahead of it drags them with its full Coulomb
force; a cylinder pressed straight into a block gives its landing nodes none (measured there:
19 Newton iterations instead of 24 and a step cut, README).

A step's guess: the problem's, which extrapolates the last steps' motion, if it already solves
the step (a body pressed or dragged steadily: those steps are linear once the stick/slip pattern
stays, and take no Newton iteration); otherwise SNES starts from a sticking guess
(:meth:`NodalFriction.fallback`; from it alone, the steady steps took 3–5 iterations each).

Reversals: from the sticking guess a node that slid in the last step starts on the cone's edge
with no slip yet. Its return mapping then says slip,
whose 2-D tangent is zero: Newton is free to move the node any distance along the face. Where
the load turns back, the node should stick, and Newton instead jumped it across the stick
interval (2b/k wide) and cycled between slipping forward and back (a dragged block pulled back
by 1e−5 / 1e−4 / 1e−3 within a step: 8 / 29 / 23 iterations). So at the initial guess a node is
linearised on the stick branch — unless the obstacle moves along it in the step (a slider
sweeping past: there the slip branch is the right first guess, and the stick one cost the
scratch demo 0.8 iterations per dragging step). The reversals now take 3 / 2 / 2.

Unloading nodes: a node whose cone has shrunk under its old force (λ fell: the trailing end of
a dragged block's face, which slipped outwards while it was pressed) starts beyond it, and its
return mapping says slip, with the zero 2-D tangent, although what the node does is move along
its force until it is back inside (its slip over the step points along its trial force:
Δũ_τ · t_trial > 0, i.e. b < |t_trial| < f_{n−1} · t̂). Newton threw such nodes across the
stick interval (2b/k, about 1.5e−6, against Newton steps of 1e−5) one way and back for 20
iterations while the rest of the face had converged. Such a node is now linearised on the stick
branch, as long as that brings it nearer its cone: held again at the next iteration only if its
excess |t_trial| − b has fallen, and otherwise released to the slip branch for the rest of the
solve (a node that does slip in the end, a corner that keeps slipping outwards, would otherwise
crawl to its slip on the stiff stick tangent). Not where the obstacle moves along the node (as
for reversals). While such nodes are held the step solver's crawl stop waits
(:attr:`NodalTerm.holding`). The dragged block's hard step (its slip zone spreading over the
face, README) took 13 / 15 / 16 / 21 Newton iterations on 64×16 / 128×32 / 256×64 / 512×128
cells and takes 7 / 8 / 10 / 12, none through the Tresca predictor; every other step of the
friction tests takes what it took.

Nodes whose tangential motion a Dirichlet part prescribes (the corner where a pushed face meets
the contact face): the solver's row there is the support's, u = u_D, so the node's friction does
not enter it, but the node still rubs on the obstacle. Its slip is the prescribed motion
relative to the obstacle's, its force the same return mapping, kept in its history and in the
obstacle's equation when a force drives it; the support's reaction there is the equilibrium
residual less that force, and the part's force includes it (:meth:`NodalFriction.
prescribed_forces`, :mod:`vpcontact.solver.support_forces`). Left out, a block pushed by its
left face between two frictional faces (𝔣 = 0.2 and 0.4 under 10 N) needed 5.897 instead of 6
on 32×16 cells: the two corners' friction.

Any Lagrange degree and either field layout (:mod:`vpcontact.model.fields`): Coulomb's threshold
𝔣 λ_i needs no area, and friction acts on the displacement unknowns only, found in SNES's vector
through the layout's ``field_indices()`` (the pressure unknowns of the mixed formulation get no
nodal term).

Tresca's nodal threshold is g_T(x_i) A_i with the HRZ area, not the consistent ∫_Γ3 g_T φ_i da: a
bound must be ≥ 0 at every node, and the consistent share of a P2 vertex is zero on a triangle
for constant g_T (negative for some varying g_T), which would leave that node frictionless
whatever the threshold. g_T(x_i) A_i is positive wherever g_T is, sums to g_T |Γ3| exactly for a
constant threshold, and to ∫ g_T da up to the quadrature error of the lumped rule (O(h²)) for a
varying one; for P1 both are the same to that order.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from vpcontact.model.friction import STICK_STIFFNESS, return_mapping
from vpcontact.model.nodal_areas import nodal_facet_sizes
from vpcontact.model.nodal_terms import ON_BOUND, NodalTerm

#: Newton iterations a Coulomb step may take from the sticking guess before the Tresca
#: predictor (:meth:`NodalFriction.freeze`) starts it again: above the 7–9 of the hardest steps
#: that converge from it (the dragged block's first pressing step on 256×64 and 512×128
#: cells, and since unloading nodes stick, its hard dragging step: 10 and 12), below the crawl
#: of the ones that did not (12–36, README), which the crawl stop
#: (:data:`~vpcontact.solver.retries.CRAWL_ITERATIONS`) now cuts short anyway
SECOND_TRY = 15


class NodalFriction(NodalTerm):
    """The friction of one Signorini part, as nodal terms of the step's SNES residual and
    Jacobian (see the module docstring).

    Args:
        part: the :class:`~vpcontact.model.signorini_part.SignoriniPart` (framed nodes).
        shear_modulus: the body's G.
        facet_tags: the mesh's facet tags (Γ3 is ``part.law.tag``), for the nodal areas.

    Indices: ``u_tangential`` and ``u_slots`` are local indices of u's dofs; ``tangential`` and
    ``slots`` the same unknowns' local positions in SNES's vector (set by :meth:`bind`).
    """

    def __init__(self, part, shear_modulus: float, facet_tags):
        super().__init__(part)
        V = part.u.function_space
        cd = part.nodes
        self.friction = part.law.friction
        self.areas = part.areas
        self.sizes = nodal_facet_sizes(V, facet_tags, part.law.tag, cd.nodes)
        self.stiffness = STICK_STIFFNESS * shear_modulus / self.sizes * self.areas
        self.force_old = np.zeros(self.tangential.shape)  # f_{n−1}
        self.x_old = np.zeros(self.tangential.shape)      # x̃_τ at the last step (SNES units)
        self.shift = np.zeros(self.tangential.shape)      # the obstacle's tangential motion
        self._predicted = np.full(self.tangential.shape, np.nan)  # the step's initial x̃_τ
        self.last: Optional[dict] = None                  # the accepted step's state
        self.touching: Optional[np.ndarray] = None        # on the obstacle (bind, commit)
        # an obstacle driven by a force moves by an unknown d along e: the tangential part of
        # its motion at node i is τ_i · e per unit of d (see :meth:`bind`)
        self._drive = (np.einsum("nkt,k->nt", self.frame_tangents, part.direction[:self.bs])
                       if getattr(part, "driven", False) else None)
        self._drive_row: Optional[int] = None   # δ's global row in SNES's vector
        self._d_old = 0.0                        # the obstacle's d at the last step
        self._frozen: Optional[np.ndarray] = None  # the predictor's thresholds (see freeze)
        self._excess: Optional[np.ndarray] = None  # |t| − b of the unloading nodes held (see
        #                                  _unloading; NaN: not held, −∞: released) in this solve

    def bind(self, scale: float, dirichlet_dofs: np.ndarray, layout) -> None:
        """See :meth:`NodalTerm.bind`; also the row of a force-driven obstacle's unknown."""
        super().bind(scale, dirichlet_dofs, layout)
        if self._drive is not None:  # δ_j: after all the fields' unknowns, on the last rank
            self._drive_row = self.num_fields + self.part.driven_index
            self._d_old = self.part.displacement
        if self.touching is None:  # at the start: the nodes whose gap is closed with u = 0
            self.touching = self.part.bound_gaps() / scale <= ON_BOUND

    # -- the state at an iterate ------------------------------------------------------------
    def _shift(self) -> np.ndarray:
        """The obstacle's tangential motion at the nodes over the step (at this iterate)."""
        if self._drive is None:
            return self.shift
        return self.shift + self._drive * (self.part.displacement - self._d_old)

    def _trial(self, x: np.ndarray):
        shift = self._shift()
        slip = (x[self.tangential] - self.x_old) * self.scale - shift
        slip = np.where(self.touching[:, None], slip, -shift)  # landing: the obstacle moves past
        # (a prescribed tangential row slips too: by its prescribed motion, see prescribed_forces)
        return self.force_old - self.stiffness[:, None] * slip, slip

    def _bound(self, lam: np.ndarray) -> np.ndarray:
        if self._frozen is not None:  # the predictor's fixed thresholds, where pressed
            return np.where(lam > 0, self._frozen, 0.0)
        return self.friction.nodal_bound(lam, self.part.nodes.points, self.areas)

    def _new_solve(self) -> None:
        """A new guess or predictor stage: no unloading node held yet (see :meth:`_unloading`)."""
        self._excess = None
        self.holding = False

    def _unloading(self, st: dict, moving: np.ndarray) -> np.ndarray:
        """The nodes beyond their cone that move along their trial force (Δũ_τ · t_trial > 0:
        the cone shrank under the old force, see the module docstring), touching since the
        step's start, the obstacle not moving along them, and, if held at the last Jacobian of
        this solve, now nearer their cone: linearised on the stick branch; a held node that is
        not nearer is released to the slip branch for the rest of the solve. Remembers the
        held nodes' excess |t_trial| − b (−∞: released) for the next Jacobian."""
        excess = st["size"] - st["bound"]
        along = (st["beyond"] & self.touching & ~moving
                 & (np.einsum("nt,nt->n", st["slip"], st["trial"]) > 0))
        released = np.zeros_like(along)
        if self._excess is not None:
            released = self._excess == -np.inf
            held = ~np.isnan(self._excess) & ~released
            released |= held & (excess >= self._excess)  # (not nearer: slip from now on)
            along &= ~released
        self._excess = np.where(along, excess, np.where(released, -np.inf, np.nan))
        return along

    def move(self, delta: np.ndarray) -> None:
        """The obstacle's points at the nodes move by ``delta`` (N, 3) over the step (a
        translation, a rotation or both): the slip is relative to them."""
        self.shift = np.einsum("nkt,nk->nt", self.frame_tangents, delta[:, :self.bs])

    def state(self, x: np.ndarray, lam: np.ndarray) -> dict:
        """Nodal friction at the iterate x with normal forces λ, this rank."""
        trial, slip = self._trial(x)
        bound = self._bound(lam)
        force = return_mapping(trial, bound)
        size = np.linalg.norm(trial, axis=1)
        return {"lam": lam, "trial": trial, "size": size, "bound": bound, "force": force,
                "slip": slip,
                "beyond": size > bound,  # the return mapping's branch
                # (nodes in contact: λ above the round-off of an inactive node's residual)
                "slips": (size > bound * (1 + 1e-12))
                & (lam > 1e-8 * max(float(lam.max(initial=0.0)), np.finfo(float).tiny))}

    # -- hooks of the step solver --------------------------------------------------------------
    def residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """b ← b − f on the tangential rows (λ read off b first: −s F̃_ν where positive, at
        nodes on their bound; 0 off it — see the module docstring)."""
        xs, values = x.getArray(readonly=True), b.getArray()
        st = self.state(xs, self.read_multipliers(xs, values))
        values[self.tangential] -= np.where(self.free, st["force"], 0.0)
        if self._drive is not None:  # the obstacle feels −f: its equation along e gains Σ f·τe
            # (at every node: one whose tangential motion is prescribed rubs on it too)
            along = self.comm.allreduce(float(np.sum(st["force"] * self._drive)), op=MPI.SUM)
            start, end = x.getOwnershipRange()
            if start <= self._drive_row < end:
                values[self._drive_row - start] += along

    def jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """A ← A − ∂f/∂x̃ on the tangential rows (A assembled without friction; λ of the last
        residual, at the same iterate); with an obstacle driven by a force, also the column and
        the row of its unknown δ (the slip depends on it, and its equation on f). Collective
        (assembles A)."""
        xs = x.getArray(readonly=True)
        st = self.state(xs, self._lam)
        start = A.getOwnershipRange()[0]
        k = self.stiffness * self.scale  # ∂(k slip)/∂x̃
        landing = ~self.touching
        # at the step's initial guess, a node the obstacle does not move along is linearised on
        # the stick branch (see the module docstring: reversals)
        moving = np.any(self._shift(), axis=1)
        holds = np.all(xs[self.tangential] == self._predicted, axis=1) & ~moving
        unloading = self._unloading(st, moving)
        holds |= unloading
        # (the crawl stop waits while unloading nodes are held: retries.CRAWL_ITERATIONS)
        self.holding = self.comm.allreduce(bool(unloading.any()), op=MPI.LOR)
        driven = self._drive is not None
        slope = self.friction.threshold_slope  # ∂b/∂λ (Coulomb's 𝔣), or None
        # one (node, tangential slot a, global columns, values of ∂b_τa/∂x̃_col) per row piece
        entries = []
        for i in range(len(self.slots)):
            rows = self.tangential[i]
            free = self.free[i]
            if not free.any() and not driven:
                continue
            d = len(rows)
            size = np.linalg.norm(st["trial"][i])
            if not st["beyond"][i] or holds[i]:  # stick: f = trial, ∂f/∂slip = −k I
                block = k[i] * np.eye(d)
                direction = None
            else:  # slip: f = b t̂; ∂f/∂slip = −(b/|t|) k (I − t̂t̂ᵀ); ∂f/∂x̃ ∋ t̂ ∂b/∂x̃
                direction = st["trial"][i] / size
                block = st["bound"][i] / size * k[i] * (np.eye(d) - np.outer(direction, direction))
            own = (start + rows).astype(PETSc.IntType)
            coupled = (direction is not None and slope is not None
                       and self._frozen is None and st["lam"][i] > 0)
            if coupled:
                cols, values = self.normal_row(A, i)
                # −∂f/∂x̃ = −f̂ 𝔣 ∂λ/∂x̃ = f̂ 𝔣 s ∂F̃_ν/∂x̃
                factor = slope * self.signs[i]
            for a in range(d):
                if not landing[i]:  # (a landing node's slip does not depend on its unknowns)
                    entries.append((i, a, own, block[a]))
                if driven:  # slip = … − (τ·e) δ: ∂b_τ/∂δ̃ = −block (τ·e)
                    entries.append((i, a, np.array([self._drive_row], dtype=PETSc.IntType),
                                    np.array([-block[a] @ self._drive[i]])))
                if coupled:
                    entries.append((i, a, cols, factor * direction[a] * values))
        for i, a, cols, values in entries:  # (a prescribed row keeps the solver's: u − u_D)
            if self.free[i, a]:
                A.setValues(int(start + self.tangential[i][a]), cols, values,
                            addv=PETSc.InsertMode.ADD_VALUES)
        if driven:  # b_δ gains Σ f·(τ·e): its row is −Σ (τ·e)ᵀ ∂b_τ/∂x̃
            for i, a, cols, values in entries:
                A.setValues(self._drive_row, cols, -self._drive[i][a] * values,
                            addv=PETSc.InsertMode.ADD_VALUES)
        A.assemble()

    def prescribed_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """(local u dofs, values): the accepted step's friction force on the body at the
        tangential dofs a Dirichlet part prescribes (see the module docstring: the node keeps
        its friction, and the support's reaction is the residual less it)."""
        last = self.last
        return self.at_prescribed_rows(np.zeros(self.tangential.shape) if last is None
                                       else last["force"])

    #: What :meth:`arrays` saves of the accepted step's state (for the outputs).
    _LAST = ("force", "slip", "slips", "lam")

    def arrays(self) -> dict:
        """The nodal history a checkpoint must hold (this rank's nodes): f_{n−1}, x̃_τ of the
        last step and the last step's state for the outputs."""
        arrays = {"friction_force_old": self.force_old, "friction_x_old": self.x_old,
                  "friction_touching": self.touching}
        if self.last is not None:
            arrays.update({f"friction_last_{k}": self.last[k] for k in self._LAST})
        return arrays

    def restore(self, arrays: dict) -> None:
        """Continue from :meth:`arrays` (a checkpoint without them: no history yet)."""
        if "friction_force_old" not in arrays:
            return
        self.force_old = np.array(arrays["friction_force_old"], dtype=float)
        self.x_old = np.array(arrays["friction_x_old"], dtype=float)
        if "friction_touching" in arrays:
            self.touching = np.array(arrays["friction_touching"], dtype=bool)
        if self._drive is not None:
            self._d_old = self.part.displacement
        self.shift[:] = 0.0
        if "friction_last_force" in arrays:
            self.last = {k: np.array(arrays[f"friction_last_{k}"]) for k in self._LAST}

    #: the extrapolated guess is kept only where it already solves the step (see :meth:`predict`)
    first_try = 0

    def _pressed(self) -> np.ndarray:
        """The nodes pressed at the last step (at the start: touching the obstacle)."""
        return self.touching if self.last is None else self.last["lam"] > 0

    def predict(self, x: PETSc.Vec, first_try: int) -> None:
        """The step's first guess is the problem's, which extrapolates the last steps' motion;
        SNES takes it only if it already solves the step (``first_try = 0``: a body pressed or
        dragged steadily, whose steps are then linear, needs no Newton iteration), and otherwise
        starts again sticking (:meth:`fallback`). Where another term asks for a longer first
        try (friction on a compliant part in the same scene), this part sticks from the start."""
        self._predicted[:] = np.nan
        self._new_solve()
        if first_try > 0:
            self.fallback(x)

    def has_fallback(self) -> bool:
        """A sticking guess exists where nodes were pressed at the last step (collective)."""
        return self.comm.allreduce(bool(np.any(self.free & self._pressed()[:, None])),
                                   op=MPI.LOR)

    def fallback(self, x: PETSc.Vec) -> None:
        """The sticking guess: the tangential unknowns of the nodes pressed at the last step
        where the obstacle has taken them (no slip). Newton then starts on the stick branch with
        its stiffness k and leaves it where the trial force leaves the cone. From the
        extrapolated guess instead, a step that reverses the drag after sliding starts with
        every node slipping forward, and with the stick interval only 2b/k wide Newton jumps
        across it, slipping forward and back in turn (measured: no convergence in 50 iterations
        with a 1e−5 reversal). The first step sticks the nodes touching at the start: a floor
        sliding from t = 0 under a block pressed onto it had every node's bound 𝔣λ near zero
        and Newton slipping either way in turn (no convergence at any step size)."""
        values = x.getArray()
        held = self.free & self._pressed()[:, None]
        stuck = self.x_old + self._shift() / self.scale
        values[self.tangential] = np.where(held, stuck, values[self.tangential])
        self._predicted = values[self.tangential].copy()
        self._new_solve()

    @property
    def second_try(self) -> Optional[int]:
        """A law whose thresholds follow the normal force (Coulomb): Newton iterations from the
        sticking guess before the Tresca predictor (:meth:`freeze`); a law with fixed thresholds
        (Tresca) has none (None)."""
        return SECOND_TRY if self.friction.threshold_slope is not None else None

    def freeze(self, stick: bool) -> None:
        """The Tresca predictor of a Coulomb step that the sticking guess did not solve within
        :data:`SECOND_TRY` iterations: the thresholds fixed at ∞ (``stick``: every pressed node
        sticks) or at 𝔣 λ_i from the last residual (then Tresca's law, b_i = 𝔣 λ̄_i where a
        node is pressed), and the Jacobian without Coulomb's coupling to the normal unknown.
        Newton with fixed thresholds spreads a slip zone in a few iterations, where Coulomb's,
        whose thresholds move with the iterate, grows it by about one node per iteration
        (README: the dragged block on 256×64 cells, 35 iterations → 22)."""
        self._frozen = (np.full(len(self._lam), np.inf) if stick else
                        self.friction.nodal_bound(self._lam, self.part.nodes.points, self.areas))
        self._new_solve()

    def thaw(self) -> None:
        """Coulomb's own thresholds again (see :meth:`freeze`)."""
        self._frozen = None
        self._new_solve()

    def commit(self, x: np.ndarray) -> None:
        """The step is accepted at x (SNES units; λ of the last residual, evaluated there)."""
        st = self.state(x, self._lam)
        self.last = st
        self.force_old = st["force"].copy()
        self.x_old = x[self.tangential].copy()
        self.touching = self.on_bound(x)
        if self._drive is not None:
            self._d_old = self.part.displacement
        self.shift[:] = 0.0
