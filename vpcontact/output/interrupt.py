# SPDX-License-Identifier: MIT
"""Stopping a run cleanly on SIGINT (Ctrl-C) or SIGTERM (what a batch scheduler sends at its
time limit).

While installed, the handlers only note the signal. The time loop asks :meth:`StopRequest.agreed`
after each accepted step: every rank takes part (an allreduce of the signals seen), so all ranks
stop after the same step even when only some received the signal, and none is left waiting in a
collective call. A step in progress when the signal arrives is finished (it is usually a fraction
of a second; SNES returns to Python at every residual evaluation) and then the run stops: the
outputs are closed, a checkpoint and ``summary.json`` (``"completed": false``, the signal named)
are written, and the command exits with 128 + the signal number (130 for SIGINT, 143 for
SIGTERM). A second signal while stopping exits at once with that status.
"""

from __future__ import annotations

import os
import signal
from typing import Optional

from mpi4py import MPI

SIGNALS = (signal.SIGINT, signal.SIGTERM)


class StopRequest:
    """Notes SIGINT/SIGTERM while installed (use as a context manager)."""

    def __init__(self):
        self.received = 0  # signal number, 0 when none
        self._previous = {}

    def __enter__(self) -> "StopRequest":
        for sig in SIGNALS:
            self._previous[sig] = signal.signal(sig, self._note)
        return self

    def __exit__(self, *exc) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous.clear()

    def _note(self, signum, frame) -> None:
        if self.received:  # a second signal: stop now
            os._exit(128 + signum)
        self.received = signum

    def agreed(self, comm=MPI.COMM_WORLD) -> Optional[str]:
        """The name of a signal any rank has received, or None (collective)."""
        signum = comm.allreduce(self.received, op=MPI.MAX)
        return signal.Signals(signum).name if signum else None
