//! Wheel speed from quadrature edges: pulse-count mode and period mode, with a
//! hysteresis switch between them (paper 004, section 2.2; spec section 5).
//!
//! The estimator is fed the way firmware feeds it: every decoded edge with its
//! time stamp from a capture timer running at the reference clock `f`
//! ([`on_edge`](SpeedEstimator::on_edge), or
//! [`on_transition`](SpeedEstimator::on_transition) straight from the
//! decoder), and the boundaries of the measuring windows
//! ([`end_window`](SpeedEstimator::end_window) from a periodic timer, or
//! [`poll`](SpeedEstimator::poll) from a loop). Time stamps are `u32` ticks of
//! `f` that may wrap: every span is a wrapping difference, exact for spans
//! under 2^32 ticks (71 minutes at 1 MHz).
//!
//! With `N` encoder lines, gear ratio `G` (encoder-shaft revolutions per wheel
//! revolution) and wheel radius `R` (m), one x4 count is `pi R / (2 N G)` m of
//! wheel travel, and `K = pi R f / (2 N G)` (m/s) is the speed of one count
//! per tick. Speeds are signed, m/s, positive forward (counting up).
//!
//! * **Pulse-count mode**: `C` net counts in a window of `W` ticks
//!   (`W = T f`, \[assumed\] `T` = 10 ms):
//!   `S = K C / W = pi C R / (2 N T G)`, resolution `K / W = pi R / (2 N T G)`.
//!   The estimate is the average velocity over the window, also when the
//!   direction changes inside it (net count). Edge-position errors of the
//!   encoder (phase error between A and B, duty-cycle error) move single
//!   edges: they add up to their spread (in counts) to the one-count
//!   quantisation.
//! * **Period mode**: `C` ticks between an edge and the `M`-th edge before it,
//!   all in the same direction: `S = K M / C = pi R f M / (2 N C G)`. With
//!   `M = 1` this is the spec's "counts of f between successive x4 edges"
//!   (**\[fix\]** of the paper: R included). The reported resolution is the
//!   one-tick step `K M / (C (C - 1)) = S / (C - 1)`, i.e. the spec's
//!   `S^2 2 N G / (pi R f M)` to first order, and a strict bound on the
//!   error against the average speed over the span. **Default `M = 4`**
//!   (deviation, configurable): four x4 edges are one full line period, from
//!   one edge to the same physical edge, so phase and duty-cycle errors
//!   cancel exactly; with `M = 1` a 5 % phase error is a 20 % speed error.
//!   The span restarts at every change of direction (the paper's open issue:
//!   "a change in the direction bit inside a time window may cause error")
//!   and after an invalid transition.
//!
//! **Switching** happens at each window boundary on the window's pulse count
//! `|C|`: pulse to period mode when `|C| <` [`to_period_below`] (\[assumed\] 8),
//! period to pulse mode when `|C| >` [`to_pulse_above`] (\[assumed\] 12). The
//! band in between is the hysteresis: a speed whose count jitters by less
//! than the band switches at most once.
//!
//! **Degenerate cases in period mode.** No edge for longer than the
//! standstill timeout (\[assumed\] 0.1 s), or no edge in the whole window and
//! no complete span: speed 0, reported in period mode with resolution
//! `K / E`, `E` the ticks since the last edge (a shaft that crossed no edge
//! moved less than one edge spacing, so for ideal edges its average speed is
//! below `K / E`). Edges in the window but no complete span yet (start-up,
//! just after a reversal or an invalid transition): the window's pulse-count
//! estimate, reported as
//! [`Mode::Pulse`] (the mode says how the value was measured; the switching
//! state is [`SpeedEstimator::mode`]). Each estimate carries the span of ticks
//! it averages over, so its latency is explicit.
//!
//! [`to_period_below`]: SpeedConfig::to_period_below
//! [`to_pulse_above`]: SpeedConfig::to_pulse_above
//!
//! ```
//! use locus_odometry::quadrature::Direction;
//! use locus_odometry::speed::{Mode, SpeedConfig, SpeedEstimator};
//!
//! let config = SpeedConfig::<f32>::paper();
//! let k = config.speed_scale(); // pi R f / (2 N G) = 157.08 m/s
//! let mut est = SpeedEstimator::new(config, 0).unwrap();
//!
//! // 500 edges/s forward, one edge every 2000 ticks; this 20 ms window holds
//! // 10 counts, not above 12: it stays in period mode.
//! for i in 1..=10u32 {
//!     est.on_edge(i * 2000, Direction::Forward);
//! }
//! let e = est.end_window(20_000).unwrap();
//! assert_eq!(e.mode, Mode::Period);
//! assert!((e.speed - k * 4.0 / 8000.0).abs() < 1e-6); // 4 edges in 8000 ticks
//! assert_eq!((e.from_tick, e.to_tick), (12_000, 20_000));
//!
//! // 2000 edges/s: 20 counts > 12, so the window is measured in pulse mode.
//! for i in 1..=20u32 {
//!     est.on_edge(20_000 + i * 500, Direction::Forward);
//! }
//! let e = est.end_window(30_000).unwrap();
//! assert_eq!(e.mode, Mode::Pulse);
//! assert!((e.speed - k * 20.0 / 10_000.0).abs() < 1e-6);
//! assert!((e.resolution - k / 10_000.0).abs() < 1e-7);
//! ```

