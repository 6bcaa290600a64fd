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
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import ProblemError

KINDS = ("linear", "pchip", "cubic")
#: points at which a function profile is sampled to check it against the pin line
SAMPLES = 2001
#: relative step of the central differences for a function given without its slope
FD_STEP = 1e-5


class WallProfile:
    """A wall y = h(x) (mm): from a function or an (x, y) table.

    Build one with :meth:`from_table`, :meth:`from_function`, :meth:`flat` or
    :func:`load_profile_csv`. Calling it gives h(x); :meth:`slope` h'(x) and
    :meth:`curvature` h''(x), vectorised over x.
    """

    def __init__(self, height: Callable, slope: Callable, curvature: Callable, *,
                 x_range: tuple[float, float], name: str, key: tuple):
        self._h, self._dh, self._d2h = height, slope, curvature
        self.x_range = (float(x_range[0]), float(x_range[1]))
        self.name = name
        self._key = key

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
            xs = np.asarray(x, dtype=float).ravel()
            ys = np.asarray(y, dtype=float).ravel()
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

            return cls(h, dh, d2h, x_range=(lo, hi), name=name, key=key)
        from scipy.interpolate import CubicSpline, PchipInterpolator

        f = PchipInterpolator(xs, ys) if kind == "pchip" else \
            CubicSpline(xs, ys, bc_type="natural")
        f1, f2 = f.derivative(1), f.derivative(2)

        def inside(fun, t, outside):
            t = np.asarray(t, dtype=float)
            c = np.clip(t, lo, hi)
            return np.where((t < lo) | (t > hi), outside(c), fun(c))

        return cls(lambda t: inside(f, t, f), lambda t: inside(f1, t, np.zeros_like),
                   lambda t: inside(f2, t, np.zeros_like), x_range=(lo, hi), name=name,
                   key=key)

    @classmethod
    def from_function(cls, height: Callable, slope: Callable | None = None,
                      curvature: Callable | None = None, *,
                      x_range: tuple[float, float] = (-np.inf, np.inf),
                      name: str = "function") -> WallProfile:
        """A profile h(x) given as a vectorised function (mm → mm).

        ``slope`` (h') and ``curvature`` (h'') are optional; where missing they
        are central differences (relative step FD_STEP on the x scale), good
        to about 1e-10 relative for smooth h. ``x_range`` is where h is
        defined (outside it the wall is continued flat).
        """
        if not callable(height):
            raise ProblemError(f"wall_profile: height must be a function of x, got "
                               f"{type(height).__name__}")
        lo, hi = float(x_range[0]), float(x_range[1])
        if not lo < hi:
            raise ProblemError(f"wall_profile: x_range must be (low, high) with low < high, "
                               f"got {x_range!r}")
        scale = 1.0 if not np.isfinite(hi - lo) else max(hi - lo, 1e-9)
        d = FD_STEP * scale

        def h(t):
            t = np.asarray(t, dtype=float)
            return np.asarray(height(np.clip(t, lo, hi)), dtype=float) * np.ones_like(t)

        def dh(t):
            t = np.asarray(t, dtype=float)
            c = np.clip(t, lo, hi)
            v = slope(c) if slope is not None else (height(c + d) - height(c - d)) / (2 * d)
            return np.where((t < lo) | (t > hi), 0.0, np.asarray(v, float) * np.ones_like(t))

        def d2h(t):
            t = np.asarray(t, dtype=float)
            c = np.clip(t, lo, hi)
            if curvature is not None:
                v = curvature(c)
            else:
                v = (dh(c + d) - dh(c - d)) / (2 * d)
            return np.where((t < lo) | (t > hi), 0.0, np.asarray(v, float) * np.ones_like(t))

        return cls(h, dh, d2h, x_range=(lo, hi), name=name, key=("function", id(height)))

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
        return WallProfile(lambda t: -self._h(t), lambda t: -self._dh(t),
                           lambda t: -self._d2h(t), x_range=self.x_range,
                           name=f"mirror of {self.name}", key=("mirror", self._key))

    # -- evaluation -----------------------------------------------------------
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
        SAMPLES points."""
        lo, hi = self.x_range
        tol = 1e-9 * max(1.0, abs(x_high - x_low))
        if lo > x_low + tol or hi < x_high - tol:
            raise ProblemError(f"{parameter}: the profile must cover the chain's x range "
                               f"[{x_low:g}, {x_high:g}] mm, it covers [{lo:g}, {hi:g}] mm")
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


def load_profile_csv(path, kind: str = "pchip", *, parameter: str = "wall_profile"
                     ) -> WallProfile:
    """A profile from a CSV file: a header line, then one ``x,y`` pair (mm) per line.

    Blank lines and lines starting with ``#`` are skipped.
    """
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as exc:
        raise ProblemError(f"{parameter}: cannot read {str(p)!r} ({exc.strerror})") from exc
    rows = [r for r in csv.reader(text.splitlines())
            if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    if not rows:
        raise ProblemError(f"{parameter}: {p.name} is empty (expected a header and x,y rows)")
    try:
        [float(c) for c in rows[0]]
    except ValueError:
        pass
    else:
        raise ProblemError(f"{parameter}: {p.name} must start with a header line (e.g. x,y), "
                           f"got the numbers {','.join(rows[0])!r}")
    xs, ys = [], []
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != 2:
            raise ProblemError(f"{parameter}: {p.name} row {line} must be x,y (two numbers), "
                               f"got {','.join(row)!r}")
        try:
            xs.append(float(row[0]))
            ys.append(float(row[1]))
        except ValueError:
            raise ProblemError(f"{parameter}: {p.name} row {line} is not two numbers: "
                               f"{','.join(row)!r}") from None
    return WallProfile.from_table(xs, ys, kind, name=p.name, parameter=parameter)
