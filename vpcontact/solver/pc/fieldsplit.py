# SPDX-License-Identifier: MIT
"""The mixed formulation's block preconditioner: PCFIELDSPLIT (Schur complement factorization)
with one p-multigrid cycle on the displacement block (:mod:`.p_multigrid`) and, on the Schur
block, the weighted pressure mass matrix or the vertex stars' Schur complement
(:mod:`.star_schur`; with the cycle's coarse term, :mod:`.coarse_schur`, experimental).

:class:`BlockPreconditioner` is the application context of the split: it gives a PC of type
fieldsplit its fields and Schur matrix (:meth:`~BlockPreconditioner.configure`, wherever one
is set up: SNES's KSP, SNES VI's lagged solver) and registers the coarse space on which the
python PCs under the split find their own context (:mod:`.context`). The options below go
under the step solver's prefix (and ``lagged_`` inside SNES VI); the user's override them.
"""

from __future__ import annotations

from typing import Optional

from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

from vpcontact.solver import linear
import vpcontact.solver.pc.p_multigrid as p_multigrid
import vpcontact.solver.pc.star_schur as star_schur

#: KSP/PC options of the iterative solver of the mixed formulation (under the step's prefix;
#: user options override them).
MIXED_OPTIONS = {
    "ksp_type": "fgmres",
    "ksp_rtol": linear.ITERATIVE_RTOL,
    "ksp_max_it": 500,
    "ksp_gmres_restart": 200,
    "ksp_norm_type": "unpreconditioned",
    "pc_type": "fieldsplit",
    "pc_fieldsplit_type": "schur",
    # lower: as few outer iterations as "full" with one displacement solve less per application
    "pc_fieldsplit_schur_fact_type": "lower",
    "fieldsplit_u_ksp_type": "preonly",
    # one two-level cycle: P2 smoothing, a P1 Galerkin coarse problem under GAMG
    # (vpcontact.solver.pc.p_multigrid)
    "fieldsplit_u_pc_type": "python",
    "fieldsplit_u_pc_python_type": "vpcontact.solver.pc.p_multigrid.PMultigrid",
    # the Schur block: three Chebyshev–Jacobi sweeps on the weighted mass matrix S_p (not on
    # PETSc's Schur-complement operator: "pc_type ksp" iterates on S_p alone); diag(M)⁻¹M has
    # its spectrum in [1/2, 5/2] on P1 tetrahedra ([1/2, 2] on triangles) for any positive
    # cellwise weight
    "fieldsplit_p_ksp_type": "preonly",
    "fieldsplit_p_pc_type": "ksp",
    "fieldsplit_p_ksp_ksp_type": "chebyshev",
    "fieldsplit_p_ksp_ksp_max_it": 3,
    "fieldsplit_p_ksp_ksp_norm_type": "none",
    "fieldsplit_p_ksp_ksp_chebyshev_eigenvalues": "0.5,2.5",
    "fieldsplit_p_ksp_pc_type": "jacobi",
}


#: The Schur block's options where its matrix is the stars' Schur complement
#: (:mod:`~vpcontact.solver.pc.star_schur`; with the vertex-star smoothing): six Chebyshev–Jacobi
#: sweeps with the spectrum bound estimated for every new matrix — its Jacobi spectrum is not
#: bounded a priori as the mass matrix's is ([0.52, 2.15] at 44 508 unknowns, [0.20, 3.06] at
#: 143 128 on the paper's 3-D test; with the mass matrix's fixed bounds GMRES took 25 iterations
#: there, with three sweeps 19, with six 16, factorized 16).
STAR_SCHUR_OPTIONS = {
    "fieldsplit_p_ksp_ksp_max_it": 6,
    "fieldsplit_p_ksp_ksp_chebyshev_esteig": "0,0.05,0,1.1",
}


def _schur_prefixes(options: dict) -> set:
    """The prefixes (none, ``lagged_``) under which ``options`` configure a Schur block."""
    return {key[:-len("fieldsplit_p_ksp_ksp_type")] for key in options
            if key.endswith("fieldsplit_p_ksp_ksp_type")}


def star_schur_options(options: dict) -> dict:
    """``options`` (as :data:`MIXED_OPTIONS`, or prefixed like :func:`lagged_options`) with the
    Schur block set up for the stars' Schur complement."""
    result = dict(options)
    for prefix in _schur_prefixes(options):
        result.pop(prefix + "fieldsplit_p_ksp_ksp_chebyshev_eigenvalues", None)
        result.update({prefix + key: value for key, value in STAR_SCHUR_OPTIONS.items()})
    return result


