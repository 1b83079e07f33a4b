//! The Cortex-M4F firmware under emulation.
//!
//! Builds `locus-fw` for `thumbv7em-none-eabihf` (release), runs it under
//! `qemu-system-arm -machine mps2-an386 -cpu cortex-m4` with semihosting and
//! `-icount shift=6`, and checks:
//! * the emulated run's checksum of every step's state and its final belief,
//!   odometry pose and counts equal, bit for bit, this host's `f32` run of
//!   the same sequence (`locus_fw_app::run`, the same code and feature set);
//! * the flash and RAM footprint of the filter, models, decoder and CORDIC
//!   (see [`footprint`]) is under 32 KiB and 4 KiB;
//!
//! and prints the instructions per step (from the SysTick under icount,
//! calibrated against a block of `nop`s).
//!
//! A missing `qemu-system-arm` or `llvm-nm` is a failure, not a skip:
//! `scripts/test.sh` installs both.
//!
//! Run: `cargo test -p locus-fw-app --target x86_64-unknown-linux-gnu -- --nocapture`
//! (from `firmware/`).

use core::time::Duration;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::Instant;

use locus_fw_app::square_data;

const THUMB: &str = "thumbv7em-none-eabihf";
/// `-icount shift`: every instruction advances the virtual clock `2^6` ns.
const ICOUNT_SHIFT: u32 = 6;
/// Longest the emulated run may take (wall clock).
const QEMU_TIMEOUT: Duration = Duration::from_secs(120);

/// Flash budget of the counted parts (bytes).
const FLASH_BUDGET: u64 = 32 * 1024;
/// RAM budget of the counted parts (bytes).
const RAM_BUDGET: u64 = 4 * 1024;

/// The firmware workspace (`firmware/`).
fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Builds the release firmware once (own target directory, so the nested
/// cargo does not wait for the outer one's lock) and returns the ELF.
fn firmware_elf() -> &'static Path {
    static ELF: OnceLock<PathBuf> = OnceLock::new();
    ELF.get_or_init(|| {
        let target_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("firmware-build");
        let status = Command::new(env!("CARGO"))
            .current_dir(workspace())
            .args([
                "build",
                "--release",
                "--locked",
                "-p",
                "locus-fw",
                "--target",
                THUMB,
            ])
            .arg("--target-dir")
            .arg(&target_dir)
            .status()
            .expect("running cargo to build the firmware");
        assert!(status.success(), "building the firmware failed: {status}");
        let elf = target_dir.join(THUMB).join("release").join("locus-fw");
        assert!(elf.is_file(), "no firmware ELF at {}", elf.display());
        elf
    })
}

/// The firmware's output, `key value...` per line, and whether QEMU exited
/// with success.
struct Emulated {
    lines: BTreeMap<String, Vec<String>>,
    raw: String,
}

impl Emulated {
    fn value(&self, key: &str) -> &[String] {
        self.lines
            .get(key)
            .unwrap_or_else(|| panic!("no `{key}` in the firmware's output:\n{}", self.raw))
    }

    fn u64(&self, key: &str) -> u64 {
        self.value(key)[0]
            .parse()
            .unwrap_or_else(|e| panic!("`{key}`: {e}\n{}", self.raw))
    }

    fn f32_bits(&self, key: &str) -> u32 {
        let v = &self.value(key)[0];
        u32::from_str_radix(v.trim_start_matches("0x"), 16)
            .unwrap_or_else(|e| panic!("`{key}` {v}: {e}"))
    }
}

