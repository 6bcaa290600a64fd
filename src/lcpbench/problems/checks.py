"""Validators for the library's boundary: one clear ProblemError per bad input.

Every public entry point (the scenes, :func:`lcpbench.solve`, the LCP readers)
checks its arguments here before computing anything. A bad value gives one
:class:`~lcpbench.errors.ProblemError` whose message names the parameter,
says what is allowed and shows what was given, with its type::

    links must be an integer in [4, 100000] or 'auto', got True (bool)
    length must be a number in [0.001, 100000] mm, got 1e+300 (float)
    scaled must be True or False, got 'no' (str)

What counts as a number
-----------------------
A real number: a Python ``int`` or ``float``, or a numpy integer or floating
scalar. Refused: ``bool`` and ``numpy.bool_`` (``True`` is not 1 link),
strings (even ``'3'``), arrays and lists (even of one element), complex
values, ``None``, and NaN or ±inf. An integer parameter also accepts a float
with an integral value (``140.0``, as JSON may give it), never ``2.5``.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable

import numpy as np

from ..errors import ProblemError


def describe(value) -> str:
    """``value`` as a user wrote it, shortened, for error messages: a string quoted, a
    number or a flag as its value (``3.0``, ``True``, not ``np.float64(3.0)``), else its
    ``repr``. No type name: a user reads "got -30.0", not an internal class."""
    if isinstance(value, (numbers.Number, np.generic)) and not isinstance(value, str):
        text = str(value)
    else:
        text = repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return text


def _is_bool(value) -> bool:
    return isinstance(value, (bool, np.bool_))


def _is_real(value) -> bool:
    """A real scalar: int, float, numpy integer/floating; never bool, str, array or complex."""
    if _is_bool(value) or isinstance(value, (str, bytes, np.ndarray)):
        return False
    return isinstance(value, (numbers.Real, np.integer, np.floating))


def _fmt(x: float) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


def allowed_range(low: float | None, high: float | None, low_open: bool, high_open: bool,
                  unit: str = "") -> str:
    """Text of an interval, e.g. ``in (0, 360) degrees`` or ``>= 0 N/mm``."""
    unit = f" {unit}" if unit else ""
    if low is not None and high is not None:
        return (f"in {'(' if low_open else '['}{_fmt(low)}, {_fmt(high)}"
                f"{')' if high_open else ']'}{unit}")
    if low is not None:
        return f"{'>' if low_open else '>='} {_fmt(low)}{unit}"
    if high is not None:
        return f"{'<' if high_open else '<='} {_fmt(high)}{unit}"
    return f"finite{unit}"


def check_number(name: str, value, *, low: float | None = None, high: float | None = None,
                 low_open: bool = False, high_open: bool = False, integer: bool = False,
                 unit: str = "", alternative: str = "") -> float | int:
    """``value`` as a float (an int if ``integer``), or one ProblemError.

    Parameters
    ----------
    name : str
        The parameter's name, as the user typed it.
    value :
        What was given.
    low, high : float, optional
        Bounds of the allowed interval (None: unbounded on that side).
    low_open, high_open : bool
        Whether the bound itself is excluded.
    integer : bool
        Require an integral value; returns ``int``.
    unit : str
        Unit shown after the interval.
    alternative : str
        Text of another allowed form, appended as "or ..." (e.g. ``"'auto'"``);
        the caller checks that form itself before calling.

    Returns
    -------
    float or int

    Raises
    ------
    ProblemError
        ``"<name> must be a number in [a, b] <unit>, got <value> (<type>)"``
        (``an integer`` when ``integer``) for a value of the wrong type, a
        non-integral one, NaN or inf, or one outside the interval.
    """
    kind_ = type(value)
    if kind_ is float or kind_ is int or _is_real(value):  # (exact types: no ABC check)
        try:
            x = float(value)
        except (TypeError, ValueError, OverflowError):
            x = math.nan
        if (math.isfinite(x) and not (integer and not x.is_integer())
                and not (low is not None and (x < low or (low_open and x == low)))
                and not (high is not None and (x > high or (high_open and x == high)))):
            return int(value) if integer else x
    # the message is built only for a value that fails (scenes check seven numbers)
    kind = "an integer" if integer else "a number"
    what = f"{kind} {allowed_range(low, high, low_open, high_open, unit)}"
    if alternative:
        what += f" or {alternative}"
    raise ProblemError(f"{name} must be {what}, got {describe(value)}")


def check_choice(name: str, value, choices: Iterable) -> object:
    """``value`` if it is one of ``choices`` (compared with ``==``, same type), else ProblemError.

    Raises
    ------
    ProblemError
        ``"<name> must be one of 'a', 'b', got <value> (<type>)"``.
    """
    choices = tuple(choices)
    for c in choices:
        if type(value) is type(c) and value == c:
            return value
    listed = ", ".join(repr(c) for c in choices)
    raise ProblemError(f"{name} must be one of {listed}, got {describe(value)}")


def check_flag(name: str, value) -> bool:
    """``value`` as a bool if it is a real bool (``True``/``False``/``numpy.bool_``).

    Raises
    ------
    ProblemError
        ``"<name> must be True or False, got <value> (<type>)"``; strings such
        as ``'no'`` and numbers such as ``0`` are refused (``'no'`` is truthy).
    """
    if not _is_bool(value):
        raise ProblemError(f"{name} must be True or False, got {describe(value)}")
    return bool(value)
