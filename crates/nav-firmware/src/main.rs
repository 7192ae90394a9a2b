//! The firmware (on `target_os = "none"`: QEMU mps2-an386/an500 with semihosting) and the host
//! reference (elsewhere): both run every case of the library in f32 and f64 and print the same
//! output lines; the firmware adds the cost of each call (`t` lines) and the stack
//! high-water mark (`s` lines).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod target;

#[cfg(not(target_os = "none"))]
fn main() {
    use nav_firmware::{precision, run_all, Probe};
    use std::io::Write;

    /// Prints the outputs; calls are not timed on the host.
    struct Stdout(std::io::BufWriter<std::io::StdoutLock<'static>>);
    impl Probe for Stdout {
        fn begin(&mut self, case: &str) {
            let _ = writeln!(self.0, "case {case}");
        }
        fn value(&mut self, x: f64) {
            let _ = writeln!(self.0, "v {:016x}", x.to_bits());
        }
        fn tic(&mut self) {}
        fn toc(&mut self, _step: &'static str) {}
        fn end(&mut self) {
            let _ = writeln!(self.0, "end");
        }
    }

    let mut out = Stdout(std::io::BufWriter::new(std::io::stdout().lock()));
    let _ = writeln!(out.0, "precision {}", precision::<f32>());
    let r32 = run_all::<f32, _>(&mut out);
    let _ = writeln!(out.0, "precision {}", precision::<f64>());
    let r64 = r32.and_then(|()| run_all::<f64, _>(&mut out));
    let _ = out.0.flush();
    if let Err((case, e)) = r64 {
        eprintln!("error: case {case}: {e}");
        std::process::exit(1);
    }
    println!("done");
}
