//! Hostile telemetry with valid CRCs: a sequence number far ahead, an
//! encoder count that jumps, a time stamp that jumps, IR readings no sensor
//! gives, through real UDP sockets on loopback and, as a property over
//! arbitrary packets, through the host's receive path. The host never
//! stalls, keeps a finite and plausible belief, and counts every packet in
//! exactly one class. And the simulated robot clamps absurd commands.

use core::time::Duration;
use std::net::UdpSocket;
use std::thread;

use locus_link::receiver::{MAX_JUMP, RESYNC_AFTER};
use locus_link::{CommandPacket, MAX_PACKET, Telemetry};
use locus_net::host::{Dropped, Host, HostConfig, HostReport, Outcome, run_host};
use locus_net::plausible::Implausible;
use locus_odometry::Wheel;
use locus_sim::closed_loop::SquareConfig;
use locus_simlink::{RobotConfig, host_config, run_robot};
use proptest::prelude::*;

/// Telemetry period of the scripted robot (us).
const PERIOD_US: u64 = 10_000;

fn config() -> HostConfig {
    HostConfig {
        use_ir: false,
        ..host_config(&SquareConfig::default())
    }
}

/// Counts per 10 ms at 0.1 m/s on the square robot's wheels.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
fn counts_per_step() -> u32 {
    let s = SquareConfig::default();
    let q = Wheel::new(s.encoder_lines, s.encoder_gear, s.wheel_radius).quantum();
    (0.001 / q).round() as u32
}

/// Packet `k` of a robot driving straight at 0.1 m/s.
fn straight(k: u32) -> Telemetry {
    let mut t = Telemetry::new(k, u64::from(k) * PERIOD_US);
    t.counts = [k * counts_per_step(); 2];
    t
}

fn encode(t: &Telemetry) -> Vec<u8> {
    let mut out = [0u8; MAX_PACKET];
    let n = t.encode(&mut out).unwrap();
    out[..n].to_vec()
}

/// A scripted robot on loopback: waits for the host's hello, then sends
/// `packets` 1 ms apart and falls silent; the host runs until quiet.
fn run_scripted(packets: Vec<Vec<u8>>) -> HostReport {
    let robot = UdpSocket::bind("127.0.0.1:0").unwrap();
    let robot_addr = robot.local_addr().unwrap();
    let host = UdpSocket::bind("127.0.0.1:0").unwrap();
    let script = thread::spawn(move || {
        let mut buf = [0u8; 64];
        let (_, host_addr) = robot.recv_from(&mut buf).unwrap();
        for p in &packets {
            robot.send_to(p, host_addr).unwrap();
            thread::sleep(Duration::from_millis(1));
        }
    });
    let report = run_host(&host, robot_addr, &config(), &mut |_| {}).unwrap();
    script.join().unwrap();
    report
}

fn clean_run() -> HostReport {
    run_scripted((0..200).map(|k| encode(&straight(k))).collect())
}

#[test]
fn a_sequence_jump_is_suspect_and_costs_nothing() {
    let clean = clean_run();
    let mut packets: Vec<_> = (0..200).map(|k| encode(&straight(k))).collect();
    // 2^31 - 1 ahead of the newest: once counted as 2 147 483 646 lost,
    // predicted through (38 s at 100 % CPU), and every later packet late.
    let mut jump = straight(99);
    jump.sequence = 99 + ((1 << 31) - 1);
    packets.insert(100, encode(&jump));
    let report = run_scripted(packets);
    let c = report.counters;
    assert_eq!((c.suspect, c.lost, c.late, c.applied), (1, 0, 0, 200));
    assert_eq!(report.estimates, clean.estimates);
}

#[test]
fn an_encoder_jump_is_refused_and_the_belief_kept() {
    let clean = clean_run();
    let mut packets: Vec<Vec<u8>> = Vec::new();
    for k in 0..200 {
        let mut t = straight(k);
        if k == 100 {
            // Once: the estimate went to x = 866 km for good.
            t.counts[0] = t.counts[0].wrapping_add((1 << 31) - 1);
        }
        packets.push(encode(&t));
    }
    let report = run_scripted(packets);
    let c = report.counters;
    assert_eq!((c.implausible, c.applied), (1, 199));
    // Counts are cumulative: the next packet carries the refused travel,
    // so the final estimate is the clean run's.
    let last = |r: &HostReport| r.estimates.last().unwrap().1;
    assert_eq!(last(&report), last(&clean));
}

