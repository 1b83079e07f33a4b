//! The Cortex-M4F firmware as a robot on the link: `locus-fw-link` (the
//! firmware workspace, `firmware/`) built for `thumbv7em-none-eabihf` and
//! run under `qemu-system-arm -machine mps2-an386` with its UART0 on a
//! pseudo-terminal (`-serial pty`); the host (`run_host_over` on the
//! [`Serial`] transport, opened on that pty) localises it.
//!
//! The firmware replays its recorded 3000 steps (the `square` run, seed 1)
//! through its own `f32` filter, sends each step's encoder counts and IR
//! reading as COBS-framed telemetry, prints its own belief per step over
//! semihosting, and waits for the command acknowledging each packet. The
//! test checks that nothing is lost on this clean line (every telemetry
//! packet applied, every command received, nothing dropped at either end),
//! that the firmware's run is the recorded one (checksum), and that the
//! host's `f64` estimates agree with the firmware's `f32` beliefs step by
//! step (see [`POSITION_BOUND`]).
//!
//! A missing `qemu-system-arm` is a failure, not a skip: `scripts/test.sh`
//! installs it.

extern crate alloc;

use alloc::collections::BTreeMap;
use core::time::Duration;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Instant;

use locus_net::host::run_host_over;
use locus_net::transport::Serial;
use locus_sim::closed_loop::{SquareConfig, StepRecord, run_square};
use locus_simlink::host_config;

const THUMB: &str = "thumbv7em-none-eabihf";
/// Steps of the recorded sequence; telemetry 0 comes before the first.
const STEPS: u64 = 3000;
/// The recorded run's checksum (`docs/firmware.md`): the link firmware's
/// filter runs exactly the recorded `f32` run.
const CHECKSUM: u32 = 0xfd50_52b4;
/// Longest the whole emulated run may take (wall clock).
const QEMU_TIMEOUT: Duration = Duration::from_secs(120);

/// Largest position difference, host `f64` estimate against the firmware's
/// `f32` belief, at any step (m). Measured: 8.47e-6 m (step 1813; RMS over
/// the steps 5.4e-6 m, 7.5e-6 m after the last step).
///
/// Both sides see the same counts and the same `f32` IR readings and make
/// the same gate decisions (1784 corrections, 28 rejected), so the
/// difference is the firmware's `f32` arithmetic alone: the firmware
/// against the simulator's in-process `f64` filter differs by the same
/// 8.47e-6 m, the host not at all (below). Unit
/// roundoff 6e-8 on coordinates near 1 m, accumulated in `P` and the gain
/// over 3000 predictions and 1784 corrections, gives some hundred ulps.
/// The figure is deterministic (the firmware's run is pinned by its
/// checksum, the host's by applying every packet in order), so the bound
/// leaves only a little room, for a toolchain's different rounding: 1e-5 m,
/// still 1/1000 of the filter's own position standard deviation (about
/// 1 cm).
const POSITION_BOUND: f64 = 1e-5;
/// Largest heading difference (rad), as [`POSITION_BOUND`]. Measured:
/// 3.02e-6 rad.
const HEADING_BOUND: f64 = 4e-6;

/// RAM budget of the firmware (bytes, `docs/firmware.md`).
const RAM_BUDGET: u64 = 4096;

fn firmware_workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../firmware")
}

/// Builds `locus-fw-link` (release, its own target directory inside this
/// test's, so the nested cargo does not wait for the outer one's lock).
fn firmware_elf() -> PathBuf {
    let target_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("firmware-build");
    let status = Command::new(env!("CARGO"))
        .current_dir(firmware_workspace())
        .args(["build", "--release", "--locked", "-p", "locus-fw"])
        .args(["--bin", "locus-fw-link", "--target", THUMB])
        .arg("--target-dir")
        .arg(&target_dir)
        .status()
        .expect("running cargo to build the firmware");
    assert!(status.success(), "building the firmware failed: {status}");
    let elf = target_dir.join(THUMB).join("release").join("locus-fw-link");
    assert!(elf.is_file(), "no firmware ELF at {}", elf.display());
    elf
}

