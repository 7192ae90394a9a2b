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
//! The index ([`SpaceTimeIndex`]) buckets the volumes by start time (a counting sort into
//! compact 40-byte records rounded outward to f32) and sweeps them in that order over a
//! uniform grid of horizontal cells sized from the median volume box (grown by h): each cell
//! keeps the volumes still alive in it, so a new volume is tested only against volumes that
//! share a cell with it and overlap it in time, and each pair once, in the cell that holds
//! the lower corner of the two boxes' intersection. Volumes spanning more than
//! [`MAX_CELLS_PER_VOLUME`] cells are kept aside and tested against every volume. Exact tests
//! follow ([`geometry`]). Expected cost O(n + k) for n volumes and k candidate pairs;
//! [`brute_force`] is the O(n²) reference the tests compare with.
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

/// Grid cell of a coordinate (`inv` = 1 / cell size), clamped to `0..dim`. Monotone in x,
/// which is all the owner rule needs.
fn cell(x: f64, origin: f64, inv: f64, dim: usize) -> usize {
    let c = (x - origin) * inv;
    if c >= 0.0 {
        // truncation is the floor here (c ≥ 0), and saturates on huge values
        (c as usize).min(dim - 1)
    } else {
        0
    }
}

/// A uniform grid of horizontal (x, y) cells; time is not a grid axis but the sweep order.
#[derive(Clone, Copy, Debug)]
struct Grid {
    origin: [f64; 2],
    /// 1 / cell size per axis, 1/m.
    inv: [f64; 2],
    dims: [usize; 2],
}

/// Most cells of the grid (so that the per-cell lists stay a few MB).
const MAX_GRID_CELLS: usize = 1 << 20;

impl Grid {
    /// Cells covering [x0, x1 + h] × [y0, y1 + h] of a record's box: (x0, x1, y0, y1), inclusive.
    /// The upper edge is grown by `h` with the same expression as [`may_meet`] uses, so that
    /// two records the filter passes share the cell of their intersection's lower corner.
    fn span(&self, r: &Rec, h: f64) -> [usize; 4] {
        let c = |x: f64, k: usize| cell(x, self.origin[k], self.inv[k], self.dims[k]);
        [
            c(r.b[0] as f64, 0),
            c(r.b[2] as f64 + h, 0),
            c(r.b[1] as f64, 1),
            c(r.b[3] as f64 + h, 1),
        ]
    }

    /// The cell holding the lower corner of the intersection of two records' boxes.
    fn owner(&self, a: &Rec, b: &Rec) -> (usize, usize) {
        (
            cell(
                a.b[0].max(b.b[0]) as f64,
                self.origin[0],
                self.inv[0],
                self.dims[0],
            ),
            cell(
                a.b[1].max(b.b[1]) as f64,
                self.origin[1],
                self.inv[1],
                self.dims[1],
            ),
        )
    }
}

