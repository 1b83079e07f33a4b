//! The robot link on real UDP sockets on loopback: the `square` run through
//! the link against the in-process run, and the same run through a
//! fault-injecting proxy (loss, duplicates, reordering, corruption) whose
//! injections the host's counters must match exactly; the robot's
//! watchdog; the host's configuration check. The robot endpoint is the
//! simulator's (`locus_simlink`).

extern crate alloc;

use alloc::sync::Arc;
use core::net::SocketAddr;
use core::sync::atomic::{AtomicBool, Ordering};
use core::time::Duration;
use std::collections::HashMap;
use std::net::UdpSocket;
use std::thread;

use locus_link::Telemetry;
use locus_net::host::{HostConfig, HostReport, run_host};
use locus_sim::closed_loop::{SquareConfig, run_square};
use locus_simlink::{RobotConfig, RobotReport, host_config, run_robot};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

const SEED: u64 = 1;
/// Robot seconds per wall second: the 141 s run takes about 5.6 s.
const TIME_SCALE: f64 = 25.0;

fn bind() -> UdpSocket {
    UdpSocket::bind("127.0.0.1:0").unwrap()
}

/// Position RMSE (m) of the host's estimates against the robot's truth,
/// over the applied packets after the first.
#[allow(clippy::cast_precision_loss)]
fn rmse(robot: &RobotReport, host: &HostReport) -> f64 {
    let truth: HashMap<u32, _> = robot.truth.iter().copied().collect();
    let (mut sum, mut n) = (0.0, 0usize);
    for (seq, x) in host.estimates.iter().filter(|(s, _)| *s > 0) {
        let t = truth[seq];
        sum += (t.x - x[0]).powi(2) + (t.y - x[1]).powi(2);
        n += 1;
    }
    (sum / n as f64).sqrt()
}

/// Runs robot and host, the host talking to `host_peer` (the robot, or a
/// proxy in front of it).
fn run_link(robot_socket: UdpSocket, host_peer: Option<SocketAddr>) -> (RobotReport, HostReport) {
    let robot_addr = robot_socket.local_addr().unwrap();
    let robot_cfg = RobotConfig {
        square: SquareConfig::default(),
        seed: SEED,
        time_scale: TIME_SCALE,
        ..RobotConfig::default()
    };
    let robot = thread::spawn(move || run_robot(&robot_socket, &robot_cfg).unwrap());
    let host_socket = bind();
    let host = run_host(
        &host_socket,
        host_peer.unwrap_or(robot_addr),
        &host_config(&SquareConfig::default()),
        &mut |_| {},
    )
    .unwrap();
    (robot.join().unwrap(), host)
}

#[test]
fn square_through_the_link_matches_the_in_process_run() {
    let in_process = run_square(&SquareConfig::default(), SEED, &mut |_| {}).unwrap();
    let (robot, host) = run_link(bind(), None);
    let link = rmse(&robot, &host);
    let c = host.counters;
    println!(
        "in-process RMSE {:.3} cm, link RMSE {:.3} cm; {} packets sent, {:?}; lockstep {}/{} ticks; watchdog stops {}; clock {:?}",
        in_process.position_rmse * 100.0,
        link * 100.0,
        robot.sent,
        c,
        robot.on_time,
        robot.ticks,
        robot.watchdog_stops,
        host.clock
    );
    assert_eq!(host.laps, 2);
    assert_eq!(c.applied, robot.sent);
    assert_eq!(
        (c.lost, c.duplicate, c.late, c.corrupt, c.malformed),
        (0, 0, 0, 0, 0)
    );
    assert!(
        (link - in_process.position_rmse).abs() <= 0.10 * in_process.position_rmse,
        "link {link} m vs in-process {} m",
        in_process.position_rmse
    );
    // The host stopped sending after the laps: the watchdog stopped the
    // robot (on a loaded machine a stalled host may trip it earlier too).
    assert!(robot.watchdog_stops >= 1);
    // Simulated time runs TIME_SCALE times faster than the host's clock.
    let drift = host.clock.unwrap().drift;
    assert!(
        (drift - (TIME_SCALE - 1.0)).abs() < 0.01 * TIME_SCALE,
        "drift {drift}"
    );
}

