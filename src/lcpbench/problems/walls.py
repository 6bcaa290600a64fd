"""Walls of any profile y = h(x): a stenosis, a bend, a step (issue 17, item 3).

The paper's wall is flat, y = h. A :class:`WallProfile` is a wall whose height
depends on x, given either as a function or as a table of (x, y) points
interpolated piecewise-linearly (``kind="linear"``), by monotone cubic
Hermite pieces (``"pchip"``, C¹, no overshoot: the default) or by a natural
cubic spline (``"cubic"``, C²). It gives the height h(x), the slope h'(x) and
the curvature h''(x) (the energy reference's Newton polish uses it).

Outside a table's x range the wall is continued flat (the end value, slope
0); :meth:`WallProfile.check_for` refuses a profile that does not cover the
chain's x range in the first place, or that crosses the pin line.

A CSV file holds one ``x,y`` pair per line (mm) after a header line
(:func:`load_profile_csv`). Bad input is one :class:`~lcpbench.errors.ProblemError`
naming the parameter: NaN or inf values, x not strictly increasing, fewer
than two points, an unknown ``kind``, a profile at or below the pin line
(an upper wall) or at or above it (a lower wall) within the chain's reach.
"""

from __future__ import annotations

import csv
from array import array
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import ProblemError
from .checks import describe
from .profile_table import exact_pieces, hermite_pieces, linear_pieces

KINDS = ("linear", "pchip", "cubic")
#: points at which a function profile is sampled to check it against the pin line
SAMPLES = 2001
#: relative step of the central differences for a function given without its slope
FD_STEP = 1e-5
#: step (mm) of the slope's central differences, extrapolated (Richardson), for a
#: function given without its slope: truncation ~d⁴ h⁽⁵⁾ and round-off ~ε|h|/d are both
#: ~1e-12 for walls whose features are millimetres wide (a stenosis, a bump)
SLOPE_STEP = 5e-4
#: largest profile CSV read, bytes (16 MiB: about half a million x,y rows)
MAX_PROFILE_BYTES = 16 * 2**20


def _checked(fun: Callable, what: str, name: str) -> Callable:
    """``fun`` (a user's h, h' or h'') whose exceptions and non-numeric answers are one
    ProblemError naming the profile, never a traceback from inside the model."""
    def call(t):
        try:
            value = fun(t)
        except ProblemError:
            raise
        except Exception as exc:
            why = " ".join(str(exc).split())[:200]
            raise ProblemError(f"wall_profile {name!r}: the {what} function raised "
                               f"{type(exc).__name__}: {why}") from exc
        try:
            arr = np.asarray(value)
        except Exception:
            arr = np.asarray(None)
        if arr.dtype.kind not in "biuf":
            raise ProblemError(f"wall_profile {name!r}: the {what} function must return "
                               f"numbers (mm, one per x), it returned {describe(value)}")
        try:
            if arr.shape and arr.shape != np.shape(t):  # (one per x, or one for all: fine)
                np.broadcast_shapes(arr.shape, np.shape(t))
        except ValueError:
            raise ProblemError(f"wall_profile {name!r}: the {what} function must return one "
                               f"number per x: {np.size(t)} x values gave shape "
                               f"{arr.shape}") from None
        return arr.astype(float, copy=False)

    return call


def _richardson_slope(height: Callable, x: np.ndarray, d: float) -> np.ndarray:
    """h'(x) by central differences at steps d and d/2, extrapolated (Richardson):
    (4 D(d/2) − D(d)) / 3, whose truncation error is O(d⁴), not O(d²): a plain
    difference at a relative step of FD_STEP was off by ~4e-9 on a 3 mm stenosis, too
    far for the table's SLOPE_TOL, so such a profile had no table."""
    wide = (height(x + d) - height(x - d)) / (2 * d)
    narrow = (height(x + 0.5 * d) - height(x - 0.5 * d)) / d
    return (4.0 * np.asarray(narrow, float) - np.asarray(wide, float)) / 3.0


#: the points of :meth:`WallProfile.extremes` (a scene's nearest reach of its wall)
REACH_GRID = 2001