fn cells_of(s: &[usize; 4]) -> usize {
    (s[1] - s[0] + 1) * (s[3] - s[2] + 1)
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

/// f32 at or below x (rounded toward −∞).
fn down(x: f64) -> f32 {
    let y = x as f32;
    if y as f64 > x {
        y.next_down()
    } else {
        y
    }
}

/// f32 at or above x (rounded toward +∞).
fn up(x: f64) -> f32 {
    let y = x as f32;
    if (y as f64) < x {
        y.next_up()
    } else {
        y
    }
}

/// What the pre-filter of a candidate pair reads, one 40-byte record per volume: the
/// outline's box (x0, y0, x1, y1, m), the time interval relative to the index's time origin
/// (s) and the altitude range (lower, upper, m), all in f32 rounded outward; the intent and
/// the volume's original index. The filter compares outward-rounded values with correctly
/// rounded operations, which are monotone, so it never rejects a pair that [`exact`] accepts.
#[derive(Clone, Copy, Debug, Default)]
struct Rec {
    b: [f32; 4],
    t: [f32; 2],
    z: [f32; 2],
    intent: u32,
    id: u32,
}

/// Whether two records may be within the buffers `h`, `v` while their times overlap
/// (never false when [`exact`] finds them; see [`Rec`]).
#[inline]
fn may_meet(a: &Rec, b: &Rec, h: f64, v: f64) -> bool {
    a.t[0] <= b.t[1] && b.t[0] <= a.t[1] && may_meet_in_space(a, b, h, v)
}

/// [`may_meet`] without the time test.
#[inline]
fn may_meet_in_space(a: &Rec, b: &Rec, h: f64, v: f64) -> bool {
    a.b[0] as f64 <= b.b[2] as f64 + h
        && b.b[0] as f64 <= a.b[2] as f64 + h
        && a.b[1] as f64 <= b.b[3] as f64 + h
        && b.b[1] as f64 <= a.b[3] as f64 + h
        && a.z[0] as f64 - b.z[1] as f64 <= v
        && b.z[0] as f64 - a.z[1] as f64 <= v
}

/// Entries a cell's list keeps in its own cache line before spilling to a vector.
const SLOT: usize = 7;

/// A cell's list of volumes still alive in it: record position and end time (relative,
/// f32 rounded up); the first [`SLOT`] in one cache line, the rest in the cell's spill
/// vector (non-empty only when the slot is full).
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(64))]
struct Slot {
    len: u32,
    pos: [u32; SLOT],
    t1: [f32; SLOT],
}

impl Slot {
    fn push(&mut self, spill: &mut Vec<(u32, f32)>, pos: u32, t1: f32) {
        let n = self.len as usize;
        if n < SLOT {
            self.pos[n] = pos;
            self.t1[n] = t1;
            self.len += 1;
        } else {
            spill.push((pos, t1));
        }
    }

    /// Drops the entries that end at or before `alive_after` and calls `f` on the others.
    fn visit(&mut self, spill: &mut Vec<(u32, f32)>, alive_after: f64, mut f: impl FnMut(u32)) {
        let n_slot = self.len as usize;
        // the spill vector is read only when the slot is full (its header is another line)
        let n_spill = if n_slot == SLOT { spill.len() } else { 0 };
        let mut w = 0;
        // compaction in place: slot entries are read before spill entries, and writes lag reads
        for k in 0..n_slot + n_spill {
            let (q, t1) = if k < n_slot {
                (self.pos[k], self.t1[k])
            } else {
                spill[k - n_slot]
            };
            if t1 as f64 <= alive_after {
                continue;
            }
            if w < SLOT {
                self.pos[w] = q;
                self.t1[w] = t1;
            } else {
                spill[w - SLOT] = (q, t1);
            }
            w += 1;
            f(q);
        }
        self.len = w.min(SLOT) as u32;
        if n_spill > 0 {
            spill.truncate(w.saturating_sub(SLOT));
        }
    }
}

/// Index of the volumes by intent and by (cell, start time), for the departure-delay search:
/// built on its first use.
#[derive(Debug)]
struct DelayIndex {
    /// (intent << 32 | record position), sorted.
    by_intent: Vec<u64>,
    /// Cell c's records are `cell_recs[cell_start[c]..cell_start[c + 1]]`, in increasing
    /// positions (so in start-time bucket order); large volumes are not in cells.
    cell_start: Vec<u32>,
    cell_recs: Vec<u32>,
    /// Longest duration of a record in each cell, s.
    cell_maxdur: Vec<f64>,
}

