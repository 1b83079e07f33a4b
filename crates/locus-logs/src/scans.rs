//! The scans of a log's beam sensors, stored flat: every range of every
//! scan in one `Vec<f32>`, so a log of many long scans costs 4 bytes a
//! beam and 24 bytes a scan, with no allocation per scan.
//!
//! A range is stored as `f32` (about 7 significant digits: 0.1 mm at
//! 1 km, finer than any range sensor), with two special values:
//! [`NO_RETURN`] (`f32::INFINITY`: the beam saw nothing before its
//! `max_range`; written `max`) and [`MISSING`] (`f32::NAN`: no valid
//! reading, e.g. one below the sensor's `min_range`; written `-`).

/// A beam that saw nothing within its sensor's `max_range` (written `max`).
pub const NO_RETURN: f32 = f32::INFINITY;

/// A beam with no valid reading (written `-`).
pub const MISSING: f32 = f32::NAN;

/// What one stored range means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reading {
    /// A range, m (finite, within the sensor's limits when read from a
    /// file).
    Range(f32),
    /// No return ([`NO_RETURN`]).
    NoReturn,
    /// No valid reading ([`MISSING`]).
    Missing,
}

impl Reading {
    /// The meaning of a stored range: `+inf` is no return, NaN (or `-inf`,
    /// which a reader never stores) missing, anything else a range.
    #[must_use]
    pub fn of(stored: f32) -> Self {
        if stored == NO_RETURN {
            Self::NoReturn
        } else if stored.is_finite() {
            Self::Range(stored)
        } else {
            Self::Missing
        }
    }
}

/// One scan: the ranges of every beam of a beam sensor, taken at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scan<'a> {
    /// Time the scan was taken, s.
    pub time: f64,
    /// The beam sensor's id.
    pub sensor: u32,
    /// One stored range per beam, in beam order ([`Reading::of`]).
    pub ranges: &'a [f32],
}

/// The scans of a log in file order, stored flat (see the module
/// documentation). Equality compares ranges bit for bit (so `MISSING`
/// equals itself).
#[derive(Debug, Clone, Default)]
pub struct Scans {
    times: Vec<f64>,
    sensors: Vec<u32>,
    /// Where each scan's ranges end in `ranges` (its start is the end of
    /// the scan before it, or 0).
    ends: Vec<usize>,
    ranges: Vec<f32>,
}

impl Scans {
    /// No scans, with room for `scans` scans of `ranges` ranges in all.
    #[must_use]
    pub fn with_capacity(scans: usize, ranges: usize) -> Self {
        Self {
            times: Vec::with_capacity(scans),
            sensors: Vec::with_capacity(scans),
            ends: Vec::with_capacity(scans),
            ranges: Vec::with_capacity(ranges),
        }
    }

    /// Appends a scan taken at `time` (s) by beam sensor `sensor`.
    pub fn push(&mut self, time: f64, sensor: u32, ranges: &[f32]) {
        self.ranges.extend_from_slice(ranges);
        self.close(time, sensor);
    }

    /// Appends a range to the scan being built (see [`Scans::close`]).
    pub(crate) fn push_range(&mut self, range: f32) {
        self.ranges.push(range);
    }

    /// Ends the scan being built: the ranges pushed since the last scan.
    pub(crate) fn close(&mut self, time: f64, sensor: u32) {
        self.times.push(time);
        self.sensors.push(sensor);
        self.ends.push(self.ranges.len());
    }

    /// Number of scans.
    #[must_use]
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether there is no scan.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Number of ranges of all scans.
    #[must_use]
    pub fn ranges_len(&self) -> usize {
        self.ranges.len()
    }

    /// Scan `i` (in file order), `None` past the last.
    #[must_use]
    pub fn get(&self, i: usize) -> Option<Scan<'_>> {
        let end = *self.ends.get(i)?;
        let start = if i == 0 { 0 } else { self.ends[i - 1] };
        Some(Scan {
            time: self.times[i],
            sensor: self.sensors[i],
            ranges: &self.ranges[start..end],
        })
    }

    /// The scans in file order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = Scan<'_>> + '_ {
        (0..self.len()).map(|i| self.get(i).expect("in range"))
    }

    /// The scans' times, s, in file order.
    #[must_use]
    pub fn times(&self) -> &[f64] {
        &self.times
    }
}

impl PartialEq for Scans {
    fn eq(&self, other: &Self) -> bool {
        self.times == other.times
            && self.sensors == other.sensors
            && self.ends == other.ends
            && self.ranges.len() == other.ranges.len()
            && self
                .ranges
                .iter()
                .zip(&other.ranges)
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scans_share_one_buffer_and_read_back_in_order() {
        let mut s = Scans::default();
        assert!(s.is_empty() && s.get(0).is_none());
        s.push(1.0, 0, &[1.0, NO_RETURN, MISSING]);
        s.push(1.5, 2, &[]);
        s.push(2.0, 0, &[0.5, 0.25, 4.0]);
        assert_eq!(s.len(), 3);
        assert_eq!(s.ranges_len(), 6);
        let third = s.get(2).unwrap();
        assert_eq!((third.time, third.sensor), (2.0, 0));
        assert_eq!(third.ranges, [0.5, 0.25, 4.0]);
        assert!(s.get(1).unwrap().ranges.is_empty());
        let first = s.get(0).unwrap();
        assert_eq!(
            first
                .ranges
                .iter()
                .map(|r| Reading::of(*r))
                .collect::<Vec<_>>(),
            [Reading::Range(1.0), Reading::NoReturn, Reading::Missing]
        );
        assert_eq!(s.iter().map(|x| x.sensor).collect::<Vec<_>>(), [0, 2, 0]);
        assert_eq!(s, s.clone(), "MISSING equals itself");
        let mut t = s.clone();
        t.push_range(1.0);
        assert_ne!(s, t, "a range pushed counts");
        t.close(3.0, 0);
        assert_ne!(s, t);
        assert_eq!(Reading::of(f32::NEG_INFINITY), Reading::Missing);
    }
}
