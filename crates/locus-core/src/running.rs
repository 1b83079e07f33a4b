//! The running filter: one belief carried through time, the filter every
//! loop of Locus runs (simulator, robot-link host, firmware, demo, teaching
//! UI, log replay).
//!
//! [`Ekf`] is stateless; a loop needs more around it: the time of the
//! belief, the gate's recovery from over-confidence, a consistency monitor
//! of the NIS, and, for logs whose measurements arrive late, a history so
//! that a late measurement is applied at its own time. [`RunningFilter`]
//! holds exactly that, in fixed arrays (`no_std`, no allocation):
//!
//! * [`Track`]: the belief, its time (s), the count of consecutive gate
//!   rejections, and the caller's own data `X` carried beside the belief
//!   (e.g. the input in force), all restored together on a re-run.
//! * [`Track::predict`] and [`Track::correct`] are the two operations; a
//!   correction returns a typed [`Update`] (applied, with the NIS, `S` and
//!   the gain; gated; no measurement) or an error, **and on any error the
//!   track is unchanged**.
//! * Recovery ([`Recovery`]): after `after` consecutive rejections the
//!   covariance is inflated by `inflation` (leaving the states the model
//!   holds fixed as they are) and the measurement tried once more; the
//!   inflation compounds over further rejections until a
//!   measurement fits. A chi-square gate alone can lock an over-confident
//!   filter out for good.
//! * History (`H` > 0): [`RunningFilter::insert`] puts an event at its place
//!   in time order and re-runs the later ones, so the estimates equal those
//!   of an in-order run (the same operations in the same order).
//!
//! For a loop that applies its events as they come (`H = 0`), the filter's
//! own [`RunningFilter::predict`] and [`RunningFilter::correct`] act on its
//! track directly and feed the consistency monitor.

use core::cmp::Ordering;

use nalgebra::{SMatrix, SVector};

use crate::{
    Belief, ConsistencyMonitor, Correction, Ekf, Error, MeasurementModel, MotionModel, Scalar,
    ScaledNoise, StudentT, cast,
};

/// Recovery from over-confidence: after `after` consecutive gate rejections
/// the covariance is inflated by `inflation` and the rejected measurement
/// is tried once more.
///
/// The inflation respects what the model holds fixed: the variances of the
/// states in `held` (a constant the prior says is known, e.g. a bias held
/// at 0 +- 1e-6) stay as they are. With `D = diag(d)`, `d_i = sqrt(k)` for
/// a free state and 1 for a held one, the covariance becomes `D P D`: free
/// variances and their covariances grow by `k`, a covariance between a free
/// and a held state by `sqrt(k)`, every correlation is kept, and `P` stays
/// positive definite. Inflating the whole `P` would make a held state free
/// after a few recoveries (`k^n` compounds: 15 inflations by 4 turn a
/// standard deviation of 1e-6 into 0.03), and a "known" bias could then
/// absorb any error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Recovery<T> {
    /// Consecutive rejections that trigger an inflation (>= 1).
    pub after: u32,
    /// Factor the free variances are multiplied by (finite, > 1).
    pub inflation: T,
    /// The states the inflation leaves alone: bit `i` set holds state `i`
    /// (states 64 and above cannot be held).
    pub held: u64,
}

impl<T: Scalar> Recovery<T> {
    /// A recovery policy.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] unless `after >= 1` and `inflation` is
    /// finite and > 1.
    pub fn new(after: u32, inflation: T) -> Result<Self, Error> {
        if after == 0 {
            return Err(Error::InvalidParameter("recovery: `after` must be >= 1"));
        }
        if !(inflation > T::one() && inflation.is_finite()) {
            return Err(Error::InvalidParameter(
                "recovery: inflation must be finite and > 1",
            ));
        }
        Ok(Self {
            after,
            inflation,
            held: 0,
        })
    }

