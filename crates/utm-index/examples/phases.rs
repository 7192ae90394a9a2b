//! Times the phases of a search over synthetic intents:
//! `cargo run --release -p utm-index --example phases -- N_INTENTS THREADS` (defaults 100000, 1):
//! index build, encounter scan (conflicts), and the departure-delay search (max 86 400 s, the CLI default) of the
//! later intent of up to 1000 conflicting intent pairs.
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
    println!(
        "build: {:.3} s (main thread CPU {:.3} s)",
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
    let (entries, big) = idx.stats();
    let mut later: Vec<u32> = enc
        .iter()
        .map(|e| v.intent(e.a as usize).max(v.intent(e.b as usize)))
        .collect();
    later.sort_unstable();
    later.dedup();
    println!(
        "{} conflicting volume pairs, {} distinct later intents; {entries} cell entries, {big} large",
        enc.len(),
        later.len()
    );
    later.truncate(1000);
    let (t, c) = (Instant::now(), cpu_s());
    let mut n_free = 0;
    for &i in &later {
        if let Ok(Some(_)) = idx.earliest_delay(i, 86_400.0) {
            n_free += 1;
        }
    }
    println!(
        "delay search ({} intents, {n_free} freed within a day): {:.3} s (main thread CPU {:.3} s, first call builds the delay index)",
        later.len(),
        t.elapsed().as_secs_f64(),
        cpu_s() - c
    );
    let (t, c) = (Instant::now(), cpu_s());
    for &i in &later {
        let _ = idx.earliest_delay(i, 86_400.0);
    }
    println!(
        "delay search again: {:.3} ms per intent (main thread CPU {:.3} ms)",
        t.elapsed().as_secs_f64() * 1e3 / later.len().max(1) as f64,
        (cpu_s() - c) * 1e3 / later.len().max(1) as f64
    );
}
