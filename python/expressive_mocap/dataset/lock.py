"""The advisory lock a run holds on its dataset folder (``OUT/.lock``)."""

from __future__ import annotations

import json
import os
import socket
import sys
import time
from pathlib import Path

from ..errors import DatasetError
from .format import LOCK


class FolderLock:
    """An advisory lock (``flock``) on ``folder/.lock``, held while a run writes the folder: a
    second run on the same folder fails at once, saying which process holds it. The lock goes
    with the process (a killed run leaves no stale lock); the file stays, as deleting a lock file
    others may be waiting on would let two runs lock two different files. Works between
    processes of one machine and on local file systems; over NFS it depends on the server."""

    def __init__(self, folder: Path):
        self.folder = folder
        self.path = folder / LOCK
        self.handle: int | None = None

    def refuse_if_held(self) -> None:
        """Raise the error :meth:`__enter__` would if another run holds the lock now, creating
        nothing (no lock file: nobody holds it). For the checks made before locking: a folder
        another run is writing is named as that, not judged half-written."""
        import fcntl

        try:
            handle = os.open(self.path, os.O_RDONLY | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0))
        except OSError:
            return  # none yet, or not ours to open: __enter__ says which
        try:
            fcntl.flock(handle, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            raise self._busy(handle) from None
        except OSError:
            pass
        finally:
            os.close(handle)

    def __enter__(self) -> FolderLock:
        import fcntl

        try:  # O_NOFOLLOW: a link planted at .lock must not make us write into its target
            handle = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0), 0o666)
        except OSError as error:
            raise DatasetError(f"cannot lock {self.path}: {error.strerror or error}") from None
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            busy = self._busy(handle)
            os.close(handle)
            raise busy from None
        except OSError as error:
            os.close(handle)
            raise DatasetError(f"cannot lock {self.path}: {error.strerror or error}") from None
        record = {
            "pid": os.getpid(),
            "host": socket.gethostname(),
            "since": time.strftime("%Y-%m-%d %H:%M:%S"),
            "command": " ".join(sys.argv)[:500],
        }
        os.ftruncate(handle, 0)
        os.pwrite(handle, json.dumps(record).encode(), 0)
        self.handle = handle
        return self

    def _busy(self, handle: int) -> DatasetError:
        holder = _holder(handle)
        return DatasetError(f"{self.folder} is being written by another run ({holder}); wait for it to end or stop it")

    def __exit__(self, *exc) -> None:
        if self.handle is not None:
            os.close(self.handle)  # releases the flock
            self.handle = None


def _holder(handle: int) -> str:
    """Who holds the lock, from what it wrote into the lock file."""
    try:
        record = json.loads(os.pread(handle, 4096, 0))
        return f"process {record['pid']} on {record['host']} since {record['since']}: {record['command']}"
    except (OSError, ValueError, KeyError, TypeError, RecursionError):
        return "a process that has not said which yet"


__all__ = ["FolderLock"]
