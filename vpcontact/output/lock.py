# SPDX-License-Identifier: MIT
"""One run at a time per output folder.

``vpcontact run`` holds an exclusive ``flock`` on ``DIR/.vpcontact.lock`` while it writes into
DIR; a second run into the same folder finds it held and refuses (exit 2) instead of
interleaving its files with the first one's. The operating system releases the lock when the
process ends however it ends (a crash or SIGKILL included), so a dead run never leaves a folder
locked; the file itself says who holds it (host, pid, start time) and is removed by a run that
ends normally. (``flock`` is local to a machine; on network file systems it may not exclude a
run on another host.)
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import socket
import time
from pathlib import Path
from typing import Optional

from vpcontact.errors import InputError

LOCK_NAME = ".vpcontact.lock"


def check_folder(out: Path) -> None:
    """Refuse an output folder that cannot be one: an existing file, or a path under a file."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out}: an existing file, not a folder; choose a folder")
    for parent in out.parents:
        if parent.exists():
            if not parent.is_dir():
                raise InputError(f"--out {out}: {parent} is a file, so no folder can be made there")
            if not os.access(parent, os.W_OK | os.X_OK):
                raise InputError(f"--out {out}: no permission to create or write into {parent}")
            break


class OutputLock:
    """The exclusive lock of an output folder, taken on rank 0 (all ranks learn the outcome)."""

    def __init__(self, out: Path, comm):
        self.out = Path(out)
        self.comm = comm
        self._file = None
        problem: Optional[str] = None
        if comm.rank == 0:
            problem = self._acquire()
        problem = comm.bcast(problem, root=0)
        if problem is not None:
            raise InputError(problem)

    def _acquire(self) -> Optional[str]:
        path = self.out / LOCK_NAME
        try:
            self.out.mkdir(parents=True, exist_ok=True)
            f = open(path, "a+")
        except OSError as err:
            return f"--out {self.out}: cannot write there ({err.strerror or err})"
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            if err.errno not in (errno.EAGAIN, errno.EACCES):
                f.close()
                return f"--out {self.out}: cannot lock it ({err.strerror or err})"
            f.seek(0)
            holder = f.read().strip()
            f.close()
            try:
                who = json.loads(holder)
                who = f"pid {who['pid']} on {who['host']}, started {who['started']}"
            except (ValueError, KeyError, TypeError):
                who = "another process"
            return (f"--out {self.out}: another vpcontact run ({who}) is writing into this "
                    "folder; wait for it to end or choose another --out")
        f.seek(0)
        f.truncate()
        f.write(json.dumps({"host": socket.gethostname(), "pid": os.getpid(),
                            "started": time.strftime("%Y-%m-%d %H:%M:%S")}) + "\n")
        f.flush()
        self._file = f
        return None

    def release(self) -> None:
        """Remove the lock file and release the lock (rank 0; no collective call)."""
        if self._file is not None:
            try:
                (self.out / LOCK_NAME).unlink()
            except OSError:
                pass
            self._file.close()
            self._file = None
