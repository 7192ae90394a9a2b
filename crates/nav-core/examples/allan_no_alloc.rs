//! Overlapping Allan deviation with caller-owned buffers (no heap), as on a microcontroller.
//!
//! Run with `cargo run --example allan_no_alloc`.
use uasnav_core::allan::{cluster_sizes, oadev_into, AllanPoint, TauSpacing};
use uasnav_core::NavError;

const N: usize = 4096;

fn main() -> Result<(), NavError> {
    // White rate noise from a small linear congruential generator (no `rand` on the target).
    let mut state: u32 = 1;
    let mut rate = [0.0f32; N];
    for r in rate.iter_mut() {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        *r = (state >> 8) as f32 / (1u32 << 24) as f32 - 0.5; // uniform, σ = 1/√12 rad/s
    }
    let mut ms = [0usize; 16];
    let k = cluster_sizes(N, TauSpacing::Octave, &mut ms);
    let mut phase = [0.0f32; N + 1];
    let empty = AllanPoint {
        tau_s: 0.0,
        m: 0,
        avar: 0.0,
        adev: 0.0,
        n_terms: 0,
        rel_error: 0.0,
    };
    let mut out = [empty; 16];
    oadev_into(&rate, 0.01, &ms[..k], &mut phase, &mut out[..k])?;
    for p in &out[..k] {
        println!(
            "tau {:8.2} s  adev {:.3e} rad/s  (±{:.0} %)",
            p.tau_s,
            p.adev,
            100.0 * p.rel_error
        );
    }
    Ok(())
}
