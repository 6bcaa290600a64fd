"""Tests of the LCP file reader and writer (Siconos .dat and .npz).

The peer collection's README is the independent reference for the layout:
``lcp_exp_murty.dat`` is upper triangular (column-major storage), and each
``*_block.dat`` file must give the same M and q as its dense sibling.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from lcpbench.errors import ProblemError
from lcpbench.problems import lcpfile
from lcpbench.problems.lcpfile import LCPProblem, read_lcp, write_lcp
from lcpbench.solvers.lemke import lemke

PEER = Path(__file__).resolve().parents[1] / "data" / "siconos-lcp"  # Siconos LCPs
PEER_FILES = sorted(PEER.glob("*.dat"))
BLOCK_PAIRS = [("lcp_deudeu", 2), ("lcp_ortiz", 4), ("lcp_trivial", 9)]

needs_peer = pytest.mark.skipif(not PEER.is_dir(), reason="peer Siconos data not present")


# --- 1. the peer collection -----------------------------------------------------------------


@needs_peer
def test_peer_collection_is_complete():
    assert len(PEER_FILES) == 20
    assert sum(p.stem.endswith("_block") for p in PEER_FILES) == 3


@needs_peer
@pytest.mark.parametrize("path", PEER_FILES, ids=lambda p: p.stem)
def test_every_peer_file_reads(path):
    prob = read_lcp(path)
    assert isinstance(prob, LCPProblem)
    n = prob.size
    assert n >= 2 and prob.M.shape == (n, n) and prob.q.shape == (n,)
    assert prob.M.dtype == float and np.all(np.isfinite(prob.M)) and np.all(np.isfinite(prob.q))
    assert prob.name == path.stem
    first = int(path.read_text().split()[0])
    assert n == first


@needs_peer
@pytest.mark.parametrize("stem, n", BLOCK_PAIRS, ids=[s for s, _ in BLOCK_PAIRS])
def test_block_storage_equals_dense_sibling(stem, n):
    dense = read_lcp(PEER / f"{stem}.dat")
    block = read_lcp(PEER / f"{stem}_block.dat")
    assert dense.size == block.size == n
    np.testing.assert_array_equal(block.M, dense.M)
    np.testing.assert_array_equal(block.q, dense.q)


@needs_peer
def test_ortiz_is_column_major_by_hand():
    # lcp_ortiz.dat lists 3 -1 0 0 / 1 2 1 0 / ...: those are the COLUMNS of M.
    M = read_lcp(PEER / "lcp_ortiz.dat").M
    np.testing.assert_array_equal(M[:, 0], [3, -1, 0, 0])
    np.testing.assert_array_equal(M[0], [3, 1, 0, -1])
    assert not np.array_equal(M, M.T)  # non-symmetric: a transposition would show


@needs_peer
@pytest.mark.parametrize("stem", ["lcp_exp_murty", "lcp_exp_murty2"])
def test_murty_is_upper_triangular(stem):
    # README: "lcp_exp_murty.dat is upper triangular" (Murty 1988, ch. 6): 1 on the
    # diagonal, 2 above it.
    M = read_lcp(PEER / f"{stem}.dat").M
    expected = np.triu(np.full((6, 6), 2.0), k=1) + np.eye(6)
    np.testing.assert_array_equal(M, expected)


@needs_peer
def test_murty2_shows_lemke_exponential_pivots():
    # README: Siconos' Lemke needs 63 pivots on lcp_exp_murty2 (2^6 - 1); read transposed
    # the problem would be easy. Our Lemke also counts the initial pivot of z0.
    prob = read_lcp(PEER / "lcp_exp_murty2.dat")
    assert lemke(prob.M, prob.q).iterations >= 63
    assert lemke(prob.M.T, prob.q).iterations < 10


@needs_peer
def test_free_text_after_q_is_ignored():
    # lcp_CPS_1.dat ends with "Remark 4.1.14 CPS 2009 / set of solution is ...".
    prob = read_lcp(PEER / "lcp_CPS_1.dat")
    np.testing.assert_array_equal(prob.M, np.ones((2, 2)))
    np.testing.assert_array_equal(prob.q, [-1.0, -1.0])


# --- 2. round trips -------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("suffix", [".dat", ".npz"])
def test_round_trip_is_exact(tmp_path, seed, suffix):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 12))
    M = rng.normal(size=(n, n)) * 10.0 ** rng.integers(-300, 300, size=(n, n))
    M[rng.random((n, n)) < 0.2] = 0.0
    q = rng.normal(size=n) * 10.0 ** rng.integers(-20, 20, size=n)
    q[0] = -0.0
    path = write_lcp(tmp_path / f"p{seed}{suffix}", M, q)
    assert path == tmp_path / f"p{seed}{suffix}" and path.is_file()
    prob = read_lcp(path)
    assert prob.name == f"p{seed}"
    assert prob.M.tobytes() == M.tobytes() and prob.q.tobytes() == q.tobytes()  # bit for bit


def test_dat_written_is_column_major_with_comment(tmp_path):
    M = np.array([[1.0, 2.0], [3.0, 4.0]])
    path = write_lcp(tmp_path / "small.dat", M, [5.0, 6.0])
    lines = path.read_text().splitlines()
    assert lines[:5] == ["2", "0", "2", "2", "2\t2"]
    assert lines[5:8] == ["1 3", "2 4", "5 6"]  # columns, then q
    assert any(line.startswith("#") for line in lines[8:])


def test_explicit_format_and_sparse_input(tmp_path):
    M = sp.csr_matrix(np.array([[2.0, 0.0], [1.0, 3.0]]))
    path = write_lcp(tmp_path / "a.lcp", M, [1.0, -1.0], fmt="npz")
    assert path.name == "a.lcp"  # no suffix appended
    prob = read_lcp(path, fmt="npz")
    np.testing.assert_array_equal(prob.M, M.toarray())


def test_uppercase_suffix(tmp_path):
    write_lcp(tmp_path / "A.DAT", np.eye(2), [1.0, 2.0])
    np.testing.assert_array_equal(read_lcp(tmp_path / "A.DAT").M, np.eye(2))


# --- 3. malformed files ---------------------------------------------------------------------

GOOD = "2\n0\n2\n2\n2 2\n1 0\n0 1\n-1 -1\n"

MALFORMED = {
    "too few matrix numbers": ("2\n0\n2\n2\n2 2\n1 0 0\n-1 -1\n", "file ends early"),
    "missing q": ("2\n0\n2\n2\n2 2\n1 0 0 1\n-1\n", "file ends early: q needs 2"),
    "empty": ("", "file ends early: expected the problem size n"),
    "only comments": ("# nothing here\n", "file ends early"),
    "extra numbers": ("2\n0\n2\n2\n2 2\n1 0 0 1 7\n-1 -1\n", "1 extra number"),
    "non-numeric in M": ("2\n0\n2\n2\n2 2\n1 x 0 1\n-1 -1\n", "line 6: non-numeric token 'x'"),
    "non-numeric in q": ("2\n0\n2\n2\n2 2\n1 0 0 1\n-1 abc\n", "non-numeric token 'abc' in q"),
    "nan": ("2\n0\n2\n2\n2 2\n1 nan 0 1\n-1 -1\n", "non-finite value 'nan'"),
    "inf in q": ("2\n0\n2\n2\n2 2\n1 0 0 1\n-inf -1\n", "non-finite value '-inf' in q"),
    "storage code": ("2\n7\n2\n2\n2 2\n1 0 0 1\n-1 -1\n", "unknown storage code 7"),
    "non-integer n": ("2.5\n0\n2\n2\n2 2\n1 0 0 1\n-1 -1\n", "expected an integer"),
    "zero n": ("0\n0\n0\n0\n0 0\n", "n must be >= 1"),
    "size mismatch": ("2\n0\n3\n3\n3 3\n" + "1 " * 9 + "\n-1 -1\n", "matrix is 3x3 but n = 2"),
    "repeated size": ("2\n0\n2\n2\n2 3\n1 0 0 1\n-1 -1\n", "repeated dense size"),
    "block out of order": (
        "2\n1\n2\n2\n1\n1\n1\n2\n2\n2\n1\n0 1\n0\n5\n2 1 1 2\n-5 -6\n", "expected block number 0"),
    "block sizes": (
        "2\n1\n2\n2\n1\n1\n1\n3\n2\n2\n1\n0 1\n0\n0\n2 1 1 2\n-5 -6\n", "must increase"),
    "block column range": (
        "2\n1\n2\n2\n1\n1\n1\n2\n2\n2\n1\n0 1\n4\n0\n2 1 1 2\n-5 -6\n", "out of range"),
    "block pointers": (
        "2\n1\n2\n2\n1\n1\n1\n2\n2\n2\n1\n0 3\n0\n0\n2 1 1 2\n-5 -6\n", "row pointers"),
    "block too short": ("2\n1\n2\n2\n1\n1\n1\n2\n2\n2\n1\n0 1\n0\n0\n2 1 1\n", "file ends early"),
}


def test_good_text_reads_with_comments(tmp_path):
    path = tmp_path / "good.dat"
    path.write_text("# header comment\n" + GOOD.replace("1 0\n", "1 0 # first column\n"))
    prob = read_lcp(path)
    np.testing.assert_array_equal(prob.M, np.eye(2))
    np.testing.assert_array_equal(prob.q, [-1.0, -1.0])


def test_small_block_file_by_hand(tmp_path):
    # 3x3, two block rows (sizes 1, 2) and columns (1, 2); blocks (0,0), (0,1), (1,1).
    # Block entries are column-major: block (1,1) = [[5, 7], [6, 8]].
    text = ("3\n1\n3\n3\n3\n2\n2\n1 3\n1 3\n3\n3\n0 2 3\n0 1 1\n"
            "0\n1\n1\n2 3\n2\n5 6 7 8\n-1 -2 -3\n")
    path = tmp_path / "blk.dat"
    path.write_text(text)
    prob = read_lcp(path)
    np.testing.assert_array_equal(prob.M, [[1, 2, 3], [0, 5, 7], [0, 6, 8]])
    np.testing.assert_array_equal(prob.q, [-1, -2, -3])


@pytest.mark.parametrize("text, match", MALFORMED.values(), ids=MALFORMED.keys())
def test_malformed_dat_raises(tmp_path, text, match):
    path = tmp_path / "bad.dat"
    path.write_text(text)
    with pytest.raises(ProblemError, match=match) as info:
        read_lcp(path)
    msg = str(info.value)
    assert str(path) in msg and "\n" not in msg


def test_malformed_npz_raises(tmp_path):
    only_m = tmp_path / "only_m.npz"
    np.savez(only_m, M=np.eye(2))
    with pytest.raises(ProblemError, match="missing array.*q"):
        read_lcp(only_m)
    wrong = tmp_path / "wrong.npz"
    np.savez(wrong, M=np.eye(2), q=np.ones(3))
    with pytest.raises(ProblemError, match="q must be a vector of length 2"):
        read_lcp(wrong)
    nonfinite = tmp_path / "nan.npz"
    np.savez(nonfinite, M=np.eye(2), q=np.array([np.nan, 1.0]))
    with pytest.raises(ProblemError, match="finite"):
        read_lcp(nonfinite)
    objects = tmp_path / "obj.npz"
    np.savez(objects, M=np.array([{"a": 1}], dtype=object), q=np.ones(1))
    with pytest.raises(ProblemError, match=str(objects)):
        read_lcp(objects)
    garbage = tmp_path / "garbage.npz"
    garbage.write_bytes(b"PK\x03\x04 not really a zip")
    with pytest.raises(ProblemError, match="not a readable .npz"):
        read_lcp(garbage)
    text = tmp_path / "text.npz"
    text.write_text(GOOD)
    with pytest.raises(ProblemError, match=str(text)):
        read_lcp(text)
    single = tmp_path / "single.npz"
    with open(single, "wb") as fh:
        np.save(fh, np.eye(2))
    with pytest.raises(ProblemError, match="not an .npz archive"):
        read_lcp(single)


def test_missing_file_and_unknown_suffix(tmp_path):
    with pytest.raises(ProblemError, match="no such file"):
        read_lcp(tmp_path / "absent.dat")
    with pytest.raises(ProblemError, match="no such file"):
        read_lcp(tmp_path / "absent.npz")
    other = tmp_path / "p.txt"
    other.write_text(GOOD)
    with pytest.raises(ProblemError, match=r"unknown LCP file suffix '\.txt'"):
        read_lcp(other)
    with pytest.raises(ProblemError, match="unknown LCP file format 'mat'"):
        read_lcp(other, fmt="mat")
    binary = tmp_path / "bin.dat"
    binary.write_bytes(b"\xff\xfe\x00\x01")
    with pytest.raises(ProblemError, match="cannot read"):
        read_lcp(binary)


# --- 4. write errors ------------------------------------------------------------------------


def test_write_into_missing_directory_raises(tmp_path):
    for name in ("p.dat", "p.npz"):
        with pytest.raises(ProblemError, match="cannot write"):
            write_lcp(tmp_path / "no" / "such" / "dir" / name, np.eye(2), np.ones(2))


@pytest.mark.parametrize("M, q, kw, match", [
    (np.eye(2), np.ones(2), {"fmt": "mat"}, "unknown LCP file format 'mat'"),
    (np.ones((2, 3)), np.ones(2), {}, "M must be a non-empty square"),
    (np.eye(2), np.ones(3), {}, "q must be a vector of length 2"),
    (np.eye(2), [np.inf, 1.0], {}, "finite"),
    (np.eye(2) * 1j, np.ones(2), {}, "real numeric"),
])
def test_write_rejects_bad_input(tmp_path, M, q, kw, match):
    with pytest.raises(ProblemError, match=match):
        write_lcp(tmp_path / "p.dat", M, q, **kw)
    assert not (tmp_path / "p.dat").exists()


def test_write_unknown_suffix_raises(tmp_path):
    with pytest.raises(ProblemError, match=r"unknown LCP file suffix '\.txt'"):
        write_lcp(tmp_path / "p.txt", np.eye(2), np.ones(2))


# -- size guards: refused before anything is allocated ----------------------------------
def test_sparse_block_dat_declaring_a_huge_size_is_refused(tmp_path):
    # n = 60000: a dense M of 60000² x 8 bytes = 26.8 GiB, declared in a 60-byte file
    path = tmp_path / "huge_block.dat"
    path.write_text("60000\n1\n60000 60000\n1\n1 1\n60000\n60000\n2 1\n0 1\n0\n0\n1.0\n")
    with pytest.raises(ProblemError) as info:
        read_lcp(path)
    msg = str(info.value)
    assert "n = 60000" in msg and "26.8 GiB" in msg
    assert f"at most n = {lcpfile.MAX_SIZE}" in msg


def test_dense_dat_at_the_limit_plus_one_is_refused_from_its_header(tmp_path):
    path = tmp_path / "big.dat"
    n = lcpfile.MAX_SIZE + 1
    path.write_text(f"{n}\n0\n{n} {n}\n{n} {n}\n1.0\n")
    with pytest.raises(ProblemError, match=f"n = {n}"):
        read_lcp(path)


def _npy_header_only(shape) -> bytes:
    """The bytes of a .npy file whose header declares ``shape`` (float64) and no data."""
    import io

    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buf, {"descr": "<f8", "fortran_order": False, "shape": shape})
    return buf.getvalue()


@pytest.mark.parametrize("shape_M,shape_q,bad", [
    ((2**30, 2**30), (2**30,), "M"),  # 8 EiB declared
    ((2, 2), (10**12,), "q"),
])
def test_npz_header_declaring_a_huge_array_is_refused(tmp_path, shape_M, shape_q, bad):
    import zipfile

    path = tmp_path / "huge.npz"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("M.npy", _npy_header_only(shape_M))
        zf.writestr("q.npy", _npy_header_only(shape_q))
    with pytest.raises(ProblemError) as info:
        read_lcp(path)
    msg = str(info.value)
    assert f"array {bad} declares shape" in msg and "GiB" in msg
    assert f"n <= {lcpfile.MAX_SIZE}" in msg


def test_npz_of_normal_size_still_reads(tmp_path):
    M, q = np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([-1.0, 1.0])
    path = write_lcp(tmp_path / "ok.npz", M, q)
    prob = read_lcp(path)
    np.testing.assert_array_equal(prob.M, M)
    np.testing.assert_array_equal(prob.q, q)


# -- bounded reading (issue 36): refused before reading, parsed as a stream ---------------
def _one_line(info, path) -> str:
    msg = str(info.value)
    assert str(path) in msg and "\n" not in msg
    return msg


def test_a_device_is_refused_before_it_is_opened(tmp_path):
    link = tmp_path / "zero.dat"  # /dev/zero never ends: reading it would fill the memory
    link.symlink_to("/dev/zero")
    with pytest.raises(ProblemError, match="is a device, not a regular file") as info:
        read_lcp(link)
    _one_line(info, link)
    with pytest.raises(ProblemError, match="is a device, not a regular file"):
        read_lcp("/dev/zero", fmt="npz")


def test_a_directory_and_a_pipe_are_refused(tmp_path):
    folder = tmp_path / "folder.dat"
    folder.mkdir()
    with pytest.raises(ProblemError, match="is a directory, not a regular file"):
        read_lcp(folder)
    fifo = tmp_path / "fifo.dat"
    os.mkfifo(fifo)  # opening it would wait for a writer
    with pytest.raises(ProblemError, match="is a pipe, not a regular file"):
        read_lcp(fifo)


def test_a_file_far_larger_than_its_header_promises_is_refused_unread(tmp_path):
    # n = 3, dense: 3*3 + 3 + 5 = 17 numbers, at most 17 * 64 bytes + 1 MiB of comments.
    # The file is sparse (no disk): 2 GB of NUL bytes that would take > 1 GB to read.
    path = tmp_path / "huge.dat"
    with open(path, "wb") as fh:
        fh.write(b"3\n0\n3 3\n3 3\n")
        fh.truncate(2 * 10**9)
    with pytest.raises(ProblemError) as info:
        read_lcp(path)
    msg = _one_line(info, path)
    assert f"takes {2 * 10**9} bytes" in msg and "n = 3" in msg
    assert f"at most {17 * lcpfile.BYTES_PER_NUMBER + lcpfile.FREE_TEXT_BYTES} bytes" in msg
    assert "refused without reading it" in msg


def test_the_size_bound_of_a_block_file_counts_its_block_numbers(tmp_path):
    # sparse block storage, n = 2: at most 2*4 + 5*2 + 10 = 28 numbers
    limit = 28 * lcpfile.BYTES_PER_NUMBER + lcpfile.FREE_TEXT_BYTES
    path = tmp_path / "blk.dat"
    path.write_text("2\n1\n2\n2\n1\n1\n1\n2\n2\n2\n1\n0 1\n0\n0\n2 1 1 2\n-5 -6\n"
                    + "#" * (limit + 1))
    with pytest.raises(ProblemError, match=f"at most {limit} bytes"):
        read_lcp(path)
    path.write_text(GOOD + "# " + "a note " * 1000)  # free text well within the bound
    np.testing.assert_array_equal(read_lcp(path).M, np.eye(2))


def test_a_5000_digit_integer_is_one_line(tmp_path):
    path = tmp_path / "digits.dat"
    path.write_text("1" * 5000 + "\n0\n2 2\n2 2\n1 0 0 1\n-1 -1\n")
    with pytest.raises(ProblemError, match="line 1: the problem size n has 5000 digits"):
        read_lcp(path)
    path.write_text(GOOD.replace("1 0\n", "1" * 5000 + " 0\n"))
    with pytest.raises(ProblemError, match="line 6: a number of more than 4096 characters"
                       ) as info:
        read_lcp(path)
    assert len(str(info.value)) < 300  # the token is not printed whole
    path.write_text(GOOD.replace("1 0\n", "1" * 400 + " 0\n"))  # 1.1e399: inf
    with pytest.raises(ProblemError, match=r"line 6: non-finite value '1+'\.\.\. \(400 char"):
        read_lcp(path)


def test_text_that_is_not_utf8_is_one_line(tmp_path):
    path = tmp_path / "latin1.dat"
    path.write_bytes(GOOD.encode() + "# Müller\n".encode("latin-1"))
    with pytest.raises(ProblemError, match="not UTF-8 text") as info:
        read_lcp(path)
    _one_line(info, path)


@pytest.mark.parametrize("chunk", [1, 2, 3, 5, 8, 13])
def test_tokens_comments_and_line_numbers_across_chunk_boundaries(tmp_path, monkeypatch,
                                                                  chunk):
    monkeypatch.setattr(lcpfile, "CHUNK_CHARS", chunk)
    path = tmp_path / "c.dat"
    path.write_text("# header ##\n2#n\n0\n2\n2\n2 2 # dims\n1 0#col 0\n0 1\n-1 -1\nnote 3 4\n")
    prob = read_lcp(path)
    np.testing.assert_array_equal(prob.M, np.eye(2))
    np.testing.assert_array_equal(prob.q, [-1.0, -1.0])
    for text, match in (MALFORMED["non-numeric in M"], MALFORMED["extra numbers"],
                        MALFORMED["block too short"]):
        path.write_text(text)
        with pytest.raises(ProblemError, match=match):
            read_lcp(path)


def test_round_trip_in_small_chunks(tmp_path, monkeypatch):
    monkeypatch.setattr(lcpfile, "CHUNK_CHARS", 7)
    rng = np.random.default_rng(7)
    M, q = rng.normal(size=(5, 5)), rng.normal(size=5)
    prob = read_lcp(write_lcp(tmp_path / "r.dat", M, q))
    assert prob.M.tobytes() == M.tobytes() and prob.q.tobytes() == q.tobytes()


def test_a_token_longer_than_the_limit_across_chunks_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(lcpfile, "CHUNK_CHARS", 100)
    path = tmp_path / "long.dat"
    path.write_text(GOOD.replace("0 1\n", "0 " + "7" * 5000 + "\n"))
    with pytest.raises(ProblemError, match="line 7: a token of more than 4096 characters"):
        read_lcp(path)
