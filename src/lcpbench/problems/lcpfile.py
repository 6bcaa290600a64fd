"""Read and write LCP files: Siconos ``.dat`` and numpy ``.npz``.

An LCP: find ``z >= 0`` with ``w = M z + q >= 0`` and ``z'w = 0``.

Siconos ``.dat`` (the test collection of Siconos numerics): whitespace-separated
numbers, anything after ``#`` a comment::

    n                        size of the problem
    storage                  0 = dense, 1 = sparse block
    size0 size1              matrix dimensions
    -- dense (0) --
    size0 size1              repeated
    size0*size1 numbers      M, COLUMN-MAJOR: M[i, j] = values[i + j*size0]
    -- sparse block (1) --   (Siconos ``SBM_new_from_file``)
    nbblocks                 number of stored blocks (0: M = 0, nothing follows)
    nb0 nb1                  number of block rows and block columns
    nb0 integers             cumulative row sizes: block row r ends at row sizes0[r]
    nb1 integers             cumulative column sizes
    filled1 filled2          lengths of the two index arrays
    filled1 integers         row pointers: block row r holds blocks ptr[r]..ptr[r+1]-1
    filled2 integers         block column of each stored block
    per stored block k, in order: the integer k, then its entries COLUMN-MAJOR
    -- both --
    n numbers                q

Free text after ``q`` (a note, as in several Siconos files) is ignored, as
Siconos ignores it; extra *numbers* after ``q`` are a count error. The block
layout was worked out from the ``*_block.dat`` files of the Siconos
collection and checked against their dense siblings (``lcp_ortiz`` is
non-symmetric, so it also pins down the column-major order inside a block).

``.npz``: arrays named ``M`` (n x n) and ``q`` (n).

Size limit
----------
``M`` is read into a dense float64 array, so a file may declare at most
:data:`MAX_SIZE` = 16384 complementarity pairs (M then takes 2 GiB). The
size is checked as soon as it is known — the header of a ``.dat`` file, the
``.npy`` headers inside an ``.npz`` archive — before anything is allocated:
a file declaring more is refused with a ProblemError that gives the declared
size, the memory it would need and the limit (never a MemoryError).

Bounded reading
---------------
Only regular files are read: a device (``/dev/zero``), a pipe or a directory is
refused before it is opened. A ``.dat`` file is refused, from its size and
header alone, when it takes more than :data:`BYTES_PER_NUMBER` bytes per
number the header promises plus :data:`FREE_TEXT_BYTES` (a 2 GB file that
says n = 3 is not read). It is then parsed as a stream, :data:`CHUNK_CHARS`
characters at a time, into the arrays: the memory is M and q plus one chunk.
Text that is not UTF-8, a token longer than :data:`MAX_TOKEN_CHARS` and a
header integer of more than :data:`MAX_INT_DIGITS` digits are one-line
ProblemErrors naming the file.
"""

from __future__ import annotations

import os
import re
import stat
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lcpbench.errors import ProblemError

#: Formats understood by :func:`read_lcp` and :func:`write_lcp`, by suffix.
FORMATS = ("dat", "npz")

_INT = re.compile(r"[+-]?\d+\Z")

#: Largest n read into a dense n x n float64 M (16384² x 8 bytes = 2 GiB).
MAX_SIZE = 16384
#: Most bytes a ``.dat`` file may take per number its header promises (``%.17g`` takes
#: at most 24 and a separator) ...
BYTES_PER_NUMBER = 64
#: ... plus this many for the header, comments and a note after ``q``.
FREE_TEXT_BYTES = 2**20
#: Characters read from a ``.dat`` file at a time: the text in memory at once.
CHUNK_CHARS = 2**20
#: Longest token of a ``.dat`` file, in characters (a number takes at most a few dozen).
MAX_TOKEN_CHARS = 4096
#: Most digits of an integer in a ``.dat`` header (n itself is at most MAX_SIZE).
MAX_INT_DIGITS = 18


