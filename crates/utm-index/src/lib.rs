//! Space-time index of 4D volumes (ASTM F3548-21 `Volume4D`) for strategic deconfliction.
//!
//! Units and frames, stated once: horizontal coordinates are metres east (x) and north (y) in
//! one local tangent plane (the caller projects WGS-84 positions; `uasnav.utm` uses an ENU
//! plane at the data set's centre); altitudes are metres (WGS-84 ellipsoidal, `W84`, for F3548
//! data — any one vertical datum works); times are seconds on one clock (e.g. Unix time).
//!
//! A volume is an outline (a simple polygon or a circle) extruded between two altitudes, alive
//! over a time interval. Two volumes of *different* intents **conflict** when their outlines
//! intersect (horizontal distance 0, closed sets), their altitude ranges intersect (closed)
//! and their time intervals overlap for a positive duration (`[t₀, t₁)`: a volume that ends
//! when another starts is a hand-over, not an overlap). With buffers h, v > 0 the search also
//! returns **near misses**: volumes overlapping in time whose horizontal distance is ≤ h and
//! vertical gap ≤ v, with both distances.
//!
//! The index ([`SpaceTimeIndex`]) hashes each volume's bounding box (grown by h/2
//! horizontally) into a uniform grid of (x, y, t) cells, sized from the median volume, sorts
//! the (cell, volume) entries by a radix sort, and tests only pairs that share a cell —
//! each pair once, in the cell that holds the lower corner of the two boxes' intersection.
//! Volumes spanning more than [`MAX_CELLS_PER_VOLUME`] cells are kept aside and tested
//! against every box. Exact tests follow ([`geometry`]). Expected cost O(n + k) for n volumes
//! and k candidate pairs; [`brute_force`] is the O(n²) reference the tests compare with.
//!
//! [`SpaceTimeIndex::earliest_delay`] finds the smallest departure delay d ≥ 0 of one intent
//! such that none of its volumes, shifted by d, conflicts with a volume of another intent:
//! each spatially intersecting pair (b, c) forbids the open interval
//! (c.t₀ − b.t₁, c.t₁ − b.t₀) of delays; the answer is the smallest d outside their union.
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![deny(clippy::unwrap_used, clippy::expect_used)]

pub mod geometry;
pub mod synthetic;

use core::fmt;
use geometry::{outline_dist, Outline, Pt};
use std::borrow::Cow;

/// Volumes spanning more grid cells than this are tested against every volume instead.
pub const MAX_CELLS_PER_VOLUME: u64 = 256;
/// Most polygon vertices one volume may have.
pub const MAX_VERTICES: usize = 10_000;

/// Errors of this crate: bad input, named by volume index.
#[derive(Clone, Debug, PartialEq)]
pub enum IndexError {
    /// Arrays of different lengths.
    Length {
        /// Which array.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A volume is invalid (non-finite, empty interval, bad outline).
    Volume {
        /// Volume index.
        index: usize,
        /// What is wrong.
        problem: &'static str,
    },
    /// A search parameter is invalid.
    Parameter(&'static str),
}

impl fmt::Display for IndexError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            IndexError::Length {
                what,
                expected,
                got,
            } => {
                write!(f, "{what}: expected length {expected}, got {got}")
            }
            IndexError::Volume { index, problem } => write!(f, "volume {index}: {problem}"),
            IndexError::Parameter(p) => write!(f, "{p}"),
        }
    }
}

impl std::error::Error for IndexError {}

/// A set of volumes in structure-of-arrays form (what Python hands over without copies of
/// objects). Volume `i` belongs to intent `intent[i]`; its outline is the polygon
/// `vertices[offsets[i]..offsets[i+1]]`, or, if that range is empty, the circle `circle[i]`.
///
/// The arrays are borrowed or owned ([`Cow`]): the Python binding lends numpy's buffers
/// without copying them.
#[derive(Clone, Debug)]
pub struct Volumes<'a> {
    intent: Cow<'a, [u32]>,
    alt: Cow<'a, [[f64; 2]]>,
    time: Cow<'a, [[f64; 2]]>,
    offsets: Vec<usize>,
    vertices: Cow<'a, [Pt]>,
    circle: Cow<'a, [[f64; 3]]>,
    bbox: Vec<[f64; 4]>,
}