/// The space-time index of a volume set (borrowed), built once per search buffer.
///
/// The volumes are bucketed by start time (a counting sort into at most 2¹⁶ buckets) into
/// compact records. [`Self::encounters`] sweeps them in that order over a uniform grid of
/// horizontal cells, each holding the list of the volumes still alive in it: a new volume is
/// tested only against volumes that share one of its cells and have not ended before its
/// bucket starts, and lists are purged of ended volumes as they are read. A pair is tested
/// in one cell only, the one holding the lower corner of the intersection of the two boxes.
#[derive(Debug)]
pub struct SpaceTimeIndex<'a> {
    volumes: &'a Volumes<'a>,
    search: Search,
    grid: Grid,
    /// Records by start-time bucket: bucket k holds `recs[bucket_start[k]..bucket_start[k + 1]]`,
    /// the volumes with ⌊(t₀ − `t_origin`) · `t_scale`⌋ = k (the last bucket also those above).
    recs: Vec<Rec>,
    bucket_start: Vec<u32>,
    t_origin: f64,
    t_scale: f64,
    /// Longest volume duration, s.
    max_dur: f64,
    /// Positions of the volumes spanning more than [`MAX_CELLS_PER_VOLUME`] cells (sorted):
    /// tested against every volume instead.
    big: Vec<u32>,
    delays: std::sync::OnceLock<DelayIndex>,
}

/// First window of the departure-delay search, s (widened ×4 until it holds the answer).
const INITIAL_DELAY_WINDOW_S: f64 = 900.0;

/// Most start-time buckets.
const MAX_BUCKETS: usize = 1 << 16;

impl<'a> SpaceTimeIndex<'a> {
    /// Builds the index for conflicts and near misses within `search`'s buffers (this thread).
    pub fn new(volumes: &'a Volumes<'a>, search: Search) -> Result<Self, IndexError> {
        Self::with_threads(volumes, search, 1)
    }