use locus_core::cast;

use crate::error::Error;
use crate::quadrature::{Direction, Transition};
use crate::wheel::{Real, Wheel};

/// The largest number of edges a period-mode span may cover
/// ([`SpeedConfig::period_edges`]).
pub const MAX_PERIOD_EDGES: u32 = 16;

/// How a speed was measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Counts in a fixed window (accurate at high speed).
    Pulse,
    /// Reference-clock ticks between edges (accurate at low speed).
    Period,
}

/// Parameters of the speed measurement, in `f32` (MCU) or `f64` (PC). All
/// \[assumed\] defaults are those of spec section 5 ([`SpeedConfig::paper`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedConfig<T> {
    /// The encoder and wheel: lines `N`, gear `G`, radius `R` (m).
    /// \[assumed\] 500 lines, G = 1, R = 0.05 m ([`Wheel::assumed`]).
    pub wheel: Wheel<T>,
    /// `f`, the reference clock of the capture timer, Hz (>= 1): time stamps
    /// are ticks of this clock. \[assumed\] 1 MHz.
    pub clock_hz: u32,
    /// `T`, the pulse-count window, s; [`SpeedEstimator::poll`] closes a
    /// window after `round(T f)` ticks (>= 1). \[assumed\] 10 ms.
    pub window: T,
    /// Switch from pulse to period mode when a window holds fewer than this
    /// many counts (absolute). \[assumed\] 8.
    pub to_period_below: u32,
    /// Switch from period to pulse mode when a window holds more than this
    /// many counts (absolute); `>= to_period_below`. \[assumed\] 12.
    pub to_pulse_above: u32,
    /// `M`, the number of x4 edges a period-mode span covers, 1..=
    /// [`MAX_PERIOD_EDGES`]. 4 (one line period) cancels phase and duty-cycle
    /// errors; 1 is the paper's literal "successive edges". Default 4.
    pub period_edges: u32,
    /// In period mode, report standstill (speed 0) when no edge came for this
    /// long, s (`round(timeout f)` >= 1 tick). \[assumed\] 0.1 s.
    pub standstill_timeout: T,
    /// The switching state at start. Default [`Mode::Period`] (a robot starts
    /// at rest).
    pub initial_mode: Mode,
    /// How far the encoder's A/B phase and duty-cycle errors can move a single
    /// x4 edge from its ideal position, counts (>= 0; 0 for an ideal
    /// encoder, the default). A window's count is then uncertain by
    /// `1 + edge_spread` counts, and the pulse-mode and standstill
    /// resolutions are reported as `K / W (1 + edge_spread)` and
    /// `K / E (1 + edge_spread)`. Period mode over a full line period
    /// (`period_edges = 4`) is not affected: the errors cancel.
    pub edge_spread: T,
}