impl<'a> Volumes<'a> {
    /// Checks and stores a volume set.
    ///
    /// * `intent` — intent number of each volume (n).
    /// * `alt` — (lower, upper) altitude, m, lower ≤ upper (n).
    /// * `time` — (start, end), s, start < end (n).
    /// * `offsets` — n + 1 non-decreasing indices into `vertices`, from 0 to its length.
    /// * `vertices` — polygon vertices (x east, y north), m; a polygon has ≥ 3.
    /// * `circle` — (x, y, radius) m for volumes with no vertices (radius > 0); ignored otherwise.
    pub fn new(
        intent: impl Into<Cow<'a, [u32]>>,
        alt: impl Into<Cow<'a, [[f64; 2]]>>,
        time: impl Into<Cow<'a, [[f64; 2]]>>,
        offsets: Vec<usize>,
        vertices: impl Into<Cow<'a, [Pt]>>,
        circle: impl Into<Cow<'a, [[f64; 3]]>>,
    ) -> Result<Self, IndexError> {
        let (intent, alt, time) = (intent.into(), alt.into(), time.into());
        let (vertices, circle) = (vertices.into(), circle.into());
        let n = intent.len();
        for (what, got) in [
            ("alt", alt.len()),
            ("time", time.len()),
            ("circle", circle.len()),
        ] {
            if got != n {
                return Err(IndexError::Length {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        if offsets.len() != n + 1 {
            return Err(IndexError::Length {
                what: "offsets",
                expected: n + 1,
                got: offsets.len(),
            });
        }
        if offsets.first() != Some(&0) || offsets.last() != Some(&vertices.len()) {
            return Err(IndexError::Parameter(
                "offsets must run from 0 to the number of vertices",
            ));
        }
        if vertices
            .iter()
            .any(|v| !(v[0].is_finite() && v[1].is_finite()))
        {
            return Err(IndexError::Parameter("non-finite vertex coordinate"));
        }
        let mut bbox = Vec::with_capacity(n);
        for i in 0..n {
            let bad = |problem| Err(IndexError::Volume { index: i, problem });
            let (a, t, c) = (alt[i], time[i], circle[i]);
            if !(a[0].is_finite() && a[1].is_finite()) || a[0] > a[1] {
                return bad("altitude bounds must be finite with lower ≤ upper");
            }
            if !(t[0].is_finite() && t[1].is_finite()) || t[0] >= t[1] {
                return bad("time bounds must be finite with start < end");
            }
            let (lo, hi) = (offsets[i], offsets[i + 1]);
            if hi < lo {
                return bad("offsets decrease");
            }
            let b = if hi == lo {
                if !(c.iter().all(|x| x.is_finite()) && c[2] > 0.0) {
                    return bad("a volume without vertices needs a circle with finite centre and radius > 0");
                }
                [c[0] - c[2], c[1] - c[2], c[0] + c[2], c[1] + c[2]]
            } else {
                let poly = &vertices[lo..hi];
                if poly.len() < 3 {
                    return bad("a polygon needs at least 3 vertices");
                }
                if poly.len() > MAX_VERTICES {
                    return bad("polygon has more than 10 000 vertices");
                }
                poly.iter().fold(
                    [
                        f64::INFINITY,
                        f64::INFINITY,
                        f64::NEG_INFINITY,
                        f64::NEG_INFINITY,
                    ],
                    |b, p| {
                        [
                            b[0].min(p[0]),
                            b[1].min(p[1]),
                            b[2].max(p[0]),
                            b[3].max(p[1]),
                        ]
                    },
                )
            };
            bbox.push(b);
        }
        Ok(Volumes {
            intent,
            alt,
            time,
            offsets,
            vertices,
            circle,
            bbox,
        })
    }

    /// Number of volumes.
    pub fn len(&self) -> usize {
        self.intent.len()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.intent.is_empty()
    }

    /// Intent of volume `i`.
    pub fn intent(&self, i: usize) -> u32 {
        self.intent[i]
    }

    /// (start, end) of volume `i`, s.
    pub fn time(&self, i: usize) -> [f64; 2] {
        self.time[i]
    }

    fn outline(&self, i: usize) -> Outline<'_> {
        let (lo, hi) = (self.offsets[i], self.offsets[i + 1]);
        if hi > lo {
            Outline::Polygon(&self.vertices[lo..hi])
        } else {
            let c = self.circle[i];
            Outline::Circle([c[0], c[1]], c[2])
        }
    }
}

/// Search parameters: the near-miss buffers (0, 0 for conflicts only).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Search {
    /// Report pairs whose outlines are at most this far apart, m (≥ 0).
    pub horizontal_m: f64,
    /// … and whose altitude ranges are at most this far apart, m (≥ 0).
    pub vertical_m: f64,
}

impl Search {
    fn check(&self) -> Result<(), IndexError> {
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        if ok(self.horizontal_m) && ok(self.vertical_m) {
            Ok(())
        } else {
            Err(IndexError::Parameter("buffers must be finite and ≥ 0 m"))
        }
    }
}

/// Two volumes of different intents that overlap in time and come within the buffers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Encounter {
    /// Volume index (a < b).
    pub a: u32,
    /// Volume index.
    pub b: u32,
    /// Start of the time overlap, s.
    pub t_start: f64,
    /// End of the time overlap, s.
    pub t_end: f64,
    /// Horizontal distance between the outlines, m (0 if they intersect).
    pub horizontal_m: f64,
    /// Vertical gap between the altitude ranges, m (0 if they overlap).
    pub vertical_m: f64,
}

impl Encounter {
    /// Whether the volumes intersect in space and time (a conflict, not a near miss).
    pub fn is_conflict(&self) -> bool {
        self.horizontal_m == 0.0 && self.vertical_m == 0.0
    }
}

/// The exact test of volumes `a` and `b` (any order); None if they are of the same intent,
/// do not overlap in time, or are farther apart than the buffers.
fn exact(v: &Volumes<'_>, a: usize, b: usize, s: &Search) -> Option<Encounter> {
    // one order for the arithmetic, whatever the caller's: bit-identical results
    let (a, b) = (a.min(b), a.max(b));
    if v.intent[a] == v.intent[b] {
        return None;
    }
    let (ta, tb) = (v.time[a], v.time[b]);
    let (t0, t1) = (ta[0].max(tb[0]), ta[1].min(tb[1]));
    if t0 >= t1 {
        return None;
    }
    let (za, zb) = (v.alt[a], v.alt[b]);
    let gap = (za[0].max(zb[0]) - za[1].min(zb[1])).max(0.0);
    if gap > s.vertical_m {
        return None;
    }
    let (ba, bb) = (v.bbox[a], v.bbox[b]);
    let h = s.horizontal_m;
    if ba[0] > bb[2] + h || bb[0] > ba[2] + h || ba[1] > bb[3] + h || bb[1] > ba[3] + h {
        return None;
    }
    let d = outline_dist(v.outline(a), v.outline(b));
    if d > h {
        return None;
    }
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    Some(Encounter {
        a: lo as u32,
        b: hi as u32,
        t_start: t0,
        t_end: t1,
        horizontal_m: d,
        vertical_m: gap,
    })
}

/// Every encounter by testing all pairs: O(n²), the reference for tests and benchmarks.
pub fn brute_force(v: &Volumes<'_>, s: &Search) -> Result<Vec<Encounter>, IndexError> {
    s.check()?;
    let mut out = Vec::new();
    for a in 0..v.len() {
        for b in a + 1..v.len() {
            if let Some(e) = exact(v, a, b, s) {
                out.push(e);
            }
        }
    }
    Ok(out)
}

/// Grid cell of a coordinate (`inv` = 1 / cell size: a multiply, not a divide, per call —
/// the build computes 9 of these per volume). Monotone in x, which is all the owner rule needs.
fn cell(x: f64, origin: f64, inv: f64) -> i64 {
    ((x - origin) * inv).floor() as i64
}

/// The grid: cell sizes, origin and extent (in cells) of the data.
#[derive(Clone, Copy, Debug)]
struct Grid {
    origin: [f64; 3],
    /// 1 / cell size per axis, 1/m, 1/m, 1/s.
    inv: [f64; 3],
    dims: [u64; 3],
}

impl Grid {
    fn range(&self, lo: f64, hi: f64, axis: usize) -> (i64, i64) {
        let max = self.dims[axis] as i64 - 1;
        (
            cell(lo, self.origin[axis], self.inv[axis]).clamp(0, max),
            cell(hi, self.origin[axis], self.inv[axis]).clamp(0, max),
        )
    }