    /// The same policy, leaving the states `indices` as they are (see
    /// [`Recovery`]).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if an index is 64 or more.
    pub fn holding(mut self, indices: &[usize]) -> Result<Self, Error> {
        for &i in indices {
            if i >= 64 {
                return Err(Error::InvalidParameter(
                    "recovery: only states 0 to 63 can be held",
                ));
            }
            self.held |= 1 << i;
        }
        Ok(self)
    }

    /// Inflates `p` in place: `D P D` (see [`Recovery`]); exactly `k P` when
    /// nothing is held.
    pub fn inflate<const N: usize>(&self, p: &mut SMatrix<T, N, N>) {
        let k = self.inflation;
        if self.held == 0 {
            *p *= k;
            return;
        }
        let root = k.sqrt();
        let free = |i: usize| i >= 64 || self.held & (1 << i) == 0;
        for j in 0..N {
            for i in 0..N {
                let factor = match (free(i), free(j)) {
                    (true, true) => k,
                    (false, false) => continue,
                    _ => root,
                };
                p[(i, j)] *= factor;
            }
        }
    }
}

/// How the running filter corrects: the stateless [`Ekf`] (covariance
/// update form and optional gate) and an optional [`Recovery`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rules<T: Scalar> {
    /// Update form and gate.
    pub ekf: Ekf<T>,
    /// Recovery after consecutive gate rejections (`None`: a rejected
    /// measurement is only counted).
    pub recovery: Option<Recovery<T>>,
}

impl<T: Scalar> Rules<T> {
    /// Rules with `ekf` and no recovery.
    pub fn new(ekf: Ekf<T>) -> Self {
        Self {
            ekf,
            recovery: None,
        }
    }

    /// The same rules with a recovery policy.
    #[must_use]
    pub fn with_recovery(mut self, recovery: Recovery<T>) -> Self {
        self.recovery = Some(recovery);
        self
    }
}

/// What a correction did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Update<T: Scalar, const N: usize, const M: usize> {
    /// The measurement corrected the belief. `first` is the attempt on the
    /// belief before an inflation, if the covariance was inflated first
    /// (the measurement was then applied only after recovery).
    Applied {
        /// The applied correction: posterior, `S` and gain as applied (with
        /// the noise divided by `weight`); its NIS is the one the gate
        /// tested, against the nominal noise.
        correction: Correction<T, N, M>,
        /// The rejected attempt before the inflation, if any.
        first: Option<Correction<T, N, M>>,
        /// The weight the correction was applied with, in (0, 1]: 1 without
        /// [`Track::correct_robust`].
        weight: T,
    },
    /// The gate rejected the measurement; the belief is kept (inflated if
    /// `first` is set: the retry after the inflation was rejected too).
    Gated {
        /// The (last) rejected attempt.
        correction: Correction<T, N, M>,
        /// The rejected attempt before the inflation, if any.
        first: Option<Correction<T, N, M>>,
    },
    /// The model predicts no measurement at this state (nothing changed).
    NoMeasurement,
}

impl<T: Scalar, const N: usize, const M: usize> Update<T, N, M> {
    /// Whether the measurement corrected the belief.
    pub fn applied(&self) -> bool {
        matches!(self, Update::Applied { .. })
    }

    /// Whether the covariance was inflated by the recovery.
    pub fn inflated(&self) -> bool {
        matches!(
            self,
            Update::Applied { first: Some(_), .. } | Update::Gated { first: Some(_), .. }
        )
    }

    /// The attempt on the belief as it was before this call (before any
    /// inflation): its NIS and `S` are those of the measurement against
    /// the prior. `None` for [`Update::NoMeasurement`].
    pub fn first_attempt(&self) -> Option<&Correction<T, N, M>> {
        match self {
            Update::Applied {
                correction, first, ..
            }
            | Update::Gated { correction, first } => Some(first.as_ref().unwrap_or(correction)),
            Update::NoMeasurement => None,
        }
    }