impl<T: Real> SpeedConfig<T> {
    /// The \[assumed\] defaults of spec section 5: N = 500, G = 1, R = 0.05 m,
    /// f = 1 MHz, T = 10 ms, period mode below 8 counts, pulse mode above 12;
    /// M = 4, standstill after 0.1 s, starting in period mode.
    pub fn paper() -> Self {
        Self {
            wheel: Wheel::assumed(),
            clock_hz: 1_000_000,
            window: cast(0.01),
            to_period_below: 8,
            to_pulse_above: 12,
            period_edges: 4,
            standstill_timeout: cast(0.1),
            initial_mode: Mode::Period,
            edge_spread: T::ZERO,
        }
    }

    /// `K = pi R f / (2 N G)`, m/s: the speed of one count per tick (the
    /// wheel's distance per count times `f`).
    pub fn speed_scale(&self) -> T {
        self.wheel.quantum() * T::from_uint(self.clock_hz)
    }

    /// The window `T f` in ticks, rounded.
    pub fn window_ticks(&self) -> u32 {
        seconds_to_ticks(self.window, self.clock_hz)
    }

    /// The standstill timeout in ticks, rounded.
    pub fn standstill_ticks(&self) -> u32 {
        seconds_to_ticks(self.standstill_timeout, self.clock_hz)
    }

    /// Checks every field against its documented range.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first offending field.
    pub fn validate(&self) -> Result<(), Error> {
        let positive = |v: T| v.is_finite() && v > T::ZERO;
        self.wheel.validate()?;
        if self.clock_hz == 0 {
            return Err(Error::InvalidParameter("clock_hz must be >= 1"));
        }
        if !positive(self.window) || self.window_ticks() == 0 {
            return Err(Error::InvalidParameter(
                "window must be finite and at least one clock tick",
            ));
        }
        if self.to_period_below > self.to_pulse_above {
            return Err(Error::InvalidParameter(
                "to_period_below must be <= to_pulse_above",
            ));
        }
        if self.period_edges == 0 || self.period_edges > MAX_PERIOD_EDGES {
            return Err(Error::InvalidParameter(
                "period_edges must be 1..=MAX_PERIOD_EDGES",
            ));
        }
        if !positive(self.standstill_timeout) || self.standstill_ticks() == 0 {
            return Err(Error::InvalidParameter(
                "standstill_timeout must be finite and at least one clock tick",
            ));
        }
        if !positive(self.speed_scale()) {
            return Err(Error::InvalidParameter(
                "pi R f / (2 N G) must be finite and > 0",
            ));
        }
        let spread_ok = self.edge_spread >= T::ZERO && self.edge_spread.is_finite();
        if !spread_ok {
            return Err(Error::InvalidParameter(
                "edge_spread must be finite and >= 0 counts",
            ));
        }
        Ok(())
    }
}

impl<T: Real> Default for SpeedConfig<T> {
    /// [`SpeedConfig::paper`].
    fn default() -> Self {
        Self::paper()
    }
}

/// `round(seconds * hz)` saturated to `0..=u32::MAX` (0 for non-finite input).
fn seconds_to_ticks<T: Real>(seconds: T, hz: u32) -> u32 {
    let ticks = libm::round(seconds.to_f64() * f64::from(hz));
    if ticks.is_finite() && ticks > 0.0 {
        if ticks >= u32::MAX as f64 {
            u32::MAX
        } else {
            ticks as u32
        }
    } else {
        0
    }
}

