//! The robot link over a byte stream on real pseudo-terminals: the robot
//! on one pty, the host on another, and a "cable" between their master
//! ends (two relay threads). Clean, the `square` run matches the
//! in-process run as over UDP; with the cable damaging telemetry frames
//! (a flipped bit, a lost byte, a cut frame, garbage between frames), every
//! damage shows up once in the counters and nothing else is lost.

extern crate alloc;

use alloc::sync::Arc;
use core::sync::atomic::{AtomicBool, Ordering};
use core::time::Duration;
use std::io::{Read, Write};
use std::thread::{self, JoinHandle};

use locus_link::framing::{FrameDecoder, MAX_FRAME, encode_frame};
use locus_net::host::{HostReport, run_host_over};
use locus_net::transport::Serial;
use locus_sim::closed_loop::{SquareConfig, run_square};
use locus_simlink::{RobotConfig, RobotReport, host_config, run_robot_over};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serialport::{SerialPort, TTYPort};

const SEED: u64 = 1;

/// The two runs take turns: each keeps four threads busy in real time, and
/// a 2-core test machine would starve one run with the other.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
/// Robot seconds per wall second: a 10 ms tick is 1 ms of wall time, room
/// for two relays and a pty's line discipline on a loaded machine (the
/// 141 s run takes about 14 s).
const TIME_SCALE: f64 = 10.0;

/// What the cable did to the telemetry frames.
#[derive(Debug, Default, Clone, Copy)]
struct Damage {
    /// Frames with one bit of the packet flipped (re-framed: a CRC error).
    flipped: u64,
    /// Frames with one byte lost.
    lost_byte: u64,
    /// Frames cut short (then a delimiter).
    cut: u64,
    /// Runs of garbage bytes sent between two frames.
    garbage: u64,
}

impl Damage {
    /// Telemetry packets that cannot arrive.
    fn packets(&self) -> u64 {
        self.flipped + self.lost_byte + self.cut
    }
    /// Frames the receiving side must drop, at framing or packet level.
    fn frames(&self) -> u64 {
        self.packets() + self.garbage
    }
}

/// A relay thread copying `from` to `to` until `stop`; with `damage`, it
/// re-frames each telemetry packet and damages some (seeded).
fn relay(
    mut from: TTYPort,
    mut to: TTYPort,
    stop: Arc<AtomicBool>,
    damage: bool,
) -> JoinHandle<Damage> {
    thread::spawn(move || {
        let mut rng = StdRng::seed_from_u64(11);
        let mut done = Damage::default();
        let mut decoder = FrameDecoder::<MAX_FRAME>::new();
        let mut buf = [0u8; 512];
        let mut frame = [0u8; MAX_FRAME];
        let mut frames = 0u64;
        from.set_timeout(Duration::from_millis(5)).unwrap();
        while !stop.load(Ordering::Relaxed) {
            let n = match from.read(&mut buf) {
                Ok(n) => n,
                Err(_) => continue,
            };
            // A write fails only once the far end has closed (its run is
            // over): what it would have read is of no use then.
            if !damage {
                let _ = to.write_all(&buf[..n]);
                continue;
            }
            let mut rest = &buf[..n];
            while !rest.is_empty() {
                let (used, event) = decoder.feed(rest);
                rest = &rest[used..];
                let Some(Ok(packet)) = event else { continue };
                let mut packet = packet.to_vec();
                frames += 1;
                // The first frames pass intact (the handshake).
                let roll: f64 = if frames > 5 { rng.random() } else { 1.0 };
                let mut out: Vec<u8>;
                if roll < 0.03 {
                    let i = rng.random_range(0..packet.len());
                    packet[i] ^= 1 << rng.random_range(0..8);
                    done.flipped += 1;
                    out = framed(&packet, &mut frame);
                } else if roll < 0.06 {
                    out = framed(&packet, &mut frame);
                    // Not a delimiter: one of the COBS bytes inside.
                    out.remove(rng.random_range(1..out.len() - 1));
                    done.lost_byte += 1;
                } else if roll < 0.08 {
                    out = framed(&packet, &mut frame);
                    let keep = rng.random_range(2..out.len() - 2);
                    out.truncate(keep);
                    out.push(0);
                    done.cut += 1;
                } else if roll < 0.10 {
                    out = (0..rng.random_range(1..20))
                        .map(|_| rng.random_range(1..=255u8))
                        .collect();
                    out.extend(framed(&packet, &mut frame));
                    done.garbage += 1;
                } else {
                    out = framed(&packet, &mut frame);
                }
                let _ = to.write_all(&out);
            }
        }
        done
    })
}

fn framed(packet: &[u8], frame: &mut [u8; MAX_FRAME]) -> Vec<u8> {
    let n = encode_frame(packet, frame).unwrap();
    frame[..n].to_vec()
}

