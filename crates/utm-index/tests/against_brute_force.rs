//! Property tests: the index finds exactly the encounters that testing every pair finds.
use proptest::prelude::*;
use utm_index::{brute_force, Search, SpaceTimeIndex, Volumes};

/// A random volume: a polygon (3–7 vertices on a star around a centre, so it is simple) or
/// a circle; sizes spread over two orders of magnitude so some volumes span many cells.
fn volume() -> impl Strategy<Value = Spec> {
    (
        0u32..12,
        (0.0..2000.0f64, 0.0..2000.0f64, 5.0..400.0f64),
        prop::collection::vec((0.3..1.0f64, 0.0..1.0f64), 3..8),
        any::<bool>(),
        (0.0..120.0f64, 1.0..60.0f64),
        (0.0..3600.0f64, 1.0..900.0f64),
    )
        .prop_map(
            |(intent, (cx, cy, r), radial, is_circle, (z, dz), (t, dt))| {
                let n = radial.len();
                let verts = if is_circle {
                    vec![]
                } else {
                    radial
                        .iter()
                        .enumerate()
                        .map(|(k, (f, j))| {
                            let a = (k as f64 + 0.8 * j) / n as f64 * std::f64::consts::TAU;
                            [cx + r * f * a.cos(), cy + r * f * a.sin()]
                        })
                        .collect()
                };
                (intent, verts, [cx, cy, r], [z, z + dz], [t, t + dt])
            },
        )
}

type Spec = (u32, Vec<[f64; 2]>, [f64; 3], [f64; 2], [f64; 2]);

fn build(vols: &[Spec]) -> Volumes<'static> {
    let mut offsets = vec![0];
    let mut verts = Vec::new();
    for v in vols {
        verts.extend_from_slice(&v.1);
        offsets.push(verts.len());
    }
    Volumes::new(
        vols.iter().map(|v| v.0).collect::<Vec<_>>(),
        vols.iter().map(|v| v.3).collect::<Vec<_>>(),
        vols.iter().map(|v| v.4).collect::<Vec<_>>(),
        offsets,
        verts,
        vols.iter().map(|v| v.2).collect::<Vec<_>>(),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn index_equals_brute_force(
        vols in prop::collection::vec(volume(), 0..120),
        h in prop_oneof![Just(0.0), 0.0..300.0f64],
        v in prop_oneof![Just(0.0), 0.0..50.0f64],
        threads in 1usize..4,
    ) {
        let set = build(&vols);
        let s = Search { horizontal_m: h, vertical_m: v };
        let mut want = brute_force(&set, &s).unwrap_or_else(|e| panic!("{e}"));
        want.sort_unstable_by_key(|e| (e.a, e.b));
        let idx = SpaceTimeIndex::new(&set, s).unwrap_or_else(|e| panic!("{e}"));
        let got = idx.encounters(threads);
        prop_assert_eq!(got, want);
    }

    #[test]
    fn earliest_delay_is_free_and_smallest(
        vols in prop::collection::vec(volume(), 1..60),
        intent in 0u32..12,
    ) {
        let set = build(&vols);
        let idx = SpaceTimeIndex::new(&set, Search::default()).unwrap_or_else(|e| panic!("{e}"));
        let max = 20_000.0;
        let d = idx.earliest_delay(intent, max).unwrap_or_else(|e| panic!("{e}"));
        // brute force: shift the intent's volumes and test all pairs
        let conflicts_at = |delay: f64| {
            let shifted: Vec<_> = vols
                .iter()
                .map(|v| {
                    let mut w = v.clone();
                    if w.0 == intent { w.4 = [w.4[0] + delay, w.4[1] + delay]; }
                    w
                })
                .collect();
            brute_force(&build(&shifted), &Search::default())
                .unwrap_or_else(|e| panic!("{e}"))
                .iter()
                // overlaps shorter than 1 µs are the rounding of t + d, not a conflict
                .any(|e| (shifted[e.a as usize].0 == intent || shifted[e.b as usize].0 == intent) && e.t_end - e.t_start > 1e-6)
        };
        match d {
            Some(d) => {
                prop_assert!(!conflicts_at(d), "delay {} still conflicts", d);
                // no smaller free delay on a fine grid below it
                let mut x = 0.0;
                while x < d - 1e-6 {
                    prop_assert!(conflicts_at(x), "delay {} < {} is already free", x, d);
                    x += (d / 50.0).max(1.0);
                }
            }
            None => prop_assert!(conflicts_at(max) || conflicts_at(0.0)),
        }
    }
}