/// One speed measurement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate<T> {
    /// Signed speed of the wheel's contact point, m/s (positive forward).
    pub speed: T,
    /// How it was measured.
    pub mode: Mode,
    /// The quantisation step of this measurement, m/s (>= 0): pulse mode
    /// `K / W`, period mode `|S| / (C - 1)`, standstill `K / E` (see the
    /// module documentation).
    pub resolution: T,
    /// First tick of the span the speed averages over (a window boundary, the
    /// first edge of a period-mode span, or the last edge before standstill).
    pub from_tick: u32,
    /// Last tick of that span (the window boundary, or the last edge of a
    /// period-mode span).
    pub to_tick: u32,
}

/// The two-mode speed estimator of one wheel. Allocation-free; all state is
/// a few words plus `MAX_PERIOD_EDGES + 1` time stamps.
#[derive(Debug, Clone)]
pub struct SpeedEstimator<T> {
    config: SpeedConfig<T>,
    k: T,
    window_ticks: u32,
    standstill_ticks: u32,
    mode: Mode,
    switches: u32,
    window_start: u32,
    window_count: i32,
    /// Ring of the time stamps of the current same-direction run of edges.
    stamps: [u32; MAX_PERIOD_EDGES as usize + 1],
    /// Where the next stamp goes (the oldest once the ring is full).
    next: usize,
    /// Edges in the current run, capped at `period_edges + 1`.
    run: usize,
    /// Direction of the current run (`None` after an invalid transition).
    direction: Option<Direction>,
    /// Tick of the last edge, invalid transition, or of the start.
    last_activity: u32,
}

impl<T: Real> SpeedEstimator<T> {
    /// A new estimator in `config.initial_mode`, whose first window starts at
    /// tick `now`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if `config` fails [`SpeedConfig::validate`].
    pub fn new(config: SpeedConfig<T>, now: u32) -> Result<Self, Error> {
        config.validate()?;
        Ok(Self::fresh(config, now))
    }

    /// A new estimator from an already validated configuration.
    fn fresh(config: SpeedConfig<T>, now: u32) -> Self {
        Self {
            config,
            k: config.speed_scale(),
            window_ticks: config.window_ticks(),
            standstill_ticks: config.standstill_ticks(),
            mode: config.initial_mode,
            switches: 0,
            window_start: now,
            window_count: 0,
            stamps: [0; MAX_PERIOD_EDGES as usize + 1],
            next: 0,
            run: 0,
            direction: None,
            last_activity: now,
        }
    }

    /// Forgets all history and restarts at tick `now` in the initial mode
    /// (the switch count is kept).
    pub fn reset(&mut self, now: u32) {
        let switches = self.switches;
        *self = Self {
            switches,
            ..Self::fresh(self.config, now)
        };
    }

    /// The configuration.
    pub const fn config(&self) -> &SpeedConfig<T> {
        &self.config
    }

    /// The switching state: the mode the next window will be measured in,
    /// unless that window's count moves it across a threshold.
    pub const fn mode(&self) -> Mode {
        self.mode
    }

    /// How many times the switching state changed (saturating): a chatter
    /// diagnostic.
    pub const fn mode_switches(&self) -> u32 {
        self.switches
    }

    /// The net count of the current window so far (counts, signed).
    pub const fn window_count(&self) -> i32 {
        self.window_count
    }

    /// One x4 edge in `direction`, captured at tick `tick`. Edges must be fed
    /// in time order.
    pub fn on_edge(&mut self, tick: u32, direction: Direction) {
        self.window_count = self.window_count.saturating_add(direction.sign());
        if self.direction != Some(direction) {
            self.direction = Some(direction);
            self.run = 0;
            self.next = 0;
        }
        let ring = self.config.period_edges as usize + 1;
        self.stamps[self.next] = tick;
        self.next = (self.next + 1) % ring;
        self.run = (self.run + 1).min(ring);
        self.last_activity = tick;
    }

    /// An invalid transition at tick `tick`: no count, and the period-mode
    /// span restarts (edges may have been missed).
    pub fn on_invalid(&mut self, tick: u32) {
        self.direction = None;
        self.run = 0;
        self.next = 0;
        self.last_activity = tick;
    }