class WallProfile:
    """A wall y = h(x) (mm): from a function or an (x, y) table.

    Build one with :meth:`from_table`, :meth:`from_function`, :meth:`flat` or
    :func:`load_profile_csv`. Calling it gives h(x); :meth:`slope` h'(x) and
    :meth:`curvature` h''(x), vectorised over x.
    """

    def __init__(self, height: Callable, slope: Callable, curvature: Callable, *,
                 x_range: tuple[float, float], name: str, key: tuple,
                 pieces: tuple[np.ndarray, np.ndarray] | None = None):
        self._h, self._dh, self._d2h = height, slope, curvature
        self.x_range = (float(x_range[0]), float(x_range[1]))
        self.name = name
        self._key = key
        self._pieces = pieces  # a table's own pieces (exact); else tabulated on demand
        self._tabulated: dict = {}
        self._passed: set = set()  # (x_low, x_high, side) that check_for has passed
        self._extremes: dict = {}  # (x_low, x_high) -> (min h, max h) on REACH_GRID points

    # -- construction ---------------------------------------------------------
    @classmethod
    def from_table(cls, x, y, kind: str = "pchip", *, name: str = "table",
                   parameter: str = "wall_profile") -> WallProfile:
        """A profile through the points (x_i, y_i) (mm), interpolated by ``kind``.

        ``parameter`` names the input in error messages.
        """
        if not isinstance(kind, str) or kind not in KINDS:
            raise ProblemError(f"{parameter}: kind must be one of {', '.join(KINDS)}, "
                               f"got {kind!r}")
        try:
            # copies: the profile, its tables and its checks are fixed once built
            xs = np.array(x, dtype=float).ravel()
            ys = np.array(y, dtype=float).ravel()
        except (TypeError, ValueError):
            raise ProblemError(f"{parameter}: x and y must be numbers (mm)") from None
        if xs.size != ys.size:
            raise ProblemError(f"{parameter}: x and y must have the same length, got "
                               f"{xs.size} and {ys.size}")
        if xs.size < 2:
            raise ProblemError(f"{parameter}: a table needs at least 2 points, got {xs.size}")
        bad = ~(np.isfinite(xs) & np.isfinite(ys))
        if bad.any():
            i = int(np.argmax(bad))
            raise ProblemError(f"{parameter}: point {i + 1} is not finite (x = {float(xs[i])!r}, "
                               f"y = {float(ys[i])!r}); NaN and inf are not allowed")
        if np.any(np.diff(xs) <= 0):
            i = int(np.argmax(np.diff(xs) <= 0))
            raise ProblemError(f"{parameter}: x must be strictly increasing, but point "
                               f"{i + 2} (x = {xs[i + 1]:g}) follows x = {xs[i]:g}")
        lo, hi = float(xs[0]), float(xs[-1])
        key = ("table", kind, xs.tobytes(), ys.tobytes())
        if kind == "linear":
            def h(t):
                return np.interp(t, xs, ys)

            steps = np.diff(ys) / np.diff(xs)

            def dh(t):
                t = np.asarray(t, dtype=float)
                i = np.clip(np.searchsorted(xs, t, side="right") - 1, 0, steps.size - 1)
                return np.where((t < lo) | (t > hi), 0.0, steps[i])

            def d2h(t):
                return np.zeros_like(np.asarray(t, dtype=float))

            return cls(h, dh, d2h, x_range=(lo, hi), name=name, key=key,
                       pieces=linear_pieces(xs, ys))
        from scipy.interpolate import CubicSpline, PchipInterpolator

        f = PchipInterpolator(xs, ys) if kind == "pchip" else \
            CubicSpline(xs, ys, bc_type="natural")
        f1, f2 = f.derivative(1), f.derivative(2)

        def inside(fun, t, outside):
            t = np.asarray(t, dtype=float)
            c = np.clip(t, lo, hi)
            return np.where((t < lo) | (t > hi), outside(c), fun(c))

        def height(t):  # (continued flat: the end value, f at the clipped x, everywhere)
            return f(np.clip(np.asarray(t, dtype=float), lo, hi))

        return cls(height, lambda t: inside(f1, t, np.zeros_like),
                   lambda t: inside(f2, t, np.zeros_like), x_range=(lo, hi), name=name,
                   key=key, pieces=exact_pieces(f.x, f.c))

    @classmethod
    def from_function(cls, height: Callable, slope: Callable | None = None,
                      curvature: Callable | None = None, *,
                      x_range: tuple[float, float] = (-np.inf, np.inf),
                      name: str = "function") -> WallProfile:
        """A profile h(x) given as a vectorised function (mm → mm).

        ``slope`` (h') and ``curvature`` (h'') are optional; where missing they
        are central differences: the slope's at SLOPE_STEP and half of it,
        extrapolated (Richardson), good to about 1e-12 for walls with features
        millimetres wide, which its table of cubic pieces (:meth:`pieces`) needs;
        the curvature's of that slope at relative step FD_STEP on the x scale. ``x_range`` is where h is
        defined (outside it the wall is continued flat).
        """
        if not callable(height):
            raise ProblemError(f"wall_profile: height must be a function of x, got "
                               f"{describe(height)}")
        lo, hi = float(x_range[0]), float(x_range[1])
        if not lo < hi:
            raise ProblemError(f"wall_profile: x_range must be (low, high) with low < high, "
                               f"got {x_range!r}")
        scale = 1.0 if not np.isfinite(hi - lo) else max(hi - lo, 1e-9)
        d = FD_STEP * scale
        key = ("function", id(height))
        height = _checked(height, "height", name)
        slope = None if slope is None else _checked(slope, "slope", name)
        curvature = None if curvature is None else _checked(curvature, "curvature", name)

        def h(t):
            t = np.asarray(t, dtype=float)
            v = height(np.clip(t, lo, hi))  # (a float array: _checked)
            # a copy (the function's own array may be a buffer it writes again, e.g. from
            # the slope asked next); a constant, or a scalar x: times ones, an array per x
            return v.copy() if t.ndim and v.shape == t.shape else v * np.ones_like(t)

        def dh(t):
            t = np.asarray(t, dtype=float)
            c = np.clip(t, lo, hi)
            v = slope(c) if slope is not None else _richardson_slope(height, c, SLOPE_STEP)
            return np.where((t < lo) | (t > hi), 0.0, np.asarray(v, float) * np.ones_like(t))

        def d2h(t):
            t = np.asarray(t, dtype=float)
            c = np.clip(t, lo, hi)
            if curvature is not None:
                v = curvature(c)
            else:
                v = (dh(c + d) - dh(c - d)) / (2 * d)
            return np.where((t < lo) | (t > hi), 0.0, np.asarray(v, float) * np.ones_like(t))

        return cls(h, dh, d2h, x_range=(lo, hi), name=name, key=key)

    @classmethod
    def flat(cls, height: float) -> WallProfile:
        """The flat wall y = height (the paper's), as a profile."""
        hh = float(height)
        return cls.from_function(lambda t: np.full_like(np.asarray(t, float), hh),
                                 lambda t: np.zeros_like(np.asarray(t, float)),
                                 lambda t: np.zeros_like(np.asarray(t, float)),
                                 name=f"flat {hh:g} mm")

    def mirrored(self) -> WallProfile:
        """The wall y = −h(x) (the lower wall of a symmetric channel)."""
        own = None if self._pieces is None else (self._pieces[0], -self._pieces[1])
        return WallProfile(lambda t: -self._h(t), lambda t: -self._dh(t),
                           lambda t: -self._d2h(t), x_range=self.x_range,
                           name=f"mirror of {self.name}", key=("mirror", self._key),
                           pieces=own)

    def pieces(self, x_low: float, x_high: float) -> tuple[np.ndarray, np.ndarray] | None:
        """The wall as cubic pieces (breakpoints, coefficients) over the x range
        [x_low, x_high] (mm) that a chain can reach, the form the compiled kernels
        evaluate (:mod:`lcpbench.problems.profile_table`): a table's own pieces, or a
        function's tabulated once per range; None where a function needs more
        pieces than :data:`~lcpbench.problems.profile_table.MAX_PIECES`."""
        if self._pieces is not None:
            return self._pieces
        lo, hi = max(self.x_range[0], float(x_low)), min(self.x_range[1], float(x_high))
        key = (lo, hi)
        if key not in self._tabulated:
            self._tabulated[key] = hermite_pieces(self, self.slope, lo, hi)
        return self._tabulated[key]

    # -- evaluation -----------------------------------------------------------
    def extremes(self, x_low: float, x_high: float) -> tuple[float, float]:
        """(min h, max h) (mm) over :data:`REACH_GRID` equally spaced x in
        [``x_low``, ``x_high``], kept per range (the scenes of a batch share a profile)."""
        key = (float(x_low), float(x_high))
        got = self._extremes.get(key)
        if got is None:
            h = self(np.linspace(key[0], key[1], REACH_GRID))
            got = self._extremes[key] = (float(np.min(h)), float(np.max(h)))
        return got

    def __call__(self, x):
        """h(x) (mm)."""
        return self._h(np.asarray(x, dtype=float))

    def slope(self, x):
        """h'(x) (dimensionless)."""
        return self._dh(np.asarray(x, dtype=float))

    def curvature(self, x):
        """h''(x) (1/mm)."""
        return self._d2h(np.asarray(x, dtype=float))

    def __eq__(self, other) -> bool:
        return isinstance(other, WallProfile) and self._key == other._key

    def __hash__(self) -> int:
        return hash(self._key)

    def __repr__(self) -> str:
        return f"WallProfile({self.name}, x in [{self.x_range[0]:g}, {self.x_range[1]:g}] mm)"

    def to_dict(self) -> dict:
        """What the JSON of a result shows: its name and x range (not the function)."""
        return {"name": self.name, "x_range": list(self.x_range)}

    # -- checks against a chain -----------------------------------------------
    def check_for(self, x_low: float, x_high: float, *, side: str,
                  parameter: str = "wall_profile") -> None:
        """ProblemError unless the profile covers [x_low, x_high] (mm) and stays
        strictly above (``side="upper"``) or below (``"lower"``) the pin line y = 0
        there. A table is checked at its points and on a fine grid; a function on
        SAMPLES points. A range and side that passed once are not sampled again (the
        profile is a fixed function, as its tables assume: :meth:`pieces`), so scenes
        that share a profile pay for one check."""
        lo, hi = self.x_range
        tol = 1e-9 * max(1.0, abs(x_high - x_low))
        if lo > x_low + tol or hi < x_high - tol:
            raise ProblemError(f"{parameter}: the profile must cover the chain's x range "
                               f"[{x_low:g}, {x_high:g}] mm, it covers [{lo:g}, {hi:g}] mm")
        passed = (float(x_low), float(x_high), side)
        if passed in self._passed:
            return
        t = np.linspace(x_low, x_high, SAMPLES)
        y = self(t)
        if not np.all(np.isfinite(y)):
            raise ProblemError(f"{parameter}: the profile is not finite within "
                               f"[{x_low:g}, {x_high:g}] mm")
        bad = y <= 0 if side == "upper" else y >= 0
        if bad.any():
            i = int(np.argmax(bad))
            where = "at or below" if side == "upper" else "at or above"
            raise ProblemError(f"{parameter}: the {side} wall crosses the pin line: it is "
                               f"{where} y = 0 (y = {y[i]:g} mm at x = {t[i]:g} mm); the "
                               f"pins sit on y = 0")
        if SAMPLES == REACH_GRID:  # the grid of :meth:`extremes` over this range: its
            # numbers from these heights (a chain's build asks for them next)
            self._extremes.setdefault((float(x_low), float(x_high)),
                                      (float(np.min(y)), float(np.max(y))))
        self._passed.add(passed)


