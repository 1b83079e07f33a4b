//! Locus on a Cortex-M4F as a robot on the link: the recorded `square`
//! sequence of [`locus_fw_app`] run step by step as `locus-fw` runs it,
//! with each step's telemetry (encoder counts, IR reading) sent as a COBS
//! frame over UART0 and the host's wheel commands received on it
//! ([`locus_fw_app::link`]). Run under QEMU's `mps2-an386` with UART0 on a
//! pseudo-terminal and without `-icount` (`qemu-system-arm -machine
//! mps2-an386 -cpu cortex-m4 -display none -monitor none
//! -semihosting-config enable=on,target=native -serial pty -kernel ELF`;
//! see `docs/firmware.md`), and `locus host --robot serial:/dev/pts/N`
//! localises it. (`cargo run --bin locus-fw-link -- -serial pty` works
//! too, but under its runner's `-icount` the timeouts count instructions,
//! 64 ns of virtual time each, not the host's time: with no host, the 30 s
//! handshake ended after 24.5 s of wall time on this VM.)
//!
//! # Loop
//! 1. Wait up to [`HANDSHAKE_S`] for a first valid command (the host sends
//!    zero-speed commands until its first telemetry), as
//!    `locus_simlink` does: nothing is sent before someone listens.
//! 2. Send telemetry 0 (time 0, counts 0, no reading).
//! 3. For each recorded step `k = 1..=3000`: run the step (decode, predict,
//!    IR correction, odometry, checksum), send telemetry `k`, print the
//!    firmware's own belief over semihosting (`belief k 0xX 0xY 0xTHETA`,
//!    `f32` bits), then wait for the command acknowledging `k`, at most
//!    [`PACING_MS`]: the stream is paced by the host, so a host slower
//!    than QEMU loses nothing, and a lost command costs at most the
//!    timeout (counted as `pacing_timeouts`).
//! 4. Print the final report (belief, checksum, counts) and the link's
//!    counters, linger [`LINGER_MS`] (so the host, which ends after a quiet
//!    spell, is not cut off by the line closing), exit.
//!
//! The robot has no motors: commands are counted, not applied. Time comes
//! from the SysTick on the 25 MHz board clock (run without `-icount`, QEMU's
//! virtual clock follows the host's).
#![no_std]
#![no_main]

mod stack;
mod uart;

use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use locus_fw_app::link::{LinkRobot, acknowledges};
use locus_fw_app::{Firmware, square_data};
use locus_link::framing::MAX_FRAME;

use uart::Uart;

/// The board clock driving the SysTick and the UART (Hz).
const CLOCK_HZ: u64 = 25_000_000;
/// UART0's divider: 115 200 baud from the 25 MHz clock (QEMU does not model
/// the rate; a real board would).
const BAUDDIV: u32 = 217;
/// Longest wait for the host's first command (s).
const HANDSHAKE_S: u64 = 30;
/// Longest wait for the command acknowledging a telemetry packet (ms):
/// long enough for a host thread held up on a loaded machine (100 ms was
/// exceeded once in a few runs on a 2-core VM shared with builds), shorter
/// than the host's quiet spell (0.5 s by default), so that a lost command
/// never ends the host's run.
const PACING_MS: u64 = 250;
/// Time the firmware stays on the line after the run (ms): longer than
/// the host's quiet spell (0.5 s by default).
const LINGER_MS: u64 = 2_000;

/// A 64-bit tick count from the down-counting 24-bit SysTick; must be read
/// at least every 0.67 s (2^24 ticks at 25 MHz) to see every wrap.
struct Clock {
    last: u32,
    ticks: u64,
}

impl Clock {
    fn new() -> Self {
        Self {
            last: SYST::get_current(),
            ticks: 0,
        }
    }

    fn now(&mut self) -> u64 {
        let v = SYST::get_current();
        self.ticks += u64::from(self.last.wrapping_sub(v) & 0x00FF_FFFF);
        self.last = v;
        self.ticks
    }
}

/// What [`Line::wait_for`] waits for.
#[derive(Clone, Copy)]
enum Until {
    /// Any valid new command (the handshake).
    AnyCommand,
    /// A command acknowledging telemetry `k` or a later one (pacing).
    Acknowledging(u32),
    /// Nothing: receive and count until the time is up.
    Timeout,
}

/// The link's state besides [`LinkRobot`]: the UART and the pacing counts.
struct Line {
    uart: Uart,
    robot: LinkRobot,
    clock: Clock,
    /// Telemetry packets whose acknowledging command came within
    /// [`PACING_MS`].
    acknowledged: u32,
    /// Telemetry packets whose acknowledging command did not.
    pacing_timeouts: u32,
    /// Received bytes the UART overwrote before they were read.
    rx_overruns: u32,
    frame: [u8; MAX_FRAME],
}

