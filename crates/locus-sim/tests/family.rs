//! The simulated family (`locus_sim::family`): seeded, readable by the
//! Locus CSV reader, and its noise as stated (against the true path).

use std::path::Path;

use locus_core::wrap_angle;
use locus_logs::locus_csv::{self, LocusLog};
use locus_sim::family::{
    Correlated, Generated, Member, OdometrySource, SensorKind, generate, generate_with,
};

fn member(name: &str) -> Member {
    Member::named(name).unwrap_or_else(|| panic!("no member {name}"))
}

fn parse(text: &str) -> LocusLog {
    locus_csv::parse(text, Path::new("family.csv")).expect("the generated log parses")
}

/// Sample standard deviation about zero.
#[allow(clippy::cast_precision_loss)]
fn rms(values: &[f64]) -> f64 {
    (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt()
}

/// Robust spread: 1.4826 times the median absolute value.
fn robust(values: &[f64]) -> f64 {
    let mut a: Vec<f64> = values.iter().map(|v| v.abs()).collect();
    a.sort_by(f64::total_cmp);
    1.4826 * a[a.len() / 2]
}

/// Range and bearing residuals (measured minus true, from the true path,
/// the log's sensor x and the true sensor yaw), with time and landmark.
fn residuals(g: &Generated, log: &LocusLog) -> Vec<(u32, f64, f64, f64)> {
    let mount_x = log.sensor.map_or(0.0, |s| s.x);
    assert_eq!(
        mount_x, g.truth.sensor_x,
        "the sensor line gives the true x"
    );
    assert_eq!(log.sensor.map_or(0.0, |s| s.yaw), 0.0, "the log says yaw 0");
    log.measurements
        .iter()
        .map(|m| {
            let [x, y, th] = g.path.pose_at(m.time);
            let (sx, sy) = (x + mount_x * th.cos(), y + mount_x * th.sin());
            let l = log.landmarks.iter().find(|l| l.id == m.id).unwrap();
            let (dx, dy) = (l.x - sx, l.y - sy);
            let bearing = wrap_angle(dy.atan2(dx) - th - g.truth.sensor_yaw);
            (
                m.id,
                m.time,
                m.range - dx.hypot(dy),
                m.bearing.map_or(f64::NAN, |b| wrap_angle(b - bearing)),
            )
        })
        .collect()
}

fn within(what: &str, got: f64, want: f64, tolerance: f64) {
    assert!(
        (got / want - 1.0).abs() <= tolerance,
        "{what}: {got} against {want} (tolerance {:.0} %)",
        100.0 * tolerance
    );
}

#[test]
fn the_same_seed_gives_the_same_log_and_another_seed_another() {
    let m = member("laser-5hz-offset").scaled(0.1);
    let (a, ta) = generate(&m, 7);
    let (b, tb) = generate(&m, 7);
    assert_eq!(a, b);
    assert_eq!(ta, tb);
    let (c, _) = generate(&m, 8);
    assert_ne!(a, c);
}

#[test]
fn every_member_parses_with_odometry_sightings_and_truth() {
    for m in Member::family() {
        let g = generate_with(&m.scaled(0.1), m.seed);
        if m.needs_v3 {
            assert!(g.text.starts_with("# Locus log v3"));
        }
        let log = parse(&g.text);
        let expected = (m.duration * 0.1 * m.odometry.rate).round() as usize + 1;
        assert_eq!(log.odometry.len(), expected, "{}", m.name);
        assert_eq!(log.measurements.len(), g.sightings, "{}", m.name);
        assert!(g.sightings > 0, "{}: no sightings", m.name);
        assert!(log.truth.poses().len() > 100, "{}", m.name);
        assert!(log.start.is_none() && log.noise == Default::default());
        // The truth gives the pose at the first odometry time.
        assert_eq!(log.truth.poses()[0].time, log.odometry[0].time);
        // As many landmarks in view as asked, roughly (they are scattered
        // at random).
        let ratio = g.mean_in_view() / m.sensor.in_view;
        assert!(
            (0.4..2.0).contains(&ratio),
            "{}: {} in view on average, {} asked",
            m.name,
            g.mean_in_view(),
            m.sensor.in_view
        );
    }
}

#[test]
fn the_truth_records_are_the_true_path_with_the_heading_offset() {
    let m = member("laser-5hz-offset").scaled(0.2);
    let g = generate_with(&m, 3);
    let log = parse(&g.text);
    for p in log.truth.poses().iter().step_by(97) {
        let [x, y, th] = g.path.pose_at(p.time);
        assert!((p.x - x).abs() < 1e-12 && (p.y - y).abs() < 1e-12);
        assert!((wrap_angle(p.theta - th) - m.truth_heading_offset).abs() < 1e-12);
    }
    // The robot stays near its area.
    let far = log
        .truth
        .poses()
        .iter()
        .map(|p| p.x.hypot(p.y))
        .fold(0.0, f64::max);
    assert!(far < m.area_radius + 1.5, "went {far} m from the centre");
}

#[test]
fn white_sighting_noise_is_as_stated() {
    for name in ["precise-30hz", "noisy-wheels-100hz", "wide-range-2hz"] {
        let m = member(name);
        let g = generate_with(&m, m.seed);
        let r = residuals(&g, &parse(&g.text));
        let ranges: Vec<f64> = r.iter().map(|e| e.2).collect();
        let bearings: Vec<f64> = r.iter().map(|e| e.3).collect();
        within(
            &format!("{name} range"),
            rms(&ranges),
            g.truth.sigma_range,
            0.05,
        );
        within(
            &format!("{name} bearing"),
            rms(&bearings),
            g.truth.sigma_bearing,
            0.05,
        );
    }
}

#[test]
fn outliers_are_the_stated_share_and_the_rest_as_stated() {
    let m = member("outliers-5pct");
    let g = generate_with(&m, m.seed);
    let r = residuals(&g, &parse(&g.text));
    let sr = g.truth.sigma_range;
    let sb = g.truth.sigma_bearing;
    let outliers = r
        .iter()
        .filter(|e| e.2.abs() > 6.0 * sr || e.3.abs() > 6.0 * sb)
        .count();
    #[allow(clippy::cast_precision_loss)]
    let share = outliers as f64 / r.len() as f64;
    // A uniform draw falls within 6 sigma of the truth now and then.
    assert!((0.04..0.055).contains(&share), "outlier share {share}");
    let ranges: Vec<f64> = r.iter().map(|e| e.2).collect();
    within("robust range spread", robust(&ranges), sr, 0.06);
}

/// Correlation of residuals `e` of the same landmark `lag` seconds apart
/// (pairs within 1 ms of it).
fn autocorrelation(
    r: &[(u32, f64, f64, f64)],
    lag: f64,
    pick: fn(&(u32, f64, f64, f64)) -> f64,
) -> f64 {
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (i, a) in r.iter().enumerate() {
        for b in &r[i + 1..] {
            let gap = b.1 - a.1;
            if gap > lag + 1e-3 {
                break;
            }
            if b.0 == a.0 && (gap - lag).abs() < 1e-3 {
                let (x, y) = (pick(a), pick(b));
                sab += x * y;
                saa += x * x;
                sbb += y * y;
            }
        }
    }
    sab / (saa * sbb).sqrt()
}

#[test]
fn correlated_noise_has_its_marginal_sigma_and_time_constant() {
    let base = member("correlated-only-15hz");
    let tau = 1.0;
    let m = Member {
        duration: 600.0,
        sensor: locus_sim::family::Sensor {
            rate: 10.0,
            correlated: Some(Correlated {
                tau,
                sigma_range: 0.05,
                sigma_bearing: 0.004,
            }),
            ..base.sensor
        },
        ..base
    };
    let g = generate_with(&m, 21);
    let r = residuals(&g, &parse(&g.text));
    let ranges: Vec<f64> = r.iter().map(|e| e.2).collect();
    let bearings: Vec<f64> = r.iter().map(|e| e.3).collect();
    within("range sigma", rms(&ranges), 0.05, 0.1);
    within("bearing sigma", rms(&bearings), 0.004, 0.1);
    // exp(-lag / tau) at lag = tau and 2 tau, read back as a time constant.
    for lag in [tau, 2.0 * tau] {
        let rho = autocorrelation(&r, lag, |e| e.2);
        within(
            &format!("range tau at lag {lag} s"),
            -lag / rho.ln(),
            tau,
            0.2,
        );
        let rho = autocorrelation(&r, lag, |e| e.3);
        within(
            &format!("bearing tau at lag {lag} s"),
            -lag / rho.ln(),
            tau,
            0.2,
        );
    }
    // White noise has none: one scan apart, about 0.
    let white = member("precise-30hz");
    let g = generate_with(&white, 5);
    let r = residuals(&g, &parse(&g.text));
    let rho = autocorrelation(&r, 1.0 / 30.0, |e| e.2);
    assert!(rho.abs() < 0.05, "white noise correlated: {rho}");
}

#[test]
fn odometry_noise_and_calibration_are_the_truth_in_the_filters_terms() {
    for name in [
        "noisy-wheels-100hz",
        "commanded-lag-0.2s",
        "laser-5hz-offset",
    ] {
        let m = member(name);
        let g = generate_with(&m, m.seed);
        let t = g.truth;
        let log = parse(&g.text);
        let dt = 1.0 / m.odometry.rate;
        // The calibrated unicycle's velocities against the true ones over
        // each record's period (shifted by the delay).
        let (mut ev, mut ew) = (Vec::new(), Vec::new());
        for o in &log.odometry {
            let (v, w) = g.path.velocity_at(o.time + t.odometry_delay + 0.5 * dt);
            ev.push(t.v_scale * o.v - v);
            ew.push(t.omega_scale * o.omega + t.omega_bias - w);
        }
        within(&format!("{name} q_v"), rms(&ev).powi(2) * dt, t.q_v, 0.05);
        within(
            &format!("{name} q_omega"),
            rms(&ew).powi(2) * dt,
            t.q_omega,
            0.05,
        );
        if let OdometrySource::Wheels { track, sigma_wheel } = m.odometry.source {
            within(
                "wheel q_v",
                t.q_v,
                sigma_wheel * sigma_wheel / 2.0 * dt,
                1e-12,
            );
            within(
                "wheel q_omega",
                t.q_omega,
                2.0 * (sigma_wheel / track).powi(2) * dt,
                1e-12,
            );
        }
    }
}

#[test]
fn beacons_are_range_records_with_the_stated_noise() {
    let m = member("uwb-beacons");
    assert_eq!(m.sensor.kind, SensorKind::RangeOnly);
    assert!(m.needs_v3);
    let g = generate_with(&m, m.seed);
    assert!(g.truth.sigma_bearing.is_nan());
    assert!(!g.text.contains("\nmeasurement,"));
    let mut residual = Vec::new();
    for line in g.text.lines().filter(|l| l.starts_with("range,")) {
        let f: Vec<f64> = line[6..].split(',').map(|v| v.parse().unwrap()).collect();
        let (t, id, range) = (f[0], f[1], f[2]);
        let [x, y, th] = g.path.pose_at(t);
        let (sx, sy) = (
            x + m.sensor.mount_x * th.cos(),
            y + m.sensor.mount_x * th.sin(),
        );
        let &(_, lx, ly) = g.landmarks.iter().find(|l| f64::from(l.0) == id).unwrap();
        residual.push(range - (lx - sx).hypot(ly - sy));
    }
    assert_eq!(residual.len(), g.sightings);
    within("beacon range", rms(&residual), g.truth.sigma_range, 0.05);
}