def _gib(nbytes: float) -> str:
    return f"{nbytes / 2**30:.3g} GiB"


def check_size(n: int, where: str) -> None:
    """ProblemError unless an LCP of size ``n`` fits :data:`MAX_SIZE` (before allocating)."""
    if n > MAX_SIZE:
        raise ProblemError(
            f"{where}: declares an LCP of size n = {n} (a dense M of {_gib(8.0 * n * n)}); "
            f"lcpbench reads at most n = {MAX_SIZE} ({_gib(8.0 * MAX_SIZE**2)})")


@dataclass
class LCPProblem:
    """An LCP ``w = M z + q``, ``0 <= z`` perp ``w >= 0`` with dense ``M``.

    Attributes
    ----------
    M : ndarray, shape (n, n)
    q : ndarray, shape (n,)
    name : str
        Usually the file's stem.
    """

    M: np.ndarray
    q: np.ndarray
    name: str = ""

    @property
    def size(self) -> int:
        """The number of complementarity pairs ``n``."""
        return int(self.q.size)


def _format_of(path: Path, fmt: str | None) -> str:
    if fmt is None:
        fmt = path.suffix.lower().lstrip(".")
        if fmt not in FORMATS:
            raise ProblemError(f"{path}: unknown LCP file suffix {path.suffix!r}; "
                               f"expected one of {', '.join('.' + f for f in FORMATS)}")
        return fmt
    if fmt not in FORMATS:
        raise ProblemError(f"unknown LCP file format {fmt!r}; expected one of "
                           f"{', '.join(FORMATS)} or None (from the suffix)")
    return fmt


def _check_arrays(M, q, where: str) -> tuple[np.ndarray, np.ndarray]:
    """Dense float ``M`` (n x n) and ``q`` (n), finite, or ProblemError naming ``where``."""
    try:
        M = np.asarray(M.toarray() if hasattr(M, "toarray") else M)
        q = np.asarray(q)
        if np.iscomplexobj(M) or np.iscomplexobj(q):
            raise ValueError("complex values")
        M, q = np.array(M, dtype=float), np.array(q, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"{where}: M and q must be real numeric arrays ({exc})") from exc
    if M.ndim != 2 or M.shape[0] != M.shape[1] or M.shape[0] == 0:
        raise ProblemError(f"{where}: M must be a non-empty square matrix, got shape {M.shape}")
    if q.ndim != 1 or q.size != M.shape[0]:
        raise ProblemError(f"{where}: q must be a vector of length {M.shape[0]}, "
                           f"got shape {q.shape}")
    if not (np.all(np.isfinite(M)) and np.all(np.isfinite(q))):
        raise ProblemError(f"{where}: M and q must be finite (found NaN or inf)")
    return M, q


# -- Siconos .dat ---------------------------------------------------------------------------
def _show(tok: str) -> str:
    """A token for a message: quoted, and cut short when it is long."""
    if len(tok) <= 40:
        return repr(tok)
    return f"{tok[:20]!r}... ({len(tok)} characters)"


