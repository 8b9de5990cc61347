# SPDX-License-Identifier: MIT
"""The Schur complement of the mixed formulation's field split, approximated on the vertex stars.

With the vertex-star smoothing (:mod:`~vpcontact.solver.pc.star_smoother`) the displacement block's
preconditioner already holds every star's block A_s of A factorized. Its local Schur complements,
summed with the sweep's damping ω,

    Ŝ = C − ω Σ_s B_s A_s⁻¹ B_sᵀ        (B_s: the pressure rows' block on star s's unknowns)

approximate the Schur complement C − B Ã⁻¹ Bᵀ of the cycle Ã as the field split uses it, and
follow the tangent wherever the body flows, its contact constraints (the active bounds' columns
of M are zero) included. The weighted pressure mass S_p (:mod:`~vpcontact.model.fields`) takes
each point's compliance and cannot see how a thin soft layer is held by its stiff neighbours:
on the paper's 3-D test (the linearized scheme's window, its first step's second system;
``bench/results/field_split_parts_*.json``) GMRES takes 15 / 16 / 21 iterations with S_p at 6 400 /
44 508 / 143 128 unknowns and 16 / 17 / 16 with Ŝ (six Chebyshev–Jacobi sweeps), against 14 /
13 / 12 with the cycle's own Schur complement formed. Ŝ couples pressure nodes two vertices
apart (about 54 entries per row in 3-D against S_p's 14); it is assembled from the factors with
every new matrix, in C++ (``PatchSmoother.schur_sum``), its contributions to other processes'
rows sent by PETSc's assembly.
"""

from __future__ import annotations

from typing import Optional

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

import vpcontact.solver.pc.coarse_schur as coarse_schur
import vpcontact.solver.pc.star_smoother as star_smoother


