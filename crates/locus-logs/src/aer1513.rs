//! The laser_wall_1d data set (University of Toronto AER1513, assignment 1:
//! a robot on a rail measures its distance to a wall with a laser
//! rangefinder; Vicon gives its true position), read into a Locus log.
//!
//! The text file (`dataset1.txt`, see `../shared/data/README.md`) has
//! three header lines `# wall_x_m L`, `# r_var_m2 R`, `# v_var_m2_per_s2
//! V`, then `t v r x_true` per line (s, m/s, m, m). The log it becomes:
//!
//! - a `wall` at `x = L` from `(L, -5)` to `(L, 5)` (the rail is the x
//!   axis; the wall is perpendicular to it, 10 m long so that the beam
//!   always meets it);
//! - one beam sensor (id 0) of one beam at the robot's origin facing +x,
//!   ranges valid in [[`MIN_RANGE`], [`MAX_RANGE`]) (the data's ranges all
//!   lie within; the sensor's own limits are not published);
//! - per data line: `odometry,t,v,0`, `scan,t,0,r` and `truth,t,x_true,0`
//!   (truth of positions only: the robot's heading is 0 by construction on
//!   the rail, but Vicon gave only x, so none is claimed);
//! - a `start` at the first truth position with heading 0 (the rail's
//!   direction: known by construction, not measured), and no `noise`
//!   records: the published `r_var` and `v_var` are returned beside the log
//!   ([`Aer1513::r_var`], [`Aer1513::v_var`]), for a baseline that uses
//!   them, but a replay is meant to estimate the noise from the log.

use std::path::Path;

use crate::beam_sensor::BeamSensor;
use crate::error::{Error, FieldProblem, Result, excerpt};
use crate::locus_csv::LocusLog;
use crate::mrclam::{Groundtruth, Odometry, TruthPose};
use crate::scans::Scans;
use crate::sensor::SensorMount;
use crate::text::{TimeOrder, existing, read_text, records};
use crate::wall::Wall;

/// Smallest range the converted beam sensor reports as valid, m.
pub const MIN_RANGE: f64 = 0.5;

/// Range at and beyond which the converted beam sensor reports no return, m.
pub const MAX_RANGE: f64 = 5.0;

/// Half the length of the converted wall, m (it spans y in `+-5`).
pub const WALL_HALF_LENGTH: f64 = 5.0;

/// The data set as a Locus log, with the figures the course published.
#[derive(Debug, Clone, PartialEq)]
pub struct Aer1513 {
    /// The log (see the module documentation).
    pub log: LocusLog,
    /// The wall's position on the rail, m (`l`).
    pub wall_x: f64,
    /// The published variance of a range, m^2 (`r_var`).
    pub r_var: f64,
    /// The published variance of a speed, m^2/s^2 (`v_var`).
    pub v_var: f64,
}

/// The header lines, in the order they are looked for.
const HEADERS: [&str; 3] = ["wall_x_m", "r_var_m2", "v_var_m2_per_s2"];

/// What a missing header line is called in its error.
const MISSING: [&str; 3] = [
    "`# wall_x_m` header line",
    "`# r_var_m2` header line",
    "`# v_var_m2_per_s2` header line",
];

/// Reads the data set's text file at `path` (plain or `.xz`).
///
/// # Errors
/// As [`crate::locus_csv::read`] for the file; [`Error::Missing`] for a
/// header line that is absent; a malformed header value or data line
/// ([`Error::Field`], [`Error::Record`]: a time that goes back, a line of
/// more than 4 fields) naming its line and field.
pub fn read(path: &Path) -> Result<Aer1513> {
    let file = existing(path)?;
    parse(&read_text(&file)?, &file)
}