    fn key(&self, cx: i64, cy: i64, ct: i64) -> u64 {
        (cx as u64 * self.dims[1] + cy as u64) * self.dims[2] + ct as u64
    }
}

fn median(mut xs: Vec<f64>) -> f64 {
    if xs.is_empty() {
        return 1.0;
    }
    let k = xs.len() / 2;
    let (_, m, _) = xs.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
    *m
}

/// LSD radix sort of (key, value) pairs packed as `key << 32 | value`, by the key's low
/// `key_bits` bits, in passes of at most 11 bits (2048 buckets: the counters stay in L1).
fn radix_sort(entries: &mut Vec<u64>, key_bits: u32) {
    let passes = key_bits.div_ceil(11).max(1);
    let width = key_bits.div_ceil(passes).max(1);
    let mask = (1u64 << width) - 1;
    let mut buf = vec![0u64; entries.len()];
    let mut count = vec![0usize; 1 << width];
    for p in 0..passes {
        let shift = 32 + p * width;
        count.iter_mut().for_each(|c| *c = 0);
        for &e in entries.iter() {
            count[((e >> shift) & mask) as usize] += 1;
        }
        let mut sum = 0;
        for c in count.iter_mut() {
            let n = *c;
            *c = sum;
            sum += n;
        }
        for &e in entries.iter() {
            let d = ((e >> shift) & mask) as usize;
            buf[count[d]] = e;
            count[d] += 1;
        }
        std::mem::swap(entries, &mut buf);
    }
}

/// The space-time index of a volume set (borrowed), built once per search buffer.
#[derive(Debug)]
pub struct SpaceTimeIndex<'a> {
    volumes: &'a Volumes<'a>,
    search: Search,
    grid: Grid,
    /// (cell key << 32 | volume), sorted by key.
    entries: Vec<u64>,
    /// Volumes spanning too many cells: tested against every volume.
    big: Vec<u32>,
    /// Volumes renumbered in the order of their lowest cell, so that volumes tested together
    /// lie together in memory: `order[new] = original`, `rank[original] = new`. Every array
    /// below and the entries use the new numbers.
    order: Vec<u32>,
    rank: Vec<u32>,
    /// Per volume, in one cache line: its box grown by h/2 horizontally, its time interval
    /// and its altitude range (x0, y0, x1, y1, t0, t1, z0, z1) — the whole pre-filter of a
    /// candidate pair reads two lines and rejects before touching the original arrays.
    boxes: Vec<[f64; 8]>,
    intent: Vec<u32>,
}