    /// Builds the index with up to `threads` threads (each fills the records of one range of
    /// start-time buckets).
    pub fn with_threads(
        volumes: &'a Volumes<'a>,
        search: Search,
        threads: usize,
    ) -> Result<Self, IndexError> {
        search.check()?;
        let threads = threads.clamp(1, 64);
        let n = volumes.len();
        if n >= u32::MAX as usize {
            return Err(IndexError::Parameter("too many volumes (at most 2³² − 1)"));
        }
        let h = search.horizontal_m;
        // time range and the buckets
        let (mut t_lo, mut t_hi, mut max_dur) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
        for t in volumes.time.iter() {
            t_lo = t_lo.min(t[0]);
            t_hi = t_hi.max(t[0]);
            max_dur = max_dur.max(t[1] - t[0]);
        }
        let n_buckets = (n / 32).clamp(1, MAX_BUCKETS);
        let t_origin = if n > 0 { t_lo } else { 0.0 };
        let t_scale = if t_hi > t_lo {
            n_buckets as f64 / (t_hi - t_lo)
        } else {
            0.0
        };
        let bucket = |t0: f64| (((t0 - t_origin) * t_scale) as usize).min(n_buckets - 1);
        let mut bucket_start = vec![0u32; n_buckets + 1];
        for t in volumes.time.iter() {
            bucket_start[bucket(t[0]) + 1] += 1;
        }
        for k in 0..n_buckets {
            bucket_start[k + 1] += bucket_start[k];
        }
        // horizontal cells about the median box grown by the buffer (from a sample)
        let step = (n / 65_536).max(1);
        let ext = median(
            volumes
                .bbox
                .iter()
                .step_by(step)
                .map(|b| (b[2] - b[0]).max(b[3] - b[1]) + h)
                .collect(),
        );
        let mut size = [CELL_PER_MEDIAN_BOX * ext.max(1e-3); 2];
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for b in volumes.bbox.iter() {
            for k in 0..2 {
                lo[k] = lo[k].min(b[k]);
                hi[k] = hi[k].max(b[k + 2] + h);
            }
        }
        if n == 0 {
            (lo, hi) = ([0.0; 2], [1.0; 2]);
        }
        let dims = loop {
            let d = [0, 1].map(|k| {
                ((((hi[k] - lo[k]) / size[k]).floor()).min(1e9) as usize).saturating_add(1)
            });
            if d[0].saturating_mul(d[1]) <= MAX_GRID_CELLS {
                break d;
            }
            let k = if d[0] >= d[1] { 0 } else { 1 };
            size[k] *= 2.0;
        };
        let grid = Grid {
            origin: lo,
            inv: size.map(|s| 1.0 / s),
            dims,
        };
        // fill the records bucket by bucket: each thread owns a range of buckets (a slice of
        // the records) and reads every volume, keeping those of its range
        let mut recs = vec![Rec::default(); n];
        let fill = |out: &mut [Rec], k0: usize, k1: usize| -> Vec<u32> {
            let base = bucket_start[k0] as usize;
            let mut next: Vec<u32> = bucket_start[k0..k1]
                .iter()
                .map(|&s| s - base as u32)
                .collect();
            let mut big = Vec::new();
            for (i, t) in volumes.time.iter().enumerate() {
                let k = bucket(t[0]);
                if k < k0 || k >= k1 {
                    continue;
                }
                let (b, z) = (volumes.bbox[i], volumes.alt[i]);
                let p = &mut next[k - k0];
                let r = Rec {
                    b: [down(b[0]), down(b[1]), up(b[2]), up(b[3])],
                    t: [down(t[0] - t_origin), up(t[1] - t_origin)],
                    z: [down(z[0]), up(z[1])],
                    intent: volumes.intent[i],
                    id: i as u32,
                };
                if cells_of(&grid.span(&r, h)) > MAX_CELLS_PER_VOLUME as usize {
                    big.push(base as u32 + *p);
                }
                out[*p as usize] = r;
                *p += 1;
            }
            big
        };
        let mut big = if threads == 1 || n < 65_536 {
            fill(&mut recs, 0, n_buckets)
        } else {
            let per = n.div_ceil(threads) as u32;
            let mut cuts = vec![0usize];
            for t in 1..threads {
                cuts.push(
                    bucket_start
                        .partition_point(|&s| s < per * t as u32)
                        .min(n_buckets),
                );
            }
            cuts.push(n_buckets);
            cuts.dedup();
            let mut parts = Vec::new();
            let mut rest: &mut [Rec] = &mut recs;
            for w in cuts.windows(2) {
                let len = (bucket_start[w[1]] - bucket_start[w[0]]) as usize;
                let (part, tail) = rest.split_at_mut(len);
                parts.push((part, w[0], w[1]));
                rest = tail;
            }
            std::thread::scope(|sc| {
                let hs: Vec<_> = parts
                    .into_iter()
                    .map(|(part, k0, k1)| {
                        let f = &fill;
                        sc.spawn(move || f(part, k0, k1))
                    })
                    .collect();
                // a worker that panicked (a bug) re-panics here: never a silently short answer
                hs.into_iter()
                    .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                    .collect()
            })
        };
        big.sort_unstable();
        Ok(SpaceTimeIndex {
            volumes,
            search,
            grid,
            recs,
            bucket_start,
            t_origin,
            t_scale,
            max_dur,
            big,
            delays: std::sync::OnceLock::new(),
        })
    }

    /// Number of (cell, volume) memberships of the volumes in the grid, and of volumes kept
    /// aside as too large.
    pub fn stats(&self) -> (usize, usize) {
        let h = self.search.horizontal_m;
        let cells: usize = self
            .recs
            .iter()
            .map(|r| cells_of(&self.grid.span(r, h)))
            .filter(|&c| c <= MAX_CELLS_PER_VOLUME as usize)
            .sum();
        (cells, self.big.len())
    }

    fn n_buckets(&self) -> usize {
        self.bucket_start.len() - 1
    }

    /// A relative time at or before the start of every record of bucket `k` and after
    /// (one bucket earlier than its lower edge: a margin for the rounding).
    fn started_by(&self, k: usize) -> f64 {
        if self.t_scale > 0.0 {
            (k as f64 - 1.0) / self.t_scale
        } else {
            f64::NEG_INFINITY
        }
    }