#[test]
fn a_time_stamp_jump_cannot_make_a_travel_plausible() {
    let mut host = Host::new(&config()).unwrap();
    for k in 0..10 {
        assert!(matches!(
            host.receive(&encode(&straight(k)), 0.0),
            Outcome::Applied(_)
        ));
    }
    let before = *host.belief();
    let mut t = straight(10);
    t.timestamp_us = 1_000_000 * 1_000_000;
    t.counts[0] = t.counts[0].wrapping_add(1 << 30);
    assert!(matches!(
        host.receive(&encode(&t), 0.0),
        Outcome::Dropped(Dropped::Implausible(Implausible::TimeGap { .. }))
    ));
    assert_eq!(*host.belief(), before);
    let mut t = straight(11);
    t.ir = Some([-0.2, 0.3]);
    assert!(matches!(
        host.receive(&encode(&t), 0.0),
        Outcome::Dropped(Dropped::Implausible(Implausible::IrReading { .. }))
    ));
    assert!(matches!(
        host.receive(&encode(&straight(12)), 0.0),
        Outcome::Applied(_)
    ));
}

#[test]
fn a_robot_whose_counters_restart_is_followed_not_locked_out() {
    let mut host = Host::new(&config()).unwrap();
    for k in 0..10 {
        host.receive(&encode(&straight(k)), 0.0);
    }
    // The robot restarts: sequence, time and counts from 0 again, far
    // behind. The receiver re-anchors after RESYNC_AFTER in a row.
    let mut applied_after = 0;
    for k in 0..RESYNC_AFTER + 5 {
        let mut t = straight(k);
        t.sequence = k.wrapping_sub(5000);
        if let Outcome::Applied(_) = host.receive(&encode(&t), 0.0) {
            applied_after += 1;
        }
    }
    assert_eq!(applied_after, 6);
    // The counters alone restart (same sequence): refused, then followed.
    let mut host = Host::new(&config()).unwrap();
    for k in 0..10 {
        host.receive(&encode(&straight(k)), 0.0);
    }
    let mut outcomes = Vec::new();
    for k in 10..10 + RESYNC_AFTER + 5 {
        let mut t = straight(k);
        t.counts = [(k - 10) * counts_per_step() + (1 << 31); 2];
        outcomes.push(matches!(
            host.receive(&encode(&t), 0.0),
            Outcome::Applied(_)
        ));
    }
    let applied = outcomes.iter().filter(|a| **a).count();
    assert_eq!(applied, 5, "{outcomes:?}");
    assert_eq!(host.counters().resync, 1);
}

#[test]
fn the_robot_clamps_an_absurd_command_and_keeps_running() {
    let robot = UdpSocket::bind("127.0.0.1:0").unwrap();
    let robot_addr = robot.local_addr().unwrap();
    let cfg = RobotConfig {
        time_scale: 20.0,
        idle_exit: 0.5,
        ..RobotConfig::default()
    };
    let run = thread::spawn(move || run_robot(&robot, &cfg));
    let host = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut out = [0u8; 64];
    for sequence in 0..20 {
        let c = CommandPacket {
            sequence,
            ack: u32::MAX,
            right: 3e38,
            left: -3e38,
        };
        let n = c.encode(&mut out).unwrap();
        host.send_to(&out[..n], robot_addr).unwrap();
        thread::sleep(Duration::from_millis(2));
    }
    let report = run.join().unwrap().expect("the robot keeps running");
    assert!(report.clamped >= 1, "{}", report.clamped);
    assert!(
        report
            .truth
            .iter()
            .all(|(_, p)| p.x.is_finite() && p.y.is_finite())
    );
}

