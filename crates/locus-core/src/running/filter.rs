//! The [`RunningFilter`]: rules, a current [`Track`], a history of the
//! last `H` events in time order (each with the track after it) in a
//! fixed ring buffer (`no_std`, no allocation), and a NIS consistency
//! monitor. [`RunningFilter::insert`] puts an [`Event`] at its place in
//! canonical order and re-runs the later ones; with `H = 0` the filter's
//! own predict and correct act on its track directly. Times in s.

use core::cmp::Ordering;

use nalgebra::SVector;

use super::{Rules, Track, Update};
use crate::{Belief, ConsistencyMonitor, Error, MeasurementModel, MotionModel, Scalar};

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
    /// As [`Ekf::predict`](crate::Ekf::predict); the belief is then unchanged.
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
