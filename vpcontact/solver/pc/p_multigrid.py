# SPDX-License-Identifier: MIT
"""A two-level p-multigrid cycle for the P2 displacement block of the mixed formulation.

Algebraic multigrid coarsens a P2 vector Laplacian-like matrix poorly: its graph is dense (a P2
tetrahedron couples 30 unknowns) and the aggregates GAMG builds from it neither follow the
element's two kinds of nodes nor keep the rigid-body modes well, so one GAMG V-cycle on the
displacement block of the Taylor–Hood Jacobian loses accuracy as the mesh is refined. On the
same mesh, P1 is a natural coarse space with an exact embedding: the interpolation I₁² (P1 →
P2, vertex values kept, edge midpoints the mean of their vertices) is a sparse matrix with one
or two entries per row. One cycle of this preconditioner is

    y  = S(b)                              smoothing on A (P2), from zero: vertex stars
    y += P GAMG(Pᵀ(b − A y))               coarse correction: A_c = Pᵀ A P (Galerkin, P1)
    y += S(b − A y)                        the same smoothing again (a symmetric cycle)

with P = Rᵀ I₁² (R the contact frames, when the unknowns are rotated) whose rows at identity
rows of A (Dirichlet conditions; the active bounds of SNES VI's full-size matrix) are zero, so
the coarse correction leaves them alone. The coarse problem is P1 elasticity-like, which GAMG
(with the rigid-body modes of the P1 vertices) handles as well as it does the displacement
formulation. Measured on single solves of the flowing beam's tangent (the paper's 3-D test,
G_eff = 10³ on x < 2; ``bench/p_multigrid.py`` → ``bench/results/p_multigrid.json``), FGMRES
iterations to 1e−8 at 1 038 / 6 400 / 19 690 / 44 508 / 143 128 unknowns: 51 / 57 / 62 / 66 / 76
→ 52 / 55 / 56 / 58 / 61 with vpcontact's unknowns (p the mean stress), 34 / 41 / 48 / 54 / 62
→ 30 / 31 / 33 / 32 / 38 with Herrmann's; the set-up at 143 128 unknowns takes 1.6 s instead of
28 s (GAMG's on the dense P2 graph), the solve 7.4 s instead of 24 s.

S is one damped sweep over the vertex stars, each solved exactly
(:mod:`~vpcontact.solver.pc.star_smoother`), on displacement blocks of :data:`STARS_FROM` rows or
more; on smaller ones the KSP ``pmg_smooth_`` (two Chebyshev–Jacobi sweeps). Where the body
flows, point smoothing leaves the volume-keeping modes of the soft tangent to the Krylov
method, and its iterations grow with the mesh; the stars reach them, at about 1.4 times the
cost per Krylov iteration. Options (under the displacement split's prefix, e.g.
``lagged_fieldsplit_u_`` inside SNES VI): ``pmg_smooth_stars auto | true | false``, and
``pmg_smooth_*`` and ``pmg_coarse_*`` for the KSP smoother and the coarse level.

PETSc creates the context (``pc_type python``, ``pc_python_type`` this module's
:class:`PMultigrid`) for the displacement split; it finds its spaces on the PC
(:func:`~vpcontact.solver.pc.context.get_appctx`: registered by :func:`register` under the step
solver's options prefix, which the sub-PC's prefix starts with).
"""

from __future__ import annotations

import functools
from typing import Optional

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.cpp.fem.petsc import interpolation_matrix
from petsc4py import PETSc

from vpcontact.errors import SolverOptionError
from vpcontact.solver.near_nullspace import rigid_body_modes
import vpcontact.solver.pc.coarse_schur as coarse_schur
import vpcontact.solver.pc.context as context
import vpcontact.solver.pc.star_smoother as star_smoother

#: Displacement blocks from this many rows on are smoothed over the vertex stars (option
#: ``pmg_smooth_stars auto``, the default). Measured in the time loop of the paper's 3-D test
#: (its data, iterative solver, k = 0.01; README), with the column-stored star factors and the
#: stars refactorized only where the active set changed: per step, the stars cost 1.15× the
#: Chebyshev–Jacobi sweeps' time at 6 400 unknowns (6 018 rows), tie at 11 829 (11 253 rows),
#: and save 25 % (linearized scheme, t = 0.05–0.08) and 12 % (implicit, t = 0.3–0.4; its run
#: from t = 0 took 5 min instead of 17) at 19 690 (18 759 rows). (It was 40 000 while a sweep
#: cost 1.7× what it costs now.)
STARS_FROM = 15_000

