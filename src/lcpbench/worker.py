"""A Python subprocess that answers length-prefixed messages: one utility for every worker.

The sweep's job workers (:mod:`lcpbench.bench.pool`) and the Siconos bridge's
solver process (:mod:`lcpbench.solvers.siconos_bridge`, run by the *system*
interpreter) are both a Python subprocess that reads requests on its stdin
and writes answers on a private copy of its stdout. This module is both
halves of that, and it imports the standard library only: the Siconos
worker script loads it by file path under an interpreter where lcpbench is
not installed.

Messages are byte strings, each framed by its length (8 bytes, little
endian); what is inside (pickles, JSON and raw floats) is the caller's.

Parent side: :class:`WorkerProcess` spawns the interpreter, writes and reads
messages with deadlines (a hung worker never blocks the caller past one),
kills it, and asks the child to die with its parent.

Child side: :func:`child_channel` keeps the original stdout for the protocol
and points fd 1 at stderr (so libraries that print cannot corrupt it);
:func:`die_with_parent` has the kernel SIGKILL the child when its parent
dies (Linux ``PR_SET_PDEATHSIG``); :func:`read_message` and
:func:`write_message` move one message.
"""

from __future__ import annotations

import os
import select
import struct
import subprocess
import sys
import threading
import time

_HEAD = struct.Struct("<Q")
#: set by the parent: its pid, when the child is to die with it
PARENT_ENV = "LCPBENCH_WORKER_PARENT"


class WorkerDied(Exception):
    """The worker closed its pipe (exited, crashed or was killed)."""


# -- child side -------------------------------------------------------------------------
def die_with_parent() -> None:
    """Linux: have the kernel SIGKILL this process when the parent that spawned it dies.

    Only if the parent asked for it (:data:`PARENT_ENV`, set by
    :class:`WorkerProcess` when spawned from the parent's main thread: the
    kernel's "parent" is the thread that forked). Without it a worker of a
    killed sweep finishes (or hangs in) its current job before it notices the
    closed pipe. Elsewhere the closed pipe still ends the worker.
    """
    parent = os.environ.get(PARENT_ENV)
    if not parent:
        return
    import ctypes
    import signal

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL))  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # not Linux
        return
    if str(os.getppid()) != parent:  # the parent died before prctl took effect
        os._exit(0)


def child_channel():
    """(input, output) binary streams of the protocol, for the child.

    The output is a duplicate of the original stdout; fd 1 (and ``sys.stdout``)
    then point at stderr, so anything printed by Python or C code goes there.
    """
    out = os.fdopen(os.dup(1), "wb", buffering=0)
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    return sys.stdin.buffer, out


def _read_exact(fh, n: int) -> bytes:
    out = bytearray()
    while len(out) < n:
        chunk = fh.read(n - len(out))
        if not chunk:
            break
        out += chunk
    return bytes(out)


def read_message(fh) -> bytes | None:
    """The next message on ``fh``, or None at the end of input."""
    head = _read_exact(fh, _HEAD.size)
    if not head:
        return None
    if len(head) < _HEAD.size:
        raise EOFError("end of input inside a message header")
    (size,) = _HEAD.unpack(head)
    data = _read_exact(fh, size)
    if len(data) < size:
        raise EOFError("end of input inside a message")
    return data


def write_message(fh, data: bytes) -> None:
    fh.write(_HEAD.pack(len(data)) + data)
    fh.flush()