    /// Start-time bucket of an absolute time, clamped (monotone in t).
    fn bucket_of(&self, t: f64) -> usize {
        let k = ((t - self.t_origin) * self.t_scale).max(0.0);
        (k as usize).min(self.n_buckets() - 1)
    }

    fn is_big(&self, p: usize) -> bool {
        self.big.binary_search(&(p as u32)).is_ok()
    }

    /// The sweep over the buckets `k0..k1`, after seeding the cell lists with the records of
    /// earlier buckets still alive when `k0` starts; appends the encounters found to `out`.
    fn sweep(&self, k0: usize, k1: usize, out: &mut Vec<Encounter>) {
        let (h, vb) = (self.search.horizontal_m, self.search.vertical_m);
        let g = &self.grid;
        let ny = g.dims[1];
        let mut slots = vec![Slot::default(); g.dims[0] * ny];
        let mut spill: Vec<Vec<(u32, f32)>> = vec![Vec::new(); g.dims[0] * ny];
        let small = |r: &Rec| {
            let s = g.span(r, h);
            (s, cells_of(&s) <= MAX_CELLS_PER_VOLUME as usize)
        };
        if k0 > 0 && k0 < k1 {
            // a record of a bucket more than the longest duration (and a margin) before k0
            // has ended before k0 starts
            let back = (self.max_dur * self.t_scale).ceil().min(1e9) as usize + 2;
            let from = self.bucket_start[k0.saturating_sub(back)] as usize;
            let alive_after = self.started_by(k0);
            for p in from..self.bucket_start[k0] as usize {
                let r = &self.recs[p];
                let (s, is_small) = small(r);
                if r.t[1] as f64 > alive_after && is_small {
                    for cx in s[0]..=s[1] {
                        for cy in s[2]..=s[3] {
                            let c = cx * ny + cy;
                            slots[c].push(&mut spill[c], p as u32, r.t[1]);
                        }
                    }
                }
            }
        }
        for k in k0..k1 {
            let alive_after = self.started_by(k);
            for p in self.bucket_start[k] as usize..self.bucket_start[k + 1] as usize {
                let r = &self.recs[p];
                let (s, is_small) = small(r);
                if !is_small {
                    continue;
                }
                for cx in s[0]..=s[1] {
                    for cy in s[2]..=s[3] {
                        let c = cx * ny + cy;
                        slots[c].visit(&mut spill[c], alive_after, |q| {
                            let o = &self.recs[q as usize];
                            if o.intent != r.intent
                                && may_meet(r, o, h, vb)
                                && g.owner(r, o) == (cx, cy)
                            {
                                if let Some(e) =
                                    exact(self.volumes, r.id as usize, o.id as usize, &self.search)
                                {
                                    out.push(e);
                                }
                            }
                        });
                        slots[c].push(&mut spill[c], p as u32, r.t[1]);
                    }
                }
            }
        }
    }