/// QEMU running the firmware, its stdout (QEMU's own messages and the
/// firmware's semihosting output) read line by line on a thread.
struct Emulator {
    child: Child,
    lines: mpsc::Receiver<String>,
    raw: Vec<String>,
}

impl Emulator {
    fn start(elf: &Path) -> Self {
        let mut child = Command::new("qemu-system-arm")
            .args(["-machine", "mps2-an386", "-cpu", "cortex-m4"])
            .args(["-display", "none", "-monitor", "none"])
            .args(["-semihosting-config", "enable=on,target=native"])
            .args(["-serial", "pty"])
            .arg("-kernel")
            .arg(elf)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap_or_else(|e| {
                panic!(
                    "cannot start qemu-system-arm ({e}); install it (Debian: \
                     apt-get install qemu-system-arm; scripts/test.sh does)"
                )
            });
        let stdout = child.stdout.take().expect("QEMU's stdout");
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Self {
            child,
            lines,
            raw: Vec::new(),
        }
    }

    /// The next line within `timeout`, or `None` once QEMU's stdout closed
    /// or the time is up.
    fn line(&mut self, timeout: Duration) -> Option<String> {
        let line = self.lines.recv_timeout(timeout).ok()?;
        self.raw.push(line.clone());
        Some(line)
    }

    /// The pseudo-terminal QEMU connected UART0 to.
    fn pty(&mut self) -> String {
        loop {
            let line = self
                .line(Duration::from_secs(20))
                .unwrap_or_else(|| panic!("QEMU named no pty:\n{}", self.raw.join("\n")));
            if let Some(rest) = line.strip_prefix("char device redirected to ") {
                return rest
                    .split_whitespace()
                    .next()
                    .expect("a device after 'redirected to'")
                    .to_owned();
            }
        }
    }