/// Parses the text of the data set's file; `path` names it in errors.
///
/// # Errors
/// As [`read`].
pub fn parse(text: &str, path: &Path) -> Result<Aer1513> {
    let mut header = [None; 3];
    for (i, line) in text.lines().enumerate() {
        let Some(rest) = line.trim_start().strip_prefix('#') else {
            continue;
        };
        let mut words = rest.split_ascii_whitespace();
        let (Some(key), Some(value)) = (words.next(), words.next()) else {
            continue;
        };
        if let Some(k) = HEADERS.iter().position(|h| *h == key) {
            let field_error = |problem| Error::Field {
                path: path.to_path_buf(),
                line: i + 1,
                column: 3,
                field: HEADERS[k],
                problem,
            };
            let v: f64 = value
                .parse()
                .map_err(|_| field_error(FieldProblem::NotANumber(excerpt(value))))?;
            // The wall's position may be any finite number; the variances
            // must be > 0.
            if !v.is_finite() {
                return Err(field_error(FieldProblem::NotFinite(excerpt(value))));
            }
            if k > 0 && v <= 0.0 {
                return Err(field_error(FieldProblem::OutOfRange {
                    value: v.to_string(),
                    expected: "> 0",
                }));
            }
            header[k] = Some(v);
        }
    }
    let [wall_x, r_var, v_var] = [0, 1, 2].map(|k| {
        header[k].ok_or(Error::Missing {
            path: path.to_path_buf(),
            what: MISSING[k],
        })
    });
    let (wall_x, r_var, v_var) = (wall_x?, r_var?, v_var?);
    let sensor = BeamSensor {
        id: 0,
        mount: SensorMount::default(),
        min_range: MIN_RANGE,
        max_range: MAX_RANGE,
        angle_0: 0.0,
        angle_step: 0.0,
        count: 1,
    };
    let rows = text.lines().count();
    let mut odometry = Vec::with_capacity(rows);
    let mut truth = Vec::with_capacity(rows);
    let mut scans = Scans::with_capacity(rows, rows);
    let mut order = TimeOrder::new();
    for mut f in records(text, path) {
        let time = f.f64("t")?;
        order.check(&f, time)?;
        let v = f.f64("v")?;
        let r = f.non_negative("r")?;
        let x = f.f64("x_true")?;
        f.end(4)?;
        odometry.push(Odometry {
            time,
            v,
            omega: 0.0,
        });
        scans.push(time, 0, &[sensor.reading(r)]);
        truth.push(TruthPose {
            time,
            x,
            y: 0.0,
            theta: 0.0,
        });
    }
    // The rail is the x axis and the robot faces along it: its heading is
    // 0 by construction, its first position the first truth's.
    let start = truth.first().map(|t| TruthPose { theta: 0.0, ..*t });
    let log = LocusLog {
        start,
        odometry,
        // Times were checked not to decrease.
        truth: Groundtruth::positions(truth).unwrap_or_default(),
        walls: vec![Wall {
            x1: wall_x,
            y1: -WALL_HALF_LENGTH,
            x2: wall_x,
            y2: WALL_HALF_LENGTH,
        }],
        beam_sensors: vec![sensor],
        scans,
        ..LocusLog::default()
    };
    Ok(Aer1513 {
        log,
        wall_x,
        r_var,
        v_var,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("dataset1.txt")
    }

    const HEAD: &str = "# wall_x_m 4.5\n# r_var_m2 0.0004\n# v_var_m2_per_s2 0.002\n# t v r x\n";

    #[test]
    fn lines_become_odometry_scans_and_truth() {
        let d = parse(
            &format!("{HEAD}0 0 3.5 1\n0.1 0.2 3.48 1.02\n0.2 0.2 7 1.04\n"),
            p(),
        )
        .unwrap();
        assert_eq!((d.wall_x, d.r_var, d.v_var), (4.5, 0.0004, 0.002));
        assert_eq!(d.log.walls[0].x1, 4.5);
        assert_eq!(d.log.odometry[1].v, 0.2);
        assert_eq!(d.log.scans.get(1).unwrap().ranges, [3.48_f32]);
        assert_eq!(
            d.log.scans.get(2).unwrap().ranges,
            [crate::scans::NO_RETURN],
            "beyond MAX_RANGE"
        );
        assert!(!d.log.truth.has_heading());
        assert!(d.log.noise.is_empty());
        assert_eq!(d.log.start.map(|s| s.theta), Some(0.0));
        let text = crate::locus_csv::write(&d.log);
        assert_eq!(crate::locus_csv::parse(&text, p()).unwrap(), d.log);
    }

    #[test]
    fn malformed_files_name_the_line_and_field() {
        let e = parse("# r_var_m2 1\n# v_var_m2_per_s2 1\n0 0 1 1\n", p()).unwrap_err();
        assert_eq!(e.to_string(), "dataset1.txt: no `# wall_x_m` header line");
        let e = parse(&format!("{HEAD}0 0 3.5 1\n0.1 0.2 -3 1\n"), p()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "dataset1.txt:6: field \"r\" (column 3): -3 is out of range: >= 0"
        );
        let e = parse(&format!("{HEAD}1 0 3.5 1\n0.5 0 3 1\n"), p()).unwrap_err();
        assert!(
            e.to_string().starts_with("dataset1.txt:6: time 0.5 s"),
            "{e}"
        );
        let e = parse("# wall_x_m 4\n# r_var_m2 0\n# v_var_m2_per_s2 1\n", p()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "dataset1.txt:2: field \"r_var_m2\" (column 3): 0 is out of range: > 0"
        );
        let e = parse(&format!("{HEAD}0 0 3.5\n"), p()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "dataset1.txt:5: field \"x_true\" (column 4): missing"
        );
    }
}
