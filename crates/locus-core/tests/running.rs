//! The running filter: a late event gives the estimates of an in-order run;
//! a full history finalises its oldest event; the gate's recovery inflates
//! and retries; an error keeps the belief; nothing allocates.

use locus_core::nalgebra::{Matrix3, Vector2, Vector3};
use locus_core::{
    Belief, ChiSquareGate, Ekf, Error, Event, Placement, Recovery, Rules, RunningFilter, Track,
    Update,
};
use locus_models::range_bearing::RangeBearing;
use locus_models::unicycle::{Unicycle, Velocities};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// A timeline event: a velocity command or a range-bearing sighting of a
/// landmark, with the outcome written back by `apply`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Ev {
    Input {
        time: f64,
        v: f64,
        omega: f64,
    },
    Sighting {
        time: f64,
        landmark: [f64; 2],
        z: [f64; 2],
        applied: bool,
    },
}

impl Event for Ev {
    fn time(&self) -> f64 {
        match self {
            Ev::Input { time, .. } | Ev::Sighting { time, .. } => *time,
        }
    }
}

/// The input in force, carried in the track.
type Input = (f64, f64);

fn apply(rules: &Rules<f64>, track: &mut Track<f64, 3, Input>, e: &mut Ev) -> Result<(), Error> {
    let (v, omega) = track.extra;
    track.predict_to(&rules.ekf, e.time(), |dt| {
        (
            Unicycle::new(0.01 / dt, 0.01 / dt),
            Velocities { v, omega, dt },
        )
    })?;
    match e {
        Ev::Input { v, omega, .. } => track.extra = (*v, *omega),
        Ev::Sighting {
            landmark,
            z,
            applied,
            ..
        } => {
            let model = RangeBearing::new(
                Vector2::new(landmark[0], landmark[1]),
                Vector2::zeros(),
                0.1,
                0.02,
            );
            *applied = track
                .correct(rules, &model, &Vector2::new(z[0], z[1]))?
                .applied();
        }
    }
    Ok(())
}

fn timeline(seed: u64, n: usize) -> Vec<Ev> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut out = Vec::new();
    for i in 0..n {
        let time = 0.1 * (i + 1) as f64;
        if i % 5 == 4 {
            out.push(Ev::Sighting {
                time: time - 0.15,
                landmark: [rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0)],
                z: [rng.random_range(0.5..4.0), rng.random_range(-1.0..1.0)],
                applied: false,
            });
        } else {
            out.push(Ev::Input {
                time,
                v: rng.random_range(0.0..0.3),
                omega: rng.random_range(-0.5..0.5),
            });
        }
    }
    out
}

fn rules() -> Rules<f64> {
    Rules::new(Ekf::default().with_gate(ChiSquareGate::new(0.999).unwrap()))
        .with_recovery(Recovery::new(3, 4.0).unwrap())
}

fn start() -> Track<f64, 3, Input> {
    Track::new(
        Belief::new(Vector3::zeros(), Matrix3::identity() * 0.01),
        0.0,
        (0.0, 0.0),
    )
}

/// Runs `events` in the given arrival order through a filter of history
/// `H`, returning the finalised events in order.
fn run<const H: usize>(events: &[Ev]) -> Vec<(Ev, Track<f64, 3, Input>)> {
    let mut f = RunningFilter::<f64, 3, H, Ev, Input>::new(rules(), start());
    let mut out = Vec::new();
    for e in events {
        let (_, evicted) = f.insert(*e, apply).unwrap();
        out.extend(evicted);
    }
    while let Some(e) = f.pop_final_before(f64::INFINITY) {
        out.push(e);
    }
    out
}

#[test]
fn late_events_give_the_in_order_estimates() {
    let events = timeline(7, 300);
    let mut sorted = events.clone();
    sorted.sort_by(|a, b| a.time().total_cmp(&b.time()));
    // Arrival order: each sighting arrives after the input that follows it
    // in time (0.05 s late).
    let reference = run::<64>(&sorted);
    let late = run::<64>(&events);
    assert_ne!(sorted, events, "the timeline has late sightings");
    assert_eq!(reference.len(), events.len());
    assert_eq!(
        late, reference,
        "a late sighting must be applied at its own time"
    );
    assert!(
        reference
            .iter()
            .any(|(e, _)| matches!(e, Ev::Sighting { applied: true, .. }))
    );
}

