//! The noise levels a log declares for its robot (the `noise` records of a
//! Locus log).

/// Noise levels declared by a log, each optional. A replay may use them in
/// place of its own defaults.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NoiseRecords {
    /// Power spectral density of the forward-speed noise, m^2/s (white noise
    /// on `v`: a step of `dt` seconds gets variance `q_v / dt`).
    pub q_v: Option<f64>,
    /// Power spectral density of the turn-rate noise, rad^2/s.
    pub q_omega: Option<f64>,
    /// Standard deviation of a measured range, m.
    pub sigma_range: Option<f64>,
    /// Standard deviation of a measured bearing, rad.
    pub sigma_bearing: Option<f64>,
    /// Standard deviation of a beam sensor's range (`scan` records), m
    /// (version 4).
    pub sigma_beam: Option<f64>,
}

impl NoiseRecords {
    /// The names of the levels of odometry and landmark sightings, as
    /// written in a `noise` record: the levels a replay of landmark
    /// sightings settles.
    pub const NAMES: [&'static str; 4] = ["q_v", "q_omega", "sigma_range", "sigma_bearing"];

    /// The names of every level, as written in a `noise` record, in the
    /// order [`NoiseRecords::iter`] yields them: [`NoiseRecords::NAMES`],
    /// then the beam sensors' `sigma_beam` (version 4).
    pub const ALL_NAMES: [&'static str; 5] = [
        "q_v",
        "q_omega",
        "sigma_range",
        "sigma_bearing",
        "sigma_beam",
    ];

    /// The level named `name` (one of [`NoiseRecords::ALL_NAMES`]), `None`
    /// for any other name.
    #[must_use]
    pub fn get(&self, name: &str) -> Option<Option<f64>> {
        Some(match name {
            "q_v" => self.q_v,
            "q_omega" => self.q_omega,
            "sigma_range" => self.sigma_range,
            "sigma_bearing" => self.sigma_bearing,
            "sigma_beam" => self.sigma_beam,
            _ => return None,
        })
    }

    /// The slot of the level named `name` (one of
    /// [`NoiseRecords::ALL_NAMES`]), `None` for any other name.
    pub fn get_mut(&mut self, name: &str) -> Option<&mut Option<f64>> {
        match name {
            "q_v" => Some(&mut self.q_v),
            "q_omega" => Some(&mut self.q_omega),
            "sigma_range" => Some(&mut self.sigma_range),
            "sigma_bearing" => Some(&mut self.sigma_bearing),
            "sigma_beam" => Some(&mut self.sigma_beam),
            _ => None,
        }
    }

    /// The levels that are given, as `(name, value)`, in the order of
    /// [`NoiseRecords::ALL_NAMES`].
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        Self::ALL_NAMES
            .into_iter()
            .filter_map(|name| Some((name, self.get(name).flatten()?)))
    }

    /// Whether no level is given.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.iter().next().is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_reach_their_own_fields() {
        let mut n = NoiseRecords::default();
        assert!(n.is_empty());
        for (i, name) in NoiseRecords::ALL_NAMES.into_iter().enumerate() {
            *n.get_mut(name).unwrap() = Some(f64::from(u8::try_from(i).unwrap()) + 0.5);
        }
        assert_eq!(
            n,
            NoiseRecords {
                q_v: Some(0.5),
                q_omega: Some(1.5),
                sigma_range: Some(2.5),
                sigma_bearing: Some(3.5),
                sigma_beam: Some(4.5),
            }
        );
        let listed: Vec<_> = n.iter().collect();
        assert_eq!(
            listed,
            [
                ("q_v", 0.5),
                ("q_omega", 1.5),
                ("sigma_range", 2.5),
                ("sigma_bearing", 3.5),
                ("sigma_beam", 4.5)
            ]
        );
        assert_eq!(n.get("q"), None);
        assert!(n.get_mut("Q_V").is_none());
        n.q_omega = None;
        assert_eq!(
            n.iter().map(|(k, _)| k).collect::<Vec<_>>(),
            ["q_v", "sigma_range", "sigma_bearing", "sigma_beam"]
        );
        assert_eq!(NoiseRecords::ALL_NAMES[..4], NoiseRecords::NAMES);
    }
}