/// Runs the firmware under QEMU once.
fn emulated() -> &'static Emulated {
    static RUN: OnceLock<Emulated> = OnceLock::new();
    RUN.get_or_init(|| {
        let elf = firmware_elf();
        let mut child = Command::new("qemu-system-arm")
            .args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
            .args(["-semihosting-config", "enable=on,target=native"])
            .args(["-icount", &format!("shift={ICOUNT_SHIFT}")])
            .arg("-kernel")
            .arg(elf)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| {
                panic!(
                    "cannot start qemu-system-arm ({e}); install it (Debian: \
                     apt-get install qemu-system-arm; scripts/test.sh does)"
                )
            });
        // Drain both pipes on threads, so a full pipe cannot stall QEMU.
        let drain = |pipe: Option<Box<dyn Read + Send>>| {
            std::thread::spawn(move || {
                let mut text = Vec::new();
                if let Some(mut p) = pipe {
                    let _ = p.read_to_end(&mut text);
                }
                text
            })
        };
        let stdout = drain(
            child
                .stdout
                .take()
                .map(|p| Box::new(p) as Box<dyn Read + Send>),
        );
        let stderr = drain(
            child
                .stderr
                .take()
                .map(|p| Box::new(p) as Box<dyn Read + Send>),
        );
        let start = Instant::now();
        let status = loop {
            if let Some(status) = child.try_wait().expect("waiting for qemu") {
                break status;
            }
            if start.elapsed() > QEMU_TIMEOUT {
                let _ = child.kill();
                let _ = child.wait();
                panic!("the firmware did not finish within {QEMU_TIMEOUT:?} under QEMU");
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let out_stdout = stdout.join().expect("stdout reader");
        let out_stderr = stderr.join().expect("stderr reader");
        let raw = String::from_utf8_lossy(&out_stdout).into_owned();
        let err = String::from_utf8_lossy(&out_stderr);
        assert!(
            status.success(),
            "the firmware failed under QEMU ({status}):\n{raw}\n{err}"
        );
        assert!(
            raw.lines().any(|l| l.trim() == "done"),
            "no `done` line:\n{raw}"
        );
        let lines = raw
            .lines()
            .filter_map(|l| {
                let mut it = l.split_whitespace();
                let key = it.next()?.to_owned();
                Some((key, it.map(str::to_owned).collect()))
            })
            .collect();
        Emulated { lines, raw }
    })
}

#[test]
fn the_emulated_firmware_is_bit_identical_to_the_host_f32_run() {
    let host = locus_fw_app::run().expect("host run");
    let fw = emulated();
    let mut mismatches = Vec::new();
    for (name, value) in host.floats() {
        let bits = fw.f32_bits(name);
        if bits != value.to_bits() {
            mismatches.push(format!(
                "{name}: firmware 0x{bits:08x} ({}), host 0x{:08x} ({value})",
                f32::from_bits(bits),
                value.to_bits()
            ));
        }
    }
    for (name, value) in host.integers() {
        let v = fw.u64(name);
        if v != u64::from(value) {
            mismatches.push(format!("{name}: firmware {v}, host {value}"));
        }
    }
    assert!(
        mismatches.is_empty(),
        "emulated firmware and host differ:\n{}\nfirmware output:\n{}",
        mismatches.join("\n"),
        fw.raw
    );
    assert_eq!(host.steps as usize, square_data::STEPS);
    println!(
        "checksum 0x{:08x} over {} steps: firmware == host (bit-identical final belief, P, odometry pose)",
        host.checksum, host.steps
    );
}

#[test]
fn the_f32_filter_follows_the_simulators_f64_filter() {
    let host = locus_fw_app::run().expect("host run");
    let sim = square_data::SIM_ESTIMATE;
    let truth = square_data::TRUTH;
    for (i, (f32_value, f64_value)) in host.x.iter().zip(sim).enumerate() {
        let d = (f64::from(*f32_value) - f64_value).abs();
        assert!(
            d < 2e-3,
            "component {i}: f32 {f32_value} vs simulator f64 {f64_value}"
        );
    }
    let err = (f64::from(host.x[0]) - truth[0]).hypot(f64::from(host.x[1]) - truth[1]);
    let sd = f64::from(host.p[0] + host.p[4]).sqrt();
    assert!(
        err < 0.05 && err < 4.0 * sd,
        "position error {err} m, sd {sd} m"
    );
    assert!(host.corrections > 1000, "{host:?}");
    assert_eq!(host.invalid_transitions, 0);
}