#[test]
fn a_full_history_finalises_its_oldest_event_and_stays_exact() {
    let events = timeline(9, 200);
    let mut sorted = events.clone();
    sorted.sort_by(|a, b| a.time().total_cmp(&b.time()));
    // A history of 2 still holds the one event a sighting jumps over.
    assert_eq!(run::<2>(&events), run::<64>(&sorted));
    let mut f = RunningFilter::<f64, 3, 2, Ev, Input>::new(rules(), start());
    let (mut finalised, mut late) = (0, 0);
    for e in &events[..10] {
        let (placement, evicted) = f.insert(*e, apply).unwrap();
        late += usize::from(placement == Placement::Late { rerun: 1 });
        finalised += usize::from(evicted.is_some());
        assert!(f.pending() <= 2);
    }
    assert_eq!((late, finalised), (2, 8));
}

/// A filter put back with `restore` from the parts `base`, `history` and
/// `monitor` read at some point (here into a filter whose ring starts
/// elsewhere, with other events in it) goes on exactly as the original did
/// from there, late events and a full history included.
#[test]
fn a_restored_filter_goes_on_as_the_original_did() {
    let events = timeline(11, 300);
    let mut f = RunningFilter::<f64, 3, 8, Ev, Input>::new(rules(), start());
    let mut other = RunningFilter::<f64, 3, 8, Ev, Input>::new(rules(), start());
    for e in &events[..37] {
        f.insert(*e, apply).unwrap();
        other.insert(*e, apply).unwrap();
    }
    for e in &events[..5] {
        other.insert(*e, apply).unwrap();
    }
    let (base, history, monitor) = (
        *f.base(),
        f.history().copied().collect::<Vec<_>>(),
        f.monitor().clone(),
    );
    assert!(history.len() > 2 && history.len() == f.pending());
    other.restore(&base, history.iter(), &monitor).unwrap();
    let mut out = (Vec::new(), Vec::new());
    for e in &events[37..] {
        out.0.extend(f.insert(*e, apply).unwrap().1);
        out.1.extend(other.insert(*e, apply).unwrap().1);
    }
    while let Some(e) = f.pop_final_before(f64::INFINITY) {
        out.0.push(e);
    }
    while let Some(e) = other.pop_final_before(f64::INFINITY) {
        out.1.push(e);
    }
    assert!(out.0.len() > 200);
    assert_eq!(out.0, out.1);
    // More events than the history holds: refused, the filter unchanged.
    let mut small = RunningFilter::<f64, 3, 2, Ev, Input>::new(rules(), start());
    assert!(matches!(
        small.restore(&base, history.iter(), &monitor),
        Err(Error::InvalidParameter(_))
    ));
    assert_eq!(small.pending(), 0);
}

#[test]
fn recovery_inflates_after_consecutive_rejections_then_applies() {
    let rules = Rules::new(Ekf::default().with_gate(ChiSquareGate::new(0.99).unwrap()))
        .with_recovery(Recovery::new(2, 1e6).unwrap());
    let mut f = RunningFilter::<f64, 3>::start(
        rules,
        Belief::new(Vector3::zeros(), Matrix3::identity() * 1e-4),
        (),
    );
    let model = RangeBearing::new(Vector2::new(2.0, 0.0), Vector2::zeros(), 0.05, 0.01);
    // The robot is really at x = 1: the landmark reads 1 m, not 2 m.
    let z = Vector2::new(1.0, 0.0);
    let first = f.correct(&model, &z).unwrap();
    assert!(matches!(first, Update::Gated { first: None, .. }));
    assert_eq!(f.track().rejections, 1);
    assert_eq!(
        f.belief().p,
        Matrix3::identity() * 1e-4,
        "gated: belief kept"
    );
    let second = f.correct(&model, &z).unwrap();
    assert!(second.applied() && second.inflated(), "{second:?}");
    let nis_prior = second.first_attempt().unwrap().nis;
    assert!(nis_prior > ChiSquareGate::<f64>::new(0.99).unwrap().threshold(2));
    assert!((f.belief().x[0] - 1.0).abs() < 0.05, "{}", f.belief().x);
    assert_eq!(f.track().rejections, 0);
    assert_eq!(f.monitor().len(), 2);
    // S and the gain of the applied correction are the filter's.
    let c = second.correction().unwrap();
    assert!((c.s - c.s.transpose()).amax() == 0.0 && c.s[(0, 0)] > 0.0);
    assert_eq!(c.gain.nrows(), 3);
}