/// Runs robot and host over two pty pairs joined by relays; with `damage`,
/// the robot-to-host relay damages telemetry. Also returns the sequence of
/// the telemetry packet whose estimate completed the laps (the first the
/// host sent no command for), if it came.
fn run_serial(damage: bool) -> (RobotReport, HostReport, Damage, Option<u32>) {
    let _turn = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (robot_master, robot_end) = TTYPort::pair().expect("pty pair");
    let (host_master, host_end) = TTYPort::pair().expect("pty pair");
    let stop = Arc::new(AtomicBool::new(false));
    let up = relay(
        robot_master.try_clone_native().unwrap(),
        host_master.try_clone_native().unwrap(),
        stop.clone(),
        damage,
    );
    let down = relay(host_master, robot_master, stop.clone(), false);
    let robot_cfg = RobotConfig {
        square: SquareConfig::default(),
        seed: SEED,
        time_scale: TIME_SCALE,
        // 1 s of wall time without a command before the robot gives up: a
        // host stalled that long by a busy machine is a slow host, not a
        // finished run.
        idle_exit: 10.0,
        ..RobotConfig::default()
    };
    // The robot's end of the line stays open until the relays have
    // stopped. A pty has no transmit queue (the robot's drain returns at
    // once): its last frames wait in the master for the relay to read them.
    // Once the slave is closed, a poll of the master reports a hangup
    // along with the data, and serialport's read then fails without
    // reading, so those frames would never reach the host, which is still
    // listening (it ends only after `quiet` without telemetry). A UART
    // sends what was written whatever its writer does next.
    let robot = thread::spawn(move || {
        let port: Box<dyn SerialPort> = Box::new(robot_end);
        let mut link = Serial::new(port);
        let report = run_robot_over(&mut link, &robot_cfg).unwrap();
        (report, link)
    });
    let port: Box<dyn SerialPort> = Box::new(host_end);
    let mut laps_end = None;
    let host = run_host_over(
        &mut Serial::new(port),
        &host_config(&SquareConfig::default()),
        &mut |step| {
            if step.command.is_none() {
                laps_end.get_or_insert(step.sequence);
            }
        },
    )
    .unwrap();
    let (robot, robot_end) = robot.join().unwrap();
    stop.store(true, Ordering::Relaxed);
    let damage = up.join().unwrap();
    down.join().unwrap();
    drop(robot_end);
    (robot, host, damage, laps_end)
}

/// Position RMSE (m) of the host's estimates against the robot's truth,
/// over the packets after the first up to sequence `last`.
#[allow(clippy::cast_precision_loss)]
fn rmse(robot: &RobotReport, host: &HostReport, last: u32) -> f64 {
    let truth: std::collections::HashMap<u32, _> = robot.truth.iter().copied().collect();
    let (mut sum, mut n) = (0.0, 0usize);
    for (seq, x) in host
        .estimates
        .iter()
        .filter(|(s, _)| (1..=last).contains(s))
    {
        let t = truth[seq];
        sum += (t.x - x[0]).powi(2) + (t.y - x[1]).powi(2);
        n += 1;
    }
    (sum / n as f64).sqrt()
}

#[test]
fn square_over_a_serial_link_matches_the_in_process_run() {
    let in_process = run_square(&SquareConfig::default(), SEED, &mut |_| {}).unwrap();
    let (robot, host, _, laps_end) = run_serial(false);
    // The same span as the in-process run, which ends on the estimate that
    // completes the laps. Over the link the robot then stands still until
    // `idle_exit` (about 1000 more packets, all at the final error, up to
    // twice the run's RMSE), which alone would lift the RMSE by 3 to 8 per
    // cent.
    let link = rmse(
        &robot,
        &host,
        laps_end.expect("the host completed its laps"),
    );
    let c = host.counters;
    println!(
        "in-process RMSE {:.3} cm, serial RMSE {:.3} cm; {} packets; {:?}; framing {:?}; lockstep {}/{}",
        in_process.position_rmse * 100.0,
        link * 100.0,
        robot.sent,
        c,
        host.framing,
        robot.on_time,
        robot.ticks,
    );
    assert_eq!(host.laps, 2);
    assert_eq!(c.applied, robot.sent);
    assert_eq!(
        (c.lost, c.duplicate, c.late, c.corrupt, c.malformed),
        (0, 0, 0, 0, 0)
    );
    assert_eq!(host.framing.dropped(), 0);
    assert_eq!(robot.framing.dropped(), 0);
    assert!(
        (link - in_process.position_rmse).abs() <= 0.10 * in_process.position_rmse,
        "serial {link} m vs in-process {} m",
        in_process.position_rmse
    );
}

#[test]
fn line_damage_is_counted_once_and_costs_only_the_frames_it_touches() {
    let (robot, host, damage, _) = run_serial(true);
    let c = host.counters;
    let f = host.framing;
    println!(
        "injected {damage:?}; host {c:?}; framing {f:?}; {} sent",
        robot.sent
    );
    assert!(damage.packets() >= 10 && damage.garbage >= 3, "{damage:?}");
    // Every damaged frame is dropped exactly once, by the framing (COBS)
    // or by the packet decoder (CRC, length).
    assert_eq!(f.dropped() + c.corrupt + c.malformed, damage.frames());
    // Every other telemetry packet arrives.
    assert_eq!(c.applied + damage.packets(), robot.sent);
    assert_eq!(
        (c.duplicate, c.late, c.suspect, c.implausible),
        (0, 0, 0, 0)
    );
    assert_eq!(host.laps, 2);
}