    /// The last attempt (the applied one, or the last rejected one).
    pub fn correction(&self) -> Option<&Correction<T, N, M>> {
        match self {
            Update::Applied { correction, .. } | Update::Gated { correction, .. } => {
                Some(correction)
            }
            Update::NoMeasurement => None,
        }
    }
}

/// The belief at a time and what is carried beside it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Track<T: Scalar, const N: usize, X = ()> {
    /// The belief.
    pub belief: Belief<T, N>,
    /// The time of the belief, s.
    pub time: f64,
    /// Consecutive gate rejections so far.
    pub rejections: u32,
    /// The caller's data carried with the belief (restored with it when
    /// the history is re-run), e.g. the input in force.
    pub extra: X,
}

impl<T: Scalar, const N: usize, X> Track<T, N, X> {
    /// A track at `time` (s) with `belief`, no rejections, and `extra`.
    pub fn new(belief: Belief<T, N>, time: f64, extra: X) -> Self {
        Self {
            belief,
            time,
            rejections: 0,
            extra,
        }
    }

    /// Prediction with `model` and input `u` (spec section 1:
    /// `X- = f(X+, u, 0)`, `P- = A P+ A^T + W Q W^T`). The time is not
    /// changed: the caller's model knows what interval `u` covers (see
    /// [`Track::predict_to`]).
    ///
    /// # Errors
    /// As [`Ekf::predict`]; the track is then unchanged.
    #[inline(always)]
    pub fn predict<Mo, const NQ: usize>(
        &mut self,
        ekf: &Ekf<T>,
        model: &Mo,
        u: &Mo::Input,
    ) -> Result<(), Error>
    where
        Mo: MotionModel<T, N, NQ>,
    {
        self.belief = ekf.predict(&self.belief, model, u)?;
        Ok(())
    }

    /// Prediction to `time` (s): `step(dt)` gives the model and input for
    /// the interval `dt = time - self.time`. Nothing happens unless
    /// `dt > 0` (an event at or before the track's time does not move it).
    ///
    /// # Errors
    /// As [`Ekf::predict`]; the track is then unchanged.
    #[inline]
    pub fn predict_to<Mo, const NQ: usize>(
        &mut self,
        ekf: &Ekf<T>,
        time: f64,
        step: impl FnOnce(f64) -> (Mo, Mo::Input),
    ) -> Result<(), Error>
    where
        Mo: MotionModel<T, N, NQ>,
    {
        let dt = time - self.time;
        if dt > 0.0 {
            let (model, u) = step(dt);
            self.belief = ekf.predict(&self.belief, &model, &u)?;
            self.time = time;
        }
        Ok(())
    }

