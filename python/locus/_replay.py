"""``locus.replay``: a recorded log through the engine of ``locus replay``."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Dict, Iterable, List, Mapping, Optional, Union

import numpy as np

from . import _locus
from ._cluster import spread

EVENTS = ("odometry", "sighting", "scan")


@dataclass(frozen=True)
class Smoothed:
    """The Rauch-Tung-Striebel smoother's track, one row per step."""

    poses: np.ndarray
    """(N, 3): x [m], y [m], heading [rad]."""
    covariances: np.ndarray
    """(N, 3, 3): the pose's covariance [m^2, m rad, rad^2]."""
    calibration: np.ndarray
    """(N, 4): speed scale, turn-rate scale, turn-rate bias [rad/s], bearing bias [rad]."""


@dataclass(frozen=True)
class Replay:
    """A replayed log: one row per event (odometry record, sighting or scan),
    in time order, with the filter's estimate after it.

    ``metrics`` is the replay's ``metrics.json`` as a dict (the results
    schema of docs/results.md: accuracy against the ground truth, 3-sigma
    shares, NEES, the settled noise and calibration); a figure that cannot
    be computed is ``None``.
    """

    name: str
    times: np.ndarray
    """(N,): the event's time [s], as in the log."""
    elapsed: np.ndarray
    """(N,): time since the first odometry record [s]."""
    events: np.ndarray
    """(N,): 0 odometry, 1 landmark sighting, 2 scan (see ``EVENTS``)."""
    landmarks: np.ndarray
    """(N,): the sighted landmark's id, or the scan's sensor id; -1 for odometry."""
    nis: np.ndarray
    """(N,): the correction's normalised innovation squared; NaN where none."""
    poses: np.ndarray
    """(N, 3): x [m], y [m], heading [rad]."""
    covariances: np.ndarray
    """(N, 3, 3): the pose's covariance [m^2, m rad, rad^2]."""
    calibration: np.ndarray
    """(N, 4): speed scale, turn-rate scale, turn-rate bias [rad/s], bearing bias [rad]."""
    dead_reckoning: np.ndarray
    """(N, 3): odometry alone, x [m], y [m], heading [rad]."""
    truth: np.ndarray
    """(N, 3): the ground truth at the event's time; NaN where the log has none."""
    smoothed: Optional[Smoothed]
    """The smoothed track (``smooth=True``), else None."""
    metrics: dict

    def sigmas(self) -> np.ndarray:
        """(N, 3): the standard deviations of x [m], y [m] and heading [rad]."""
        return np.sqrt(np.diagonal(self.covariances, axis1=1, axis2=2))

    def to_pandas(self):
        """The steps as a pandas DataFrame (pandas must be installed), one
        row per event, columns named with their units."""
        import pandas as pd

        p, c, t, d = self.poses, self.covariances, self.truth, self.dead_reckoning
        cols = {
            "time_s": self.times,
            "elapsed_s": self.elapsed,
            "event": pd.Categorical.from_codes(self.events, EVENTS),
            "landmark": self.landmarks,
            "nis": self.nis,
            "x_m": p[:, 0],
            "y_m": p[:, 1],
            "theta_rad": p[:, 2],
            "var_x_m2": c[:, 0, 0],
            "cov_xy_m2": c[:, 0, 1],
            "cov_xtheta_mrad": c[:, 0, 2],
            "var_y_m2": c[:, 1, 1],
            "cov_ytheta_mrad": c[:, 1, 2],
            "var_theta_rad2": c[:, 2, 2],
            "v_scale": self.calibration[:, 0],
            "omega_scale": self.calibration[:, 1],
            "omega_bias_rad_per_s": self.calibration[:, 2],
            "bearing_bias_rad": self.calibration[:, 3],
            "odo_x_m": d[:, 0],
            "odo_y_m": d[:, 1],
            "odo_theta_rad": d[:, 2],
            "true_x_m": t[:, 0],
            "true_y_m": t[:, 1],
            "true_theta_rad": t[:, 2],
        }
        if self.smoothed is not None:
            s = self.smoothed
            cols.update(
                smoothed_x_m=s.poses[:, 0],
                smoothed_y_m=s.poses[:, 1],
                smoothed_theta_rad=s.poses[:, 2],
                smoothed_var_x_m2=s.covariances[:, 0, 0],
                smoothed_var_y_m2=s.covariances[:, 1, 1],
                smoothed_var_theta_rad2=s.covariances[:, 2, 2],
            )
        return pd.DataFrame(cols)


