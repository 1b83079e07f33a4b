//! The host's live settings (`Host::set_noise`, `set_gate`, `set_use_ir`,
//! `set_control`, `set_stopped`, `set_teleop`) and the live loop
//! (`run_host_live`, what `locus serve --robot` runs): bad values are
//! refused and change nothing, good ones take effect from the next packet,
//! the drive mode picks the command, and on loopback an `R` multiplied by
//! 100 mid-run lowers the NIS of the corrections that follow.

use core::ops::ControlFlow;
use core::time::Duration;
use std::net::UdpSocket;
use std::thread;

use locus_control::{Twist, wheel_speeds};
use locus_link::{MAX_PACKET, Telemetry};
use locus_net::Error;
use locus_net::host::{Drive, Host, HostConfig, Outcome, run_host_live};
use locus_net::transport::Udp;
use locus_sim::closed_loop::SquareConfig;
use locus_simlink::{RobotConfig, host_config, run_robot};

fn config() -> HostConfig {
    host_config(&SquareConfig::default())
}

/// Telemetry `seq` at `seq` x 10 ms with both encoders at `counts`, no IR.
fn packet(seq: u32, counts: u32) -> Vec<u8> {
    let mut t = Telemetry::new(seq, u64::from(seq) * 10_000);
    t.counts = [counts, counts];
    let mut out = [0u8; MAX_PACKET];
    let n = t.encode(&mut out).unwrap();
    out[..n].to_vec()
}

/// The command sent for `bytes` at `host_time` (the packet must apply).
fn command(host: &mut Host, bytes: &[u8], host_time: f64) -> [f32; 2] {
    match host.receive(bytes, host_time) {
        Outcome::Applied(step) => step.command.expect("a command"),
        other => panic!("not applied: {other:?}"),
    }
}

#[test]
fn setters_refuse_bad_values_and_change_nothing() {
    let mut host = Host::new(&config()).unwrap();
    let before = *host.config();
    for bad in [
        host.set_noise(f64::NAN, 1e-6, 2.5e-5, 2.5e-5),
        host.set_noise(1e-6, -1.0, 2.5e-5, 2.5e-5),
        host.set_noise(1e-6, 1e-6, 0.0, 2.5e-5),
        host.set_noise(1e-6, 1e-6, 2.5e-5, f64::INFINITY),
        host.set_gate(Some(1.0)),
        host.set_gate(Some(0.0)),
        host.set_gate(Some(f64::NAN)),
        host.set_control(locus_control::Config {
            v_ref: 0.0,
            ..before.control
        }),
        host.set_control(locus_control::Config {
            k_cross: f64::NAN,
            ..before.control
        }),
        host.set_teleop(f64::NAN, 0.0, 1.0),
        host.set_teleop(0.0, 0.0, f64::INFINITY),
    ] {
        assert!(matches!(bad, Err(Error::Config(_))), "{bad:?}");
    }
    assert_eq!(*host.config(), before, "nothing changed");
    // Inside the host's domain, outside the limits the simulator and the
    // teaching UI share (locus_models::settings): refused alike.
    for bad in [
        host.set_noise(1e-6, 1e-6, 2.0, 2.5e-5),
        host.set_control(locus_control::Config {
            v_ref: 1.0,
            ..before.control
        }),
    ] {
        assert!(matches!(bad, Err(Error::OutOfRange { .. })), "{bad:?}");
    }
    assert_eq!(*host.config(), before, "nothing changed");
    assert_eq!(host.drive(0.0), Drive::Path);

    host.set_noise(2e-6, 3e-6, 1e-3, 2e-3).unwrap();
    host.set_gate(None).unwrap();
    host.set_use_ir(false);
    let control = locus_control::Config {
        v_ref: 0.2,
        k_pos: 2.0,
        ..before.control
    };
    host.set_control(control).unwrap();
    let c = host.config();
    let l = &c.localiser;
    assert_eq!((l.q11, l.q22, l.r11, l.r22), (2e-6, 3e-6, 1e-3, 2e-3));
    assert_eq!(l.gate_confidence, None);
    assert!(!c.use_ir);
    assert_eq!(c.control, control);
    host.set_gate(Some(0.99)).unwrap();
    assert_eq!(host.config().localiser.gate_confidence, Some(0.99));
}

