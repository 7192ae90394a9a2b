"""Named unit conversions."""

from __future__ import annotations

import numpy as np
import pytest

from uasnav.errors import InputError, UnitError
from uasnav.units import convert, dimension, known_units, parse_quantity


@pytest.mark.parametrize(
    ("value", "src", "dst", "expected"),
    [
        (1.0, "deg/s", "rad/s", np.pi / 180),
        (1.0, "deg/h", "rad/s", np.pi / 180 / 3600),
        (1.0, "deg/√h", "rad/√s", np.pi / 180 / 60),
        (1.0, "deg/sqrt(h)", "rad/s/√Hz", np.pi / 180 / 60),
        (1.0, "g", "m/s^2", 9.80665),
        (40.0, "µg/√Hz", "m/s/√s", 40e-6 * 9.80665),
        (3.8, "mdps/√Hz", "deg/√h", 3.8e-3 * 60),
        (0.05, "m/s/√h", "m/s/√s", 0.05 / 60),
        (2.0, "m/s/h", "m/s^2", 2.0 / 3600),
        (400.0, "ft", "m", 121.92),
        (2.0, "degC/min", "degC/s", 2.0 / 60),
    ],
)
def test_conversions(value, src, dst, expected):
    assert convert(value, src, dst) == pytest.approx(expected, rel=1e-12)
    assert convert(convert(value, src, dst), dst, src) == pytest.approx(value, rel=1e-12)


def test_dimension_mismatch_and_unknown_units():
    with pytest.raises(UnitError, match="different dimensions"):
        convert(1.0, "deg/h", "deg/√h")
    with pytest.raises(UnitError, match="unknown unit"):
        convert(1.0, "furlong/fortnight", "m/s")
    assert dimension("deg/√h") == "rad/√s"
    assert "deg/√h" in known_units()
    np.testing.assert_allclose(convert([1.0, 2.0], "deg", "rad"), np.radians([1.0, 2.0]))


@pytest.mark.parametrize(
    ("text", "to", "value", "unit"),
    [
        ("15deg/h", "rad/s", 15.0, "deg/h"),
        ("15 deg/h", "rad/s", 15.0, "deg/h"),
        ("  7e-5 rad/s ", "rad/s", 7e-5, "rad/s"),
        ("-.5E+2deg/s", "rad/s", -50.0, "deg/s"),
        ("3.18 deg/sqrt(h)", "rad/√s", 3.18, "deg/√h"),
        ("3.18 deg / √h", "rad/√s", 3.18, "deg/√h"),
        ("2 m/s/h", "m/s^2", 2.0, "m/s/h"),
        ("40 µg/√Hz", "m/s/√s", 40.0, "µg/√Hz"),
        ("1.5 1/K", "ppm/degC", 1.5, "1/K"),
    ],
)
def test_parse_quantity_equals_convert(text, to, value, unit):
    assert parse_quantity(text, to) == convert(value, unit, to)  # the same arithmetic, bit for bit


def test_parse_quantity_errors_name_the_text():
    with pytest.raises(UnitError, match=r"--residual-bias: '15 m/s': .*different dimensions"):
        parse_quantity("15 m/s", "rad/s", what="--residual-bias")
    with pytest.raises(UnitError, match=r"'15 furlong': unknown unit 'furlong'"):
        parse_quantity("15 furlong", "rad/s")
    for bad in ("15", "deg/h", "", "nan rad/s", "fifteen deg/h"):
        with pytest.raises(InputError, match=r"gbi: expected '<number><unit>'.*got"):
            parse_quantity(bad, "rad/s", what="gbi")
    with pytest.raises(InputError, match=r"got 15\.0"):
        parse_quantity(15.0, "rad/s")  # type: ignore[arg-type]