impl<'a> SpaceTimeIndex<'a> {
    /// Builds the index for conflicts and near misses within `search`'s buffers (this thread).
    pub fn new(volumes: &'a Volumes<'a>, search: Search) -> Result<Self, IndexError> {
        Self::with_threads(volumes, search, 1)
    }

    /// Builds the index with up to `threads` threads: the cell entries are split by grid
    /// column (the most significant part of the key), generated and sorted per column
    /// range in parallel, then concatenated — the same sorted entries as one thread.
    pub fn with_threads(
        volumes: &'a Volumes<'a>,
        search: Search,
        threads: usize,
    ) -> Result<Self, IndexError> {
        search.check()?;
        let threads = threads.clamp(1, 64);
        if volumes.len() >= u32::MAX as usize {
            return Err(IndexError::Parameter("too many volumes (at most 2³² − 1)"));
        }
        let half = search.horizontal_m / 2.0;
        let grown: Vec<[f64; 4]> = volumes
            .bbox
            .iter()
            .map(|b| [b[0] - half, b[1] - half, b[2] + half, b[3] + half])
            .collect();
        // cells about twice the median volume: a volume touches ~1.5 cells per axis
        let ext = median(
            grown
                .iter()
                .map(|b| (b[2] - b[0]).max(b[3] - b[1]))
                .collect(),
        );
        let dur = median(volumes.time.iter().map(|t| t[1] - t[0]).collect());
        let mut size = [2.0 * ext.max(1.0), 2.0 * ext.max(1.0), 2.0 * dur.max(1.0)];
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (b, t) in grown.iter().zip(volumes.time.iter()) {
            for (k, (l, h)) in [(b[0], b[2]), (b[1], b[3]), (t[0], t[1])]
                .into_iter()
                .enumerate()
            {
                lo[k] = lo[k].min(l);
                hi[k] = hi[k].max(h);
            }
        }
        if volumes.is_empty() {
            lo = [0.0; 3];
            hi = [1.0; 3];
        }
        // coarsen until the cell keys fit in 32 bits
        let dims = loop {
            let d: Vec<u64> = (0..3)
                .map(|k| (((hi[k] - lo[k]) / size[k]).floor() as u64).saturating_add(1))
                .collect();
            let total = d[0].saturating_mul(d[1]).saturating_mul(d[2]);
            if total < (1 << 32) {
                break [d[0], d[1], d[2]];
            }
            let k = (0..3).max_by_key(|&k| d[k]).unwrap_or(0);
            size[k] *= 2.0;
        };
        let grid = Grid {
            origin: lo,
            inv: size.map(|s| 1.0 / s),
            dims,
        };
        let key_bits = 64 - (dims[0] * dims[1] * dims[2]).leading_zeros();
        // renumber the volumes by their lowest cell (locality of the scans below)
        let first_cell = |b: &[f64; 4], t: &[f64; 2]| {
            (
                grid.range(b[0], b[0], 0).0,
                grid.range(b[1], b[1], 1).0,
                grid.range(t[0], t[0], 2).0,
            )
        };
        let mut first: Vec<u64> = grown
            .iter()
            .zip(volumes.time.iter())
            .enumerate()
            .map(|(i, (b, t))| {
                let (cx, cy, ct) = first_cell(b, t);
                grid.key(cx, cy, ct) << 32 | i as u64
            })
            .collect();
        radix_sort(&mut first, key_bits.max(1));
        let order: Vec<u32> = first.iter().map(|e| (e & 0xffff_ffff) as u32).collect();
        drop(first);
        let mut rank = vec![0u32; order.len()];
        for (new, &orig) in order.iter().enumerate() {
            rank[orig as usize] = new as u32;
        }
        let boxes: Vec<[f64; 8]> = order
            .iter()
            .map(|&o| {
                let (b, t, z) = (
                    grown[o as usize],
                    volumes.time[o as usize],
                    volumes.alt[o as usize],
                );
                [b[0], b[1], b[2], b[3], t[0], t[1], z[0], z[1]]
            })
            .collect();
        drop(grown);
        let intent: Vec<u32> = order.iter().map(|&o| volumes.intent[o as usize]).collect();
        // cell ranges of a volume, and whether it is large (kept aside); recomputed where
        // needed rather than stored: a table of them would be ≈ 100 MB of fresh memory
        let span = |b: &[f64; 8]| {
            let (x0, x1) = grid.range(b[0], b[2], 0);
            let (y0, y1) = grid.range(b[1], b[3], 1);
            let (t0, t1) = grid.range(b[4], b[5], 2);
            let n = ((x1 - x0 + 1) * (y1 - y0 + 1) * (t1 - t0 + 1)) as u64;
            ([x0, x1, y0, y1, t0, t1], n > MAX_CELLS_PER_VOLUME)
        };
        let mut big = Vec::new();
        // column ranges [cuts[k], cuts[k+1]) of about equal volume counts, one per thread
        let dx = dims[0] as i64;
        let mut per_col = vec![0usize; if threads > 1 { dims[0] as usize } else { 0 }];
        for (i, b) in boxes.iter().enumerate() {
            let (s, is_big) = span(b);
            if is_big {
                big.push(i as u32);
            } else if threads > 1 {
                per_col[s[0] as usize] += 1;
            }
        }
        let n_small = boxes.len() - big.len();
        let cuts: Vec<i64> = if threads == 1 || n_small < 65_536 {
            vec![0, dx]
        } else {
            let mut cuts = vec![0];
            let mut acc = 0;
            for (c, n) in per_col.iter().enumerate() {
                acc += n;
                if acc * threads >= n_small * cuts.len() && cuts.len() < threads {
                    cuts.push(c as i64 + 1);
                }
            }
            cuts.push(dx);
            cuts.dedup();
            cuts
        };
        drop(per_col);
        let entries_of = |lo: i64, hi: i64| {
            let mut entries = Vec::with_capacity(n_small * 3 / (cuts.len() - 1).max(1) + 16);
            for (i, b) in boxes.iter().enumerate() {
                let (s, is_big) = span(b);
                if is_big || s[1] < lo || s[0] >= hi {
                    continue;
                }
                for cx in s[0].max(lo)..=s[1].min(hi - 1) {
                    for cy in s[2]..=s[3] {
                        for ct in s[4]..=s[5] {
                            entries.push(grid.key(cx, cy, ct) << 32 | i as u64);
                        }
                    }
                }
            }
            radix_sort(&mut entries, key_bits.max(1));
            entries
        };
        let entries = if cuts.len() <= 2 {
            entries_of(0, dx)
        } else {
            let parts: Vec<Vec<u64>> = std::thread::scope(|sc| {
                let hs: Vec<_> = cuts
                    .windows(2)
                    .map(|w| {
                        let (lo, hi) = (w[0], w[1]);
                        let f = &entries_of;
                        sc.spawn(move || f(lo, hi))
                    })
                    .collect();
                hs.into_iter()
                    .map(|h| h.join().unwrap_or_default())
                    .collect()
            });
            parts.concat()
        };
        Ok(SpaceTimeIndex {
            volumes,
            search,
            grid,
            entries,
            big,
            order,
            rank,
            boxes,
            intent,
        })
    }