    /// Every remaining line, once QEMU has exited with success.
    fn finish(mut self) -> Vec<String> {
        let start = Instant::now();
        while self
            .line(QEMU_TIMEOUT.saturating_sub(start.elapsed()))
            .is_some()
        {}
        let status = loop {
            if let Some(status) = self.child.try_wait().expect("waiting for QEMU") {
                break status;
            }
            if start.elapsed() > QEMU_TIMEOUT {
                let _ = self.child.kill();
                let _ = self.child.wait();
                panic!("the firmware did not finish within {QEMU_TIMEOUT:?}");
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        assert!(
            status.success(),
            "the firmware failed under QEMU ({status}):\n{}",
            self.raw.join("\n")
        );
        core::mem::take(&mut self.raw)
    }
}

impl Drop for Emulator {
    fn drop(&mut self) {
        // A failed assertion must not leave QEMU running.
        if matches!(self.child.try_wait(), Ok(None)) {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// The firmware's `key value...` lines, and its per-step beliefs.
struct Output {
    values: BTreeMap<String, Vec<String>>,
    beliefs: BTreeMap<u32, [f32; 3]>,
    raw: String,
}

impl Output {
    fn parse(lines: &[String]) -> Self {
        let bits = |s: &str| f32::from_bits(u32::from_str_radix(&s[2..], 16).unwrap());
        let mut values = BTreeMap::new();
        let mut beliefs = BTreeMap::new();
        for l in lines {
            let w: Vec<&str> = l.split_whitespace().collect();
            match w.as_slice() {
                ["belief", k, x, y, th] => {
                    let k: u32 = k.parse().unwrap();
                    assert!(
                        beliefs.insert(k, [bits(x), bits(y), bits(th)]).is_none(),
                        "belief {k} printed twice"
                    );
                }
                [key, rest @ ..] => {
                    values.insert(
                        (*key).to_owned(),
                        rest.iter().map(|s| (*s).to_owned()).collect(),
                    );
                }
                [] => {}
            }
        }
        Self {
            values,
            beliefs,
            raw: lines.join("\n"),
        }
    }

    fn u64(&self, key: &str) -> u64 {
        let v = self
            .values
            .get(key)
            .unwrap_or_else(|| panic!("no `{key}` in the firmware's output:\n{}", self.raw));
        v[0].parse()
            .unwrap_or_else(|e| panic!("`{key}`: {e}\n{}", self.raw))
    }
}

#[test]
fn the_emulated_firmware_is_localised_by_the_host_over_its_uart() {
    let elf = firmware_elf();
    let mut qemu = Emulator::start(&elf);
    let pty = qemu.pty();
    let mut link = Serial::open(&pty, 115_200).expect("opening QEMU's pty");

    // The firmware's recorded run is `SquareConfig::default()`'s (seed 1):
    // the host runs that localiser on the link's 32-bit counts.
    let cfg = host_config(&SquareConfig::default());
    let started = Instant::now();
    let host = run_host_over(&mut link, &cfg, &mut |_| {}).expect("the host run");
    let host_time = started.elapsed();
    drop(link);
    let fw = Output::parse(&qemu.finish());

    // The firmware ran the recorded sequence, bit for bit.
    assert!(fw.values.contains_key("done"), "no `done`:\n{}", fw.raw);
    assert_eq!(fw.u64("steps"), STEPS);
    assert_eq!(
        fw.u64("checksum"),
        u64::from(CHECKSUM),
        "the link firmware's filter run differs from the recorded run"
    );

    // Nothing lost on the clean line, either way.
    let c = host.counters;
    println!(
        "host: applied {} lost {} duplicate {} late {} corrupt {} malformed {} suspect {} \
         implausible {} resync {}; framing {:?}; filter errors {}; corrections {}; \
         commands sent {}; {:.2} s",
        c.applied,
        c.lost,
        c.duplicate,
        c.late,
        c.corrupt,
        c.malformed,
        c.suspect,
        c.implausible,
        c.resync,
        host.framing,
        host.filter_errors,
        host.corrections,
        host.commands_sent,
        host_time.as_secs_f64()
    );
    for key in [
        "stack_high_water",
        "firmware_state_bytes",
        "link_state_bytes",
        "telemetry_sent",
        "acknowledged",
        "pacing_timeouts",
        "commands_applied",
        "commands_lost",
        "commands_duplicate",
        "commands_late",
        "commands_corrupt",
        "commands_malformed",
        "commands_suspect",
        "frames",
        "frames_dropped",
        "rx_overruns_after",
        "corrections",
        "rejected",
        "unassociated",
    ] {
        println!("firmware: {key} {}", fw.u64(key));
    }
    assert_eq!(c.applied, STEPS + 1, "telemetry 0..=3000 applied");
    assert_eq!(
        [
            c.lost,
            c.duplicate,
            c.late,
            c.corrupt,
            c.malformed,
            c.suspect,
            c.implausible,
            c.resync
        ],
        [0; 8],
        "host counters: {c:?}"
    );
    assert_eq!(host.framing.dropped(), 0, "{:?}", host.framing);
    assert_eq!(host.framing.discarded, 0, "{:?}", host.framing);
    assert_eq!(host.filter_errors, 0);
    assert_eq!(fw.u64("telemetry_sent"), STEPS + 1);
    // Every packet waited for its acknowledgement: in time, or (a host
    // thread held up for longer than the timeout on a loaded machine) the
    // firmware went on without it. A late command still arrives and is
    // counted below; it is not a loss.
    assert_eq!(
        fw.u64("acknowledged") + fw.u64("pacing_timeouts"),
        STEPS + 1
    );
    assert_eq!(
        fw.u64("commands_applied"),
        host.commands_sent,
        "every command the host sent reached the firmware"
    );
    for key in [
        "commands_lost",
        "commands_duplicate",
        "commands_late",
        "commands_corrupt",
        "commands_malformed",
        "commands_suspect",
        "frames_dropped",
        "rx_overruns_after",
    ] {
        assert_eq!(fw.u64(key), 0, "{key}");
    }
    assert_eq!(fw.u64("frames"), host.commands_sent);
    // The link firmware's stack (its `.data`/`.bss`, 22 bytes, are in the
    // firmware workspace's `footprint_of_the_link_firmware`).
    assert!(
        fw.u64("stack_high_water") < RAM_BUDGET,
        "stack high-water {} bytes",
        fw.u64("stack_high_water")
    );
    // The same gate decisions on both sides.
    assert_eq!(host.corrections, fw.u64("corrections"));

    // The host's estimates against the firmware's own beliefs, step by step,
    // and both against the simulator's in-process f64 filter on the same
    // run (the recorded sequence is its first 3000 steps).
    assert_eq!(host.estimates.len() as u64, STEPS + 1);
    assert_eq!(fw.beliefs.len() as u64, STEPS + 1);
    let mut sim = Vec::new();
    run_square(&SquareConfig::default(), 1, &mut |r: &StepRecord| {
        if sim.len() < STEPS as usize {
            sim.push(r.ekf);
        }
    })
    .expect("the in-process run");
    let host_fw = Diff::over(&host.estimates, |seq| fw.beliefs[&seq].map(f64::from));
    let host_sim = Diff::over(&host.estimates[1..], |seq| sim[seq as usize - 1]);
    let fw_sim = Diff::over(
        &fw.beliefs
            .iter()
            .skip(1)
            .map(|(k, b)| (*k, b.map(f64::from)))
            .collect::<Vec<_>>(),
        |seq| sim[seq as usize - 1],
    );
    println!("host f64 vs firmware f32: {host_fw}");
    println!("host f64 vs simulator f64 (in process): {host_sim}");
    println!("firmware f32 vs simulator f64: {fw_sim}");
    assert!(
        host_fw.position <= POSITION_BOUND,
        "position differs by {} m",
        host_fw.position
    );
    assert!(
        host_fw.heading <= HEADING_BOUND,
        "heading differs by {} rad",
        host_fw.heading
    );
    // The host is the `f64` replay of what it received, and the simulated
    // IR sensors report `f32` as the wire carries it: the host's estimates
    // are the simulator's in-process filter's, bit for bit.
    assert!(
        host_sim.position == 0.0 && host_sim.heading == 0.0,
        "the host differs from the simulator's f64 filter: {host_sim}"
    );
}

/// The largest differences between two estimate sequences, and the final
/// ones.
struct Diff {
    /// Largest position difference (m) and its sequence number.
    position: f64,
    worst: u32,
    /// Largest heading difference (rad).
    heading: f64,
    /// Position difference after the last step (m).
    last: f64,
    /// RMS of the position difference over the steps (m).
    rms: f64,
}

impl Diff {
    /// `estimates` against `reference(sequence)`.
    #[allow(clippy::cast_precision_loss)]
    fn over(estimates: &[(u32, [f64; 3])], reference: impl Fn(u32) -> [f64; 3]) -> Self {
        let mut d = Diff {
            position: 0.0,
            worst: 0,
            heading: 0.0,
            last: 0.0,
            rms: 0.0,
        };
        for (seq, [x, y, th]) in estimates {
            let r = reference(*seq);
            let p = (x - r[0]).hypot(y - r[1]);
            if p > d.position {
                d.position = p;
                d.worst = *seq;
            }
            d.heading = d.heading.max((th - r[2]).abs());
            d.last = p;
            d.rms += p * p;
        }
        d.rms = (d.rms / estimates.len() as f64).sqrt();
        d
    }
}

impl core::fmt::Display for Diff {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "position max {:.3e} m (step {}), rms {:.3e} m, last {:.3e} m; heading max {:.3e} rad",
            self.position, self.worst, self.rms, self.last, self.heading
        )
    }
}
