"""Regulations exactly at their limits, with the legal source carried by each limit."""

from __future__ import annotations

import pytest

from uasnav.errors import InputError
from uasnav.mission import load_regulations

REGS = load_regulations()


@pytest.mark.parametrize(
    ("mass_g", "lightest"),
    [
        (249.0, "C0"),
        (250.0, "C1"),
        (899.0, "C1"),
        (900.0, "C2"),
        (3990.0, "C2"),
        (4000.0, "C3"),
        (24999.0, "C3"),
    ],
)
def test_easa_class_mass_limits(mass_g: float, lightest: str) -> None:
    # EU 2019/945 Annex Parts 1–3: C0 < 250 g, C1 < 900 g, C2 < 4 kg ("less than").
    assert REGS.classes_for("easa", mtom_g=mass_g)[0] == lightest


def test_c2_is_under_4_kg_not_2_kg() -> None:
    # Some public encodings say "C2 < 2 kg" (the Art. 22 transitional rule); the class is < 4 kg.
    (c2,) = [lim for lim in REGS.jurisdictions["easa"].classes["C2"] if lim.quantity == "mtom"]
    assert c2.value_si == 4000.0 and c2.op == "lt"
    assert "2019/945" in c2.source and "Part 3" in c2.source


def test_open_category_mass_and_height() -> None:
    assert REGS.allowed("easa", "open", mtom_g=24999.0)
    assert not REGS.allowed("easa", "open", mtom_g=25000.0)
    # Art. 4(1)(e): "maintained within 120 metres" – 120 m is allowed, above is not.
    assert REGS.allowed("easa", "open", height_m=119.0)
    assert REGS.allowed("easa", "open", height_m=120.0)
    assert not REGS.allowed("easa", "open", height_m=120.001)
    assert REGS.max_height_m("easa", "open") == 120.0
    (chk,) = REGS.check("easa", "open", height_m=121.0)
    assert not chk.ok and chk.margin == pytest.approx(-1.0)
    assert "2019/947 Art. 4(1)(e)" in chk.limit.source


def test_faa_part107_limits() -> None:
    h400 = 400 * 0.3048  # 121.92 m
    assert REGS.max_height_m("faa", "part107") == pytest.approx(121.92)
    assert REGS.allowed("faa", "part107", height_m=h400)
    assert not REGS.allowed("faa", "part107", height_m=h400 + 0.01)
    assert REGS.allowed("faa", "part107", height_m=120.5)  # legal in the US, not in the EU
    assert not REGS.allowed("easa", "open", height_m=120.5)
    lb55 = 55 * 453.59237
    assert REGS.allowed("faa", "part107", mtom_g=lb55 - 1.0)
    assert not REGS.allowed("faa", "part107", mtom_g=lb55)
    # Registration: required above 0.55 lb = 249.48 g (14 CFR 48.15).
    assert REGS.classes_for("faa", mtom_g=249.0) == ["registration-exempt"]
    assert REGS.classes_for("faa", mtom_g=250.0) == []
    speed = REGS.check("faa", "part107", speed_ms=87 * 1852 / 3600)
    assert speed[0].ok and "107.51(a)" in speed[0].limit.source


def test_open_subcategories() -> None:
    # Unmarked (legacy, Art. 20): A1 below 250 g, otherwise A3 below 25 kg.
    assert REGS.open_subcategory(249.0) == "A1"
    assert REGS.open_subcategory(250.0) == "A3"
    assert REGS.open_subcategory(24999.0) == "A3"
    assert REGS.open_subcategory(25000.0) is None
    assert REGS.open_subcategory(899.0, "C1") == "A1"
    assert REGS.open_subcategory(3990.0, "C2") == "A2"
    assert REGS.open_subcategory(5000.0, "C3") == "A3"


def test_every_limit_cites_a_known_reference() -> None:
    for jur in REGS.jurisdictions.values():
        limits = [lim for lims in jur.classes.values() for lim in lims]
        limits += [lim for cat in jur.categories.values() for lim in cat.limits]
        assert limits
        for lim in limits:
            assert any(ref in lim.source for ref in jur.references), lim


def test_unknown_names_raise() -> None:
    with pytest.raises(InputError, match="unknown jurisdiction 'mars'"):
        REGS.category("mars", "open")
    with pytest.raises(InputError, match="unknown category 'closed'"):
        REGS.category("easa", "closed")