    /// Number of (cell, volume) entries and of volumes kept aside as too large.
    pub fn stats(&self) -> (usize, usize) {
        (self.entries.len(), self.big.len())
    }

    /// The cell key of the lower corner of the intersection of the boxes of `a` and `b`.
    fn owner(&self, a: usize, b: usize) -> u64 {
        let (ba, bb) = (&self.boxes[a], &self.boxes[b]);
        let g = &self.grid;
        let cx = g.range(ba[0].max(bb[0]), 0.0, 0).0;
        let cy = g.range(ba[1].max(bb[1]), 0.0, 1).0;
        let ct = g.range(ba[4].max(bb[4]), 0.0, 2).0;
        g.key(cx, cy, ct)
    }

    /// Whether the grown boxes of `a` and `b` meet and their times overlap.
    fn boxes_meet(&self, a: usize, b: usize) -> bool {
        let (ba, bb) = (&self.boxes[a], &self.boxes[b]);
        ba[0] <= bb[2]
            && bb[0] <= ba[2]
            && ba[1] <= bb[3]
            && bb[1] <= ba[3]
            && ba[4] < bb[5]
            && bb[4] < ba[5]
    }

    /// [`Self::boxes_meet`] and the altitude gap within the vertical buffer, computed as in
    /// [`exact`] (same floating-point expression, so never stricter than it).
    fn may_meet(&self, a: usize, b: usize) -> bool {
        let (ba, bb) = (&self.boxes[a], &self.boxes[b]);
        self.boxes_meet(a, b)
            && (ba[6].max(bb[6]) - ba[7].min(bb[7])).max(0.0) <= self.search.vertical_m
    }