    /// Every encounter (conflicts and, with buffers, near misses), each volume pair once,
    /// sorted by (a, b). Uses up to `threads` threads (1 = this thread only).
    pub fn encounters(&self, threads: usize) -> Vec<Encounter> {
        let (n, nb) = (self.recs.len(), self.n_buckets());
        let threads = threads.clamp(1, 64);
        let mut out: Vec<Encounter> = if threads == 1 || n < 65_536 {
            let mut out = Vec::new();
            self.sweep(0, nb, &mut out);
            out
        } else {
            // split the time order into runs of about equal counts; each run seeds itself
            // with the volumes of the earlier runs still alive when it starts
            let per = n.div_ceil(threads) as u32;
            let mut cuts = vec![0usize];
            for t in 1..threads {
                cuts.push(
                    self.bucket_start
                        .partition_point(|&s| s < per * t as u32)
                        .min(nb),
                );
            }
            cuts.push(nb);
            cuts.dedup();
            std::thread::scope(|sc| {
                let hs: Vec<_> = cuts
                    .windows(2)
                    .map(|w| {
                        let (k0, k1) = (w[0], w[1]);
                        sc.spawn(move || {
                            let mut out = Vec::new();
                            self.sweep(k0, k1, &mut out);
                            out
                        })
                    })
                    .collect();
                // a worker that panicked (a bug) re-panics here: never a silently short answer
                hs.into_iter()
                    .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                    .collect()
            })
        };
        // large volumes: against every other volume (each pair once)
        let (h, vb) = (self.search.horizontal_m, self.search.vertical_m);
        for &pa in &self.big {
            let a = &self.recs[pa as usize];
            for (q, b) in self.recs.iter().enumerate() {
                if q == pa as usize || a.intent == b.intent || !may_meet(a, b, h, vb) {
                    continue;
                }
                if q < pa as usize && self.is_big(q) {
                    continue; // tested when q was the large one
                }
                if let Some(e) = exact(self.volumes, a.id as usize, b.id as usize, &self.search) {
                    out.push(e);
                }
            }
        }
        out.sort_unstable_by_key(|e| (e.a, e.b));
        out
    }

    fn delay_index(&self) -> &DelayIndex {
        self.delays.get_or_init(|| {
            let mut by_intent: Vec<u64> = self
                .recs
                .iter()
                .enumerate()
                .map(|(p, r)| (r.intent as u64) << 32 | p as u64)
                .collect();
            radix_sort(&mut by_intent, 32);
            // counting sort of the small records by cell, stable: positions increase per cell
            let g = &self.grid;
            let ny = g.dims[1];
            let n_cells = g.dims[0] * ny;
            let mut count = vec![0u32; n_cells + 1];
            let mut cell_maxdur = vec![0.0f64; n_cells];
            let small = |r: &Rec| {
                let s = g.span(r, 0.0);
                (s, cells_of(&s) <= MAX_CELLS_PER_VOLUME as usize)
            };
            for r in &self.recs {
                let (s, is_small) = small(r);
                if !is_small {
                    continue;
                }
                let d = r.t[1] as f64 - r.t[0] as f64;
                for cx in s[0]..=s[1] {
                    for cy in s[2]..=s[3] {
                        count[cx * ny + cy + 1] += 1;
                        let m = &mut cell_maxdur[cx * ny + cy];
                        *m = m.max(d);
                    }
                }
            }
            for c in 0..n_cells {
                count[c + 1] += count[c];
            }
            let cell_start = count.clone();
            let mut cell_recs = vec![0u32; count[n_cells] as usize];
            for (p, r) in self.recs.iter().enumerate() {
                let (s, is_small) = small(r);
                if !is_small {
                    continue;
                }
                for cx in s[0]..=s[1] {
                    for cy in s[2]..=s[3] {
                        let c = &mut count[cx * ny + cy];
                        cell_recs[*c as usize] = p as u32;
                        *c += 1;
                    }
                }
            }
            DelayIndex {
                by_intent,
                cell_start,
                cell_recs,
                cell_maxdur,
            }
        })
    }

    /// The smallest delay d in [0, `max_delay_s`] such that no volume of `intent`, shifted
    /// by d, conflicts with a volume of another intent (buffers ignored: conflicts only);
    /// None if every delay up to `max_delay_s` leaves a conflict.
    ///
    /// Each volume of the intent reads only the volumes of its cells that start within the
    /// window [its start − the cell's longest duration, its end + `max_delay_s`] (and the
    /// large volumes), first over a 900 s window of delays, widened ×4 only while the answer
    /// may lie beyond it: the cost follows the traffic near the intent and the delay needed,
    /// not the data set or `max_delay_s`. The first call builds the delay index (by intent,
    /// and by cell in start-time order).
    pub fn earliest_delay(&self, intent: u32, max_delay_s: f64) -> Result<Option<f64>, IndexError> {
        if !(max_delay_s.is_finite() && max_delay_s >= 0.0) {
            return Err(IndexError::Parameter("max_delay_s must be finite and ≥ 0"));
        }
        // search a short window first and widen it only if the answer may lie beyond: the
        // delay found within a window W is the answer whenever it is < W (an interval that
        // starts at or after W cannot cover it), so the cost follows the delay needed
        let mut window = max_delay_s.min(INITIAL_DELAY_WINDOW_S);
        loop {
            let d = self.delay_within(intent, window);
            if d < window || window >= max_delay_s {
                return Ok(if d <= max_delay_s { Some(d) } else { None });
            }
            window = (window * 4.0).min(max_delay_s);
        }
    }