/// Instructions from SysTick ticks: the firmware's calibration block of
/// `calibration_nops` `nop`s took `ticks_calibration` ticks.
fn instructions(fw: &Emulated, ticks: u64) -> f64 {
    let per_insn = (fw.u64("ticks_calibration") - fw.u64("ticks_bracket")) as f64
        / fw.u64("calibration_nops") as f64;
    ticks as f64 / per_insn
}

#[test]
fn instructions_per_step_under_icount() {
    let fw = emulated();
    let steps = fw.u64("steps");
    let per = |ticks: &str, n: u64| instructions(fw, fw.u64(ticks)) / n as f64;
    let ir_steps = fw.u64("steps_with_ir");
    // Readings the association found a wall for (only those are corrected).
    let associated = fw.u64("steps_associated");
    let max = |ticks: &str| instructions(fw, fw.u64(ticks));
    let rows = [
        (
            "quadrature decode (2 wheels x 8 samples)",
            per("ticks_decode", steps),
            None,
        ),
        (
            "EKF predict (DiffDrive)",
            per("ticks_predict", steps),
            Some(max("ticks_predict_max")),
        ),
        (
            "IR data association alone (steps with IR readings)",
            per("ticks_associate", ir_steps),
            Some(max("ticks_associate_max")),
        ),
        (
            "IR reading, Localiser::ir: association + correction",
            per("ticks_correct", associated),
            Some(max("ticks_correct_max")),
        ),
        (
            "  of which the correction (minus the association)",
            per("ticks_correct", associated) - per("ticks_associate_of_associated", associated),
            None,
        ),
        ("CORDIC odometry pose", per("ticks_odometry", steps), None),
        ("checksum (harness)", per("ticks_checksum", steps), None),
    ];
    println!("instructions per step (QEMU -icount shift={ICOUNT_SHIFT}, mean over the run):");
    println!("  {:<50} {:>8} {:>8}", "part", "mean", "max");
    for (what, n, max) in rows {
        let max = max.map_or_else(String::new, |m| format!("{m:.0}"));
        println!("  {what:<50} {n:>8.0} {max:>8}");
        assert!(
            n > 10.0 && n < 1.0e6,
            "{what}: {n} instructions is implausible"
        );
    }
    println!(
        "  ({steps} steps, {ir_steps} with IR readings, {associated} associated; max: the \
         largest single step; +-1 SysTick tick = +-0.6 instruction per bracket)"
    );
    // The calibration is 1.6 ticks per instruction: SysTick at the board's
    // 25 MHz (40 ns) against 64 ns per instruction.
    let per_insn = (fw.u64("ticks_calibration") - fw.u64("ticks_bracket")) as f64
        / fw.u64("calibration_nops") as f64;
    assert!(
        (per_insn - 1.6).abs() < 0.01,
        "{per_insn} ticks per instruction"
    );
}