#[test]
fn every_robot_timing_and_limit_flag_is_checked() {
    for bad in [f64::NAN, f64::INFINITY, -1.0, 0.0] {
        for i in 0..4 {
            let mut cfg = RobotConfig::default();
            *[
                &mut cfg.time_scale,
                &mut cfg.watchdog,
                &mut cfg.idle_exit,
                &mut cfg.max_wheel_speed,
            ][i] = bad;
            assert!(cfg.validate().is_err(), "field {i} = {bad}");
        }
    }
    let cfg = RobotConfig {
        watchdog: 1.0,
        idle_exit: 0.5,
        ..RobotConfig::default()
    };
    assert!(cfg.validate().is_err(), "idle_exit below the watchdog");
    assert!(RobotConfig::default().validate().is_ok());
}

/// One fuzzed packet: a plausible step or something hostile.
#[derive(Debug, Clone)]
enum Fuzz {
    /// The next packet of a robot moving plausibly.
    Step {
        counts: [i16; 2],
        ir: Option<[f32; 2]>,
    },
    /// Any telemetry with a valid CRC.
    Any {
        sequence: u32,
        timestamp_us: u64,
        counts: [u32; 2],
        ir: Option<[f32; 2]>,
    },
    /// Any bytes.
    Bytes(Vec<u8>),
}

fn finite_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        -1e3f32..1e3,
        any::<f32>().prop_filter("finite", |v| v.is_finite())
    ]
}

fn fuzz() -> impl Strategy<Value = Fuzz> {
    let ir = proptest::option::of([finite_f32(), finite_f32()]);
    prop_oneof![
        4 => ([-8i16..8, -8i16..8], proptest::option::of([0.05f32..0.8, 0.05f32..0.8]))
            .prop_map(|(counts, ir)| Fuzz::Step { counts, ir }),
        2 => (any::<u32>(), any::<u64>(), any::<[u32; 2]>(), ir)
            .prop_map(|(sequence, timestamp_us, counts, ir)| Fuzz::Any { sequence, timestamp_us, counts, ir }),
        1 => proptest::collection::vec(any::<u8>(), 0..64).prop_map(Fuzz::Bytes),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn the_receive_path_never_stalls_or_corrupts_the_belief(
        packets in proptest::collection::vec(fuzz(), 1..80),
    ) {
        let cfg = HostConfig { use_ir: true, ..config() };
        let start = cfg.localiser.start;
        let mut host = Host::new(&cfg).unwrap();
        let (mut sequence, mut time, mut counts) = (0u32, 0u64, [0u32; 2]);
        let mut accepted_time = 0.0;
        let mut last_applied_time: Option<f64> = None;
        for (fed, p) in (1u64..).zip(&packets) {
            let bytes = match p {
                Fuzz::Step { counts: d, ir } => {
                    let mut t = Telemetry::new(sequence, time);
                    counts = [counts[0].wrapping_add_signed(d[0].into()), counts[1].wrapping_add_signed(d[1].into())];
                    t.counts = counts;
                    t.ir = *ir;
                    sequence = sequence.wrapping_add(1);
                    time += PERIOD_US;
                    encode(&t)
                }
                Fuzz::Any { sequence, timestamp_us, counts, ir } => {
                    let mut t = Telemetry::new(*sequence, *timestamp_us);
                    t.counts = *counts;
                    t.ir = *ir;
                    encode(&t)
                }
                Fuzz::Bytes(b) => b.clone(),
            };
            if let Outcome::Applied(step) = host.receive(&bytes, 0.0) {
                prop_assert!(step.skipped <= MAX_JUMP);
                if let Some(prev) = last_applied_time {
                    accepted_time += (step.robot_time - prev).max(0.0);
                }
                last_applied_time = Some(step.robot_time);
            }
            let b = host.belief();
            prop_assert!(b.x.iter().chain(b.p.iter()).all(|v| v.is_finite()), "{b:?}");
            // Plausible: no farther than the top speed over the accepted
            // robot time, plus the arena (corrections stay near the walls).
            let moved = ((b.x[0] - start[0]).powi(2) + (b.x[1] - start[1]).powi(2)).sqrt();
            prop_assert!(moved <= cfg.limits.max_speed * accepted_time + 5.0, "moved {moved} m in {accepted_time} s");
            prop_assert_eq!(host.counters().received(), fed);
        }
    }
}