impl Line {
    /// Receives until a valid new command that `until` asks for arrives,
    /// or `ticks` pass; whether one did. (One function for every wait, not
    /// one per closure: flash.)
    #[inline(never)]
    fn wait_for(&mut self, ticks: u64, until: Until) -> bool {
        let start = self.clock.now();
        loop {
            while let Some(byte) = self.uart.read() {
                if let Some(c) = self.robot.push(byte) {
                    let wanted = match until {
                        Until::AnyCommand => true,
                        Until::Acknowledging(k) => acknowledges(c.ack, k),
                        Until::Timeout => false,
                    };
                    if wanted {
                        return true;
                    }
                }
            }
            self.rx_overruns += u32::from(self.uart.take_rx_overrun());
            if self.clock.now() - start >= ticks {
                return false;
            }
        }
    }

    /// Sends telemetry `k` with the decoders' counts `now` and the reading
    /// `ir`.
    #[inline(never)]
    fn send(&mut self, k: u32, now: [u32; 2], ir: Option<[f32; 2]>) {
        match self.robot.telemetry_frame(k, now, ir, &mut self.frame) {
            Ok(n) => self.uart.write(&self.frame[..n]),
            Err(e) => fail(&e),
        }
    }

    /// Waits for the command acknowledging telemetry `k` (pacing).
    #[inline(never)]
    fn paced(&mut self, k: u32) {
        if self.wait_for(PACING_MS * CLOCK_HZ / 1000, Until::Acknowledging(k)) {
            self.acknowledged += 1;
        } else {
            self.pacing_timeouts += 1;
        }
    }
}

fn fail(what: &dyn core::fmt::Display) -> ! {
    hprintln!("error {}", what);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}

fn print_belief(k: u32, fw: &Firmware) {
    let x = fw.belief().x;
    hprintln!(
        "belief {} 0x{:08x} 0x{:08x} 0x{:08x}",
        k,
        x[0].to_bits(),
        x[1].to_bits(),
        x[2].to_bits()
    );
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
    let painted_bottom = stack::paint();
    let Some(uart) = Uart::take(BAUDDIV) else {
        fail(&"UART0 already taken");
    };
    let mut line = Line {
        uart,
        robot: LinkRobot::new(),
        clock: Clock::new(),
        acknowledged: 0,
        pacing_timeouts: 0,
        rx_overruns: 0,
        frame: [0; MAX_FRAME],
    };
    // Used in place, as in `locus-fw`.
    let mut started = Firmware::new(&square_data::CONFIG);
    let fw = match &mut started {
        Ok(fw) => fw,
        Err(e) => fail(e),
    };

    hprintln!("locus-fw-link {} waiting", env!("CARGO_PKG_VERSION"));
    // 1. Handshake.
    if !line.wait_for(HANDSHAKE_S * CLOCK_HZ, Until::AnyCommand) {
        fail(&"no command from the host within the handshake");
    }
    // 2. Telemetry 0.
    line.send(0, fw.counts(), None);
    print_belief(0, fw);
    line.paced(0);
    // 3. The recorded steps.
    let mut k = 0u32;
    for (samples, ir) in square_data::WAVEFORM.iter().zip(square_data::IR.iter()) {
        k += 1;
        if let Err(e) = fw.step(*samples, *ir) {
            fail(&e);
        }
        line.send(k, fw.counts(), *ir);
        print_belief(k, fw);
        line.paced(k);
    }
    // 4. Report.
    let Some(stack_high_water) = stack::high_water(painted_bottom) else {
        fail(&"the stack went below the painted region");
    };
    let report = fw.report();
    for (name, value) in report.floats() {
        hprintln!("{} 0x{:08x} {}", name, value.to_bits(), value);
    }
    for (name, value) in report.integers() {
        hprintln!("{} {}", name, value);
    }
    let [right, left] = line.robot.counts();
    hprintln!("link_count_right {}", right);
    hprintln!("link_count_left {}", left);
    hprintln!("telemetry_sent {}", line.robot.sent());
    hprintln!("acknowledged {}", line.acknowledged);
    hprintln!("pacing_timeouts {}", line.pacing_timeouts);
    hprintln!("rx_overruns {}", line.rx_overruns);
    hprintln!("stack_high_water {}", stack_high_water);
    hprintln!("firmware_state_bytes {}", core::mem::size_of::<Firmware>());
    hprintln!("link_state_bytes {}", core::mem::size_of::<Line>());
    // Commands still arriving (the acknowledgement of the last packet is
    // already in) are counted too.
    line.wait_for(LINGER_MS * CLOCK_HZ / 1000, Until::Timeout);
    let c = line.robot.commands();
    hprintln!("commands_applied {}", c.applied);
    hprintln!("commands_lost {}", c.lost);
    hprintln!("commands_duplicate {}", c.duplicate);
    hprintln!("commands_late {}", c.late);
    hprintln!("commands_corrupt {}", c.corrupt);
    hprintln!("commands_malformed {}", c.malformed);
    hprintln!("commands_suspect {}", c.suspect);
    let f = line.robot.framing();
    hprintln!("frames {}", f.frames);
    hprintln!("frames_dropped {}", f.dropped());
    hprintln!("rx_overruns_after {}", line.rx_overruns);
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
