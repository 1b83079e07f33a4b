//! Locus on a Cortex-M4F: runs [`locus_fw_app`]'s recorded
//! `square` sequence (quadrature decoding, the paper-001 EKF with IR wall
//! corrections, CORDIC odometry, all `f32`) and prints, over semihosting, the
//! final belief and odometry pose (as `f32` bit patterns and decimals), the
//! checksum of every step's state, the stack high-water mark and the SysTick
//! ticks spent in each part of the step; then exits with success (or failure
//! on any error or panic).
//!
//! Built for `thumbv7em-none-eabihf` and run by `cargo run --release` under
//! `qemu-system-arm -machine mps2-an386` (see `.cargo/config.toml`). Under
//! QEMU's `-icount shift=N` the virtual clock advances `2^N` ns per executed
//! instruction, so the SysTick ticks count instructions; the firmware
//! calibrates them against a block of exactly [`CALIBRATION_NOPS`] `nop`s
//! and reports ticks, which the host test converts.
//!
//! Output: one `key value` line per figure (see [`locus_fw_app::Report`]),
//! `f32`s as `key 0xBITS decimal`.
#![no_std]
#![no_main]

use core::arch::asm;

use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use locus_fw_app::{Firmware, Reading, square_data};

/// `nop`s in the calibration block (`.rept` in inline assembly, so exactly
/// this many instructions).
const CALIBRATION_NOPS: u32 = 4096;

/// Bytes of stack painted below `main`'s frame for the high-water mark.
const PAINT_BYTES: usize = 32 * 1024;
/// Gap left unpainted just below the stack pointer while painting (the
/// painting code's own use).
const PAINT_GAP: usize = 256;
/// The paint pattern.
const PAINT: u32 = 0xDEAD_BEEF;

/// Ticks spent in each part of the step, summed over the run, and how many
/// steps of each kind.
#[derive(Default)]
struct Ticks {
    decode: u32,
    predict: u32,
    predict_max: u32,
    associate: u32,
    associate_max: u32,
    readings: u32,
    /// `Firmware::correct` (association and correction, `Localiser::ir`)
    /// on the associated readings.
    correct: u32,
    correct_max: u32,
    /// The association alone on the associated readings.
    associate_of_associated: u32,
    associated: u32,
    odometry: u32,
    checksum: u32,
}

/// SysTick's current value (counts down, 24 bits).
#[inline(always)]
fn now() -> u32 {
    SYST::get_current()
}

/// Ticks from `start` to `end` on the down-counting 24-bit SysTick.
#[inline(always)]
fn elapsed(start: u32, end: u32) -> u32 {
    start.wrapping_sub(end) & 0x00FF_FFFF
}

/// Paints the stack from `PAINT_BYTES` below the current stack pointer to
/// `PAINT_GAP` below it; returns the lowest painted address.
#[allow(unsafe_code)]
#[inline(always)]
fn paint_stack() -> usize {
    let sp = cortex_m::register::msp::read() as usize;
    let bottom = sp - PAINT_BYTES;
    let mut a = bottom;
    while a < sp - PAINT_GAP {
        // SAFETY: the words between `bottom` and `sp - PAINT_GAP` are free
        // stack below the current frame (4 MiB of RAM, nothing else lives
        // there), written with volatile stores before any callee uses them.
        unsafe { core::ptr::write_volatile(a as *mut u32, PAINT) };
        a += 4;
    }
    bottom
}

/// The lowest address above `bottom` whose paint was overwritten.
#[allow(unsafe_code)]
fn lowest_used(bottom: usize) -> usize {
    let mut a = bottom;
    // SAFETY: reads of the painted region, which is ours.
    while unsafe { core::ptr::read_volatile(a as *const u32) } == PAINT {
        a += 4;
    }
    a
}

/// The top of the stack (`_stack_start` of cortex-m-rt's `link.x`).
#[allow(unsafe_code)]
fn stack_top() -> usize {
    unsafe extern "C" {
        static _stack_start: u32;
    }
    // SAFETY: only the symbol's address is taken.
    (&raw const _stack_start) as usize
}

