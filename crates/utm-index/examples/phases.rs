//! Times the phases of a search over synthetic intents: `cargo run --release --example phases -- 100000`.
use std::time::Instant;
use utm_index::{synthetic::synthetic, Search, SpaceTimeIndex};

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
    let t = Instant::now();
    let idx = SpaceTimeIndex::new(&v, Search::default()).unwrap_or_else(|e| panic!("{e}"));
    let (entries, big) = idx.stats();
    println!(
        "build ({entries} entries, {big} large): {:.3} s",
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let enc = idx.encounters(threads);
    println!(
        "encounters ({}): {:.3} s",
        enc.len(),
        t.elapsed().as_secs_f64()
    );
}
