# SPDX-License-Identifier: MIT
"""The command line's progress bar for ``vpcontact run``.

Hand-written rather than tqdm's: on a terminal it rewrites one line per step, and when the
output is a file or a pipe (CI logs, ``nohup``) it writes one plain line per tenth of the run
with the Newton iterations and the active contact nodes, where tqdm would write carriage
returns into the log.
"""

from __future__ import annotations

import sys
from typing import Optional


class ProgressBar:
    """One line on a terminal, rewritten each step; a line every 10 % of T otherwise."""

    def __init__(self, t_final: float, width: int = 30):
        self.t_final = t_final
        self.width = width
        self.tty = sys.stdout.isatty()
        self._next = 0.1

    def update(self, t: float, its: int, active: Optional[int]) -> None:
        frac = min(t / self.t_final, 1.0)
        contact = f"  active contact nodes {active}" if active is not None else ""
        text = (f"[{'#' * int(frac * self.width):{self.width}s}] {100 * frac:5.1f}%  t = {t:.4g}"
                f"  Newton its {its}{contact}")
        if self.tty:
            print("\r" + text, end="", flush=True)
        elif frac >= self._next - 1e-12 or frac >= 1.0:
            print(text, flush=True)
            while self._next <= frac + 1e-12:
                self._next += 0.1

    def close(self) -> None:
        if self.tty:
            print(flush=True)