    /// Correction with `model` and measurement `z`, behind the gate of
    /// `rules.ekf`, with `rules.recovery` (see [`Recovery`]).
    ///
    /// # Errors
    /// As [`Ekf::correct`] (except [`Error::NoMeasurement`], which is
    /// [`Update::NoMeasurement`]); the track is then unchanged, even if the
    /// error came on the retry after an inflation.
    #[inline]
    pub fn correct<Me, const M: usize>(
        &mut self,
        rules: &Rules<T>,
        model: &Me,
        z: &SVector<T, M>,
    ) -> Result<Update<T, N, M>, Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        let mut belief = self.belief;
        let mut rejections = self.rejections;
        let mut first = None;
        loop {
            let c = match rules.ekf.correct(&belief, model, z) {
                Ok(c) => c,
                Err(Error::NoMeasurement) => return Ok(Update::NoMeasurement),
                Err(e) => return Err(e),
            };
            if c.applied {
                self.belief = c.belief;
                self.rejections = 0;
                return Ok(Update::Applied {
                    correction: c,
                    first,
                    weight: T::one(),
                });
            }
            rejections = rejections.saturating_add(1);
            match rules.recovery {
                Some(r) if rejections >= r.after && first.is_none() => {
                    r.inflate(&mut belief.p);
                    first = Some(c);
                }
                _ => {
                    self.belief = belief;
                    self.rejections = rejections;
                    return Ok(Update::Gated {
                        correction: c,
                        first,
                    });
                }
            }
        }
    }
    /// As [`Track::correct`], with a correction the gate lets through
    /// weighted as Student-t noise (see [`StudentT`]): heavy tails beside
    /// the gate. A correction applied after a [`Recovery`] inflation keeps
    /// its nominal weight: the prior, not the measurement, was wrong. (A
    /// method of its own, so that a filter without it, e.g. the firmware,
    /// carries none of its code.)
    ///
    /// # Errors
    /// As [`Track::correct`]; the track is then unchanged.
    pub fn correct_robust<Me, const M: usize>(
        &mut self,
        rules: &Rules<T>,
        robust: &StudentT<T>,
        model: &Me,
        z: &SVector<T, M>,
    ) -> Result<Update<T, N, M>, Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        let (prior, rejections) = (self.belief, self.rejections);
        match self.correct(rules, model, z)? {
            Update::Applied {
                correction,
                first: None,
                ..
            } => {
                let (c, weight) = match Self::reweigh(rules, &prior, model, z, correction, *robust)
                {
                    Ok(r) => r,
                    Err(e) => {
                        self.belief = prior;
                        self.rejections = rejections;
                        return Err(e);
                    }
                };
                self.belief = c.belief;
                Ok(Update::Applied {
                    correction: c,
                    first: None,
                    weight,
                })
            }
            other => Ok(other),
        }
    }

    /// The correction `c` (applied at nominal noise to `belief`) redone
    /// with its Student-t weight, if that is below 1; with the weight. The
    /// NIS stays the nominal one.
    fn reweigh<Me, const M: usize>(
        rules: &Rules<T>,
        belief: &Belief<T, N>,
        model: &Me,
        z: &SVector<T, M>,
        c: Correction<T, N, M>,
        t: StudentT<T>,
    ) -> Result<(Correction<T, N, M>, T), Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        let weight = t.weight(c.nis, c.dof);
        if weight >= T::one() {
            return Ok((c, weight));
        }
        let scaled = ScaledNoise {
            inner: model,
            factor: T::one() / weight,
        };
        let ekf = Ekf {
            gate: None,
            ..rules.ekf
        };
        let mut w = ekf.correct(belief, &scaled, z)?;
        w.nis = c.nis;
        Ok((w, weight))
    }
}

/// An event of a timeline kept in a [`RunningFilter`]'s history.
pub trait Event: Copy {
    /// When the event happened, s.
    fn time(&self) -> f64;

    /// The canonical order of two events (`Less`: `self` first). The
    /// default orders by time; events that compare `Equal` keep the order
    /// they were inserted in.
    fn order(&self, other: &Self) -> Ordering {
        self.time().total_cmp(&other.time())
    }
}

impl Event for () {
    fn time(&self) -> f64 {
        0.0
    }
}

/// Where [`RunningFilter::insert`] put an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// After every event in the history.
    InOrder,
    /// Before `rerun` events of the history, which were re-run after it.
    Late {
        /// Events re-run.
        rerun: usize,
    },
}

/// A finalised event: it left the history and will not be re-run.
pub type Final<T, const N: usize, E, X> = (E, Track<T, N, X>);

/// What [`RunningFilter::insert`] did: where the event went, and the event
/// that became final to make room, if any.
pub type Inserted<T, const N: usize, E, X> = (Placement, Option<Final<T, N, E, X>>);