    fn groups(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let mut start = 0;
        let e = &self.entries;
        for i in 1..=e.len() {
            if i == e.len() || e[i] >> 32 != e[start] >> 32 {
                if i - start > 1 {
                    out.push((start, i));
                }
                start = i;
            }
        }
        out
    }

    fn scan(&self, groups: &[(usize, usize)]) -> Vec<Encounter> {
        let mut out = Vec::new();
        let v = self.volumes;
        for &(s, e) in groups {
            let key = self.entries[s] >> 32;
            let members = &self.entries[s..e];
            for (k, &ea) in members.iter().enumerate() {
                let a = (ea & 0xffff_ffff) as usize;
                for &eb in &members[k + 1..] {
                    let b = (eb & 0xffff_ffff) as usize;
                    if self.intent[a] == self.intent[b]
                        || !self.may_meet(a, b)
                        || self.owner(a, b) != key
                    {
                        continue;
                    }
                    let (oa, ob) = (self.order[a] as usize, self.order[b] as usize);
                    if let Some(enc) = exact(v, oa, ob, &self.search) {
                        out.push(enc);
                    }
                }
            }
        }
        out
    }

    /// Every encounter (conflicts and, with buffers, near misses), each volume pair once,
    /// sorted by (a, b). Uses up to `threads` threads (1 = this thread only).
    pub fn encounters(&self, threads: usize) -> Vec<Encounter> {
        let groups = self.groups();
        let threads = threads.clamp(1, 64);
        let mut out: Vec<Encounter> = if threads == 1 || groups.len() < 1024 {
            self.scan(&groups)
        } else {
            // split by entry count, not group count: the work is in the big groups
            let total: usize = groups.iter().map(|g| (g.1 - g.0) * (g.1 - g.0)).sum();
            let mut chunks = Vec::new();
            let (mut acc, mut start) = (0usize, 0usize);
            for (i, g) in groups.iter().enumerate() {
                acc += (g.1 - g.0) * (g.1 - g.0);
                if acc * threads >= total * (chunks.len() + 1) {
                    chunks.push(&groups[start..=i]);
                    start = i + 1;
                }
            }
            if start < groups.len() {
                chunks.push(&groups[start..]);
            }
            std::thread::scope(|sc| {
                let hs: Vec<_> = chunks
                    .iter()
                    .map(|c| sc.spawn(move || self.scan(c)))
                    .collect();
                hs.into_iter()
                    .flat_map(|h| h.join().unwrap_or_default())
                    .collect()
            })
        };
        // large volumes: against every other volume (each pair once)
        let v = self.volumes;
        let is_big = {
            let mut m = vec![false; v.len()];
            for &b in &self.big {
                m[b as usize] = true;
            }
            m
        };
        for &bi in &self.big {
            let a = bi as usize;
            for (b, &b_big) in is_big.iter().enumerate() {
                if b == a || (b_big && b < a) {
                    continue;
                }
                if self.may_meet(a, b) {
                    let (oa, ob) = (self.order[a] as usize, self.order[b] as usize);
                    if let Some(enc) = exact(v, oa, ob, &self.search) {
                        out.push(enc);
                    }
                }
            }
        }
        out.sort_unstable_by_key(|e| (e.a, e.b));
        out
    }

