//! The flags of `locus replay` (its sources, [`Source`], and the replay's
//! options, [`Flags`]) and the settings they give ([`Flags::options`],
//! a [`locus_replay::Options`]); `locus tune` and `locus family` replay with the
//! flags' defaults ([`default_config`]).

use std::path::PathBuf;

use anyhow::Context as _;
use clap::{Args as ClapArgs, Subcommand};
use locus_logs::mrclam::Dataset;
use locus_models::plausible::Limits;
use locus_replay::policy::Estimation;
use locus_replay::{Config, GaussMarkov, Log, Options};

use crate::plot::PictureArgs;
use crate::replay::relations::Reference;

/// The log replayed: its format and where it is.
#[derive(Subcommand, Debug)]
pub enum Source {
    /// A robot of a UTIAS MRCLAM dataset directory (e.g.
    /// `../shared/data/mrclam/MRCLAM_Dataset6`; files plain or `.xz`).
    /// Robot-to-robot sightings and unknown barcodes are counted and left
    /// out.
    Mrclam {
        /// The dataset directory.
        dir: PathBuf,
        /// The robot (1-5).
        #[arg(long, default_value_t = 1)]
        robot: u32,
        /// Also write the robot's log in Locus's CSV format to this file
        /// (docs/log-format.md).
        #[arg(long)]
        export: Option<PathBuf>,
        #[command(flatten)]
        common: Flags,
    },
    /// A log in Locus's CSV format (docs/log-format.md; `.xz` read
    /// directly).
    Csv {
        /// The log file.
        file: PathBuf,
        #[command(flatten)]
        common: Flags,
    },
    /// A log in libRSF's text format (e.g.
    /// `../shared/data/indoor_uwb/Indoor_UWB_Input.txt`): UWB ranges to
    /// beacons (range-only sightings), differential-drive odometry. The
    /// ranges' declared variance is not used as the noise.
    Librsf {
        /// The input file (`range2`, `odom2diff` lines).
        input: PathBuf,
        /// The ground truth (`point2` lines, positions only). Default: the
        /// input's name with `_Input` replaced by `_GT`, if that file exists.
        #[arg(long)]
        truth: Option<PathBuf>,
        /// Also write the log in Locus's CSV format to this file
        /// (docs/log-format.md).
        #[arg(long)]
        export: Option<PathBuf>,
        #[command(flatten)]
        common: Flags,
    },
    /// The laser-to-a-wall log of paper 000's sensor in one dimension
    /// (`../shared/data/laser_wall_1d/dataset1.txt`: a robot on a rail,
    /// a laser rangefinder to a wall, Vicon truth): the wall, a one-beam
    /// sensor, speed odometry and position truth (docs/log-format.md).
    LaserWall {
        /// The data file (`t v r x_true` lines after the header).
        file: PathBuf,
        /// Also write the log in Locus's CSV format to this file.
        #[arg(long)]
        export: Option<PathBuf>,
        #[command(flatten)]
        common: Flags,
    },
    /// A ROS 2 bag (rosbag2, MCAP storage: `FILE.mcap`). Its messages are
    /// decoded with the schemas stored in the file, so any message type
    /// reads; `--topics MAPPING.toml` says which topics and fields are the
    /// velocities, the landmark sightings and the truth, and holds the
    /// landmark map (docs/bags.md). The landmark sensor's mount comes from
    /// `/tf_static`. `--list` prints the topics and proposes a mapping.
    Bag {
        /// The bag (`.mcap`).
        file: PathBuf,
        /// The mapping of topics and fields (TOML, docs/bags.md).
        #[arg(long, required_unless_present = "list")]
        topics: Option<PathBuf>,
        /// Print the bag's topics, types and message counts (as `ros2 bag
        /// info` does) and a proposed mapping, and stop.
        #[arg(long)]
        list: bool,
        /// Also write the log in Locus's CSV format to this file.
        #[arg(long)]
        export: Option<PathBuf>,
        #[command(flatten)]
        common: Flags,
    },
    /// A CARMEN log with corrected poses (e.g.
    /// `../shared/data/intel_lab/intel-corrected.log.gz`): laser scans,
    /// raw odometry, the corrected poses as truth at the scan times. The
    /// map comes from `--map` (e.g. one `locus map` made).
    Carmen {
        /// The CARMEN log (`.gz` read directly).
        file: PathBuf,
        /// The map the scans are corrected against (ROS map_server YAML,
        /// or walls as text or TOML: docs/maps.md).
        #[arg(long)]
        map: PathBuf,
        /// Also write the log in Locus's CSV format to this file.
        #[arg(long)]
        export: Option<PathBuf>,
        /// Judge the replay against relative poses between scan times
        /// (`t1 t2 dx dy dz roll pitch dyaw` lines, plain or `.xz`; e.g.
        /// `../shared/data/intel_lab/intel.relations.xz`, Kuemmerle et al.
        /// 2009): the mean translational and rotational errors of the
        /// filter, the smoother, the corrected poses and raw odometry
        /// (table and metrics.json).
        #[arg(long)]
        relations: Option<PathBuf>,
        /// The relations' times minus the log's, s. Default: the Intel
        /// lab's (`locus_logs::relations::INTEL_OFFSET`).
        #[arg(long, default_value_t = locus_logs::relations::INTEL_OFFSET, value_parser = super::finite_f64, requires = "relations")]
        relations_offset: f64,
        #[command(flatten)]
        common: Flags,
    },
}