/// What the proxy did to the telemetry (commands pass untouched).
#[derive(Debug, Default)]
struct Injected {
    dropped: Vec<u32>,
    corrupted: Vec<u32>,
    duplicated: Vec<u32>,
    reordered: Vec<u32>,
}

/// A UDP proxy between host and robot that, per telemetry packet: drops it
/// (20 %), flips one bit (1 %), sends it twice (5 %), or holds it back
/// until the next packet forwarded intact has gone (5 %, one held at a
/// time; a held packet released by a quiet spell is not counted).
fn proxy(socket: &UdpSocket, robot: SocketAddr, stop: &AtomicBool) -> Injected {
    let mut rng = StdRng::seed_from_u64(7);
    let mut injected = Injected::default();
    let mut host: Option<SocketAddr> = None;
    let mut held: Option<(u32, Vec<u8>)> = None;
    let mut buf = [0u8; 2048];
    socket
        .set_read_timeout(Some(Duration::from_millis(20)))
        .unwrap();
    while !stop.load(Ordering::Relaxed) {
        let (n, from) = match socket.recv_from(&mut buf) {
            Ok(r) => r,
            Err(_) => {
                if let (Some((_, p)), Some(h)) = (held.take(), host) {
                    socket.send_to(&p, h).unwrap();
                }
                continue;
            }
        };
        if from != robot {
            host = Some(from);
            socket.send_to(&buf[..n], robot).unwrap();
            continue;
        }
        let Some(h) = host else { continue };
        let packet = &buf[..n];
        let seq = Telemetry::decode(packet).unwrap().sequence;
        let u: f64 = rng.random();
        if u < 0.20 {
            injected.dropped.push(seq);
        } else if u < 0.21 {
            let mut bad = packet.to_vec();
            let bit = rng.random_range(0..8 * n);
            bad[bit / 8] ^= 1 << (bit % 8);
            socket.send_to(&bad, h).unwrap();
            injected.corrupted.push(seq);
        } else if u < 0.26 || (u < 0.31 && held.is_some()) {
            let twice = u < 0.26;
            socket.send_to(packet, h).unwrap();
            if twice {
                socket.send_to(packet, h).unwrap();
                injected.duplicated.push(seq);
            }
            if let Some((s, p)) = held.take() {
                socket.send_to(&p, h).unwrap();
                injected.reordered.push(s);
            }
        } else if u < 0.31 {
            held = Some((seq, packet.to_vec()));
        } else {
            socket.send_to(packet, h).unwrap();
            if let Some((s, p)) = held.take() {
                socket.send_to(&p, h).unwrap();
                injected.reordered.push(s);
            }
        }
    }
    injected
}

