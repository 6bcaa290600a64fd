"""Unit suffixes and the implausible-bare-value warnings of the scene options (issue 15)."""

import argparse
import json
import math

import pytest

from lcpbench.cli import main
from lcpbench.cli._units import UNITS, implausible, parse_quantity


@pytest.mark.parametrize("text, quantity, expected", [
    ("3mm", "length", 3.0), ("0.003m", "length", 3.0), ("0.3cm", "length", 3.0),
    ("3000um", "length", 3.0), ("3000µm", "length", 3.0), ("3", "length", 3.0),
    ("150deg", "angle", 150.0), ("150°", "angle", 150.0), ("150", "angle", 150.0),
    ("32.01N*mm^2", "stiffness", 32.01), ("3.201e-5N*m^2", "stiffness", 32.01),
    ("2.45e-4N/mm", "weight", 2.45e-4), ("0.245N/m", "weight", 2.45e-4),
])
def test_suffixes_convert_exactly(text, quantity, expected):
    """Decimal factors: the converted value is the float nearest the exact product,
    so it equals the float of the same quantity written in the model's unit."""
    q = parse_quantity(text, quantity, "x")
    assert q == expected  # exact, not approx
    assert q.explicit == (not text.replace(".", "").replace("e-", "").isdigit())


def test_radians_are_degrees_times_180_over_pi():
    assert parse_quantity("2.6rad", "angle", "theta") == pytest.approx(2.6 * 180 / math.pi,
                                                                       rel=1e-15)
    assert parse_quantity(f"{math.pi}rad", "angle", "theta") == pytest.approx(180.0,
                                                                             rel=1e-15)


def test_every_table_unit_is_accepted():
    for quantity, (_, table) in UNITS.items():
        for unit in table:
            assert parse_quantity(f"1{unit}", quantity, "x").explicit


@pytest.mark.parametrize("text", ["3in", "3 furlongs", "mm", "", "3mmm"])
def test_unknown_units_are_refused_naming_the_units(text):
    with pytest.raises(argparse.ArgumentTypeError, match="height") as info:
        parse_quantity(text, "length", "height")
    assert "mm" in str(info.value)


def test_implausible_bare_values_warn_and_explicit_ones_do_not():
    h = parse_quantity("0.003", "length", "height")
    t = parse_quantity("2.618", "angle", "theta")
    ell = parse_quantity("30", "length", "length")
    (wh,) = implausible(None, h, ell)
    assert "0.003m" in wh and "mm" in wh
    (wt,) = implausible(t, None, ell)
    assert "2.618rad" in wt and "150 deg" in wt  # 2.618 rad = 150.0002 deg
    (wl,) = implausible(None, None, parse_quantity("0.03", "length", "length"))
    assert "0.03m" in wl
    # with the unit written, or a plausible value: nothing to say
    assert implausible(parse_quantity("2.618deg", "angle", "theta"),
                       parse_quantity("0.003mm", "length", "height"), ell) == []
    assert implausible(150.0, 3.0, 30.0) == []
    assert implausible(parse_quantity("10", "angle", "theta"), None, None) == []


def _solve(capsys, *args):
    code = main(["solve", "--links", "20", "--json", *args])
    out = capsys.readouterr()
    return code, json.loads(out.out), out.err


def test_cli_height_in_metres_warns_and_units_give_the_same_scene(capsys):
    code, bare, err = _solve(capsys, "--height", "0.003")
    assert code == 0 and "lcpbench: warning: --height 0.003" in err and "0.003m" in err
    _, mm, err_mm = _solve(capsys, "--height", "3mm", "--theta", "150deg")
    _, m, err_m = _solve(capsys, "--height", "0.003m")
    assert err_mm == err_m == ""
    assert mm["total_force"] == m["total_force"] != bare["total_force"]


def test_cli_theta_in_radians_warns(capsys):
    code, _, err = _solve(capsys, "--theta", "2.618")
    assert code == 0 and "radians" in err and "--theta 2.618rad" in err
    _, rad, err = _solve(capsys, "--theta", "2.618rad")
    _, deg, _ = _solve(capsys, "--theta", f"{math.degrees(2.618)!r}")
    assert err == "" and rad["total_force"] == deg["total_force"]


def test_cli_unknown_unit_is_one_line_exit_2(capsys):
    assert main(["solve", "--height", "3in"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown unit 'in'" in err[0]


def test_sweep_ranges_take_units(tmp_path, capsys):
    """`sweep --height 0.003m --theta 2.618rad` is the scene of --height 3 --theta 150.0002."""
    from lcpbench.bench.store import Store

    store = tmp_path / "s.sqlite"
    base = ["sweep", "--links", "20", "--solvers", "active-set", "--settings", "default",
            "--baseline", "none", "--jobs", "1", "--quiet", "--no-report", "--store", str(store)]
    assert main([*base, "--height", "0.002m,3mm", "--theta", "90deg:150deg:60deg"]) == 0
    capsys.readouterr()
    with Store(store) as st:
        scenes = {(r["theta"], r["height"]) for r in st.runs(arrays=False)}
    assert scenes == {(90.0, 2.0), (150.0, 2.0), (90.0, 3.0), (150.0, 3.0)}
    assert main([*base, "--height", "3furlongs"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown unit 'furlongs'" in err[0]