/// A log read for `locus replay`, with what its source adds.
pub struct Loaded<'a> {
    /// The log.
    pub log: Log,
    /// Where to export it, if asked.
    pub export: Option<&'a PathBuf>,
    /// The replay's flags.
    pub flags: &'a Flags,
    /// For a robot on a rail ranging a wall: the wall's position (m) and
    /// the published range (m^2) and speed (m^2/s^2) variances, for the
    /// baselines (`locus_replay::rail`).
    pub rail: Option<[f64; 3]>,
    /// For a CARMEN log with `--relations`: the relations and the
    /// trajectories judged against them that need no replay.
    pub relations: Option<Reference>,
}

impl Source {
    /// The log, where to export it (if asked), the replay's flags and the
    /// rail's figures (see [`Loaded`]).
    ///
    /// # Errors
    /// A log or map that cannot be read, naming the file (and line).
    pub fn read(&self) -> anyhow::Result<Loaded<'_>> {
        let mut rail = None;
        let mut relations = None;
        let (log, export, flags) = self.log(&mut rail, &mut relations)?;
        Ok(Loaded {
            log,
            export,
            flags,
            rail,
            relations,
        })
    }

    fn log(
        &self,
        rail: &mut Option<[f64; 3]>,
        reference: &mut Option<Reference>,
    ) -> anyhow::Result<(Log, Option<&PathBuf>, &Flags)> {
        let name = |p: &std::path::Path| {
            p.file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
        };
        Ok(match self {
            Self::Mrclam {
                dir,
                robot,
                export,
                common,
            } => (
                Log::mrclam(&Dataset::open(dir)?, *robot)?,
                export.as_ref(),
                common,
            ),
            Self::Csv { file, common } => (Log::locus_csv(file)?, None, common),
            Self::Librsf {
                input,
                truth,
                export,
                common,
            } => {
                let truth = truth
                    .clone()
                    .or_else(|| locus_logs::librsf::sibling_truth(input));
                (
                    Log::librsf(input, truth.as_deref())?,
                    export.as_ref(),
                    common,
                )
            }
            Self::LaserWall {
                file,
                export,
                common,
            } => {
                let read = locus_logs::aer1513::read(file)?;
                *rail = Some([read.wall_x, read.r_var, read.v_var]);
                (
                    Log::from_locus(&name(file), read.log)?,
                    export.as_ref(),
                    common,
                )
            }
            Self::Bag {
                file,
                topics,
                export,
                common,
                ..
            } => {
                let mapping_path = topics
                    .as_ref()
                    .context("--topics MAPPING.toml is needed to replay a bag")?;
                (Log::bag(file, mapping_path)?, export.as_ref(), common)
            }
            Self::Carmen {
                file,
                map,
                export,
                relations,
                relations_offset,
                common,
            } => {
                let read = locus_logs::carmen::read(file)?;
                if let Some(path) = relations {
                    *reference = Some(Reference::carmen(&read, path, *relations_offset)?);
                }
                let mut log = Log::from_locus(&name(file), read.log)?;
                log.load_map(map)?;
                (log, export.as_ref(), common)
            }
        })
    }
}