#: Options of the KSP smoothing on the P2 level (smaller blocks, or ``pmg_smooth_stars false``): two
#: Chebyshev–Jacobi sweeps (before and after the coarse correction), the spectrum bound
#: estimated for every new matrix.
SMOOTHER_OPTIONS = {
    "ksp_type": "chebyshev",
    "ksp_max_it": 2,
    "ksp_norm_type": "none",
    "ksp_chebyshev_esteig": "0,0.1,0,1.1",
    "pc_type": "jacobi",
}

#: Options of the coarse level's GAMG (one V-cycle; as for the displacement formulation).
COARSE_OPTIONS = {
    "ksp_type": "preonly",
    "pc_type": "gamg",
    "pc_gamg_threshold": 0.02,
    "pc_gamg_square_graph": 1,
    "pc_gamg_coarse_eq_limit": 1000,
    "pc_gamg_reuse_interpolation": "false",
    "mg_levels_ksp_type": "chebyshev",
    "mg_levels_pc_type": "jacobi",
    "mg_levels_ksp_max_it": 2,
}

class CoarseSpace:
    """The P1 coarse space of a P2 displacement block: the interpolation P (rows laid out like
    the displacement unknowns of SNES, in its frames) and the coarse rigid-body modes; and the
    vertex stars of the P2 level's smoother (:func:`~vpcontact.solver.pc.star_smoother.
    vertex_stars`).

    Args:
        V: the P2 vector space of the displacement.
        rotation: the u-block of R (ũ = Rᵀu in local frames), or None.
    """

    def __init__(self, V: fem.FunctionSpace, rotation: Optional[PETSc.Mat] = None):
        mesh = V.mesh
        element = V.ufl_element()
        family = "Q" if mesh.ufl_cell().cellname() in ("quadrilateral", "hexahedron") else "Lagrange"
        self.V1 = fem.FunctionSpace(mesh, ufl.VectorElement(family, mesh.ufl_cell(), 1,
                                                            dim=element.value_shape()[0]))
        P = interpolation_matrix(self.V1._cpp_object, V._cpp_object)
        P.assemble()
        if rotation is not None:
            rotated = rotation.transposeMatMult(P)
            P.destroy()
            P = rotated
        self.interpolation = P
        self.block_size = self.V1.dofmap.index_map_bs
        self.modes = rigid_body_modes(self.V1)  # Cartesian: P carries the frames
        self._V = V
        #: the Schur complement assembled from the stars' factors
        #: (:class:`~vpcontact.solver.pc.star_schur.StarSchur`), where the field split uses it
        self.schur = None
        #: counts the Jacobians assembled (the step solver's); a set-up under the same count
        #: as the last one sees the same tangent, only other identity rows (SNES VI's active set)
        self.jacobian_version = 0

    @functools.cached_property
    def stars(self) -> tuple[np.ndarray, np.ndarray]:
        """The vertex stars (found when a smoother first asks: below :data:`STARS_FROM` rows
        none does)."""
        return star_smoother.vertex_stars(self._V)

    def destroy(self) -> None:
        self.interpolation.destroy()
        self.modes.destroy()


def register(prefix: str, space: CoarseSpace) -> None:
    """Make ``space`` the coarse space of every :class:`PMultigrid` under options ``prefix``
    (kept while the caller holds ``space``; :func:`~vpcontact.solver.pc.context.attach`)."""
    context.attach(prefix, space)


def lookup(prefix: str) -> CoarseSpace:
    """The coarse space registered under the longest key ``prefix`` starts with."""
    return context.lookup(prefix)


def identity_rows(A: PETSc.Mat, csr=None) -> np.ndarray:
    """Global indices of the owned rows of A with one nonzero value (their diagonal): the
    Dirichlet rows and the active bounds' rows of SNES VI's full-size matrix. ``csr``: A's
    local rows, if already fetched."""
    indptr, _, values = csr if csr is not None else A.getValuesCSR()
    zeros = np.flatnonzero(values == 0.0)  # stored zeros: few, cheaper to find than nonzeros
    counts = np.diff(indptr) - np.diff(np.searchsorted(zeros, indptr))  # nonzeros per row
    start = A.getOwnershipRange()[0]
    return (start + np.flatnonzero(counts <= 1)).astype(PETSc.IntType)