class _Tokens:
    """The whitespace-separated tokens of a text file, comments dropped, with line numbers.

    The file is read as a stream, :data:`CHUNK_CHARS` characters at a time: besides the
    arrays being filled, the reader holds one chunk and its tokens, never the whole text.
    """

    def __init__(self, path: Path, fh):
        self.path = path
        self._fh = fh
        self._toks: list[str] = []    # the tokens of the chunk in hand ...
        self._lines: list[int] = []   # ... and their line numbers
        self._pos = 0
        self._carry = ""              # a token cut by the end of the chunk
        self._lineno = 1
        self._in_comment = False
        self._eof = False

    def error(self, what: str) -> ProblemError:
        return ProblemError(f"{self.path}: {what}")

    # -- the stream -------------------------------------------------------------------
    def _read(self) -> str:
        try:
            return self._fh.read(CHUNK_CHARS)
        except UnicodeDecodeError as exc:
            raise self.error(f"cannot read: not UTF-8 text after line {self._lineno} "
                             f"({exc.reason})") from None
        except OSError as exc:
            raise self.error(f"cannot read ({exc.strerror or exc})") from exc

    def _scan(self, text: str) -> None:
        """Append the tokens of ``text`` (which ends between tokens) to the chunk in hand."""
        for i, part in enumerate(text.split("\n")):
            if i:
                self._lineno += 1
                self._in_comment = False
            if self._in_comment:
                continue
            head, hash_, _ = part.partition("#")
            self._in_comment = bool(hash_)
            words = head.split()
            self._toks.extend(words)
            self._lines.extend([self._lineno] * len(words))

    def _fill(self) -> bool:
        """Read on until a token is in hand; False at the end of the file."""
        while self._pos >= len(self._toks):
            if self._eof:
                return False
            if len(self._carry) > MAX_TOKEN_CHARS:
                raise self.error(f"line {self._lineno}: a token of more than "
                                 f"{MAX_TOKEN_CHARS} characters ({_show(self._carry)})")
            self._toks, self._lines, self._pos = [], [], 0
            chunk = self._read()
            text = self._carry + chunk
            if not chunk:
                self._eof, self._carry = True, ""
                self._scan(text)
                continue
            cut = max(text.rfind(c) for c in " \t\n\r\f\v")
            self._carry = text[cut + 1:]
            self._scan(text[:cut + 1])
            if self._in_comment:  # the cut token is part of a comment
                self._carry = ""
            elif "#" in self._carry:  # a token ended by a comment
                self._scan(self._carry)
                self._carry = ""
        return True

    def _next(self, what: str) -> tuple[str, int]:
        if not self._fill():
            raise self.error(f"file ends early: expected {what}")
        self._pos += 1
        return self._toks[self._pos - 1], self._lines[self._pos - 1]

    @property
    def line(self) -> int:
        """The line reached (of the last token taken)."""
        return self._lines[self._pos - 1] if self._pos else self._lineno

    # -- values -----------------------------------------------------------------------
    def integer(self, what: str, low: int = 0) -> int:
        tok, line = self._next(what)
        if not _INT.match(tok):
            raise self.error(f"line {line}: expected an integer for {what}, got {_show(tok)}")
        digits = len(tok.lstrip("+-").lstrip("0"))
        if digits > MAX_INT_DIGITS:
            raise self.error(f"line {line}: {what} has {digits} digits; the header's "
                             f"integers have at most {MAX_INT_DIGITS}")
        value = int(tok)
        if value < low:
            raise self.error(f"line {line}: {what} must be >= {low}, got {value}")
        return value

    def integers(self, count: int, what: str, low: int = 0) -> list[int]:
        return [self.integer(what, low) for _ in range(count)]

    def floats(self, count: int, what: str) -> np.ndarray:
        """The next ``count`` numbers, read chunk by chunk into one float array."""
        out = np.empty(count)
        done = 0
        while done < count:
            if not self._fill():
                hint = " (M or q too short?)" if what == "q" else ""
                raise self.error(f"file ends early: {what} needs {count} numbers, "
                                 f"found {done}{hint}")
            take = min(count - done, len(self._toks) - self._pos)
            chunk = self._toks[self._pos:self._pos + take]
            if max(map(len, chunk)) > MAX_TOKEN_CHARS:
                i = next(i for i, t in enumerate(chunk) if len(t) > MAX_TOKEN_CHARS)
                raise self.error(f"line {self._lines[self._pos + i]}: a number of more than "
                                 f"{MAX_TOKEN_CHARS} characters in {what} ({_show(chunk[i])})")
            try:
                values = np.array([float(t) for t in chunk])
            except ValueError:
                i = next(i for i, t in enumerate(chunk) if not _is_float(t))
                raise self.error(f"line {self._lines[self._pos + i]}: non-numeric token "
                                 f"{_show(chunk[i])} in {what}") from None
            bad = np.flatnonzero(~np.isfinite(values))
            if bad.size:
                i = int(bad[0])
                raise self.error(f"line {self._lines[self._pos + i]}: non-finite value "
                                 f"{_show(chunk[i])} in {what}")
            out[done:done + take] = values
            done += take
            self._pos += take
        return out

    def check_end(self) -> None:
        """Free text may follow ``q``; further numbers mean a wrong count."""
        if not self._fill() or not _is_float(self._toks[self._pos]):
            return
        line, extra = self._lines[self._pos], 0
        while self._fill():
            extra += sum(1 for t in self._toks[self._pos:] if _is_float(t))
            self._pos = len(self._toks)
        raise self.error(f"line {line}: {extra} extra number(s) after q "
                         "(wrong n or matrix size?)")