/// The replay's options, the same for every source.
#[derive(ClapArgs, Debug)]
pub struct Flags {
    /// Output directory (created if missing). Default:
    /// `out/replay-<log name>`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Chi-square gate confidence in (0, 1).
    #[arg(long, default_value_t = Config::default().gate.unwrap_or(0.99), value_parser = super::positive_f64)]
    pub gate: f64,
    /// No gate: apply every sighting.
    #[arg(long)]
    pub no_gate: bool,
    /// Power spectral density of the forward-speed noise, m^2/s.
    /// Default: the log's `noise` record, else estimated from the log.
    #[arg(long, value_parser = super::positive_f64)]
    pub q_v: Option<f64>,
    /// Power spectral density of the turn-rate noise, rad^2/s.
    /// Default: the log's `noise` record, else estimated from the log.
    #[arg(long, value_parser = super::positive_f64)]
    pub q_omega: Option<f64>,
    /// Range noise standard deviation, m.
    /// Default: the log's `noise` record, else estimated from the log.
    #[arg(long, value_parser = super::positive_f64)]
    pub sigma_range: Option<f64>,
    /// Bearing noise standard deviation, rad.
    /// Default: the log's `noise` record, else estimated from the log.
    #[arg(long, value_parser = super::positive_f64)]
    pub sigma_bearing: Option<f64>,
    /// Standard deviation of a beam's range (range sensors against the
    /// map: IR, laser, lidar), m. Default: the log's `noise` record, else
    /// estimated from the log.
    #[arg(long, value_parser = super::positive_f64)]
    pub sigma_beam: Option<f64>,
    /// Stationary standard deviation of the beams' range bias, m: the part
    /// of a range sensor's error that persists from scan to scan (a
    /// Gauss-Markov state; with --beam-bias-tau). Default: searched with
    /// the beams' noise when that is estimated (docs/replay.md), else held
    /// at 0.
    #[arg(long, value_parser = super::positive_f64, requires = "beam_bias_tau")]
    pub beam_bias_sigma: Option<f64>,
    /// How late the ground truth's stamps are against the robot's sensors,
    /// s: the truth is compared at its stamp minus this (0: at the stamps).
    /// Default: measured from the sensors' range readings predicted from
    /// the truth, and applied where it is decisive (docs/replay.md).
    #[arg(long, value_parser = super::finite_f64, allow_negative_numbers = true)]
    pub truth_offset: Option<f64>,
    /// Time constant of the beams' range bias, s (with --beam-bias-sigma).
    #[arg(long, value_parser = super::positive_f64, requires = "beam_bias_sigma")]
    pub beam_bias_tau: Option<f64>,
    /// Beams a scan spends at most, spread evenly over it [count, >= 1]:
    /// neighbouring beams see the same surface with errors alike, so beyond
    /// a few tens each adds little information for its time (docs/replay.md).
    #[arg(long, default_value_t = locus_replay::Beams::default().per_scan, value_parser = clap::value_parser!(u32).range(1..))]
    pub beams_per_scan: u32,
    /// Initial value of the forward-speed scale factor (a state the filter
    /// estimates: the logged speed times it is the robot's).
    #[arg(long, default_value_t = 1.0, value_parser = super::positive_f64)]
    pub v_scale: f64,
    /// Initial value of the turn-rate scale factor (estimated, as
    /// `--v-scale`).
    #[arg(long, default_value_t = 1.0, value_parser = super::positive_f64)]
    pub omega_scale: f64,
    /// Hold the calibration states at their initial values (the speed and
    /// turn-rate scales at --v-scale and --omega-scale, the turn-rate,
    /// bearing and range biases at 0: standard deviation 1e-12, no random
    /// walk): the filter of the pose alone, as the simulator's closed
    /// loops are. The default noise estimation may still free a bias the
    /// log tells; with --no-estimate every state stays held.
    #[arg(long)]
    pub hold_calibration: bool,
    /// Standard deviations of the initial estimate: x (m), y (m) and
    /// heading (rad), comma-separated. Default 0.05,0.05,0.05.
    #[arg(long, value_name = "SX,SY,STHETA", value_parser = three_positive)]
    pub initial_std: Option<[f64; 3]>,
    /// Where the robot starts: x (m), y (m) and heading (rad) in the map's
    /// frame, comma-separated, at the first odometry time. Replaces the
    /// log's start pose and the truth's; give --initial-std with it to say
    /// how far off it may be.
    #[arg(long, value_name = "X,Y,THETA", value_parser = three_finite, allow_hyphen_values = true)]
    pub start: Option<[f64; 3]>,
    /// Student-t degrees of freedom of the sightings' noise: sightings far
    /// from the prediction are down-weighted rather than only gated.
    #[arg(long, default_value_t = 4.0, value_parser = super::positive_f64)]
    pub robust_dof: f64,
    /// Gaussian sightings: no Student-t weighting (the gate alone).
    #[arg(long)]
    pub no_robust: bool,
    /// How long after an odometry record the robot moves as it says, s.
    /// Default: estimated from the log (the delay of smallest innovation likelihood
    /// on a grid from 0 to 0.4 s).
    #[arg(long, value_parser = super::finite_f64)]
    pub odometry_delay: Option<f64>,
    /// Estimate only the odometry delay from the log: the noise from the
    /// flags, the log's noise records and the built-in values (MRCLAM's:
    /// q_v 0.002 m^2/s, q_omega 0.002 rad^2/s, range 1 m, bearing
    /// 0.01 rad), the biases held at 0. By default every noise level the
    /// flags and the log's records leave open is estimated from the log
    /// itself (no ground truth), and the turn-rate and bearing biases are
    /// estimated where the whole log tells them, else held at 0 and
    /// reported as held (docs/replay.md).
    #[arg(long)]
    pub delay_only: bool,
    /// Estimate nothing: the flags, the log's noise records and the
    /// built-in values as they are (odometry delay 0 unless given, biases
    /// held at 0).
    #[arg(long, conflicts_with = "delay_only")]
    pub no_estimate: bool,
    /// Also run the Rauch-Tung-Striebel smoother over the whole log: its
    /// accuracy, 3-sigma shares and NEES beside the filter's (table and
    /// metrics.json), and the smoothed trajectory in smoothed.csv.
    #[arg(long)]
    pub smooth: bool,
    /// Find the initial pose from the first sightings (the landmarks seen
    /// in the first seconds, carried back by dead reckoning and fitted to
    /// the map; later windows if those fix none), even when the log has a
    /// start pose or ground truth. A log with neither always starts this
    /// way. A pose that fewer than half of a window's sightings support,
    /// or whose landmarks fix no heading, is refused.
    #[arg(long)]
    pub start_from_sightings: bool,
    /// Top speed of the robot, m/s: an odometry record whose speed is
    /// above it is refused as implausible (counted, listed with its line;
    /// the velocities before it held). The same rule as the robot link's
    /// (docs/log-format.md, "Plausibility").
    #[arg(long, default_value_t = Limits::GENERIC.max_speed, value_parser = super::positive_f64)]
    pub max_speed: f64,
    /// Top turn rate of the robot, rad/s (as --max-speed).
    #[arg(long, default_value_t = Limits::GENERIC.max_turn_rate, value_parser = super::positive_f64)]
    pub max_turn_rate: f64,
    /// Longest time between two odometry records, s: a record later than
    /// this after the one before it is refused (as --max-speed).
    #[arg(long, default_value_t = Limits::GENERIC.max_odometry_gap, value_parser = super::positive_f64)]
    pub max_odometry_gap: f64,
    /// Pictures.
    #[command(flatten)]
    pub pictures: PictureArgs,
    /// Foxglove output.
    #[command(flatten)]
    pub foxglove: crate::foxglove::McapArgs,
}