_STAR_CHOICES = {"auto": None, "true": True, "yes": True, "1": True,
                 "false": False, "no": False, "0": False}


def _stars_choice(key: str, value, error=ValueError) -> Optional[bool]:
    """The ``pmg_smooth_stars`` (or ``pmg_schur_coarse``) option ``key = value``: True, False or
    None (``auto``).

    Raises:
        error: naming the option and the valid values.
    """
    if str(value).lower() not in _STAR_CHOICES:
        raise error(f"{key} must be auto, true or false, got {value!r}")
    return _STAR_CHOICES[str(value).lower()]


def uses_stars(key: str, value, rows: int, error=ValueError) -> bool:
    """Whether a displacement block of ``rows`` rows is smoothed over the vertex stars, with
    ``value`` given for the option ``key`` (``auto``: from :data:`STARS_FROM` rows on)."""
    stars = _stars_choice(key, value, error)
    return rows >= STARS_FROM if stars is None else stars


def uses_coarse_schur(key: str, value, error=ValueError) -> bool:
    """Whether the Schur block of a field split smoothed over the stars takes the cycle's coarse
    term (:mod:`~vpcontact.solver.pc.coarse_schur`, experimental), with ``value`` given for the option ``key``
    (``pmg_schur_coarse``; ``auto``, the default, is no: the two factorizations cost more time
    than the iterations they save on the paper's 3-D test up to 143 128 unknowns, README)."""
    return bool(_stars_choice(key, value, error))


def check_options(options: dict) -> None:
    """Refuse a ``pmg_smooth_stars`` or ``pmg_schur_coarse`` option (under any prefix) that is
    neither ``auto`` nor a PETSc truth value: it is read only when the field split first sets
    up, inside a solve.

    Raises:
        ValueError: naming the option and the valid values.
    """
    for key, value in options.items():
        if key.endswith(("pmg_smooth_stars", "pmg_schur_coarse")):
            _stars_choice(key, value)


def _set_up(ksp: PETSc.KSP, defaults: dict) -> None:
    """Set ``ksp`` up with ``defaults`` under its prefix (options already in PETSc's database,
    the user's, take precedence; GAMG reads its levels' options while it sets up)."""
    opts = PETSc.Options()
    prefix = ksp.getOptionsPrefix()
    added = [key for key in defaults if not opts.hasName(prefix + key)]
    for key in added:
        opts[prefix + key] = defaults[key]
    try:
        ksp.setFromOptions()
        ksp.setUp()
    finally:
        for key in added:
            opts.delValue(prefix + key)