    /// The smallest delay d ≥ 0 outside the union of the forbidden delay intervals that start
    /// before `window` (the conflicts of the intent's volumes shifted by up to `window`).
    fn delay_within(&self, intent: u32, window: f64) -> f64 {
        let max_delay_s = window;
        let di = self.delay_index();
        let v = self.volumes;
        let g = &self.grid;
        let ny = g.dims[1];
        let lo_e = di
            .by_intent
            .partition_point(|&e| ((e >> 32) as u32) < intent);
        let hi_e = di
            .by_intent
            .partition_point(|&e| ((e >> 32) as u32) <= intent);
        let mut forbidden: Vec<(f64, f64)> = Vec::new();
        let mut test = |rb: &Rec, c: usize| {
            let rc = &self.recs[c];
            // space first, with the outward-rounded records (never stricter), then exactly
            if rc.intent == intent || !may_meet_in_space(rb, rc, 0.0, 0.0) {
                return;
            }
            let (b, c) = (rb.id as usize, rc.id as usize);
            let (tb, tc) = (v.time[b], v.time[c]);
            let (lo, hi) = (tc[0] - tb[1], tc[1] - tb[0]);
            if hi <= 0.0 || lo >= max_delay_s {
                return;
            }
            let (za, zc) = (v.alt[b], v.alt[c]);
            if za[0].max(zc[0]) > za[1].min(zc[1]) {
                return;
            }
            let (ba, bc) = (v.bbox[b], v.bbox[c]);
            if ba[0] > bc[2] || bc[0] > ba[2] || ba[1] > bc[3] || bc[1] > ba[3] {
                return;
            }
            if outline_dist(v.outline(b), v.outline(c)) <= 0.0 {
                forbidden.push((lo, hi));
            }
        };
        for &e in &di.by_intent[lo_e..hi_e] {
            let rb = self.recs[(e & 0xffff_ffff) as usize];
            let tb = v.time[rb.id as usize];
            let s = g.span(&rb, 0.0);
            for cx in s[0]..=s[1] {
                for cy in s[2]..=s[3] {
                    let c = cx * ny + cy;
                    let cell =
                        &di.cell_recs[di.cell_start[c] as usize..di.cell_start[c + 1] as usize];
                    // candidates start in [t0 − the cell's longest duration, t1 + max delay]:
                    // their buckets, one more each side for the rounding
                    let k0 = self.bucket_of(tb[0] - di.cell_maxdur[c]).saturating_sub(1);
                    let k1 = (self.bucket_of(tb[1] + max_delay_s) + 2).min(self.n_buckets());
                    let (p0, p1) = (self.bucket_start[k0], self.bucket_start[k1]);
                    let i0 = cell.partition_point(|&p| p < p0);
                    for &pc in &cell[i0..] {
                        if pc >= p1 {
                            break;
                        }
                        test(&rb, pc as usize);
                    }
                }
            }
            for &pc in &self.big {
                test(&rb, pc as usize);
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
        d
    }
}

/// Horizontal grid cell size in units of the median volume box: measured on the 10⁵-intent
/// benchmark (cells of about one box keep the per-cell lists short without visiting many
/// cells per volume).
const CELL_PER_MEDIAN_BOX: f64 = 2.0;

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
