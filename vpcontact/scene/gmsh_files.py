# SPDX-License-Identifier: MIT
"""A Gmsh session on rank 0 that leaves the process's SIGINT handler alone.

Debian's gmsh 4.8 Python module sets SIGINT to the default action when it is imported and puts
back the handler it found then when ``gmsh.finalize()`` runs. Either would take Ctrl-C away from
``vpcontact run``'s clean stop (:mod:`vpcontact.output.interrupt`): killed outright while a mesh
is read, or a KeyboardInterrupt traceback later when gmsh had been imported before the handler
was installed. :func:`gmsh_session` keeps whatever handler was in place, during the session and
after it.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager


@contextmanager
def gmsh_session(comm):
    """``gmsh`` initialized (quiet) on rank 0 — yielded there, None on the other ranks — and
    finalized when the block ends, with the SIGINT handler kept."""
    if comm.rank != 0:
        yield None
        return
    main = threading.current_thread() is threading.main_thread()
    handler = signal.getsignal(signal.SIGINT) if main else None
    import gmsh
    gmsh.initialize(["gmsh", "-v", "0"])  # argv[0] is the program name
    if handler is not None:
        signal.signal(signal.SIGINT, handler)
    try:
        yield gmsh
    finally:
        gmsh.finalize()
        if handler is not None:
            signal.signal(signal.SIGINT, handler)
