# SPDX-License-Identifier: MIT
"""Stage 4, outputs: what a run writes, and the run itself with its record.

Takes a problem (and for :class:`Session` a built scene); gives files in an output folder:

* :mod:`.fields`: cell-averaged stress and von Mises norm (:class:`CellStress`), the XDMF time
  series (:class:`XdmfSeries`, for ParaView) and the contact history (:class:`ContactHistory`,
  ``contact.csv``, pressure positive in compression);
* :mod:`.strains`: the viscoplastic strain ε_vp = ε − E⁻¹σ and its equivalent, per cell;
* :mod:`.probes`: point histories (``[output] probes``, ``probes.csv``);
* :mod:`.plots`, :mod:`.contact_figures`: PNG figures of the deformed state, the forces, the
  contact pressure and the contact history (matplotlib, Agg);
* :mod:`.runner`: :func:`run`, the time loop that writes these step by step, and its
  :class:`RunRecord`;
* :mod:`.session`: :class:`Session`, one simulation of a scene as ``vpcontact run`` does it:
  progress bar, ``summary.json``, figures.
"""

from vpcontact.output import plots, runner
from vpcontact.output.fields import CellStress, ContactHistory, XdmfSeries, von_mises
from vpcontact.output.runner import RunOptions, RunParts, RunRecord, summary_text, run
from vpcontact.output.session import Session

__all__ = ["CellStress", "ContactHistory", "RunRecord", "Session", "XdmfSeries", "plots",
           "summary_text", "run", "RunOptions", "RunParts", "runner", "von_mises"]