/// A state the prior holds known (a bias at 0 +- 1e-3 with no process
/// noise) stays known through any number of recoveries: only the free
/// states' variances grow, and the inflated covariance stays positive
/// definite with its correlations.
#[test]
fn recovery_leaves_held_states_as_they_are() {
    let recovery = Recovery::new(1, 4.0).unwrap().holding(&[2]).unwrap();
    let rules = Rules::new(Ekf::default().with_gate(ChiSquareGate::new(0.99).unwrap()))
        .with_recovery(recovery);
    let p0 = Matrix3::new(1e-4, 2e-5, 1e-8, 2e-5, 1e-4, 0.0, 1e-8, 0.0, 1e-6);
    let mut f = RunningFilter::<f64, 3>::start(rules, Belief::new(Vector3::zeros(), p0), ());
    // A landmark 1 m further than the belief allows: gated again and again.
    let model = RangeBearing::new(Vector2::new(2.0, 0.0), Vector2::zeros(), 1e-3, 1e-3);
    let z = Vector2::new(100.0, 0.0);
    for _ in 0..10 {
        let u = f.correct(&model, &z).unwrap();
        assert!(u.inflated() && !u.applied(), "{u:?}");
    }
    let p = f.belief().p;
    assert_eq!(p[(2, 2)], 1e-6, "the held state's variance is kept");
    let k = 4f64.powi(10);
    assert!((p[(0, 0)] / (k * 1e-4) - 1.0).abs() < 1e-12, "{p}");
    assert!((p[(0, 2)] / (k.sqrt() * 1e-8) - 1.0).abs() < 1e-12, "{p}");
    assert!(p.cholesky().is_some() && p == p.transpose());
    // Nothing held: exactly k P.
    let mut q = p0;
    Recovery::new(1, 4.0).unwrap().inflate(&mut q);
    assert_eq!(q, p0 * 4.0);
    assert!(Recovery::new(1, 4.0).unwrap().holding(&[64]).is_err());
}

#[test]
fn an_error_keeps_the_belief_and_the_history() {
    let events = timeline(3, 40);
    let mut f = RunningFilter::<f64, 3, 16, Ev, Input>::new(rules(), start());
    for e in &events[..20] {
        f.insert(*e, apply).unwrap();
    }
    let before = (*f.track(), *f.base(), f.pending());
    let bad = Ev::Sighting {
        time: 1.0,
        landmark: [1.0, 1.0],
        z: [f64::NAN, 0.0],
        applied: false,
    };
    assert!(f.insert(bad, apply).is_err());
    assert_eq!((*f.track(), *f.base(), f.pending()), before);

    let mut g = RunningFilter::<f64, 3>::start(rules(), start().belief, ());
    let model = RangeBearing::new(Vector2::new(1.0, 0.0), Vector2::zeros(), 0.1, 0.02);
    let b = *g.belief();
    assert!(g.correct(&model, &Vector2::new(f64::NAN, 0.0)).is_err());
    assert_eq!(*g.belief(), b);
}

#[test]
fn the_running_filter_does_not_allocate() {
    let events = timeline(5, 500);
    let mut f = RunningFilter::<f64, 3, 32, Ev, Input>::new(rules(), start());
    let info = allocation_counter::measure(|| {
        for e in &events {
            let r = f.insert(*e, apply).unwrap();
            core::hint::black_box(r);
        }
    });
    assert_eq!(info.count_total, 0);
}