/// The parallel build (entries split by grid column, ≥ 65 536 volumes) gives the same index and
/// the same encounters as one thread; and on a subsample both equal brute force.
#[test]
fn parallel_build_equals_serial() {
    let v = utm_index::synthetic::synthetic(3_000, 7).unwrap_or_else(|e| panic!("{e}"));
    assert!(v.len() > 65_536);
    for s in [
        Search::default(),
        Search {
            horizontal_m: 20.0,
            vertical_m: 5.0,
        },
    ] {
        let one = SpaceTimeIndex::with_threads(&v, s, 1).unwrap_or_else(|e| panic!("{e}"));
        let two = SpaceTimeIndex::with_threads(&v, s, 2).unwrap_or_else(|e| panic!("{e}"));
        let three = SpaceTimeIndex::with_threads(&v, s, 3).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(one.stats(), two.stats());
        let e1 = one.encounters(1);
        assert!(!e1.is_empty());
        assert_eq!(e1, two.encounters(2));
        assert_eq!(e1, three.encounters(1));
    }
    let sub = utm_index::synthetic::synthetic(150, 3).unwrap_or_else(|e| panic!("{e}"));
    let s = Search {
        horizontal_m: 300.0,
        vertical_m: 10.0,
    };
    let idx = SpaceTimeIndex::with_threads(&sub, s, 2).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        idx.encounters(2),
        brute_force(&sub, &s).unwrap_or_else(|e| panic!("{e}"))
    );
}

/// A dense random set (2 000 volumes in 2 km × 1 h, sizes over two orders of magnitude, plus
/// a few volumes spanning the whole area that the index keeps aside as large) spreads over
/// many start-time buckets and cells: encounters equal brute force for several buffers, and
/// every intent's earliest delay equals the delay computed from all pairs without the index.
#[test]
fn dense_set_with_large_volumes_equals_brute_force() {
    let mut rng = utm_index::synthetic::SplitMix64::new(11);
    let mut vols: Vec<Spec> = Vec::new();
    for k in 0..2_000u32 {
        let (cx, cy) = (rng.uniform(0.0, 2000.0), rng.uniform(0.0, 2000.0));
        let r = if k % 500 == 7 {
            4000.0 // spans the whole area: a large volume
        } else {
            (rng.uniform(0.0, 1.0f64)).powi(3) * 200.0 + 2.0
        };
        let n = 3 + (rng.next_u64() % 5) as usize;
        let verts: Vec<[f64; 2]> = if rng.next_u64().is_multiple_of(4) {
            vec![]
        } else {
            (0..n)
                .map(|j| {
                    let a =
                        (j as f64 + 0.8 * rng.uniform(0.0, 1.0)) / n as f64 * std::f64::consts::TAU;
                    let f = rng.uniform(0.3, 1.0);
                    [cx + r * f * a.cos(), cy + r * f * a.sin()]
                })
                .collect()
        };
        let z = rng.uniform(0.0, 120.0);
        let t = rng.uniform(0.0, 3600.0);
        let dt = rng.uniform(1.0, 120.0);
        vols.push((
            k % 150,
            verts,
            [cx, cy, r],
            [z, z + rng.uniform(1.0, 40.0)],
            [t, t + dt],
        ));
    }
    let set = build(&vols);
    for s in [
        Search::default(),
        Search {
            horizontal_m: 25.0,
            vertical_m: 8.0,
        },
    ] {
        let want = brute_force(&set, &s).unwrap_or_else(|e| panic!("{e}"));
        let idx = SpaceTimeIndex::new(&set, s).unwrap_or_else(|e| panic!("{e}"));
        assert!(idx.stats().1 >= 3, "large volumes: {:?}", idx.stats());
        assert!(want.len() > 100, "{}", want.len());
        assert_eq!(idx.encounters(1), want);
    }
    // earliest delays against the definition: union of the forbidden delay intervals of all
    // spatially intersecting pairs (no index)
    let idx = SpaceTimeIndex::new(&set, Search::default()).unwrap_or_else(|e| panic!("{e}"));
    fn outline(v: &Spec) -> utm_index::geometry::Outline<'_> {
        if v.1.is_empty() {
            utm_index::geometry::Outline::Circle([v.2[0], v.2[1]], v.2[2])
        } else {
            utm_index::geometry::Outline::Polygon(&v.1)
        }
    }
    for max in [600.0, 5000.0] {
        for intent in 0..150u32 {
            let mut forbidden: Vec<(f64, f64)> = Vec::new();
            for b in vols.iter().filter(|v| v.0 == intent) {
                for c in vols.iter().filter(|v| v.0 != intent) {
                    let (lo, hi) = (c.4[0] - b.4[1], c.4[1] - b.4[0]);
                    if hi <= 0.0 || lo >= max || b.3[0].max(c.3[0]) > b.3[1].min(c.3[1]) {
                        continue;
                    }
                    if utm_index::geometry::outline_dist(outline(b), outline(c)) <= 0.0 {
                        forbidden.push((lo, hi));
                    }
                }
            }
            forbidden.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            let mut d = 0.0f64;
            for (lo, hi) in forbidden {
                if lo >= d {
                    break;
                }
                d = d.max(hi);
            }
            let want = if d <= max { Some(d) } else { None };
            assert_eq!(
                idx.earliest_delay(intent, max),
                Ok(want),
                "intent {intent}, max {max}"
            );
        }
    }
}