/// Which part of the firmware a symbol belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Part {
    /// The filter, models, decoder and CORDIC, with the maths they need.
    Counted(&'static str),
    /// Everything else.
    Excluded(&'static str),
}

/// Classifies a demangled symbol name.
fn classify(name: &str) -> Part {
    let bare = name.trim_start_matches('<');
    let starts = |p: &str| bare.starts_with(p);
    if starts("locus_fw_app::square_data::") {
        return Part::Excluded("embedded data (square_data)");
    }
    if starts("locus_fw_app::Firmware::finish_step") {
        return Part::Excluded("checksum (harness)");
    }
    if starts("locus_fw_app::Firmware::associate") {
        // The binary's timing probe; a step associates inside
        // `Firmware::correct` (`Localiser::ir`), which is counted.
        return Part::Excluded("association probe (harness timing only)");
    }
    if starts("locus_fw_app::link::") {
        return Part::Counted(
            "the link: LinkRobot (telemetry packet, CRC, COBS; command frames, receiver)",
        );
    }
    if starts("locus_fw_link::Line::") || starts("locus_fw_link::uart::") {
        return Part::Counted("the link: UART driver, pacing (locus-fw-link)");
    }
    // `Telemetry::encode`'s finiteness check over the reading and the
    // beams (`iter().chain(..)`), left out of line; `locus-fw` has none.
    if starts("locus_link::") || bare.contains("core..iter..adapters..chain..Chain") {
        return Part::Counted("the link: locus_link (out of line)");
    }
    if starts("locus_fw_app::Firmware::") {
        return Part::Counted(
            "locus_fw_app::Firmware step functions (inlined filter, models, decoder, CORDIC)",
        );
    }
    if starts("locus_core::") {
        return Part::Counted("locus_core (out of line)");
    }
    if starts("locus_models::") || starts("locus_odometry::") {
        return Part::Counted("locus_models / locus_odometry (out of line)");
    }
    if starts("nalgebra::") || starts("simba::") || starts("num_traits::") {
        return Part::Counted("nalgebra / simba (out of line)");
    }
    if starts("libm::") {
        return Part::Counted("libm");
    }
    if starts("compiler_builtins::")
        || starts("__aeabi_")
        || starts("__divmoddi4")
        || starts("__udivmoddi4")
        || starts("__mul")
        || starts("__ash")
        || starts("__lsr")
        || starts("__clz")
        || starts("__divdi3")
        || starts("__udivdi3")
        || starts("__muldi3")
        || starts("__multi3")
        || starts("__divti3")
        || starts("__udivti3")
        || starts("__modti3")
        || starts("__umodti3")
        || starts("__fix")
        || starts("__float")
        || starts("__extend")
        || starts("__trunc")
        || starts("__add")
        || starts("__sub")
        || starts("__div")
        || starts("__cmp")
        || starts("__eq")
        || starts("__ne")
        || starts("__lt")
        || starts("__le")
        || starts("__gt")
        || starts("__ge")
        || starts("__un")
        || starts("memcpy")
        || starts("memset")
        || starts("memmove")
        || starts("memcmp")
    {
        return Part::Counted("compiler runtime (soft f64, 64/128-bit integer, mem*): all of it");
    }
    if bare.starts_with(".Lanon.") {
        return Part::Counted("anonymous constants: all of them (not attributable by name)");
    }
    if starts("core::fmt")
        || starts("core::num::flt2dec")
        || starts("core::num::bignum")
        || starts("core::num::fmt")
        || bare.contains("as core::fmt::")
        || bare.contains("core..fmt..")
        || starts("core::num::bignum")
    {
        return Part::Excluded("formatting (core::fmt, float printing)");
    }
    if starts("cortex_m_semihosting") {
        return Part::Excluded("semihosting");
    }
    if starts("core::panicking")
        || starts("__rustc::rust_begin_unwind")
        || starts("core::slice::index")
        || starts("core::option::")
        || starts("core::result::unwrap_failed")
        || starts("rust_begin_unwind")
        || starts("locus_fw::panic")
        || starts("locus_fw_link::panic")
        || starts("locus_fw_link::fail")
        || starts("core::cell::panic")
    {
        return Part::Excluded("panic paths");
    }
    if starts("locus_fw::")
        || starts("locus_fw_link::")
        || starts("main")
        || starts("Reset")
        || starts("__INTERRUPTS")
        || starts("__RESET_VECTOR")
        || starts("__EXCEPTIONS")
        || starts("DefaultHandler")
        || starts("HardFault")
        || starts("DefaultPreInit")
        || starts("__pre_init")
        || starts("cortex_m_rt")
        || starts("cortex_m::")
        || starts("__cortex_m_rt")
    {
        return Part::Excluded("harness: startup, vectors, main loop, timing, stack painting");
    }
    Part::Excluded("other")
}

/// One symbol of `llvm-nm --print-size`.
struct Symbol {
    size: u64,
    kind: char,
    name: String,
}

fn llvm_tool(name: &str) -> PathBuf {
    let out = Command::new("rustc")
        .args(["--print", "sysroot"])
        .output()
        .expect("rustc --print sysroot");
    let sysroot = String::from_utf8(out.stdout).expect("utf-8 sysroot");
    let host = Command::new("rustc")
        .arg("-vV")
        .output()
        .expect("rustc -vV");
    let host = String::from_utf8(host.stdout).expect("utf-8");
    let triple = host
        .lines()
        .find_map(|l| l.strip_prefix("host: "))
        .expect("host triple");
    let tool = Path::new(sysroot.trim())
        .join("lib/rustlib")
        .join(triple)
        .join("bin")
        .join(name);
    assert!(
        tool.is_file(),
        "{} is missing: `rustup component add llvm-tools` (scripts/test.sh does)",
        tool.display()
    );
    tool
}

fn symbols(elf: &Path) -> Vec<Symbol> {
    let out = Command::new(llvm_tool("llvm-nm"))
        .args(["--demangle", "--print-size", "--size-sort"])
        .arg(elf)
        .output()
        .expect("llvm-nm");
    assert!(out.status.success(), "llvm-nm failed");
    String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .filter_map(|l| {
            let mut it = l.splitn(4, ' ');
            let _addr = it.next()?;
            let size = u64::from_str_radix(it.next()?, 16).ok()?;
            let kind = it.next()?.chars().next()?;
            Some(Symbol {
                size,
                kind,
                name: it.next()?.to_owned(),
            })
        })
        .collect()
}

/// Flash and RAM of the filter, models, decoder and CORDIC in the release
/// firmware.
///
/// **Flash** is the sum of the sizes of the ELF's code and read-only data
/// symbols (`llvm-nm --print-size`, kinds t/T/r/R) classified by
/// [`classify`] as counted: the `Firmware` step functions (`new`, `decode`,
/// `predict`, `correct`, `odometry_step`, each `#[inline(never)]`, into
/// which the localiser, the models, the decoder and the CORDIC are inlined), whatever of
/// `locus_core`, `locus_models`, `locus_odometry`, `nalgebra`/`simba` and
/// `libm` stays out of line, **all** of the compiler runtime (soft-float
/// `f64`, 64-bit division: also used by the formatting, counted in full) and
/// **all** anonymous constants (`.Lanon.*`, which cannot be attributed by
/// name; they include the format strings). Excluded: the embedded data
/// (`square_data`), semihosting, `core::fmt` and float printing, panic
/// paths, the harness (startup, vector table, `main`, timing, stack
/// painting), the association probe `Firmware::associate` (the binary times
/// it alone; the step associates inside `Firmware::correct`) and the
/// checksum.
///
/// **RAM** is the stack high-water mark the firmware measured (painted stack
/// below `main`, from reset to the end of the run, before any printing; it
/// includes the `Firmware` state in `main`'s frame, the run's timing
/// counters and cortex-m-rt's reset frame) plus `.data` and `.bss`
/// (kinds d/D/b/B symbols: cortex-m's `TAKEN` flag and semihosting's
/// handle, counted in full). No heap.
#[test]
fn footprint_of_the_filter_models_decoder_and_cordic() {
    let elf = firmware_elf();
    let (flash, ram_static) = flash_by_part(elf);
    let fw = emulated();
    let stack = fw.u64("stack_high_water");
    let ram = stack + ram_static;
    println!(
        "FLASH counted: {flash} bytes ({:.1} KiB) of a {FLASH_BUDGET}-byte budget",
        flash as f64 / 1024.0
    );
    println!(
        "RAM counted: {ram} bytes = stack high-water {stack} + .data/.bss {ram_static} \
         (Firmware state {} bytes, inside the stack figure) of a {RAM_BUDGET}-byte budget",
        fw.u64("firmware_state_bytes")
    );
    assert!(
        flash > 4096,
        "implausibly small flash figure {flash}: classification broken?"
    );
    assert!(
        flash < FLASH_BUDGET,
        "flash {flash} bytes >= {FLASH_BUDGET}"
    );
    assert!(ram < RAM_BUDGET, "RAM {ram} bytes >= {RAM_BUDGET}");
}

/// The flash of `locus-fw-link`, the firmware as a robot on the link
/// (`src/bin/locus-fw-link`), counted as for `locus-fw`
/// ([`footprint_of_the_filter_models_decoder_and_cordic`]) plus the link:
/// `LinkRobot::{telemetry_frame, push}` (each `#[inline(never)]`; the
/// telemetry encoding, CRC-32, COBS framing, command decoding and the
/// receiver are inlined into them), the UART driver and the pacing
/// (`Line::{send, wait_for, paced}`), whatever of `locus_link` stays out of
/// line; the CRC-32 table (1 KiB) is one of the anonymous constants. Its
/// stack high-water mark needs a host on the line: the host-workspace test
/// `locus-net/tests/firmware_link.rs` prints and bounds it.
#[test]
fn footprint_of_the_link_firmware() {
    let elf = firmware_elf().with_file_name("locus-fw-link");
    assert!(elf.is_file(), "no link firmware ELF at {}", elf.display());
    let (flash, ram_static) = flash_by_part(&elf);
    println!(
        "FLASH counted: {flash} bytes ({:.1} KiB) of a {FLASH_BUDGET}-byte budget; \
         .data/.bss {ram_static} bytes",
        flash as f64 / 1024.0
    );
    assert!(
        flash > 4096,
        "implausibly small flash figure {flash}: classification broken?"
    );
    assert!(
        flash < FLASH_BUDGET,
        "flash {flash} bytes >= {FLASH_BUDGET}"
    );
}

/// Prints the flash of `elf` by part and its largest counted symbols;
/// returns the counted flash and the `.data`/`.bss` bytes. Fails on a sized
/// symbol [`classify`] does not know.
fn flash_by_part(elf: &Path) -> (u64, u64) {
    let syms = symbols(elf);
    let mut parts: BTreeMap<Part, (u64, usize)> = BTreeMap::new();
    let mut ram_static = 0u64;
    let mut counted_symbols = Vec::new();
    for s in &syms {
        match s.kind {
            't' | 'T' | 'r' | 'R' => {
                let part = classify(&s.name);
                let e = parts.entry(part).or_default();
                e.0 += s.size;
                e.1 += 1;
                if matches!(part, Part::Counted(_)) {
                    counted_symbols.push((s.size, s.name.as_str()));
                }
            }
            'd' | 'D' | 'b' | 'B' => ram_static += s.size,
            _ => {}
        }
    }
    counted_symbols.sort_unstable_by(|a, b| b.cmp(a));
    let flash: u64 = parts
        .iter()
        .filter(|(p, _)| matches!(p, Part::Counted(_)))
        .map(|(_, (size, _))| size)
        .sum();
    println!(
        "flash by part (bytes, symbols), release firmware {}:",
        elf.display()
    );
    for (part, (size, n)) in &parts {
        let (tag, what) = match part {
            Part::Counted(w) => ("counted ", w),
            Part::Excluded(w) => ("excluded", w),
        };
        println!("  {tag} {size:>7} {n:>4}  {what}");
    }
    println!("largest counted symbols:");
    for (size, name) in counted_symbols.iter().take(25) {
        println!("  {size:>6}  {name}");
    }
    let unclassified: Vec<_> = syms
        .iter()
        .filter(|s| {
            s.size > 0
                && matches!(s.kind, 't' | 'T' | 'r' | 'R')
                && classify(&s.name) == Part::Excluded("other")
        })
        .map(|s| format!("{} {}", s.size, s.name))
        .collect();
    assert!(
        unclassified.is_empty(),
        "sized symbols the footprint does not classify: extend `classify`:\n{}",
        unclassified.join("\n")
    );
    (flash, ram_static)
}