class PMultigrid:
    """The PETSc python PC context of the cycle in the module docstring."""

    def __init__(self):
        self.space: Optional[CoarseSpace] = None
        self.P: Optional[PETSc.Mat] = None
        self.coarse_matrix: Optional[PETSc.Mat] = None
        self.smoother = self.coarse = None
        self.star_sweep: Optional[star_smoother.StarSmoother] = None
        self._r = self._rc = self._ec = self._dy = None
        self._version: Optional[int] = None  # the coarse space's jacobian_version at set-up
        self._identity: Optional[np.ndarray] = None  # B's identity rows at the last set-up

    def _create(self, pc: PETSc.PC) -> None:
        prefix = pc.getOptionsPrefix() or ""
        self.space = context.get_appctx(pc)
        comm = pc.getComm()
        self.smoother = PETSc.KSP().create(comm)
        self.smoother.setOptionsPrefix(prefix + "pmg_smooth_")
        self.coarse = PETSc.KSP().create(comm)
        self.coarse.setOptionsPrefix(prefix + "pmg_coarse_")

    def setUp(self, pc: PETSc.PC) -> None:
        if self.space is None:
            self._create(pc)
        A, B = pc.getOperators()
        csr = B.getValuesCSR()
        rows = identity_rows(B, csr)
        # With the same tangent as the last set-up only the identity rows (SNES VI's active
        # set) differ: the stars that hold none of the changed ones keep their factors and
        # their Schur terms
        same = self._version == self.space.jacobian_version
        stars = None
        if same and self.star_sweep is not None and self._identity is not None:
            changed = np.setxor1d(rows, self._identity) - B.getOwnershipRange()[0]
            stars = self.star_sweep.stars_of(changed)
        self._identity = rows
        # P and A_c keep their sparsity from one set-up to the next (P's zeroed rows as stored
        # zeros): only A_c's numeric product is recomputed (a new one cost 1.5x as much)
        if self.P is None:
            self.P = self.space.interpolation.copy()
            self.P.setOption(PETSc.Mat.Option.KEEP_NONZERO_PATTERN, True)
        else:
            self.space.interpolation.copy(self.P, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        P = self.P
        P.zeroRows(rows, diag=0.0)  # the coarse correction leaves fixed unknowns alone
        if self.coarse_matrix is None:
            coarse = B.ptap(P)
            coarse.setBlockSize(self.space.block_size)
            coarse.setNearNullSpace(self.space.modes)
            self.coarse_matrix = coarse
        else:
            coarse = B.ptap(P, result=self.coarse_matrix)
        self._set_up_smoother(pc, A, B, csr, stars)
        schur = self.space.schur
        coarse_term = schur.coarse if schur is not None else None
        if schur is not None:
            if self.star_sweep is None:
                raise SolverOptionError("the star Schur complement needs the vertex-star "
                                        "smoothing (pmg_smooth_stars)")
            schur.update(self.star_sweep, pc.getOptionsPrefix() or "", stars)
        if coarse_term is not None:  # its coarse term with this A_c, exact with A_c factorized
            coarse_term.update(schur.coupling, P, coarse, schur.matrix)
            coarse_schur.factorize(self.coarse, coarse)
        else:
            # With the same tangent GAMG keeps its aggregates and prolongations and recomputes
            # the Galerkin products only
            self.coarse.setOperators(coarse)
            _set_up(self.coarse, {**COARSE_OPTIONS,
                                  "pc_gamg_reuse_interpolation": "true" if same else "false"})
        self._version = self.space.jacobian_version
        if self._r is None:
            self._rc, self._r = P.createVecs()
            self._ec = self._rc.duplicate()
            self._dy = self._r.duplicate()

    def _set_up_smoother(self, pc: PETSc.PC, A: PETSc.Mat, B: PETSc.Mat, csr,
                         stars: Optional[np.ndarray]) -> None:
        """The vertex stars' sweep (only ``stars`` refactorized, if given; ``csr``: B's local
        rows), or the KSP ``pmg_smooth_`` (``pmg_smooth_stars``: ``auto`` chooses by the
        block's size, :data:`STARS_FROM`; read now: the options are in PETSc's database while
        the field split sets up)."""
        key = (pc.getOptionsPrefix() or "") + "pmg_smooth_stars"
        # (given on the command line: not checked before)
        if not uses_stars(key, PETSc.Options().getString(key, "auto"), B.getSize()[0],
                          SolverOptionError):
            self.star_sweep = None
            self.smoother.setOperators(A, B)
            _set_up(self.smoother, SMOOTHER_OPTIONS)
            return
        if self.star_sweep is None:
            self.star_sweep = star_smoother.StarSmoother(self.space.stars, B.getLocalSize()[0])
            stars = None
        self.star_sweep.set_operator(B, csr, stars)

    def apply(self, pc: PETSc.PC, b: PETSc.Vec, y: PETSc.Vec) -> None:
        A = pc.getOperators()[0]
        r, rc, ec, dy = self._r, self._rc, self._ec, self._dy
        smoother = self.star_sweep or self.smoother
        smoother.solve(b, y)
        A.mult(y, r)
        r.aypx(-1.0, b)
        self.P.multTranspose(r, rc)
        self.coarse.solve(rc, ec)
        self.P.multAdd(ec, y, y)
        A.mult(y, r)
        r.aypx(-1.0, b)
        smoother.solve(r, dy)
        y.axpy(1.0, dy)

    def destroy(self, pc: PETSc.PC) -> None:
        for obj in (self.P, self.coarse_matrix, self.smoother, self.coarse,
                    self._r, self._rc, self._ec, self._dy):
            if obj is not None:
                obj.destroy()