impl Flags {
    /// The replay's settings as the flags give them.
    pub fn options(&self) -> Options {
        Options {
            gate: (!self.no_gate).then_some(self.gate),
            robust_dof: (!self.no_robust).then_some(self.robust_dof),
            smooth: self.smooth,
            start_from_sightings: self.start_from_sightings,
            v_scale: self.v_scale,
            omega_scale: self.omega_scale,
            hold_calibration: self.hold_calibration,
            initial_std: self.initial_std,
            start: self.start,
            beams_per_scan: self.beams_per_scan,
            limits: Limits {
                max_speed: self.max_speed,
                max_turn_rate: self.max_turn_rate,
                max_odometry_gap: self.max_odometry_gap,
                ..Limits::GENERIC
            },
            noise: locus_replay::log::NoiseRecords {
                q_v: self.q_v,
                q_omega: self.q_omega,
                sigma_range: self.sigma_range,
                sigma_bearing: self.sigma_bearing,
                sigma_beam: self.sigma_beam,
            },
            odometry_delay: self.odometry_delay,
            beam_bias: self
                .beam_bias_sigma
                .zip(self.beam_bias_tau)
                .map(|(sigma, tau)| GaussMarkov { sigma, tau }),
            estimation: if self.no_estimate {
                Estimation::Nothing
            } else if self.delay_only {
                Estimation::Delay
            } else {
                Estimation::Noise
            },
            truth_offset: self.truth_offset,
        }
    }
}

