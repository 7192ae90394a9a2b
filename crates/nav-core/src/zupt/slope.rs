//! Time derivative of a sampled signal (the die temperature, for TCZUPT's dT/dt) as the
//! least-squares slope over a sliding window, updated in O(1) per sample.
//!
//! For equally spaced samples `y_0 … y_{n−1}` at local abscissae `i = 0 … n−1` the
//! least-squares slope is `(n·Σiy − Σi·Σy)/(n·Σi² − (Σi)²)` per sample step. `Σy` and `Σiy`
//! are updated when the window slides (dropping `y_0` shifts every index down by one:
//! `Σiy ← Σiy − (Σy − y_0)`), and `Σi`, `Σi²` are closed forms of `n`. To stop rounding error
//! from accumulating, the sums are recomputed from the buffer once per `capacity` pushes
//! (O(1) amortised) and the values are stored relative to the first sample.
// No unchecked indexing in library code; a proven index carries an `allow`.
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]
use crate::scalar::{from_usize, lit};
use crate::Real;

/// Capacity (samples) of the sliding window buffer; longer windows are decimated.
pub const SLOPE_CAPACITY: usize = 512;

/// Sliding-window least-squares slope estimator (units of the signal per second).
#[derive(Debug, Clone, Copy)]
pub struct SlopeEstimator<T: Real> {
    buf: [T; SLOPE_CAPACITY],
    /// Window length in stored samples (≤ capacity).
    window: usize,
    /// Store one sample out of `stride`.
    stride: usize,
    head: usize,
    n: usize,
    phase: usize,
    pushes: usize,
    reference: Option<T>,
    sum_y: T,
    sum_iy: T,
    /// Time between stored samples (s).
    step_s: T,
    slope: T,
}

impl<T: Real> SlopeEstimator<T> {
    /// An estimator of the slope over the last `window_s` seconds of a signal sampled every
    /// `dt_s` seconds. Windows longer than [`SLOPE_CAPACITY`] samples keep one sample in
    /// `stride`; the window holds at least 2 stored samples.
    pub fn new(window_s: T, dt_s: T) -> Self {
        let ratio = num_traits::Float::max(window_s / dt_s, lit::<T>(2.0));
        let samples = num_traits::ToPrimitive::to_usize(&num_traits::Float::round(ratio))
            .unwrap_or(SLOPE_CAPACITY)
            .max(2);
        let stride = samples.div_ceil(SLOPE_CAPACITY).max(1);
        let window = (samples / stride).clamp(2, SLOPE_CAPACITY);
        Self {
            buf: [T::zero(); SLOPE_CAPACITY],
            window,
            stride,
            head: 0,
            n: 0,
            phase: 0,
            pushes: 0,
            reference: None,
            sum_y: T::zero(),
            sum_iy: T::zero(),
            step_s: dt_s * from_usize::<T>(stride),
            slope: T::zero(),
        }
    }

    /// Current slope estimate (signal units per second); 0 until two samples are stored.
    #[inline]
    pub fn slope(&self) -> T {
        self.slope
    }

    /// Adds one sample (must be finite: the caller checks) and returns the updated slope.
    #[inline]
    // Ring-buffer indices are taken modulo `window`, and `window ≤ SLOPE_CAPACITY = buf.len()`
    // (clamped in `new`): every index is in range.
    #[allow(clippy::indexing_slicing)]
    pub fn push(&mut self, y: T) -> T {
        let take = self.phase == 0;
        self.phase = (self.phase + 1) % self.stride;
        if !take {
            return self.slope;
        }
        let r = *self.reference.get_or_insert(y);
        let y = y - r;
        if self.n == self.window {
            let oldest = self.buf[self.head];
            self.sum_iy -= self.sum_y - oldest;
            self.sum_y -= oldest;
            self.n -= 1;
            self.head = (self.head + 1) % self.window;
        }
        let tail = (self.head + self.n) % self.window;
        self.buf[tail] = y;
        self.sum_iy += from_usize::<T>(self.n) * y;
        self.sum_y += y;
        self.n += 1;
        self.pushes += 1;
        if self.pushes.is_multiple_of(SLOPE_CAPACITY) {
            self.recompute();
        }
        if self.n >= 2 {
            let n = from_usize::<T>(self.n);
            let si = n * (n - T::one()) / lit(2.0);
            let sii = (n - T::one()) * n * (lit::<T>(2.0) * n - T::one()) / lit(6.0);
            let den = n * sii - si * si;
            self.slope = (n * self.sum_iy - si * self.sum_y) / den / self.step_s;
        }
        self.slope
    }

    // As in `push`: indices modulo `window ≤ buf.len()`.
    #[allow(clippy::indexing_slicing)]
    fn recompute(&mut self) {
        let (mut sy, mut siy) = (T::zero(), T::zero());
        for i in 0..self.n {
            let y = self.buf[(self.head + i) % self.window];
            sy += y;
            siy += from_usize::<T>(i) * y;
        }
        self.sum_y = sy;
        self.sum_iy = siy;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_matches_batch_least_squares() {
        // A ramp with a quadratic term and quantisation: compare with the direct LS slope of
        // the last window at every step.
        let dt = 0.01_f64;
        let mut est = SlopeEstimator::new(2.0, dt);
        let y = |k: usize| {
            let t = k as f64 * dt;
            ((27.0 + 0.033 * t + 1e-3 * t * t) / 0.0625).round() * 0.0625
        };
        for k in 0..3000 {
            let s = est.push(y(k));
            if k >= 250 {
                let w = 200; // 2 s / 0.01 s
                let xs: Vec<f64> = (0..w).map(|i| i as f64 * dt).collect();
                let ys: Vec<f64> = (k + 1 - w..=k).map(y).collect();
                let mx = xs.iter().sum::<f64>() / w as f64;
                let my = ys.iter().sum::<f64>() / w as f64;
                let num: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
                let den: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
                assert!((s - num / den).abs() < 1e-9, "k={k} {s} vs {}", num / den);
            }
        }
        // A long window is decimated but still exact for a line.
        let mut est = SlopeEstimator::new(60.0, dt);
        let mut s = 0.0;
        for k in 0..10_000 {
            s = est.push(3.0 + 0.5 * k as f64 * dt);
        }
        assert!((s - 0.5).abs() < 1e-9, "{s}");
    }
}