#[test]
fn the_drive_mode_picks_the_command_from_the_next_packet() {
    let cfg = config();
    let b = cfg.localiser.wheelbase;
    let (v_ref, w_ref) = (cfg.control.v_ref, cfg.control.w_ref);
    // `reference` is never stopped or steered: its commands are the path
    // controller's for the same (standing) robot.
    let mut host = Host::new(&cfg).unwrap();
    let mut reference = Host::new(&cfg).unwrap();
    let mut seq = 0;
    let mut both = |host: &mut Host, reference: &mut Host, t: f64| {
        let bytes = packet(seq, 1000);
        seq += 1;
        let first = host.receive(&bytes, t);
        reference.receive(&bytes, t);
        first
    };
    assert!(matches!(
        both(&mut host, &mut reference, 0.0),
        Outcome::Applied(_)
    ));
    let Outcome::Applied(path) = both(&mut host, &mut reference, 0.01) else {
        panic!()
    };
    let path = path.command.unwrap();
    assert_ne!(path, [0.0, 0.0], "the controller drives off");

    host.set_stopped(true);
    assert_eq!(host.drive(0.02), Drive::Stopped);
    let bytes = packet(seq, 1000);
    assert_eq!(command(&mut host, &bytes, 0.02), [0.0, 0.0], "stopped");
    let path_now = command(&mut reference, &bytes, 0.02);
    seq += 1;

    // Teleoperation beyond the limits: clamped to v_ref and w_ref, until 0.5 s.
    host.set_teleop(5.0, 10.0, 0.5).unwrap();
    let (v1, v2) = wheel_speeds(
        Twist {
            v: v_ref,
            w: w_ref,
            done: false,
        },
        b,
    );
    #[allow(clippy::cast_possible_truncation)]
    let steered = [v1 as f32, v2 as f32];
    let bytes = packet(seq, 1000);
    assert_eq!(
        command(&mut host, &bytes, 0.03),
        steered,
        "the operator's twist"
    );
    command(&mut reference, &bytes, 0.03);
    seq += 1;
    host.set_teleop(-5.0, -10.0, 0.5).unwrap();
    let bytes = packet(seq, 1000);
    assert_eq!(
        command(&mut host, &bytes, 0.04),
        [-steered[0], -steered[1]],
        "clamped both ways"
    );
    command(&mut reference, &bytes, 0.04);
    seq += 1;
    // The operator went quiet: after `until`, back to what drove before.
    let bytes = packet(seq, 1000);
    assert_eq!(
        command(&mut host, &bytes, 0.6),
        [0.0, 0.0],
        "lapsed: stopped"
    );
    command(&mut reference, &bytes, 0.6);
    seq += 1;
    assert_eq!(host.drive(0.6), Drive::Stopped);
    host.set_teleop(0.0, 1.0, 10.0).unwrap();
    host.clear_teleop();
    assert_eq!(host.drive(0.7), Drive::Stopped, "cleared");

    host.set_stopped(false);
    let bytes = packet(seq, 1000);
    let resumed = command(&mut host, &bytes, 0.7);
    let expected = command(&mut reference, &bytes, 0.7);
    assert_eq!(resumed, expected, "the path controller again");
    assert_ne!(path_now, [0.0, 0.0]);
}

#[allow(clippy::cast_precision_loss)]
fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