def replay(
    source: Union[str, os.PathLike, Mapping[str, Any]],
    *,
    format: Optional[str] = None,
    robot: int = 1,
    topics: Union[str, os.PathLike, None] = None,
    truth_file: Union[str, os.PathLike, None] = None,
    map_file: Union[str, os.PathLike, None] = None,
    name: str = "arrays",
    smooth: bool = False,
    **overrides: Any,
) -> Replay:
    """Replays a recorded log through the EKF, as ``locus replay`` does.

    ``source`` is a path or a mapping of arrays:

    * a MRCLAM dataset directory (``robot=N``), a Locus CSV log (``.csv``,
      ``.csv.xz``), a libRSF log (``.txt``, its ground truth beside it or
      ``truth_file=``), a rosbag2 MCAP file (``.mcap``, with
      ``topics=MAPPING.toml``; the map file the mapping names is loaded),
      a CARMEN log (``.log``, ``.log.gz``: laser scans and odometry, the
      corrected poses as truth; its map from ``map_file=``, a ROS
      map_server YAML or walls) or paper 000's laser to a wall
      (``format="laser-wall"``, laser_wall_1d's ``dataset1.txt``);
      ``format=`` ("mrclam", "csv", "librsf", "bag", "carmen",
      "laser-wall") overrides the guess from the path;
    * arrays: ``odometry`` (N, 3) ``t [s], v [m/s], omega [rad/s]``, and
      optionally ``sightings`` (M, 4) ``t [s], landmark id, range [m],
      bearing [rad]`` (NaN bearing: range only), ``landmarks`` (K, 3)
      ``id, x [m], y [m]``, ``truth`` (T, 4) ``t [s], x [m], y [m],
      theta [rad]`` (NaN heading: positions only) and ``start``
      ``(x [m], y [m], theta [rad])``.

    With no keywords the settings are ``locus replay``'s defaults: the
    noise and the odometry delay estimated from the log itself. Keywords
    set what the command's flags set, under the same names
    (``locus replay csv --help``): ``gate`` (None: no gate),
    ``robust_dof`` (None: Gaussian), ``smooth``, ``start_from_sightings``,
    ``v_scale``, ``omega_scale``, ``hold_calibration``, ``initial_std``,
    ``start``, ``beams_per_scan``, ``max_speed``, ``max_turn_rate``,
    ``max_odometry_gap``, ``q_v`` [m^2/s], ``q_omega`` [rad^2/s],
    ``sigma_range`` [m], ``sigma_bearing`` [rad], ``sigma_beam`` [m],
    ``odometry_delay`` [s], ``truth_offset`` [s], ``beam_bias_sigma`` [m]
    with ``beam_bias_tau`` [s], and ``estimate`` ("noise", "delay",
    "nothing").

    Raises :class:`locus.LocusError` for a log that cannot be read or
    replayed (the file and line named), ``ValueError`` for an argument out
    of range or of the wrong shape (named), ``KeyboardInterrupt`` on Ctrl-C.
    """
    overrides["smooth"] = smooth
    if isinstance(source, Mapping):
        unknown = set(source) - {"odometry", "sightings", "landmarks", "truth", "start"}
        if unknown:
            raise ValueError(f"source: unknown arrays {sorted(unknown)}; expected odometry, "
                             "sightings, landmarks, truth, start")
        if "odometry" not in source:
            raise ValueError("source: the arrays need 'odometry' (N, 3): t [s], v [m/s], omega [rad/s]")
        as_array = lambda k: None if source.get(k) is None else np.asarray(source[k], dtype=np.float64)
        raw = _locus.replay_arrays(
            as_array("odometry"),
            sightings=as_array("sightings"),
            landmarks=as_array("landmarks"),
            truth=as_array("truth"),
            start=source.get("start"),
            name=name,
            overrides=overrides,
        )
    else:
        raw = _locus.replay_file(
            os.fspath(source),
            format=format,
            robot=robot,
            topics=None if topics is None else os.fspath(topics),
            truth=None if truth_file is None else os.fspath(truth_file),
            map=None if map_file is None else os.fspath(map_file),
            overrides=overrides,
        )
    smoothed = None
    if "smoothed_pose" in raw:
        smoothed = Smoothed(raw["smoothed_pose"], raw["smoothed_covariance"], raw["smoothed_calibration"])
    return Replay(
        name=raw["name"],
        times=raw["time"],
        elapsed=raw["elapsed"],
        events=raw["event"],
        landmarks=raw["landmark"],
        nis=raw["nis"],
        poses=raw["pose"],
        covariances=raw["covariance"],
        calibration=raw["calibration"],
        dead_reckoning=raw["dead_reckoning"],
        truth=raw["truth"],
        smoothed=smoothed,
        metrics=json.loads(raw["metrics"]),
    )


def _replay_one(source: Any, options: Dict[str, Any]) -> Replay:
    return replay(source, **options)


def replay_many(sources: Iterable[Any], client: Optional[Any] = None, **options: Any) -> List[Replay]:
    """:func:`replay` of each source with the same keywords, over a Dask
    ``client``'s workers (the files must be readable there) or this
    machine's cores."""
    return spread(_replay_one, sources, client, options=options)
