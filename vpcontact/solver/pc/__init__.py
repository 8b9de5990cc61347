# SPDX-License-Identifier: MIT
"""The iterative solver's preconditioners, behind one factory (:func:`configure`).

* :mod:`.factory`: :func:`configure` gives the step solver the iterative solver's options and
  its preconditioner's application context; nothing else chooses a preconditioner;
* :mod:`.fieldsplit`: the mixed formulation's field split (:class:`BlockPreconditioner`, its
  application context);
* :mod:`.p_multigrid`: the two-level p-multigrid cycle on the P2 displacement block (a PETSc
  python PC, :class:`~.p_multigrid.PMultigrid`);
* :mod:`.star_smoother`, :mod:`.star_schur`: the vertex-star smoother and its Schur complement;
* :mod:`.coarse_schur`: EXPERIMENTAL, the stars' Schur complement with the cycle's coarse term
  (a python PC, off by default: slower);
* :mod:`.context`: where the python PCs find their context (on the PC, by its options prefix,
  as Firedrake's ``get_appctx``).
"""

from vpcontact.solver.pc.context import attach, get_appctx
from vpcontact.solver.pc.factory import check_options, configure, iterative_options, lagged_options
from vpcontact.solver.pc.fieldsplit import BlockPreconditioner

__all__ = ["attach", "BlockPreconditioner", "check_options", "configure", "get_appctx",
           "iterative_options", "lagged_options"]