def _is_float(tok: str) -> bool:
    try:
        float(tok)
    except ValueError:
        return False
    return True


def _read_block(tk: _Tokens, size0: int, size1: int) -> np.ndarray:
    """The sparse block matrix (Siconos ``SBM_new_from_file``) as a dense array."""
    M = np.zeros((size0, size1))
    nblocks = tk.integer("the number of blocks")
    if nblocks == 0:
        return M
    nb0 = tk.integer("the number of block rows", 1)
    nb1 = tk.integer("the number of block columns", 1)
    ends0 = tk.integers(nb0, "a cumulative block row size", 1)
    ends1 = tk.integers(nb1, "a cumulative block column size", 1)
    for ends, size, kind in ((ends0, size0, "row"), (ends1, size1, "column")):
        if any(b <= a for a, b in zip(ends, ends[1:])) or ends[-1] != size:
            raise tk.error(f"cumulative block {kind} sizes {ends} must increase "
                           f"strictly up to {size}")
    filled1 = tk.integer("filled1 (length of the row pointers)", 2)
    filled2 = tk.integer("filled2 (length of the column indices)", 1)
    if filled1 > nb0 + 1 or filled2 != nblocks:
        raise tk.error(f"index lengths filled1={filled1}, filled2={filled2} do not fit "
                       f"{nb0} block rows and {nblocks} blocks")
    ptr = tk.integers(filled1, "a block row pointer")
    if ptr[0] != 0 or ptr[-1] != nblocks or any(b < a for a, b in zip(ptr, ptr[1:])):
        raise tk.error(f"block row pointers {ptr} must rise from 0 to {nblocks}")
    bcol = tk.integers(filled2, "a block column index")
    if max(bcol) >= nb1:
        raise tk.error(f"block column index {max(bcol)} out of range (< {nb1})")
    starts0, starts1 = [0, *ends0[:-1]], [0, *ends1[:-1]]
    for r in range(filled1 - 1):
        cols = bcol[ptr[r]:ptr[r + 1]]
        if len(set(cols)) != len(cols):
            raise tk.error(f"block row {r} stores block column(s) more than once: {cols}")
        for k in range(ptr[r], ptr[r + 1]):
            label = tk.integer(f"the number of block {k}")
            if label != k:
                raise tk.error(f"blocks out of order: expected block number {k}, got {label}")
            c = bcol[k]
            rows = slice(starts0[r], ends0[r])
            cols_ = slice(starts1[c], ends1[c])
            nr, nc = ends0[r] - starts0[r], ends1[c] - starts1[c]
            values = tk.floats(nr * nc, f"block {k} ({nr}x{nc})")
            M[rows, cols_] = values.reshape((nr, nc), order="F")
    return M


def _check_bytes(path: Path, nbytes: int, n: int, storage: int) -> None:
    """Refuse a file far larger than the numbers its header promises can take."""
    # dense: 5 header integers, M and q; sparse block: at most n² entries, as many block
    # numbers, and O(n) sizes and pointers
    numbers = n * n + n + 5 if storage == 0 else 2 * n * n + 5 * n + 10
    limit = BYTES_PER_NUMBER * numbers + FREE_TEXT_BYTES
    if nbytes > limit:
        raise ProblemError(
            f"{path}: the file takes {nbytes} bytes, far more than an LCP of size n = {n} "
            f"({numbers} numbers) can: at most {limit} bytes ({BYTES_PER_NUMBER} per number "
            f"and {FREE_TEXT_BYTES} for comments); refused without reading it")


