"""Unit suffixes on the command line: ``--height 3mm``, ``--theta 2.6rad``, ``--EI 32.01N*mm^2``.

A small table, not a units library: lcpbench needs four quantities (length,
angle, bending stiffness, weight per length), each with a handful of units,
converted to the model's own units (mm, degrees, N·mm², N/mm). pint would
bring a registry of thousands of units and a dependency the house list does
not allow, for what is a dozen lines here; the table is tested entry by entry
(tests/cli/test_units.py).

Conversions are exact: the number and the factor are multiplied as decimals
and rounded once to the nearest float (``0.003m`` is exactly ``3.0`` mm).
Radians are the one irrational factor (180/π), rounded once as well.

A bare number is in the model's unit. :func:`implausible` says when a bare
value looks like it was meant in another unit (a height in metres, an angle
in radians, a length in metres); the CLI then warns, naming what it assumed
and how to say otherwise.
"""

from __future__ import annotations

import argparse
import math
import re
from decimal import Decimal, InvalidOperation

#: per quantity: the model's unit, and every accepted suffix -> factor to it
UNITS: dict[str, tuple[str, dict[str, Decimal | None]]] = {
    "length": ("mm", {"mm": Decimal(1), "m": Decimal(1000), "cm": Decimal(10),
                      "um": Decimal("0.001"), "µm": Decimal("0.001")}),
    # None: radians, converted with math.degrees (180/π is irrational)
    "angle": ("deg", {"deg": Decimal(1), "°": Decimal(1), "rad": None}),
    "stiffness": ("N*mm^2", {"N*mm^2": Decimal(1), "Nmm^2": Decimal(1), "N*mm2": Decimal(1),
                             "N*m^2": Decimal(10) ** 6, "Nm^2": Decimal(10) ** 6}),
    "weight": ("N/mm", {"N/mm": Decimal(1), "N/m": Decimal("0.001")}),
}

_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf))\s*(.*?)\s*$",
                     re.IGNORECASE)


class Quantity(float):
    """A float in the model's unit that remembers whether a unit was written."""

    explicit: bool = False
    text: str = ""


def parse_quantity(text: str, quantity: str, name: str) -> Quantity:
    """``text`` (a number, optionally with a unit suffix) in the model's unit.

    Raises
    ------
    argparse.ArgumentTypeError
        For text that is not a number with one of the units of ``quantity``,
        naming ``name`` and the units allowed.
    """
    unit, table = UNITS[quantity]
    m = _NUMBER.match(str(text))
    allowed = ", ".join(table)
    if m is None:
        raise argparse.ArgumentTypeError(
            f"{name} must be a number with an optional unit ({allowed}; bare: {unit}), "
            f"got {text!r}")
    number, suffix = m.group(1), m.group(2).replace(" ", "")
    if suffix and suffix not in table:
        raise argparse.ArgumentTypeError(
            f"{name}: unknown unit {suffix!r} in {text!r}; use one of {allowed} "
            f"(a bare number is in {unit})")
    factor = table.get(suffix or unit)
    try:
        value = (math.degrees(float(number)) if factor is None
                 else float(Decimal(number) * factor))
    except InvalidOperation:  # nan / inf: the scene's own check names them
        value = float(number)
    q = Quantity(value)
    q.explicit, q.text = bool(suffix), str(text)
    return q


def quantity_type(quantity: str, name: str):
    """An argparse ``type=`` for ``quantity`` (named ``name`` in errors)."""
    def convert(text: str) -> Quantity:
        return parse_quantity(text, quantity, name)
    convert.__name__ = name  # argparse names the type in its own messages
    return convert


def _bare(value) -> bool:
    return not getattr(value, "explicit", False)


def implausible(theta, height, length) -> list[str]:
    """Warnings for bare values that look like another unit (empty when all is plausible).

    - h below 1e-3·ℓ: probably metres;
    - θ below 5° while its radian reading is an angle in (0°, 360°): probably radians;
    - ℓ below 1 mm: probably metres.
    """
    out = []
    if theta is not None and _bare(theta) and 0 < theta < 5 and 0 < math.degrees(theta) < 360:
        out.append(f"--theta {theta:g} is read as {theta:g} degrees; if you meant radians, "
                   f"write --theta {theta:g}rad (= {math.degrees(theta):.4g} deg), or "
                   f"--theta {theta:g}deg to silence this")
    if length is not None and _bare(length) and 0 < length < 1:
        out.append(f"--length {length:g} is read as {length:g} mm; if you meant metres, "
                   f"write --length {length:g}m (= {1000 * length:g} mm), or "
                   f"--length {length:g}mm to silence this")
    if height is not None and length is not None and _bare(height) and \
            0 < height < 1e-3 * length:
        out.append(f"--height {height:g} is read as {height:g} mm (below 1e-3 of the "
                   f"length {length:g} mm); if you meant metres, write --height {height:g}m "
                   f"(= {1000 * height:g} mm), or --height {height:g}mm to silence this")
    return out


__all__ = ["UNITS", "Quantity", "implausible", "parse_quantity", "quantity_type"]