/// The running filter: rules, a current [`Track`], a history of the last
/// `H` events in time order (each with the track after it), and a NIS
/// consistency monitor over the last `W` corrections.
///
/// `E` is the caller's event type (its outcome can be written into it by
/// the `apply` function of [`RunningFilter::insert`]); `X` the caller's
/// data carried in the track.
#[derive(Debug, Clone)]
pub struct RunningFilter<
    T: Scalar,
    const N: usize,
    const H: usize = 0,
    E: Event = (),
    X: Copy = (),
    const W: usize = 32,
> {
    rules: Rules<T>,
    /// The track before the oldest event in the history.
    base: Track<T, N, X>,
    /// Ring buffer of `len` entries starting at `head`.
    history: [Option<Final<T, N, E, X>>; H],
    head: usize,
    len: usize,
    monitor: ConsistencyMonitor<W>,
}

impl<T: Scalar, const N: usize, const H: usize, E: Event, X: Copy, const W: usize>
    RunningFilter<T, N, H, E, X, W>
{
    /// A running filter starting from `track`, correcting by `rules`, with
    /// a 95 % two-sided NIS consistency test over the last `W` corrections.
    pub fn new(rules: Rules<T>, track: Track<T, N, X>) -> Self {
        Self {
            rules,
            base: track,
            history: [None; H],
            head: 0,
            len: 0,
            // Cannot fail: 0.95 is inside (0, 1).
            monitor: ConsistencyMonitor::new(0.95).unwrap_or_else(|_| unreachable!()),
        }
    }

    /// The rules in force.
    pub fn rules(&self) -> &Rules<T> {
        &self.rules
    }

    /// Changes the rules from the next operation on (e.g. a new gate).
    pub fn set_rules(&mut self, rules: Rules<T>) {
        self.rules = rules;
    }

    /// The current track: after the newest event.
    pub fn track(&self) -> &Track<T, N, X> {
        match self.len {
            0 => &self.base,
            n => match &self.history[self.index(n - 1)] {
                Some((_, track)) => track,
                None => &self.base,
            },
        }
    }

    /// The current belief.
    pub fn belief(&self) -> &Belief<T, N> {
        &self.track().belief
    }

    /// The time of the current belief, s.
    pub fn time(&self) -> f64 {
        self.track().time
    }

    /// The track before the oldest event of the history (everything at or
    /// before its time is final).
    pub fn base(&self) -> &Track<T, N, X> {
        &self.base
    }

    /// Events in the history (not yet final).
    pub fn pending(&self) -> usize {
        self.len
    }

    /// The history's events (not yet final), oldest first, each with the
    /// track after it. With [`RunningFilter::base`],
    /// [`RunningFilter::monitor`] and the rules, the whole state of the
    /// filter: [`RunningFilter::restore`] puts it back.
    pub fn history(&self) -> impl Iterator<Item = &Final<T, N, E, X>> {
        (0..self.len).filter_map(|i| self.entry(i))
    }

    /// Puts the filter back in the state read from it earlier: `base`
    /// ([`RunningFilter::base`]), `history` ([`RunningFilter::history`],
    /// oldest first) and `monitor`; the rules stay. Everything the filter
    /// does afterwards is then what it did from that state, to the bit.
    ///
    /// For a caller that keeps states to run on from later: they take
    /// [`RunningFilter::pending`] entries instead of `H`, and the filter is
    /// set in place (a filter with a long history is large: 0.6 MB for 7
    /// states and 1024 events; a copy of it through the stack would not
    /// fit a thread's).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if `history` holds more than `H` events
    /// (the filter is then unchanged).
    pub fn restore<'a>(
        &mut self,
        base: &Track<T, N, X>,
        history: impl ExactSizeIterator<Item = &'a Final<T, N, E, X>>,
        monitor: &ConsistencyMonitor<W>,
    ) -> Result<(), Error>
    where
        Final<T, N, E, X>: 'a,
    {
        if history.len() > H {
            return Err(Error::InvalidParameter(
                "restore: a history longer than the filter's",
            ));
        }
        self.base = *base;
        self.head = 0;
        self.len = 0;
        for entry in history {
            self.history[self.len] = Some(*entry);
            self.len += 1;
        }
        self.monitor = monitor.clone();
        Ok(())
    }

    /// The NIS consistency monitor.
    pub fn monitor(&self) -> &ConsistencyMonitor<W> {
        &self.monitor
    }

    /// Records a correction's NIS in the consistency monitor (done by
    /// [`RunningFilter::correct`]; for the history's events, call it when an
    /// event is final so a re-run event counts once).
    pub fn record_nis(&mut self, nis: T, dof: u32) {
        let v: f64 = nis.to_subset().unwrap_or(f64::NAN);
        self.monitor.push(v, dof);
    }

    /// Position in the ring of the `i`-th pending event (`H >= 1`: only
    /// called with pending events).
    fn index(&self, i: usize) -> usize {
        (self.head + i) % H
    }

    fn entry(&self, i: usize) -> Option<&Final<T, N, E, X>> {
        self.history[self.index(i)].as_ref()
    }

    /// Removes the oldest event of the history and makes its track the
    /// base, if it happened before `limit` (s).
    pub fn pop_final_before(&mut self, limit: f64) -> Option<Final<T, N, E, X>> {
        if self.len == 0 {
            return None;
        }
        // The slot is left as it is: past the pending ones, it is not read.
        let slot = self.history[self.head].as_ref();
        let (event, track) = slot.filter(|(e, _)| e.time() < limit)?;
        let event = *event;
        self.base = *track;
        self.head = (self.head + 1) % H;
        self.len -= 1;
        Some((event, self.base))
    }

    /// Inserts `event` at its place in the canonical order
    /// ([`Event::order`]: after every event that does not order after it),
    /// applies it there with `apply` and re-runs the later events.
    ///
    /// `apply(rules, track, event)` advances `track` to the event's time
    /// and applies it; it may write its outcome into `event`. It must be
    /// deterministic: the re-run first runs on copies and only then for
    /// real, so that a failure anywhere leaves the filter as it was.
    ///
    /// With the history full, the oldest event becomes final first and is
    /// returned (the caller reports it); an event older than the base is
    /// applied on the base (see [`RunningFilter::base`]).
    ///
    /// # Errors
    /// The first error of `apply` (the filter is then unchanged).
    pub fn insert(
        &mut self,
        mut event: E,
        mut apply: impl FnMut(&Rules<T>, &mut Track<T, N, X>, &mut E) -> Result<(), Error>,
    ) -> Result<Inserted<T, N, E, X>, Error> {
        const { assert!(H > 0, "insert needs a history: H >= 1") };
        // In order with room: applied in place in the next free slot (on an
        // error the slot stays free and the filter unchanged).
        let n = self.len;
        let after = |(e, _): &Final<T, N, E, X>| e.order(&event) == Ordering::Greater;
        if n < H && (n == 0 || !self.entry(n - 1).is_some_and(after)) {
            let at = self.index(n);
            match n.checked_sub(1).map(|i| self.index(i)) {
                None => self.history[at] = Some((event, self.base)),
                Some(k) => self.history.copy_within(k..=k, at),
            }
            if let Some((e, track)) = self.history[at].as_mut() {
                *e = event;
                apply(&self.rules, track, e)?;
            }
            self.len += 1;
            return Ok((Placement::InOrder, None));
        }
        // The events that order after `event` start at `p`.
        let mut p = self.len;
        while p > 0 && self.entry(p - 1).is_some_and(after) {
            p -= 1;
        }
        let start = if p == 0 {
            self.base
        } else {
            self.entry(p - 1).map_or(self.base, |(_, t)| *t)
        };
        // Dry run on copies: the filter changes only if every step succeeds.
        if p < self.len {
            let mut track = start;
            let mut e = event;
            apply(&self.rules, &mut track, &mut e)?;
            for i in p..self.len {
                if let Some((mut later, _)) = self.entry(i).copied() {
                    apply(&self.rules, &mut track, &mut later)?;
                }
            }
        }
        let mut track = start;
        apply(&self.rules, &mut track, &mut event)?;
        let mut evicted = None;
        if self.len == H {
            if p == 0 {
                // Older than every pending event and no room: it is final
                // at once, and every pending event is re-run after it.
                self.base = track;
                evicted = Some((event, track));
                for i in 0..self.len {
                    let k = self.index(i);
                    if let Some((later, after)) = self.history[k].as_mut() {
                        apply(&self.rules, &mut track, later)?;
                        *after = track;
                    }
                }
                return Ok((Placement::Late { rerun: self.len }, evicted));
            }
            // Make room: the oldest event becomes final.
            evicted = self.pop_final_before(f64::INFINITY);
            p -= 1;
        }
        // Shift the later events one place towards the back.
        let rerun = self.len - p;
        for i in (p..self.len).rev() {
            let (from, to) = (self.index(i), self.index(i + 1));
            self.history[to] = self.history[from];
        }
        let at = self.index(p);
        self.history[at] = Some((event, track));
        self.len += 1;
        for i in (p + 1)..self.len {
            let k = self.index(i);
            if let Some((later, after)) = self.history[k].as_mut() {
                apply(&self.rules, &mut track, later)?;
                *after = track;
            }
        }
        let placement = if rerun == 0 {
            Placement::InOrder
        } else {
            Placement::Late { rerun }
        };
        Ok((placement, evicted))
    }
}