def _read_dat(path: Path, fh, nbytes: int) -> LCPProblem:
    tk = _Tokens(path, fh)
    n = tk.integer("the problem size n", 1)
    check_size(n, str(path))
    storage = tk.integer("the storage code (0 dense, 1 sparse block)")
    if storage not in (0, 1):
        raise tk.error(f"unknown storage code {storage}; expected 0 (dense) or "
                       "1 (sparse block)")
    _check_bytes(path, nbytes, n, storage)
    size0 = tk.integer("the matrix row count", 1)
    size1 = tk.integer("the matrix column count", 1)
    if (size0, size1) != (n, n):
        raise tk.error(f"matrix is {size0}x{size1} but n = {n}; an LCP needs an n x n matrix")
    if storage == 0:
        again = (tk.integer("the repeated row count"), tk.integer("the repeated column count"))
        if again != (size0, size1):
            raise tk.error(f"repeated dense size {again[0]}x{again[1]} differs from "
                           f"{size0}x{size1}")
        M = tk.floats(n * n, f"the {n}x{n} matrix").reshape((n, n), order="F")
    else:
        M = _read_block(tk, size0, size1)
    q = tk.floats(n, "q")
    tk.check_end()
    return LCPProblem(M=M, q=q, name=path.stem)


def _read_npz(path: Path) -> LCPProblem:
    # The file is opened here (not by np.load) so it is closed even when np.load fails.
    with open(path, "rb") as fh:
        try:
            data = np.load(fh, allow_pickle=False)
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            raise ProblemError(f"{path}: not a readable .npz archive ({exc})") from exc
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ProblemError(f"{path}: a single .npy array, not an .npz archive of M and q")
        with data:
            missing = [k for k in ("M", "q") if k not in data.files]
            if missing:
                raise ProblemError(f"{path}: missing array(s) {', '.join(missing)}; "
                                   f"found {', '.join(data.files) or 'none'}")
            _check_npz_headers(data, path)
            try:
                M, q = data["M"], data["q"]
            except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
                raise ProblemError(f"{path}: cannot read arrays M and q ({exc})") from exc
    M, q = _check_arrays(M, q, str(path))
    return LCPProblem(M=M, q=q, name=path.stem)


def _check_npz_headers(data, path: Path) -> None:
    """Refuse M or q whose ``.npy`` header declares more than :data:`MAX_SIZE` rows."""
    for key in ("M", "q"):
        try:
            with data.zip.open(f"{key}.npy") as fh:
                version = np.lib.format.read_magic(fh)
                read = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                        else np.lib.format.read_array_header_2_0)
                shape, _, dtype = read(fh)
        except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as exc:
            raise ProblemError(f"{path}: cannot read the header of array {key} ({exc})") from exc
        if any(int(d) > MAX_SIZE for d in shape) or len(shape) > 2:
            size = max(int(d) for d in shape) if shape else 0
            nbytes = float(np.prod([float(d) for d in shape])) * dtype.itemsize
            raise ProblemError(
                f"{path}: array {key} declares shape {tuple(shape)} ({_gib(nbytes)}); "
                f"lcpbench reads LCPs of size n <= {MAX_SIZE} (M at most "
                f"{_gib(8.0 * MAX_SIZE**2)})" if size > MAX_SIZE else
                f"{path}: array {key} must have at most 2 dimensions, got shape {tuple(shape)}")