/// Three numbers, each finite and > 0, separated by commas (`0.01,0.01,0.02`).
fn three_positive(text: &str) -> Result<[f64; 3], String> {
    three(text, super::positive_f64)
}

/// Three finite numbers separated by commas (`1.5,-2,0.3`).
fn three_finite(text: &str) -> Result<[f64; 3], String> {
    three(text, super::finite_f64)
}

/// Three numbers, each read by `parse`, separated by commas.
fn three(text: &str, parse: fn(&str) -> Result<f64, String>) -> Result<[f64; 3], String> {
    let values = text
        .split(',')
        .map(|t| parse(t.trim()))
        .collect::<Result<Vec<f64>, String>>()?;
    <[f64; 3]>::try_from(values.as_slice()).map_err(|_| {
        format!(
            "expected three values separated by commas, got {}",
            values.len()
        )
    })
}

/// The replay's settings other than the noise and the odometry delay for
/// `locus replay csv FILE` with no flags (the flags' defaults, parsed as
/// the command parses them), for benchmarks that must replay as the
/// command does (`locus family`).
pub fn default_config() -> Config {
    #[derive(clap::Parser)]
    struct NoFlags {
        #[command(flatten)]
        common: Flags,
    }
    <NoFlags as clap::Parser>::parse_from(["replay"])
        .common
        .options()
        .config()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(clap::Parser)]
    struct NoFlags {
        #[command(flatten)]
        common: Flags,
    }

    /// `locus replay` with no flags replays as the library's (and the
    /// Python package's) default options do.
    #[test]
    fn no_flags_are_the_default_options() {
        let flags = <NoFlags as clap::Parser>::parse_from(["replay"]).common;
        assert_eq!(flags.options(), Options::default());
    }
}
