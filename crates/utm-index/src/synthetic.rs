//! A seeded generator of many intents over a city and a day, for benchmarks and tests: the
//! same model as `uasnav.utm.synthetic` (random-walk flights of 10–50 legs of 150–400 m,
//! turns up to ±60°, in a 30 km square, departing over a day at 8–15 m/s, one rectangle
//! volume per leg grown by 15 m, alive ±10 s around its predicted passage), with its own
//! small PRNG (SplitMix64) so that it needs no dependency.

use crate::{IndexError, Volumes};

/// SplitMix64 (Steele, Lea & Flood 2014): a fast, well-mixed 64-bit generator.
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// `n_intents` synthetic intents (see module).
pub fn synthetic(n_intents: usize, seed: u64) -> Result<Volumes<'static>, IndexError> {
    let mut rng = SplitMix64::new(seed);
    let (city, day, buf) = (30_000.0, 86_400.0, 15.0);
    let mut intent = Vec::new();
    let mut alt = Vec::new();
    let mut time = Vec::new();
    let mut offsets = vec![0usize];
    let mut verts = Vec::new();
    for i in 0..n_intents {
        let k = 10 + (rng.next_u64() % 41) as usize;
        let (mut x, mut y) = (rng.uniform(0.0, city), rng.uniform(0.0, city));
        let mut h = rng.uniform(0.0, std::f64::consts::TAU);
        let speed = rng.uniform(8.0, 15.0);
        let mut t = rng.uniform(0.0, day);
        let z = rng.uniform(30.0, 120.0);
        for j in 0..k {
            if j > 0 {
                h += rng.uniform(-60.0, 60.0).to_radians();
            }
            let len = rng.uniform(150.0, 400.0);
            let (ux, uy) = (h.cos(), h.sin());
            let (vx, vy) = (-uy, ux);
            let (ax, ay) = (x - buf * ux, y - buf * uy);
            let (bx, by) = (x + (len + buf) * ux, y + (len + buf) * uy);
            verts.extend_from_slice(&[
                [ax - buf * vx, ay - buf * vy],
                [bx - buf * vx, by - buf * vy],
                [bx + buf * vx, by + buf * vy],
                [ax + buf * vx, ay + buf * vy],
            ]);
            offsets.push(verts.len());
            let dt = len / speed;
            intent.push(i as u32);
            alt.push([z - 10.0, z + 10.0]);
            time.push([t - 10.0, t + dt + 10.0]);
            x += len * ux;
            y += len * uy;
            t += dt;
        }
    }
    let n = intent.len();
    Volumes::new(intent, alt, time, offsets, verts, vec![[0.0; 3]; n])
}