def load_profile_csv(path, kind: str = "pchip", *, parameter: str = "wall_profile"
                     ) -> WallProfile:
    """A profile from a CSV file: a header line, then one ``x,y`` pair (mm) per line.

    Blank lines and lines starting with ``#`` are skipped. The file must be a
    regular file (not a device such as ``/dev/zero``, a pipe or a directory) of
    at most :data:`MAX_PROFILE_BYTES`, in UTF-8; it is read line by line into
    the table. Anything else is one ProblemError naming ``parameter``.
    """
    from .lcpfile import regular_file_size

    p = Path(path)
    size = regular_file_size(p, f"{parameter}: {str(p)!r}")
    if size > MAX_PROFILE_BYTES:
        raise ProblemError(f"{parameter}: {str(p)!r} takes {size} bytes; a profile CSV may "
                           f"take at most {MAX_PROFILE_BYTES} bytes (16 MiB, about half a "
                           f"million x,y rows)")
    try:
        with open(p, encoding="utf-8-sig", newline="") as fh:
            xs, ys = _csv_rows(fh, p.name, parameter)
    except UnicodeDecodeError as exc:
        raise ProblemError(f"{parameter}: {p.name} is not UTF-8 text ({exc.reason})") from None
    except csv.Error as exc:
        raise ProblemError(f"{parameter}: {p.name} is not a CSV of x,y rows ({exc})") from None
    except OSError as exc:
        raise ProblemError(f"{parameter}: cannot read {str(p)!r} ({exc.strerror})") from exc
    return WallProfile.from_table(xs, ys, kind, name=p.name, parameter=parameter)