def read_lcp(path: str | os.PathLike, *, fmt: str | None = None) -> LCPProblem:
    """Read an LCP from a Siconos ``.dat`` file or an ``.npz`` archive.

    Parameters
    ----------
    path : str or path-like
    fmt : {'dat', 'npz'}, optional
        Format; default from the file's suffix.

    Returns
    -------
    LCPProblem
        Dense ``M`` (n x n, in the file's column-major order) and ``q``;
        ``name`` is the file's stem.

    Raises
    ------
    ProblemError
        One line naming the file and the fault: missing or unreadable file,
        not a regular file (a device, pipe or directory), a ``.dat`` file far
        larger than its header's n allows, text that is not UTF-8, an oversized
        number, unknown suffix or format, unknown storage code, non-integer header,
        non-numeric or non-finite entries, too few numbers or extra numbers
        after ``q``, inconsistent sizes or block structure.
    """
    path = Path(path)
    fmt = _format_of(path, fmt)
    nbytes = regular_file_size(path)
    try:
        if fmt == "npz":
            return _read_npz(path)
        with open(path, encoding="utf-8") as fh:
            return _read_dat(path, fh, nbytes)
    except FileNotFoundError:
        raise ProblemError(f"{path}: no such file") from None
    except OSError as exc:
        raise ProblemError(f"{path}: cannot read ({exc.strerror or exc})") from exc


def regular_file_size(path: Path, what: str | None = None) -> int:
    """The size in bytes of the regular file ``path``, or ProblemError (one line).

    A device (``/dev/zero``), a pipe or a directory is refused before it is opened: a
    device never ends, and opening a pipe waits for a writer. ``what`` starts the
    message (default: the path).
    """
    where = str(path) if what is None else what
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ProblemError(f"{where}: no such file") from None
    except OSError as exc:
        raise ProblemError(f"{where}: cannot read ({exc.strerror or exc})") from exc
    if not stat.S_ISREG(st.st_mode):
        kind = ("a directory" if stat.S_ISDIR(st.st_mode) else
                "a device" if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode) else
                "a pipe" if stat.S_ISFIFO(st.st_mode) else "a socket or other special file")
        raise ProblemError(f"{where}: is {kind}, not a regular file")
    return int(st.st_size)


def write_lcp(path: str | os.PathLike, M, q, *, fmt: str | None = None) -> Path:
    """Write an LCP as a Siconos ``.dat`` file or an ``.npz`` archive.

    Parameters
    ----------
    path : str or path-like
        Written exactly as given (no suffix is appended).
    M : array_like, shape (n, n)
        Dense or scipy sparse (densified).
    q : array_like, shape (n,)
    fmt : {'dat', 'npz'}, optional
        Format; default from the suffix of ``path``.

    Returns
    -------
    Path
        The path written.

    Notes
    -----
    ``.dat`` is written with dense storage (0), one column of ``M`` per line
    (column-major), every number as ``%.17g`` so :func:`read_lcp` returns the
    same floats bit for bit. The descriptive ``#`` comment goes after ``q``:
    Siconos' own reader stops there, so the file stays readable by Siconos,
    whereas a comment before ``n`` would break it.

    Raises
    ------
    ProblemError
        On an unknown format, bad shapes or non-finite values, or when the
        file cannot be written (e.g. its directory does not exist).
    """
    path = Path(path)
    fmt = _format_of(path, fmt)
    M, q = _check_arrays(M, q, f"write_lcp({str(path)!r})")
    n = q.size
    try:
        if fmt == "npz":
            with open(path, "wb") as fh:  # a file object: numpy appends no suffix
                np.savez(fh, M=M, q=q)
        else:
            lines = [str(n), "0", str(n), str(n), f"{n}\t{n}"]
            lines += [" ".join(f"{v:.17g}" for v in col) for col in M.T]
            lines.append(" ".join(f"{v:.17g}" for v in q))
            lines.append("")
            lines.append(f"# LCP n={n} written by lcpbench: Siconos format, dense storage "
                         "(0), M column-major (one column per line), then q")
            path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    except OSError as exc:
        raise ProblemError(f"{path}: cannot write ({exc.strerror or exc})") from exc
    return path
