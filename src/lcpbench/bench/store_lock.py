"""The sweep lock file beside a store: ``flock`` on ``<store>.lock``, removed on release.

The holder writes who it is into the file (pid, host, owner, start, sweep id)
and unlinks the file *while it still holds the lock*, then closes it. A
process that was waiting on that file is then granted a lock on a file that
is no longer at the path: after every grant the waiter compares the inode
it locked (``os.fstat``) with the one at the path (``os.stat``) and, if they
differ or the path is gone, closes it and starts again. So only the holder
of the file at the path ever holds the lock, and only that holder unlinks
it. The kernel drops a lock when its process dies; the file of a killed
holder stays (with its details) and the next sweep locks it as it is.
"""

from __future__ import annotations

import fcntl
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ..errors import StoreError


@contextmanager
def hold_lock(lock_path: Path, store_path: Path, *, wait: bool = False) -> Iterator:
    """Hold the exclusive lock on ``lock_path``; yields its file, emptied, to write to.

    Raises StoreError naming the holder when the lock is taken and ``wait``
    is False, or when the lock file cannot be created. The file is removed
    when the block ends (also when it raises).
    """
    while True:
        try:
            fh = open(lock_path, "a+")
        except OSError as exc:
            raise StoreError(f"store {store_path}: cannot create its lock file "
                             f"{lock_path} ({exc.strerror or exc})") from exc
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
        except BlockingIOError:
            fh.close()
            raise StoreError(f"store {store_path} is locked by {holder(lock_path)}; wait "
                             "for it to finish, or use --wait") from None
        except BaseException:
            fh.close()
            raise
        if _is_at(fh, lock_path):
            break
        fh.close()  # its holder removed it meanwhile: lock the file now at the path
    try:
        fh.seek(0)
        fh.truncate()
        yield fh
    finally:
        try:
            os.unlink(lock_path)  # still held: nobody else can be holding this file
        except OSError:
            pass  # its folder went away or became read-only: the file stays, harmless
        fh.close()  # closing the file releases the flock


def _is_at(fh, path: Path) -> bool:
    """Whether the open file ``fh`` is the file at ``path`` (same device and inode)."""
    try:
        at = os.stat(path)
    except FileNotFoundError:
        return False
    mine = os.fstat(fh.fileno())
    return (mine.st_dev, mine.st_ino) == (at.st_dev, at.st_ino)


def holder(lock_path: Path) -> str:
    """Who holds the lock, from the lock file (best effort)."""
    try:
        info = json.loads(Path(lock_path).read_text() or "{}")
    except (OSError, ValueError):
        info = {}
    if not info:
        return "another process (no details recorded yet)"
    return (f"pid {info.get('pid', '?')} on host {info.get('host', '?')} "
            f"({info.get('owner', '?')}, started {info.get('started', '?')})")