    /// Volumes whose cells overlap the box (x0, y0, x1, y1) × [t0, t1], plus the large ones
    /// (a superset of the volumes whose grown boxes meet it), without duplicates.
    fn candidates(&self, b: [f64; 4], t0: f64, t1: f64) -> Vec<u32> {
        let g = &self.grid;
        let (x0, x1) = g.range(b[0], b[2], 0);
        let (y0, y1) = g.range(b[1], b[3], 1);
        let (c0, c1) = g.range(t0, t1, 2);
        let mut out = self.big.clone();
        for cx in x0..=x1 {
            for cy in y0..=y1 {
                let k0 = g.key(cx, cy, c0);
                let k1 = g.key(cx, cy, c1);
                let s = self.entries.partition_point(|e| e >> 32 < k0);
                for e in &self.entries[s..] {
                    if e >> 32 > k1 {
                        break;
                    }
                    out.push((e & 0xffff_ffff) as u32);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The smallest delay d in [0, `max_delay_s`] such that no volume of `intent`, shifted
    /// by d, conflicts with a volume of another intent (buffers ignored: conflicts only);
    /// None if every delay up to `max_delay_s` leaves a conflict.
    pub fn earliest_delay(&self, intent: u32, max_delay_s: f64) -> Result<Option<f64>, IndexError> {
        if !(max_delay_s.is_finite() && max_delay_s >= 0.0) {
            return Err(IndexError::Parameter("max_delay_s must be finite and ≥ 0"));
        }
        let v = self.volumes;
        let mut forbidden: Vec<(f64, f64)> = Vec::new();
        let none = Search::default();
        for b in (0..v.len()).filter(|&i| v.intent[i] == intent) {
            let tb = v.time[b];
            let r = &self.boxes[self.rank[b] as usize];
            let gb = [r[0], r[1], r[2], r[3]];
            for c in self.candidates(gb, tb[0], tb[1] + max_delay_s) {
                let c = self.order[c as usize] as usize;
                if v.intent[c] == intent {
                    continue;
                }
                let tc = v.time[c];
                let (lo, hi) = (tc[0] - tb[1], tc[1] - tb[0]);
                if hi <= 0.0 || lo >= max_delay_s {
                    continue;
                }
                // space only: test with b's time moved onto c's
                let (za, zc) = (v.alt[b], v.alt[c]);
                if za[0].max(zc[0]) > za[1].min(zc[1]) {
                    continue;
                }
                let (ba, bc) = (v.bbox[b], v.bbox[c]);
                if ba[0] > bc[2] || bc[0] > ba[2] || ba[1] > bc[3] || bc[1] > ba[3] {
                    continue;
                }
                if outline_dist(v.outline(b), v.outline(c)) <= none.horizontal_m {
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
            if hi > d {
                d = hi;
            }
        }
        Ok(if d <= max_delay_s { Some(d) } else { None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x: f64, y: f64, s: f64) -> Vec<Pt> {
        vec![[x, y], [x + s, y], [x + s, y + s], [x, y + s]]
    }

    type Spec = (u32, Vec<Pt>, [f64; 2], [f64; 2]);

    fn set(vols: &[Spec]) -> Volumes<'static> {
        let mut offsets = vec![0];
        let mut verts = Vec::new();
        for v in vols {
            verts.extend_from_slice(&v.1);
            offsets.push(verts.len());
        }
        Volumes::new(
            vols.iter().map(|v| v.0).collect::<Vec<_>>(),
            vols.iter().map(|v| v.2).collect::<Vec<_>>(),
            vols.iter().map(|v| v.3).collect::<Vec<_>>(),
            offsets,
            verts,
            vec![[0.0; 3]; vols.len()],
        )
        .unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn conflict_near_miss_and_delay() {
        let v = set(&[
            (0, square(0.0, 0.0, 10.0), [0.0, 50.0], [0.0, 100.0]),
            (1, square(5.0, 5.0, 10.0), [40.0, 60.0], [50.0, 150.0]), // conflicts with 0 over [50, 100)
            (2, square(13.0, 0.0, 5.0), [0.0, 30.0], [0.0, 100.0]),   // 3 m from 0, below 1
            (3, square(0.0, 0.0, 10.0), [0.0, 50.0], [100.0, 200.0]), // starts when 0 ends: no overlap
        ]);
        let idx = SpaceTimeIndex::new(&v, Search::default()).unwrap_or_else(|e| panic!("{e}"));
        let enc = idx.encounters(1);
        assert_eq!(enc.len(), 2, "{enc:?}"); // 0–1 and 1–3 (over [100, 150))
        assert!(enc[0].is_conflict() && (enc[0].t_start, enc[0].t_end) == (50.0, 100.0));
        let near = SpaceTimeIndex::new(
            &v,
            Search {
                horizontal_m: 3.5,
                vertical_m: 0.0,
            },
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let e = near.encounters(2);
        let e02 = e
            .iter()
            .find(|e| (e.a, e.b) == (0, 2))
            .unwrap_or_else(|| panic!("no 0–2"));
        assert!((e02.horizontal_m - 3.0).abs() < 1e-12 && !e02.is_conflict());
        // intent 1 must wait until intent 3 ends at 200: its volume starts at 50, so d = 150
        assert_eq!(idx.earliest_delay(1, 1000.0), Ok(Some(150.0)));
        assert_eq!(idx.earliest_delay(1, 100.0), Ok(None));
        assert_eq!(idx.earliest_delay(2, 10.0), Ok(Some(0.0)));
    }

    #[test]
    fn bad_input_is_an_error() {
        let e = Volumes::new(
            vec![0],
            vec![[10.0, 0.0]],
            vec![[0.0, 1.0]],
            vec![0, 3],
            square(0.0, 0.0, 1.0)[..3].to_vec(),
            vec![[0.0; 3]],
        );
        assert!(matches!(e, Err(IndexError::Volume { index: 0, .. })));
        let e = Volumes::new(
            vec![0],
            vec![[0.0, 1.0]],
            vec![[0.0, 1.0]],
            vec![0, 0],
            vec![],
            vec![[0.0, 0.0, -1.0]],
        );
        assert!(matches!(e, Err(IndexError::Volume { index: 0, .. })));
        let e = Volumes::new(
            vec![0, 1],
            vec![[0.0, 1.0]],
            vec![[0.0, 1.0]],
            vec![0, 0],
            vec![],
            vec![[0.0, 0.0, 1.0]],
        );
        assert!(matches!(e, Err(IndexError::Length { what: "alt", .. })));
    }
}