def coarse_schur_options(options: dict) -> dict:
    """``options`` as :func:`star_schur_options` gives them, with the Schur block solved with
    the cycle's coarse term (:mod:`~vpcontact.solver.pc.coarse_schur`; the cycle then factorizes
    its coarse level)."""
    result = star_schur_options(options)
    for prefix in _schur_prefixes(options):
        for key in [key for key in result  # (the inner KSP of pc_type ksp)
                    if key.startswith((prefix + "fieldsplit_p_ksp_ksp_",
                                       prefix + "fieldsplit_p_ksp_pc_"))]:
            del result[key]
        result.update({prefix + "fieldsplit_p_pc_type": "python",
                       prefix + "fieldsplit_p_pc_python_type":
                       "vpcontact.solver.pc.coarse_schur.CoarseSchurPC"})
    return result



class BlockPreconditioner:
    """Sets up PCFIELDSPLIT for a layout with a pressure field: the field index sets, the
    rigid-body modes on the displacement block, and the Schur complement's preconditioner —
    the weighted pressure mass matrix, reassembled with every Jacobian, or, where the
    displacement block is smoothed over the vertex stars, the stars' Schur complement,
    reassembled with the cycle (:mod:`~vpcontact.solver.pc.star_schur`).

    Args:
        fields: the :class:`~vpcontact.model.fields.DisplacementPressure` layout.
        near_nullspace: the rigid-body modes in the layout of the SNES vector (rotated if the
            unknowns are); their u parts go to the displacement block.
        scale: SNES's displacement scale (the Schur matrix is in SNES's units).
        stars: the displacement block is smoothed over the vertex stars (then the Schur
            complement is theirs, and the caller gives the split :func:`star_schur_options`;
            :meth:`configure` tells it which matrix each field split works on).
        coarse: with the stars, the Schur block also takes the cycle's coarse term, solved
            exactly (the caller gives the split :func:`coarse_schur_options`).
    """

    def __init__(self, fields, near_nullspace: Optional[PETSc.NullSpace], scale: float,
                 prefix: str = "", rotation: Optional[PETSc.Mat] = None, stars: bool = False,
                 coarse: bool = False):
        self.fields = fields
        indices = fields.field_indices()
        self.is_u, self.is_p = indices["displacement"], indices["pressure"]
        if near_nullspace is not None:
            vectors = fields.split(near_nullspace.getVecs())
            self._modes = PETSc.NullSpace().create(vectors=vectors, comm=self.is_u.getComm())
            self.is_u.compose("nearnullspace", self._modes)
        rotation_u = None if rotation is None else rotation.createSubMatrix(self.is_u, self.is_u)
        self.coarse_space = p_multigrid.CoarseSpace(fields.u.function_space, rotation_u)
        p_multigrid.register(prefix, self.coarse_space)
        if rotation_u is not None:
            rotation_u.destroy()
        self._configured: set = set()
        #: the lagged VI solver that applies this preconditioner (set by the step solver), or
        #: None; expired with every Jacobian (:data:`~vpcontact.solver.linear.REBUILD_WITH_EVERY_JACOBIAN`)
        self.solver = None
        self.scale = scale
        self._form = fields.schur_preconditioner_form(scale)
        self.matrix = fem_petsc.create_matrix(self._form)  # S_p
        self._assemble_matrix = fem_petsc.assemble_matrix
        #: the stars' Schur complement, or None (S_p)
        self.star_schur = (star_schur.StarSchur(self.is_u, self.is_p, coarse=coarse) if stars
                           else None)
        self.coarse_space.schur = self.star_schur

    @property
    def schur_matrix(self) -> PETSc.Mat:
        """The Schur complement's preconditioning matrix the field split is given."""
        return self.matrix if self.star_schur is None else self.star_schur.matrix

    def assemble_mass(self) -> None:
        """Assemble S_p from the current tangent."""
        self.fields.update_schur_weight()
        self.matrix.zeroEntries()
        self._assemble_matrix(self.matrix, self._form)
        self.matrix.assemble()

    def update(self) -> None:
        """Reassemble the Schur preconditioner from the current tangent (S_p; the stars' is
        reassembled with the cycle) and have the lagged VI solver rebuild the field split at
        its next solve."""
        self.coarse_space.jacobian_version += 1
        if self.star_schur is None:
            self.assemble_mass()
        if self.solver is not None and linear.REBUILD_WITH_EVERY_JACOBIAN:
            self.solver.expire()

    def configure(self, pc: PETSc.PC) -> None:
        """Give ``pc`` (type fieldsplit, from the options) its fields and Schur matrix."""
        if pc.getType() != "fieldsplit":
            return
        if self.star_schur is not None:
            self.star_schur.parents[pc.getOptionsPrefix() or ""] = pc
        if pc.handle in self._configured:
            return  # (the splits of a PC are given once; later set-ups keep them)
        self._configured.add(pc.handle)
        pc.setFieldSplitIS(("u", self.is_u), ("p", self.is_p))
        pc.setFieldSplitSchurPreType(PETSc.PC.SchurPreType.USER, self.schur_matrix)

    def destroy(self) -> None:
        self.matrix.destroy()
        if self.star_schur is not None:
            self.star_schur.parents.clear()
            self.star_schur.destroy()
        self.coarse_space.destroy()