# -- parent side ------------------------------------------------------------------------
class WorkerProcess:
    """One running worker subprocess: ``python [-I] *argv`` with framed messages.

    Parameters
    ----------
    argv : arguments after the interpreter (``["-m", "pkg.mod"]``, a script path).
    python : the interpreter (default: this one).
    env : the child's environment (default: this one's).
    stderr : where the child's stderr goes (None: inherit; a file; DEVNULL).
    isolated : run with ``-I`` (no PYTHONPATH, user site or script directory).
    die_with_parent : ask the child (it must call :func:`die_with_parent`) to
        be killed when this process dies.
    """

    def __init__(self, argv: list[str], *, python: str | None = None,
                 env: dict | None = None, stderr=None, isolated: bool = False,
                 die_with_parent: bool = True):
        env = dict(os.environ if env is None else env)
        env.pop(PARENT_ENV, None)
        if die_with_parent and threading.current_thread() is threading.main_thread():
            env[PARENT_ENV] = str(os.getpid())
        self.python = python or sys.executable
        self.proc = subprocess.Popen(
            [self.python, *(["-I"] if isolated else []), *argv], env=env,
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=stderr, bufsize=0,
            close_fds=True)
        self.owner = os.getpid()
        self._buf = bytearray()
        os.set_blocking(self.proc.stdin.fileno(), False)

    @property
    def pid(self) -> int:
        return self.proc.pid

    def fileno(self) -> int:
        """The fd to wait on for the worker's output (``select``, ``connection.wait``)."""
        return self.proc.stdout.fileno()

    def alive(self) -> bool:
        return self.owner == os.getpid() and self.proc.poll() is None

    @property
    def returncode(self) -> int | None:
        return self.proc.poll()

    # reading
    def _take(self) -> bytes | None:
        if len(self._buf) < _HEAD.size:
            return None
        (size,) = _HEAD.unpack_from(self._buf)
        end = _HEAD.size + size
        if len(self._buf) < end:
            return None
        data = bytes(self._buf[_HEAD.size:end])
        del self._buf[:end]
        return data

    def _read_some(self) -> None:
        chunk = os.read(self.fileno(), 1 << 20)
        if not chunk:
            raise WorkerDied("the worker closed its pipe")
        self._buf += chunk

    def poll(self) -> bytes | None:
        """A complete message if one has arrived, else None (reads what is ready)."""
        msg = self._take()
        if msg is not None:
            return msg
        ready, _, _ = select.select([self.fileno()], [], [], 0)
        if ready:
            self._read_some()
        return self._take()

    def recv(self, deadline: float | None = None) -> bytes:
        """The next message; TimeoutError past ``deadline`` (``time.monotonic``)."""
        while (msg := self._take()) is None:
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                raise TimeoutError
            ready, _, _ = select.select([self.fileno()], [], [], left)
            if not ready:
                raise TimeoutError
            self._read_some()
        return msg

    # writing
    def send(self, data: bytes, deadline: float | None = None) -> None:
        """Write one message without blocking past ``deadline``.

        The worker's output is read meanwhile (into the buffer), so a worker
        that answers early or dies cannot deadlock the write.
        """
        pending = memoryview(_HEAD.pack(len(data)) + data)
        wfd, rfd = self.proc.stdin.fileno(), self.fileno()
        while len(pending):
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                raise TimeoutError
            readable, writable, _ = select.select([rfd], [wfd], [], left)
            if not readable and not writable:
                raise TimeoutError
            if readable:
                self._read_some()
            if writable:
                try:
                    k = os.write(wfd, pending[:1 << 20])
                except BlockingIOError:
                    k = 0
                except OSError as exc:  # BrokenPipeError: the worker is gone
                    raise WorkerDied("the worker closed its input") from exc
                pending = pending[k:]

    def request(self, data: bytes, timeout: float | None = None) -> bytes:
        """Send one message and return the answer, all within ``timeout`` seconds."""
        deadline = None if timeout is None else time.monotonic() + timeout
        self.send(data, deadline)
        return self.recv(deadline)

    # stopping
    def kill(self) -> None:
        """SIGKILL the worker at once (a hung or misbehaving one) and close its pipes."""
        if self.owner != os.getpid():
            return  # a forked child must not kill its parent's worker
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
        self._close()

    def stop(self, timeout: float = 2.0, goodbye: bytes | None = None) -> None:
        """A clean exit: send ``goodbye`` (if given), close its input, wait; else kill."""
        if self.owner != os.getpid():
            return
        if self.proc.poll() is None:
            try:
                if goodbye is not None:
                    self.send(goodbye, time.monotonic() + timeout)
                self.proc.stdin.close()
                self.proc.wait(timeout)
            except (OSError, ValueError, TimeoutError, WorkerDied,
                    subprocess.TimeoutExpired):
                pass
        self.kill()

    def _close(self) -> None:
        for fh in (self.proc.stdin, self.proc.stdout):
            try:
                fh.close()
            except OSError:
                pass
