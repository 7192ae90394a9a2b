"""Deconfliction of F3548 intents: the Rust index against shapely (STRtree + GEOS distances) and
against brute force on random volumes, and the InterUSS flight-intent sets as test cases."""

from __future__ import annotations

import json
from datetime import datetime, timedelta, timezone

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from uasnav.cli import main
from uasnav.errors import DataFormatError, InputError
from uasnav.io.interuss import read_flight_intents
from uasnav.io.operational_intent import check_times, parse_details, read_intents, write_intent
from uasnav.utm import VolumeArrays, deconflict, earliest_delays, encounters
from uasnav.utm.strtree import strtree_encounters

NOW = datetime(2026, 11, 24, 12, 0, tzinfo=timezone.utc)
U = "utm"


def _random_volumes(rng: np.random.Generator, n: int, n_intents: int, span_m: float = 2000.0) -> VolumeArrays:
    intent = np.sort(rng.integers(0, n_intents, n)).astype(np.uint32)
    alt = np.sort(rng.uniform(0, 150, (n, 2)), axis=1)
    t0 = rng.uniform(0, 3600, n)
    time = np.column_stack([t0, t0 + rng.uniform(1, 900, n)])
    offsets, verts = [0], []
    circle = np.zeros((n, 3))
    for i in range(n):
        c = rng.uniform(0, span_m, 2)
        r = rng.uniform(5, 300)
        if rng.random() < 0.3:
            circle[i] = [c[0], c[1], r]
            offsets.append(offsets[-1])
            continue
        k = int(rng.integers(3, 9))
        ang = np.sort(rng.uniform(0, 2 * np.pi, k))  # a star polygon around c: simple
        rad = r * rng.uniform(0.2, 1.0, k)
        verts.append(c + np.column_stack([rad * np.cos(ang), rad * np.sin(ang)]))
        offsets.append(offsets[-1] + k)
    first = np.searchsorted(intent, np.arange(n_intents))
    xy = np.vstack(verts) if verts else np.zeros((0, 2))
    return VolumeArrays(
        intent, alt, time, np.array(offsets, dtype=np.uint64), xy, circle,
        tuple(f"i{k}" for k in range(n_intents)), first,
    )  # fmt: skip


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 150),
    h=st.sampled_from([0.0, 25.0, 200.0]),
    v=st.sampled_from([0.0, 10.0]),
)
def test_index_matches_shapely_and_brute_force(seed, n, h, v):
    vols = _random_volumes(np.random.default_rng(seed), n, n_intents=max(2, n // 5))
    got = encounters(vols, h, v)
    brute = encounters(vols, h, v, brute=True)
    ref = strtree_encounters(vols, h, v)
    np.testing.assert_array_equal(got[0], brute[0])
    np.testing.assert_array_equal(got[0], ref[0])  # the same pairs as an independent implementation
    np.testing.assert_array_equal(got[1], ref[1])  # the same overlap intervals
    np.testing.assert_allclose(got[2], ref[2], atol=1e-6)  # GEOS distances


def test_delay_frees_the_intent_and_is_the_smallest():
    rng = np.random.default_rng(7)
    vols = _random_volumes(rng, 120, 10, span_m=800.0)
    delays = earliest_delays(vols, range(10), max_delay_s=50_000)

    def conflicted(k: int, d: float) -> bool:
        p, ov, dist = encounters(vols.shifted(k, d))
        mine = (vols.intent[p[:, 0]] == k) | (vols.intent[p[:, 1]] == k)
        return bool(np.any(mine & (dist[:, 0] == 0) & (dist[:, 1] == 0) & (ov[:, 1] - ov[:, 0] > 1e-6)))

    assert np.all(np.isfinite(delays))
    for k, d in enumerate(delays):
        assert not conflicted(k, d)
        if d > 0:  # any earlier departure on a fine grid still conflicts
            assert all(conflicted(k, x) for x in np.linspace(0, d, 40, endpoint=False))


def _intents(name: str) -> dict:
    return {x.name: x for x in read_flight_intents(_shared / U / name, NOW)}


@pytest.fixture(autouse=True)
def _data(shared_data):
    global _shared
    _shared = shared_data


_shared = None


def _conflicting_pairs(intents: list) -> set[frozenset[str]]:
    return {frozenset(c.intents) for c in deconflict(intents).conflicts}


def test_interuss_conflicting_set():
    it = _intents("interuss_flight_intents_conflicting.yaml")
    pick = [
        "flight1_planned",
        "flight1m_planned",
        "flight1c_planned",
        "flight2_planned",
        "equal_prio_flight2m_planned",
    ]
    pairs = _conflicting_pairs([it[k] for k in pick])
    assert frozenset({"flight1_planned", "flight2_planned"}) in pairs
    assert frozenset({"flight1m_planned", "flight2_planned"}) in pairs
    # the "c" (clear) variant of flight 1 is moved east, away from flight 2
    assert frozenset({"flight1c_planned", "flight2_planned"}) not in pairs
    # flight 2m at 45–50 m is above flight 1 (up to 30 m): no conflict
    assert frozenset({"flight1_planned", "equal_prio_flight2m_planned"}) not in pairs
    res = deconflict([it["flight1_planned"], it["flight2_planned"]])
    (c,) = res.conflicts
    assert c.later == "flight2_planned" or c.later == "flight1_planned"
    assert c.overlap == (NOW - timedelta(seconds=1), NOW + timedelta(minutes=45))
    # flight 2 must wait until flight 1 ends: its 45 min 1 s
    assert c.delay_s == pytest.approx(45 * 60 + 1)


def test_interuss_non_conflicting_set():
    it = _intents("interuss_flight_intents_non_conflicting.yaml")
    ones = [k for k in it if k.startswith("flight_1")]
    twos = [k for k in it if k.startswith("flight_2")]
    for a in ones:
        for b in twos:
            res = deconflict([it[a], it[b]], horizontal_m=50.0)
            assert not res.conflicts, (a, b)
            # the bounding boxes overlap; the polygons do not: a near miss, not a conflict
            (m,) = res.near_misses
            assert 0 < m.horizontal_m < 50


def test_interuss_invalid_set():
    it = _intents("interuss_flight_intents_invalid.yaml")
    with pytest.raises(InputError, match="more than 30 days after now"):
        check_times(it["invalid_too_far_away"], NOW)
    with pytest.raises(InputError, match="may not end in the past"):
        check_times(it["invalid_recently_ended"], NOW)
    for k in ("valid_flight", "valid_activated", "valid_conflict_tiny_overlap"):
        check_times(it[k], NOW)
    # a 1 cm overlap is a conflict
    assert deconflict([it["valid_flight"], it["valid_conflict_tiny_overlap"]]).conflicts


def test_near_miss_distance_against_geodesy():
    """Two 10 m squares 100 m apart east–west at 47° N: the distance is 100 m on the ground."""
    import pymap3d

    def square(e0: float) -> dict:
        pts = [
            pymap3d.enu2geodetic(e0 + de, dn, 0, 47.0, 8.0, 0)[:2]
            for de, dn in ((0, 0), (10, 0), (10, 10), (0, 10))
        ]
        return {
            "volumes": [
                {
                    "volume": {
                        "outline_polygon": {"vertices": [{"lat": la, "lng": lo} for la, lo in pts]},
                        "altitude_lower": {"value": 500, "reference": "W84", "units": "M"},
                        "altitude_upper": {"value": 550, "reference": "W84", "units": "M"},
                    },
                    "time_start": {"value": "2026-11-24T12:00:00Z", "format": "RFC3339"},
                    "time_end": {"value": "2026-11-24T12:10:00Z", "format": "RFC3339"},
                }
            ],
            "priority": 0,
        }

    from uasnav.io.operational_intent import NamedIntent

    a = NamedIntent("a", parse_details(square(0.0)))
    b = NamedIntent("b", parse_details(square(110.0)))
    (m,) = deconflict([a, b], horizontal_m=150.0).near_misses
    assert m.horizontal_m == pytest.approx(100.0, abs=0.01)


@pytest.mark.parametrize(
    ("mutate", "match"),
    [
        (
            lambda d: d["volumes"][0]["volume"].pop("altitude_upper"),
            r"volumes\[0\]\.volume\.altitude_upper: missing",
        ),
        (
            lambda d: d["volumes"][0]["volume"]["altitude_lower"].update(reference="AMSL"),
            "not a valid AltitudeReference",
        ),
        (lambda d: d["volumes"][0]["volume"]["outline_polygon"]["vertices"].pop(), "a polygon needs 3"),
        (
            lambda d: d["volumes"][0].update(time_end=d["volumes"][0]["time_start"]),
            "time_start is not before time_end",
        ),
        (
            lambda d: d["volumes"][0]["volume"].update(
                outline_circle={"center": {"lat": 0, "lng": 0}, "radius": {"value": 5}}
            ),
            "exactly one of",
        ),
        (lambda d: d.update(volumes=[]), "at least one volume"),
    ],
)
def test_bad_intents_are_refused_by_json_path(tmp_path, mutate, match):
    good = tmp_path / "good.json"
    it = _intents("interuss_flight_intents_invalid.yaml")["valid_flight"]
    write_intent(it.details, good)
    d = json.loads(good.read_text())
    assert read_intents(good)[0].details == it.details  # round trip
    mutate(d)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(d))
    with pytest.raises(DataFormatError, match=match) as ei:
        read_intents(bad)
    assert "bad.json" in str(ei.value)


def test_cli_deconflict(tmp_path):
    d = _shared / U
    r = CliRunner().invoke(
        main,
        [
            "utm",
            "deconflict",
            str(d / "interuss_flight_intents_invalid.yaml"),
            "--now",
            "2026-11-24T12:00:00Z",
        ],
    )
    assert r.exit_code == 1 and "invalid_too_far_away" in r.stderr and "30 days" in r.stderr
    it = _intents("interuss_flight_intents_conflicting.yaml")
    for k in ("flight1_planned", "flight2_planned"):
        write_intent(it[k].details, tmp_path / f"{k}.json")
    argv = [
        "utm",
        "deconflict",
        str(tmp_path / "flight1_planned.json"),
        str(tmp_path / "flight2_planned.json"),
    ]
    r = CliRunner().invoke(main, [*argv, "--now", "2026-11-24T12:00:00Z", "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    (c,) = out["conflicts"]
    assert set(c["intents"]) == {"flight1_planned", "flight2_planned"} and c["delay_s"] == pytest.approx(2701)
    assert c["min_separation_m"] == 0.0
    r = CliRunner().invoke(main, [*argv, "--now", "2026-11-25T12:00:00Z"])
    assert r.exit_code == 1 and "may not end in the past" in r.stderr
    r = CliRunner().invoke(main, [*argv, "--now", "yesterday"])
    assert r.exit_code == 1 and "--now" in r.stderr