def _bounded(fh, name: str, parameter: str):
    """The lines of ``fh``, refusing to go past MAX_PROFILE_BYTES (a file still growing)."""
    total = 0
    for line in fh:
        total += len(line)
        if total > MAX_PROFILE_BYTES:
            raise ProblemError(f"{parameter}: {name} grew past {MAX_PROFILE_BYTES} bytes "
                               "while it was read")
        yield line


def _csv_rows(fh, name: str, parameter: str) -> tuple[array, array]:
    """The x and y columns of an open profile CSV (header checked, then skipped)."""
    xs, ys = array("d"), array("d")
    count = 0  # rows that are neither blank nor comments
    for row in csv.reader(_bounded(fh, name, parameter)):
        if not row or not any(c.strip() for c in row) or row[0].lstrip().startswith("#"):
            continue
        count += 1
        if count == 1:
            try:
                [float(c) for c in row]
            except ValueError:
                continue  # the header
            raise ProblemError(f"{parameter}: {name} must start with a header line (e.g. "
                               f"x,y), got the numbers {','.join(row)!r}")
        if len(row) != 2:
            raise ProblemError(f"{parameter}: {name} row {count} must be x,y (two numbers), "
                               f"got {','.join(row)[:80]!r}")
        try:
            x, y = float(row[0]), float(row[1])
        except ValueError:
            raise ProblemError(f"{parameter}: {name} row {count} is not two numbers: "
                               f"{','.join(row)[:80]!r}") from None
        xs.append(x)
        ys.append(y)
    if count == 0:
        raise ProblemError(f"{parameter}: {name} is empty (expected a header and x,y rows)")
    return xs, ys