    /// Feeds what the decoder returned for the sample taken at tick `tick`.
    #[inline]
    pub fn on_transition(&mut self, tick: u32, transition: Transition) {
        match transition {
            Transition::Hold => {}
            Transition::Count(direction) => self.on_edge(tick, direction),
            Transition::Invalid => self.on_invalid(tick),
        }
    }

    /// Closes the current window at tick `now` (after the edges up to `now`
    /// were fed), decides the mode from its count, and returns the speed
    /// measured in that mode. The next window starts at `now`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if the window is empty (`now` equals the
    /// previous boundary); the estimator is then unchanged.
    pub fn end_window(&mut self, now: u32) -> Result<Estimate<T>, Error> {
        if now == self.window_start {
            return Err(Error::InvalidParameter(
                "a window must span at least one tick",
            ));
        }
        Ok(self.close_window(now))
    }

    /// Closes the window if at least the configured window
    /// ([`SpeedConfig::window_ticks`]) has passed by tick `now`, as
    /// [`end_window`](Self::end_window); otherwise `None`.
    pub fn poll(&mut self, now: u32) -> Option<Estimate<T>> {
        (now.wrapping_sub(self.window_start) >= self.window_ticks).then(|| self.close_window(now))
    }

    fn close_window(&mut self, now: u32) -> Estimate<T> {
        let count = self.window_count;
        let n = count.unsigned_abs();
        let mode = match self.mode {
            Mode::Pulse if n < self.config.to_period_below => Mode::Period,
            Mode::Period if n > self.config.to_pulse_above => Mode::Pulse,
            unchanged => unchanged,
        };
        if mode != self.mode {
            self.mode = mode;
            self.switches = self.switches.saturating_add(1);
        }
        let estimate = match mode {
            Mode::Pulse => self.pulse_estimate(count, now),
            Mode::Period => self
                .period_estimate(now)
                .unwrap_or_else(|| self.pulse_estimate(count, now)),
        };
        self.window_start = now;
        self.window_count = 0;
        estimate
    }

    fn pulse_estimate(&self, count: i32, now: u32) -> Estimate<T> {
        let w = T::from_uint(now.wrapping_sub(self.window_start));
        Estimate {
            speed: self.k * T::from_int(count) / w,
            mode: Mode::Pulse,
            resolution: self.k / w * (T::ONE + self.config.edge_spread),
            from_tick: self.window_start,
            to_tick: now,
        }
    }

    /// The period-mode estimate, or `None` when there is no complete span.
    fn period_estimate(&self, now: u32) -> Option<Estimate<T>> {
        let m = self.config.period_edges as usize;
        let quiet = now.wrapping_sub(self.last_activity);
        let no_span = self.run < m + 1;
        // Standstill: no edge for the timeout, or no edge in this window and
        // no span to report (then `K / E` is tighter than the window's `K / W`).
        if quiet > self.standstill_ticks
            || (no_span && quiet >= now.wrapping_sub(self.window_start))
        {
            return Some(Estimate {
                speed: T::ZERO,
                mode: Mode::Period,
                resolution: self.k / T::from_uint(quiet) * (T::ONE + self.config.edge_spread),
                from_tick: self.last_activity,
                to_tick: now,
            });
        }
        if no_span {
            return None;
        }
        let oldest = self.stamps[self.next];
        let newest = self.stamps[(self.next + m) % (m + 1)];
        let c = newest.wrapping_sub(oldest);
        if c < 2 {
            return None;
        }
        let speed = self.k * T::from_uint(self.config.period_edges) / T::from_uint(c);
        Some(Estimate {
            speed: if self.direction == Some(Direction::Reverse) {
                -speed
            } else {
                speed
            },
            mode: Mode::Period,
            resolution: speed / T::from_uint(c - 1),
            from_tick: oldest,
            to_tick: newest,
        })
    }
}