#[test]
fn faults_are_counted_exactly_and_the_run_survives() {
    let (clean_robot, clean_host) = run_link(bind(), None);
    let clean = rmse(&clean_robot, &clean_host);

    let robot_socket = bind();
    let robot_addr = robot_socket.local_addr().unwrap();
    let proxy_socket = bind();
    let proxy_addr = proxy_socket.local_addr().unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let proxy = {
        let stop = Arc::clone(&stop);
        thread::spawn(move || proxy(&proxy_socket, robot_addr, &stop))
    };
    let (robot, host) = run_link(robot_socket, Some(proxy_addr));
    stop.store(true, Ordering::Relaxed);
    let injected = proxy.join().unwrap();
    let faulty = rmse(&robot, &host);
    let c = host.counters;
    // Lost = numbers skipped by an applied packet: between the first and
    // the newest applied.
    let first = host.estimates.first().unwrap().0;
    let newest = host.estimates.last().unwrap().0;
    let skipped = |v: &[u32]| v.iter().filter(|&&s| s > first && s < newest).count() as u64;
    println!(
        "clean RMSE {:.3} cm, faulty RMSE {:.3} cm; first applied {first}; sent {}; counters {:?}; injected: dropped {}, corrupted {}, duplicated {}, reordered {}; laps {}",
        clean * 100.0,
        faulty * 100.0,
        robot.sent,
        c,
        injected.dropped.len(),
        injected.corrupted.len(),
        injected.duplicated.len(),
        injected.reordered.len(),
        host.laps
    );
    assert_eq!(host.laps, 2);
    assert!(
        injected.dropped.len() > 1000,
        "the proxy dropped too little"
    );
    assert!(!injected.corrupted.is_empty() && !injected.reordered.is_empty());
    assert_eq!(c.corrupt, injected.corrupted.len() as u64);
    assert_eq!(c.duplicate, injected.duplicated.len() as u64);
    assert_eq!(c.late, injected.reordered.len() as u64);
    assert_eq!(c.malformed, 0);
    assert_eq!(
        c.lost,
        skipped(&injected.dropped) + skipped(&injected.corrupted) + skipped(&injected.reordered)
    );
    assert_eq!(
        c.applied + c.lost,
        u64::from(newest - first) + 1,
        "every number from the first to the newest applied is applied or lost"
    );
    assert!(
        faulty <= 1.5 * clean,
        "faulty {faulty} m vs clean {clean} m"
    );
}

/// One command, then silence: the robot drives for exactly the watchdog's
/// 0.2 s of robot time, stops, and ends after `idle_exit`.
#[test]
fn the_watchdog_stops_the_robot_when_commands_stop() {
    let robot_socket = bind();
    let robot_addr = robot_socket.local_addr().unwrap();
    let square = SquareConfig {
        initial_std: [1e-12, 1e-12, 1e-12],
        ..SquareConfig::default()
    };
    let cfg = RobotConfig {
        square,
        seed: SEED,
        time_scale: TIME_SCALE,
        ..RobotConfig::default()
    };
    let robot = thread::spawn(move || run_robot(&robot_socket, &cfg).unwrap());
    let host = bind();
    let mut buf = [0u8; 64];
    let c = locus_link::CommandPacket {
        sequence: 0,
        ack: locus_link::NO_ACK,
        right: 0.1,
        left: 0.1,
    };
    let n = c.encode(&mut buf).unwrap();
    // Resend until the robot answers (it may not be receiving yet).
    host.set_read_timeout(Some(Duration::from_millis(50)))
        .unwrap();
    let mut rx = [0u8; 256];
    loop {
        host.send_to(&buf[..n], robot_addr).unwrap();
        if host.recv_from(&mut rx).is_ok() {
            break;
        }
    }
    let report = robot.join().unwrap();
    let start = report.truth[0].1;
    let end = report.truth.last().unwrap().1;
    let moved = (end.x - start.x).hypot(end.y - start.y);
    assert_eq!(report.watchdog_stops, 1);
    assert!((moved - 0.02).abs() < 1e-9, "moved {moved} m");
    // 2 s of robot time without commands at 100 Hz: 200 ticks.
    assert_eq!(report.ticks, 200);
}

/// The host refuses a configuration it cannot run before sending anything:
/// counters of another width than the link's, no laps.
#[test]
fn the_host_refuses_an_invalid_configuration() {
    let valid = host_config(&SquareConfig::default());
    assert!(valid.validate().is_ok());
    let socket = bind();
    let nobody = bind().local_addr().unwrap();
    for cfg in [
        HostConfig {
            localiser: SquareConfig::default().localiser(20),
            ..valid
        },
        HostConfig { laps: 0, ..valid },
    ] {
        let e = run_host(&socket, nobody, &cfg, &mut |_| {}).unwrap_err();
        assert!(matches!(e, locus_net::Error::Config(_)), "{e}");
    }
}
