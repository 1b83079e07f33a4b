//! Link benchmarks (run with `cargo bench -p locus-net --bench link`).
//!
//! 1. **Load on loopback** (printed, not a criterion timing): the robot
//!    endpoint at 10 000 packets per second (time scale 100 at 100 Hz) and
//!    the host, for `LOCUS_LINK_LOAD_SECONDS` of wall time (default 30 s, the
//!    issue's figure): packets sent, applied, lost, the achieved rate, and
//!    the p50/p99 time from a packet's reception to its command's send.
//! 2. **Criterion**: one telemetry packet encoded, decoded and classified;
//!    one command encoded and decoded (the per-packet codec cost).

use core::hint::black_box;
use std::net::UdpSocket;
use std::thread;
use std::time::Instant;

use criterion::{Criterion, Throughput, criterion_group};
use locus_link::{CommandPacket, MAX_PACKET, Receiver, Telemetry};
use locus_net::host::run_host;
use locus_sim::closed_loop::SquareConfig;
use locus_simlink::{RobotConfig, host_config, run_robot};

/// Robot seconds per wall second: 100 Hz telemetry becomes 10 000 per
/// second.
const TIME_SCALE: f64 = 100.0;

#[allow(clippy::cast_precision_loss, clippy::cast_possible_truncation)]
#[allow(clippy::cast_sign_loss)]
fn load() {
    let seconds: f64 = std::env::var("LOCUS_LINK_LOAD_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(30.0);
    let robot_time = seconds * TIME_SCALE;
    // Enough laps (about 70 s each) that the robot's max_time ends the run.
    let square = SquareConfig {
        laps: (robot_time / 60.0).ceil() as usize + 1,
        max_time: robot_time,
        ..SquareConfig::default()
    };
    let robot_socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let robot_addr = robot_socket.local_addr().unwrap();
    let cfg = RobotConfig {
        square,
        seed: 1,
        time_scale: TIME_SCALE,
        ..RobotConfig::default()
    };
    let start = Instant::now();
    let robot = thread::spawn(move || run_robot(&robot_socket, &cfg).unwrap());
    let host_socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let host_cfg = host_config(&square);
    let host = run_host(&host_socket, robot_addr, &host_cfg, &mut |_| {}).unwrap();
    let robot = robot.join().unwrap();
    let wall = start.elapsed().as_secs_f64() - host_cfg.quiet.as_secs_f64();
    let mut lat = host.latency.clone();
    lat.sort_by(f64::total_cmp);
    let pct = |p: f64| lat[((lat.len() - 1) as f64 * p).round() as usize] * 1e6;
    let c = host.counters;
    println!(
        "link load: {seconds} s requested at {:.0} packets/s; robot sent {} telemetry packets in {wall:.2} s ({:.0} /s); host applied {}, lost {} (never arrived: {}), duplicate {}, late {}, corrupt {}, malformed {}; commands sent {}, robot applied {} (lost {}); on-time commands {:.1} %; receive-to-command p50 {:.1} us, p99 {:.1} us, max {:.1} us",
        TIME_SCALE / square.dt,
        robot.sent,
        robot.sent as f64 / wall,
        c.applied,
        c.lost,
        robot.sent - c.applied,
        c.duplicate,
        c.late,
        c.corrupt,
        c.malformed,
        host.commands_sent,
        robot.commands.applied,
        robot.commands.lost,
        100.0 * robot.on_time as f64 / robot.ticks.max(1) as f64,
        pct(0.5),
        pct(0.99),
        lat.last().unwrap() * 1e6,
    );
}

fn codec(c: &mut Criterion) {
    let mut group = c.benchmark_group("link");
    group.throughput(Throughput::Elements(1));
    let mut t = Telemetry::new(1, 10_000);
    t.counts = [123_456, 654_321];
    t.ir = Some([0.12, 0.13]);
    let mut buf = [0u8; MAX_PACKET];
    let mut rx = Receiver::new();
    let mut seq = 0u32;
    group.bench_function("telemetry encode+decode+classify", |b| {
        b.iter(|| {
            seq = seq.wrapping_add(1);
            t.sequence = seq;
            let n = black_box(&t).encode(&mut buf).unwrap();
            black_box(rx.receive_telemetry(black_box(&buf[..n])).unwrap())
        });
    });
    let cmd = CommandPacket {
        sequence: 1,
        ack: 2,
        right: 0.1,
        left: 0.09,
    };
    group.bench_function("command encode+decode", |b| {
        b.iter(|| {
            let n = black_box(&cmd).encode(&mut buf).unwrap();
            black_box(CommandPacket::decode(black_box(&buf[..n])).unwrap())
        });
    });
    group.finish();
}

criterion_group!(benches, codec);

fn main() {
    load();
    benches();
    Criterion::default().configure_from_args().final_summary();
}