class StarSchur:
    """Ŝ (module docstring) as a PETSc matrix in the pressure split's numbering.

    Args:
        is_u, is_p: the fields' index sets in the matrix the field split works on.
        coarse: give the pressure split Ŝ with the cycle's coarse term, solved exactly
            (:mod:`~vpcontact.solver.pc.coarse_schur`).
    """

    def __init__(self, is_u: PETSc.IS, is_p: PETSc.IS, coarse: bool = False):
        self.is_u, self.is_p = is_u, is_p
        #: the cycle's coarse term, solved exactly with Ŝ (:mod:`~vpcontact.solver.pc.coarse_schur`)
        self.coarse = coarse_schur.CoarseSchur(is_p.getComm()) if coarse else None
        #: the field-split PCs by options prefix (their operators are the matrices split:
        #: the SNES Jacobian, SNES VI's full-size matrix M), registered as they are configured
        self.parents: dict[str, PETSc.PC] = {}
        comm = is_p.getComm()
        local, size = is_p.getLocalSize(), is_p.getSize()
        self.matrix = PETSc.Mat().create(comm)
        self.matrix.setSizes(((local, size), (local, size)))
        self.matrix.setType(PETSc.Mat.Type.AIJ)
        self._coupling = self._pressure = None  # M's (u, p) and (p, p) blocks, kept
        self._pattern: Optional[tuple[np.ndarray, np.ndarray]] = None
        self._order = self._starts = self._rows = self._columns = None
        self._terms = self._terms_of = None  # the stars' terms, and (sweep, prefix) they are of

    def update(self, sweep: star_smoother.StarSmoother, prefix: str,
               stars: Optional[np.ndarray] = None) -> None:
        """Reassemble Ŝ from the stars' factors in ``sweep`` and the matrix of the field split
        whose displacement block has options ``prefix``. ``stars``: only these stars' blocks
        changed since the last update with the same ``sweep`` and ``prefix`` (the same tangent,
        another active set): the others' terms are kept."""
        parent = prefix[:-len("fieldsplit_u_")] if prefix.endswith("fieldsplit_u_") else None
        if parent not in self.parents:
            raise RuntimeError(f"StarSchur: no field split registered for {prefix!r}")
        M = self.parents[parent].getOperators()[1]
        self._coupling = M.createSubMatrix(self.is_u, self.is_p, submat=self._coupling)
        self._pressure = M.createSubMatrix(self.is_p, self.is_p, submat=self._pressure)
        starts, columns, values = self._coupling.getValuesCSR()
        key = (id(sweep), prefix)
        terms = self._terms if stars is not None and self._terms_of == key else None
        if terms is not None:
            star_rows, star_cols, star_values, star_starts = terms
            _, _, changed, changed_starts = sweep.schur_sum(starts, columns, values, stars)
            lengths = star_starts[stars + 1] - star_starts[stars]
            if np.array_equal(np.diff(changed_starts), lengths):
                # (the same pattern: each star's m x m terms in place)
                at = np.repeat(star_starts[stars] - changed_starts[:-1], lengths)
                star_values[at + np.arange(len(changed))] = changed
            else:
                terms = None
        if terms is None:
            star_rows, star_cols, star_values, star_starts = sweep.schur_sum(starts, columns,
                                                                             values)
        self._terms, self._terms_of = (star_rows, star_cols, star_values, star_starts), key
        starts, columns, values = self._pressure.getValuesCSR()
        first = self._pressure.getOwnershipRange()[0]
        entries = np.concatenate([values, -star_smoother.DAMPING * star_values])
        if terms is None:  # (kept terms: M's pattern and the stars' layout are as they were)
            rows = np.concatenate([first + np.repeat(np.arange(len(starts) - 1),
                                                     np.diff(starts)),
                                   star_rows]).astype(PETSc.IntType)
            cols = np.concatenate([columns, star_cols]).astype(PETSc.IntType)
            if self._pattern is None or not (np.array_equal(rows, self._pattern[0])
                                             and np.array_equal(cols, self._pattern[1])):
                self._new_pattern(rows, cols)
        self.matrix.zeroEntries()
        self.matrix.setValuesIJV(self._starts, self._columns, entries[self._order],
                                 addv=PETSc.InsertMode.ADD_VALUES, rowmap=self._rows)
        self.matrix.assemble()

    @property
    def coupling(self) -> Optional[PETSc.Mat]:
        """Bᵀ: the displacement rows' block on the pressure columns, as of the last update."""
        return self._coupling

    def _new_pattern(self, rows: np.ndarray, cols: np.ndarray) -> None:
        """Group the entries by row and preallocate Ŝ for their union over the processes
        (an upper bound: each process counts its own distinct entries per row)."""
        self._pattern = (rows, cols)
        self._order = np.argsort(rows, kind="stable")
        self._columns = cols[self._order]  # grouped by row, as setValuesIJV takes them
        unique_rows, counts = np.unique(rows, return_counts=True)
        self._rows = unique_rows.astype(PETSc.IntType)
        self._starts = np.concatenate([[0], np.cumsum(counts)]).astype(PETSc.IntType)
        size = self.is_p.getSize()
        comm = self.matrix.getComm().tompi4py()
        ranges = np.concatenate([[0], np.cumsum(comm.allgather(self.is_p.getLocalSize()))])
        first, last = ranges[comm.rank], ranges[comm.rank + 1]
        # distinct (row, column) pairs, split into the owner's diagonal and off-diagonal blocks
        pairs = np.unique(rows.astype(np.int64) * size + cols)
        pair_rows, pair_cols = np.divmod(pairs, size)
        owner = np.searchsorted(ranges, pair_rows, side="right") - 1
        diagonal = (pair_cols >= ranges[owner]) & (pair_cols < ranges[owner + 1])
        d_nnz = np.bincount(pair_rows[diagonal], minlength=size)
        o_nnz = np.bincount(pair_rows[~diagonal], minlength=size)
        if comm.size > 1:
            comm.Allreduce(MPI.IN_PLACE, d_nnz, op=MPI.SUM)
            comm.Allreduce(MPI.IN_PLACE, o_nnz, op=MPI.SUM)
        local = slice(first, last)
        width = last - first
        self.matrix.setPreallocationNNZ((np.minimum(d_nnz[local], width).astype(PETSc.IntType),
                                         np.minimum(o_nnz[local], size - width)
                                         .astype(PETSc.IntType)))
        self.matrix.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)

    def destroy(self) -> None:
        for obj in (self.matrix, self._coupling, self._pressure, self.coarse):
            if obj is not None:
                obj.destroy()