/// Ticks of `CALIBRATION_NOPS` `nop`s, and of an empty bracket.
#[allow(unsafe_code)]
#[inline(never)]
fn calibrate() -> (u32, u32) {
    let t0 = now();
    // SAFETY: `nop`s only.
    unsafe {
        asm!(
            ".rept 4096",
            "nop",
            ".endr",
            options(nomem, nostack, preserves_flags)
        )
    };
    let t1 = now();
    let t2 = now();
    (elapsed(t0, t1), elapsed(t1, t2))
}

fn fail(what: &dyn core::fmt::Display) -> ! {
    hprintln!("error {}", what);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

#[entry]
fn main() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        fail(&"core peripherals already taken");
    };
    core.SYST.set_clock_source(SystClkSource::Core);
    core.SYST.set_reload(0x00FF_FFFF);
    core.SYST.clear_current();
    core.SYST.enable_counter();

    let painted_bottom = paint_stack();
    let (calibration, bracket) = calibrate();

    let mut ticks = Ticks::default();
    // Used in place: moving the state out of the `Result` would put a
    // second copy of it in this frame (and in the stack high-water mark).
    let mut started = Firmware::new(&square_data::CONFIG);
    let fw = match &mut started {
        Ok(fw) => fw,
        Err(e) => fail(e),
    };
    for (samples, ir) in square_data::WAVEFORM.iter().zip(square_data::IR.iter()) {
        let t0 = now();
        let u = fw.decode(*samples);
        let t1 = now();
        if let Err(e) = fw.predict(&u) {
            fail(&e);
        }
        let t2 = now();
        // The association alone (changes nothing), to split the cost of
        // `correct`, which associates and corrects (`Localiser::ir`).
        if let Some(readings) = ir {
            let _ = core::hint::black_box(fw.associate(*readings));
        }
        let t3 = now();
        let mut associated = false;
        if let Some(readings) = ir {
            match fw.correct(*readings) {
                Ok(reading) => associated = reading != Reading::Unassociated,
                Err(e) => fail(&e),
            }
        }
        let t4 = now();
        fw.odometry_step(&u);
        let t5 = now();
        fw.finish_step();
        let t6 = now();
        ticks.decode += elapsed(t0, t1);
        let predict = elapsed(t1, t2);
        ticks.predict += predict;
        ticks.predict_max = ticks.predict_max.max(predict);
        if ir.is_some() {
            let associate = elapsed(t2, t3);
            ticks.associate += associate;
            ticks.associate_max = ticks.associate_max.max(associate);
            ticks.readings += 1;
            if associated {
                let correct = elapsed(t3, t4);
                ticks.correct += correct;
                ticks.correct_max = ticks.correct_max.max(correct);
                ticks.associate_of_associated += associate;
                ticks.associated += 1;
            }
        }
        ticks.odometry += elapsed(t4, t5);
        ticks.checksum += elapsed(t5, t6);
    }
    let report = fw.report();
    let lowest = lowest_used(painted_bottom);
    if lowest == painted_bottom {
        fail(&"the stack went below the painted region");
    }

    hprintln!("locus-fw {}", env!("CARGO_PKG_VERSION"));
    for (name, value) in report.floats() {
        hprintln!("{} 0x{:08x} {}", name, value.to_bits(), value);
    }
    for (name, value) in report.integers() {
        hprintln!("{} {}", name, value);
    }
    hprintln!("stack_high_water {}", stack_top() - lowest);
    hprintln!("firmware_state_bytes {}", core::mem::size_of::<Firmware>());
    hprintln!("calibration_nops {}", CALIBRATION_NOPS);
    hprintln!("ticks_calibration {}", calibration);
    hprintln!("ticks_bracket {}", bracket);
    hprintln!("ticks_decode {}", ticks.decode);
    hprintln!("ticks_predict {}", ticks.predict);
    hprintln!("ticks_predict_max {}", ticks.predict_max);
    hprintln!("ticks_associate {}", ticks.associate);
    hprintln!("ticks_associate_max {}", ticks.associate_max);
    hprintln!("steps_with_ir {}", ticks.readings);
    hprintln!("ticks_correct {}", ticks.correct);
    hprintln!("ticks_correct_max {}", ticks.correct_max);
    hprintln!(
        "ticks_associate_of_associated {}",
        ticks.associate_of_associated
    );
    hprintln!("steps_associated {}", ticks.associated);
    hprintln!("ticks_odometry {}", ticks.odometry);
    hprintln!("ticks_checksum {}", ticks.checksum);
    hprintln!("done");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::bkpt();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic {}", info);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}
