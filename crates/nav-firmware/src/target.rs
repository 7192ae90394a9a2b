//! The firmware side: SysTick as an instruction counter, stack painting, semihosting output
//! and exit status.
//!
//! Under `qemu-system-arm -icount shift=0` every instruction advances the virtual clock by
//! 1 ns, and SysTick (clocked from the CPU clock) counts that virtual time: the ticks between
//! two reads are proportional to the instructions executed. The ratio is measured at start-up
//! on a loop of known length (`cal` line) and applied by `check.py`.
use core::fmt::Write as _;

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hio};
use nav_firmware::{precision, run_all, Probe};
// Panics print their message through semihosting and exit QEMU with a failure status.
use panic_semihosting as _;

/// SysTick's 24-bit counter.
const RELOAD: u32 = 0x00FF_FFFF;
/// Bytes of stack painted below the probe before each timed call.
const PAINT_BYTES: usize = 32 * 1024;
/// Bytes left unpainted directly below the probe's own frame (the painter's frame lives there).
const PAINT_MARGIN: usize = 256;
const PATTERN: u32 = 0xA5C3_5A3C;

/// Fills `[top − PAINT_BYTES, top − PAINT_MARGIN)` with the pattern, `top` the current stack
/// pointer; returns `top`.
#[inline(never)]
#[allow(unsafe_code)]
fn paint() -> usize {
    let top = cortex_m::register::msp::read() as usize;
    let mut a = top - PAINT_BYTES;
    while a < top - PAINT_MARGIN {
        // SAFETY: the range lies below the current stack pointer, inside the 4 MiB RAM (the
        // stack starts at its top and the cases use a few KiB), and above this function's own
        // frame; nothing live is stored there. Volatile so that the stores are not elided.
        unsafe { core::ptr::write_volatile(a as *mut u32, PATTERN) };
        a += 4;
    }
    top
}

/// Deepest stack use (bytes below `top`) since the last `paint(top)`: the first word from the
/// bottom that no longer holds the pattern.
#[inline(never)]
#[allow(unsafe_code)]
fn high_water(top: usize) -> usize {
    let mut a = top - PAINT_BYTES;
    while a < top - PAINT_MARGIN {
        // SAFETY: the same range `paint` wrote, below the stack pointer of the caller's frame;
        // reading it only observes what the timed call left there.
        let w = unsafe { core::ptr::read_volatile(a as *const u32) };
        if w != PATTERN {
            return top - a;
        }
        a += 4;
    }
    PAINT_MARGIN
}

/// Writes one line to the host's stdout through semihosting.
struct Host(hio::HostStream);

impl Host {
    fn line(&mut self, args: core::fmt::Arguments<'_>) {
        let mut buf = Line::default();
        let _ = buf.write_fmt(args);
        let _ = buf.write_str("\n");
        let _ = self.0.write_all(&buf.bytes[..buf.len]);
    }
}

/// A line assembled before it is written: one semihosting call per line.
struct Line {
    bytes: [u8; 128],
    len: usize,
}

impl Default for Line {
    fn default() -> Self {
        Line {
            bytes: [0; 128],
            len: 0,
        }
    }
}

impl core::fmt::Write for Line {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        let n = s.len().min(self.bytes.len() - self.len);
        self.bytes[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
        Ok(())
    }
}

/// Per-step statistics, printed at the end of each case.
#[derive(Clone, Copy)]
struct Stat {
    name: &'static str,
    calls: u32,
    sum: u64,
    min: u32,
    max: u32,
    stack: usize,
}

struct Firmware {
    host: Host,
    syst: SYST,
    t0: u32,
    top: usize,
    stats: [Option<Stat>; 8],
}

impl Firmware {
    fn now() -> u32 {
        SYST::get_current()
    }
}

impl Probe for Firmware {
    fn begin(&mut self, case: &str) {
        self.stats = [None; 8];
        self.host.line(format_args!("case {case}"));
    }
    fn value(&mut self, x: f64) {
        self.host.line(format_args!("v {:016x}", x.to_bits()));
    }
    fn tic(&mut self) {
        self.top = paint();
        self.t0 = Self::now();
    }
    fn toc(&mut self, step: &'static str) {
        let t1 = Self::now();
        let ticks = self.t0.wrapping_sub(t1) & RELOAD;
        let stack = high_water(self.top);
        let slot = self
            .stats
            .iter_mut()
            .find(|s| s.is_none_or(|s| s.name == step));
        if let Some(slot) = slot {
            let s = slot.get_or_insert(Stat {
                name: step,
                calls: 0,
                sum: 0,
                min: u32::MAX,
                max: 0,
                stack: 0,
            });
            s.calls += 1;
            s.sum += u64::from(ticks);
            s.min = s.min.min(ticks);
            s.max = s.max.max(ticks);
            s.stack = s.stack.max(stack);
        }
    }
    fn end(&mut self) {
        for s in self.stats.iter().flatten() {
            self.host.line(format_args!(
                "t {} calls={} sum={} min={} max={} stack={}",
                s.name, s.calls, s.sum, s.min, s.max, s.stack
            ));
        }
        self.host.line(format_args!("end"));
    }
}

/// Ticks of `cortex_m::asm::delay(2·n)`: a two-instruction loop run n times.
fn calibrate(n: u32) -> u32 {
    let t0 = Firmware::now();
    cortex_m::asm::delay(2 * n);
    let t1 = Firmware::now();
    t0.wrapping_sub(t1) & RELOAD
}

#[entry]
fn main() -> ! {
    let ok = match (cortex_m::Peripherals::take(), hio::hstdout()) {
        (Some(p), Ok(out)) => run(p.SYST, Host(out)),
        _ => false,
    };
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}

fn run(mut syst: SYST, host: Host) -> bool {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(RELOAD);
    syst.clear_current();
    syst.enable_counter();
    let mut fw = Firmware {
        host,
        syst,
        t0: 0,
        top: 0,
        stats: [None; 8],
    };
    let n = 1_000_000;
    let ticks = calibrate(n);
    fw.host
        .line(format_args!("cal instructions={} ticks={}", 2 * n, ticks));
    fw.host
        .line(format_args!("precision {}", precision::<f32>()));
    let r = run_all::<f32, _>(&mut fw).and_then(|()| {
        fw.host
            .line(format_args!("precision {}", precision::<f64>()));
        run_all::<f64, _>(&mut fw)
    });
    let _ = &fw.syst;
    match r {
        Ok(()) => {
            fw.host.line(format_args!("done"));
            true
        }
        Err((case, e)) => {
            fw.host.line(format_args!("error: case {case}: {e}"));
            false
        }
    }
}