#[test]
fn live_loop_on_loopback_applies_a_new_r_from_the_next_packet() {
    let robot_socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let robot_addr = robot_socket.local_addr().unwrap();
    let robot_cfg = RobotConfig {
        square: SquareConfig {
            max_time: 1000.0,
            ..SquareConfig::default()
        },
        time_scale: 10.0,
        ..RobotConfig::default()
    };
    let robot = thread::spawn(move || run_robot(&robot_socket, &robot_cfg).unwrap());
    let mut cfg = config();
    cfg.laps = usize::MAX;
    let host_socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let (mut before, mut after) = (Vec::new(), Vec::new());
    let mut calls = 0u64;
    let mut last_sent = 0;
    let mut retuned_at = None;
    let mut latencies = 0;
    run_host_live(
        &mut Udp::to(&host_socket, robot_addr),
        &cfg,
        Duration::from_millis(20),
        |host, tick| {
            calls += 1;
            assert!(tick.commands_sent >= last_sent);
            last_sent = tick.commands_sent;
            let Some(step) = tick.step else {
                return ControlFlow::Continue(());
            };
            assert!(!tick.silent, "a packet was just applied");
            latencies += usize::from(tick.latency.is_some());
            match retuned_at {
                None if step.robot_time >= 25.0 => {
                    let l = host.config().localiser;
                    host.set_noise(l.q11, l.q22, 100.0 * l.r11, 100.0 * l.r22)
                        .unwrap();
                    retuned_at = Some(step.sequence);
                }
                None if step.robot_time >= 5.0 => before.extend(step.nis),
                Some(_) => after.extend(step.nis),
                None => {}
            }
            if step.robot_time >= 50.0 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
    )
    .unwrap();
    // The host stopped sending: the robot's watchdog and idle exit end it.
    let report = robot.join().unwrap();
    assert!(report.ticks >= 5000, "robot ticks {}", report.ticks);
    assert!(
        calls > 5000 && latencies > 4000,
        "calls {calls}, commands {latencies}"
    );
    assert!(
        before.len() > 100 && after.len() > 100,
        "{} / {}",
        before.len(),
        after.len()
    );
    let (b, a) = (mean(&before), mean(&after));
    println!(
        "mean NIS with R: {b:.3} ({} corrections), with 100 R: {a:.3} ({})",
        before.len(),
        after.len()
    );
    assert!(a < b / 5.0, "mean NIS {b} -> {a} after R x 100");
}

/// The details the host keeps of each IR correction (what the page shows
/// step by step) are those of the packet's correction: the same NIS,
/// innovation, decision and posterior as the step; `S`, `K` and the gate
/// agree with each other; `x-` is the prediction from the belief before
/// the packet with its wheel travels.
#[test]
fn the_host_keeps_the_details_of_every_correction_it_tries() {
    use locus_core::MotionModel;
    use locus_core::nalgebra::{Vector2, Vector3};
    use locus_models::{DiffDrive, WheelTravel};

    let robot_socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let robot_addr = robot_socket.local_addr().unwrap();
    let robot_cfg = RobotConfig {
        time_scale: 10.0,
        ..RobotConfig::default()
    };
    let robot = thread::spawn(move || run_robot(&robot_socket, &robot_cfg).unwrap());
    let cfg = config();
    let drive = DiffDrive::new(
        cfg.localiser.wheelbase,
        cfg.localiser.q11,
        cfg.localiser.q22,
    );
    let host_socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let (mut tried, mut gated, mut predicted) = (0u64, 0u64, 0u64);
    let mut before = *Host::new(&cfg).unwrap().belief();
    run_host_live(
        &mut Udp::to(&host_socket, robot_addr),
        &cfg,
        Duration::from_millis(20),
        |host, tick| {
            let Some(step) = tick.step else {
                return ControlFlow::Continue(());
            };
            let Some(nis) = step.nis else {
                assert_eq!(host.corrections_tried(), tried, "no reading tried");
                before = *host.belief();
                return ControlFlow::Continue(());
            };
            tried += 1;
            assert_eq!(host.corrections_tried(), tried);
            let d = host.last_correction().expect("details of the correction");
            assert_eq!(d.nis, nis);
            assert_eq!(Some(d.innovation), step.innovation);
            assert_eq!(d.applied, step.corrected);
            assert_eq!(d.x_post, step.estimate);
            assert_eq!(d.x_before_predict, [before.x[0], before.x[1], before.x[2]]);
            // NIS = y^T S^-1 y, K = P- H^T S^-1, and the gate's decision.
            let s = locus_core::nalgebra::Matrix2::from_fn(|i, j| d.s[i][j]);
            let y = Vector2::from(d.innovation);
            let s_inv = s.try_inverse().unwrap();
            assert!(((y.transpose() * s_inv * y)[0] - nis).abs() <= 1e-9 * nis.max(1.0));
            let p = locus_core::nalgebra::Matrix3::from_fn(|i, j| d.p_prior[i][j]);
            let h = locus_core::nalgebra::Matrix2x3::from_fn(|i, j| d.jacobian[i][j]);
            let k = p * h.transpose() * s_inv;
            for i in 0..3 {
                for j in 0..2 {
                    assert!((k[(i, j)] - d.k[i][j]).abs() <= 1e-9 * k.amax());
                }
            }
            let threshold = d.gate_threshold.expect("the square host has a gate");
            assert_eq!(d.applied, nis <= threshold);
            gated += u64::from(!d.applied);
            if step.skipped == 0 {
                let u = WheelTravel {
                    d1: d.u[0],
                    d2: d.u[1],
                };
                let x = drive.f(&Vector3::from(d.x_before_predict), &u, &Vector2::zeros());
                assert!(
                    (x - Vector3::from(d.x_prior)).amax() < 1e-12,
                    "{x} vs {:?}",
                    d.x_prior
                );
                predicted += 1;
            }
            before = *host.belief();
            if step.robot_time >= 20.0 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
    )
    .unwrap();
    robot.join().unwrap();
    println!("{tried} corrections tried ({gated} gated out), {predicted} predictions checked");
    assert!(tried > 200 && predicted > 200, "{tried} / {predicted}");
}
