//! Times the phases of a search over synthetic intents: `cargo run --release --example phases -- 100000`.
use std::time::Instant;
use utm_index::{synthetic::synthetic, Search, SpaceTimeIndex};

/// CPU time this process has run, s (Linux `/proc/self/schedstat`; NaN elsewhere): on a shared
/// machine the wall time includes waiting for a core, the CPU time does not.
fn cpu_s() -> f64 {
    std::fs::read_to_string("/proc/self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000);
    let threads: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let t = Instant::now();
    let v = synthetic(n, 0).unwrap_or_else(|e| panic!("{e}"));
    println!(
        "generate {} volumes: {:.3} s",
        v.len(),
        t.elapsed().as_secs_f64()
    );
    let (t, c) = (Instant::now(), cpu_s());
    let idx = SpaceTimeIndex::with_threads(&v, Search::default(), threads)
        .unwrap_or_else(|e| panic!("{e}"));
    let (entries, big) = idx.stats();
    println!(
        "build ({entries} entries, {big} large): {:.3} s (main thread CPU {:.3} s)",
        t.elapsed().as_secs_f64(),
        cpu_s() - c
    );
    let (t, c) = (Instant::now(), cpu_s());
    let enc = idx.encounters(threads);
    println!(
        "encounters ({}): {:.3} s (main thread CPU {:.3} s)",
        enc.len(),
        t.elapsed().as_secs_f64(),
        cpu_s() - c
    );
}
