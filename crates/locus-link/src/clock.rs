//! Robot-clock estimation: the offset and drift between the robot's clock
//! and the host's, from the pairs (robot timestamp of a packet, host time
//! it was received).
//!
//! Model: `robot = offset + (1 + drift) * host` (s). Two stages:
//!
//! 1. **Minimum-delay filter.** Host time is split into buckets of
//!    `bucket` seconds; of the pairs received in one bucket only the one
//!    with the smallest apparent delay `host - robot / (1 + drift)` (drift
//!    from the current fit, 0 before the first) is kept. Network delay only
//!    ever makes a packet late, so that pair is the one closest to the
//!    clock line.
//! 2. **Least squares.** A line through the kept pairs of the last `N`
//!    buckets (a ring buffer) and of the bucket being filled; the sums are
//!    formed about the window's means, so no running sum loses precision.
//!
//! The window spans `N * bucket` seconds: long enough to see the drift
//! (100 ppm is 0.1 ms per second), short enough to follow a drift that
//! changes with temperature. The fitted offset still contains the smallest
//! one-way delay seen in each bucket (on loopback, a few microseconds).
//! Drift is dimensionless (times 1e6 for ppm). All times are taken relative
//! to the first pair pushed, so hours of absolute time keep microsecond
//! resolution in `f64`.

/// Minimum-delay filter and least-squares line over the last `N` buckets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClockEstimator<const N: usize> {
    /// Length of a bucket of host time (s).
    bucket: f64,
    /// Kept `(host - host0, robot - robot0)` pair of each closed bucket (s),
    /// a ring buffer.
    pairs: [(f64, f64); N],
    /// Closed buckets stored, `<= N`.
    len: usize,
    /// Index of the next write.
    next: usize,
    /// First pair pushed `(host0, robot0)` (s), the origin.
    origin: Option<(f64, f64)>,
    /// The bucket being filled: its start (relative host s) and its best
    /// pair with that pair's apparent delay.
    current: Option<(f64, (f64, f64), f64)>,
    /// Rate `1 / (1 + drift)` of the last fit, for the apparent delay.
    rate: f64,
}

/// A fitted clock line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClockFit {
    /// Robot time at host time 0 (s).
    pub offset: f64,
    /// Rate error of the robot clock (dimensionless; `robot` advances
    /// `1 + drift` s per host second).
    pub drift: f64,
}

impl ClockFit {
    /// Robot time (s) at host time `host` (s).
    #[must_use]
    pub fn robot_time(&self, host: f64) -> f64 {
        self.offset + (1.0 + self.drift) * host
    }

    /// Host time (s) at robot time `robot` (s).
    #[must_use]
    pub fn host_time(&self, robot: f64) -> f64 {
        (robot - self.offset) / (1.0 + self.drift)
    }
}

/// A line `robot - r0 = mr + slope * (host - h0 - mh)` about the window's
/// means.
#[derive(Debug, Clone, Copy)]
struct Line {
    mh: f64,
    mr: f64,
    slope: f64,
}

impl<const N: usize> ClockEstimator<N> {
    /// An empty estimator with buckets of `bucket` seconds of host time
    /// (> 0; a non-positive or non-finite value is taken as 0: every pair
    /// its own bucket, no minimum-delay filtering). `N` (>= 2) buckets make
    /// the window.
    #[must_use]
    pub fn new(bucket: f64) -> Self {
        Self {
            bucket: if bucket.is_finite() && bucket > 0.0 {
                bucket
            } else {
                0.0
            },
            pairs: [(0.0, 0.0); N],
            len: 0,
            next: 0,
            origin: None,
            current: None,
            rate: 1.0,
        }
    }

    /// Pairs in the window (closed buckets plus the one being filled).
    #[must_use]
    pub fn len(&self) -> usize {
        self.len + usize::from(self.current.is_some())
    }

    /// `true` before the first pair.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Adds a pair: the robot timestamp of a packet and the host time it
    /// was received (both s). Non-finite pairs are ignored.
    pub fn push(&mut self, robot: f64, host: f64) {
        if N == 0 || !(robot.is_finite() && host.is_finite()) {
            return;
        }
        let (h0, r0) = *self.origin.get_or_insert((host, robot));
        let pair = (host - h0, robot - r0);
        let delay = pair.0 - pair.1 * self.rate;
        match self.current {
            Some((start, _, _)) if pair.0 - start >= self.bucket => {
                self.close();
                self.current = Some((pair.0, pair, delay));
            }
            Some((start, _, best)) if delay < best => {
                self.current = Some((start, pair, delay));
            }
            Some(_) => {}
            None => self.current = Some((pair.0, pair, delay)),
        }
    }

    /// Moves the current bucket's pair into the ring and refreshes the
    /// rate used for the apparent delay.
    fn close(&mut self) {
        if let Some((_, pair, _)) = self.current.take() {
            self.pairs[self.next] = pair;
            self.next = (self.next + 1) % N;
            self.len = (self.len + 1).min(N);
        }
        if let Some(l) = self.line() {
            if l.slope.is_finite() && l.slope > 0.0 {
                self.rate = 1.0 / l.slope;
            }
        }
    }

    /// The least-squares line through the window.
    #[allow(clippy::cast_precision_loss)] // N is small
    fn line(&self) -> Option<Line> {
        let closed = &self.pairs[..self.len];
        let current = self.current.map(|c| c.1);
        let n = closed.len() + usize::from(current.is_some());
        if n < 2 {
            return None;
        }
        let all = || closed.iter().copied().chain(current);
        let nf = n as f64;
        let mh = all().map(|p| p.0).sum::<f64>() / nf;
        let mr = all().map(|p| p.1).sum::<f64>() / nf;
        let (mut shh, mut shr) = (0.0, 0.0);
        for (h, r) in all() {
            shh += (h - mh) * (h - mh);
            shr += (h - mh) * (r - mr);
        }
        (shh > 0.0).then(|| Line {
            mh,
            mr,
            slope: shr / shh,
        })
    }

    /// The fitted line, or `None` with fewer than two pairs in the window
    /// or when every host time in it is the same.
    #[must_use]
    pub fn estimate(&self) -> Option<ClockFit> {
        let (h0, r0) = self.origin?;
        let l = self.line()?;
        Some(ClockFit {
            offset: r0 + l.mr - l.slope * (h0 + l.mh),
            drift: l.slope - 1.0,
        })
    }

    /// Robot time (s) at host time `host` (s), evaluated about the window's
    /// means (better conditioned than [`ClockFit::robot_time`] far from
    /// host time 0).
    #[must_use]
    pub fn robot_time(&self, host: f64) -> Option<f64> {
        let (h0, r0) = self.origin?;
        let l = self.line()?;
        Some(r0 + l.mr + l.slope * (host - h0 - l.mh))
    }
}