impl<T: Scalar, const N: usize, X: Copy, const W: usize> RunningFilter<T, N, 0, (), X, W> {
    /// A running filter without history at `belief` (time 0), with the
    /// given rules and `extra`.
    pub fn start(rules: Rules<T>, belief: Belief<T, N>, extra: X) -> Self {
        Self::new(rules, Track::new(belief, 0.0, extra))
    }

    /// The current track, to change (e.g. to reset the belief).
    pub fn track_mut(&mut self) -> &mut Track<T, N, X> {
        &mut self.base
    }

    /// Prediction of the current track ([`Track::predict`]).
    ///
    /// # Errors
    /// As [`Ekf::predict`]; the belief is then unchanged.
    #[inline(always)]
    pub fn predict<Mo, const NQ: usize>(&mut self, model: &Mo, u: &Mo::Input) -> Result<(), Error>
    where
        Mo: MotionModel<T, N, NQ>,
    {
        self.base.predict(&self.rules.ekf, model, u)
    }

    /// Correction of the current track ([`Track::correct`]); the NIS of the
    /// attempt on the prior goes to the consistency monitor.
    ///
    /// # Errors
    /// As [`Track::correct`]; the belief is then unchanged.
    #[inline]
    pub fn correct<Me, const M: usize>(
        &mut self,
        model: &Me,
        z: &SVector<T, M>,
    ) -> Result<Update<T, N, M>, Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        let update = self.base.correct(&self.rules, model, z)?;
        if let Some(c) = update.first_attempt() {
            let (nis, dof) = (c.nis, c.dof);
            self.record_nis(nis, dof);
        }
        Ok(update)
    }
}

/// The normalised estimation error squared `e^T P^-1 e` (dimensionless) of
/// an estimate with covariance `P` and error `e` (truth minus estimate,
/// angles wrapped), by a Cholesky solve; `None` if `P` is not positive
/// definite (the NEES is then undefined, not infinite).
pub fn nees<T: Scalar, const N: usize>(
    error: &SVector<T, N>,
    p: &nalgebra::SMatrix<T, N, N>,
) -> Option<T> {
    let c = p.cholesky()?;
    let v = error.dot(&c.solve(error));
    // A finite error and a factored P give a finite, non-negative NEES.
    (v >= cast::<T>(0.0) && v.is_finite()).then_some(v)
}
