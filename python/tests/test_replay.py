"""locus.replay: the engine and defaults of `locus replay`, numpy out."""

import pathlib
import subprocess
import sys

import numpy as np
import pytest

import locus


def read_log_csv(path):
    """The CLI's log.csv as a dict of float columns (empty fields NaN)."""
    with open(path) as f:
        header = f.readline().strip().split(",")
    data = np.genfromtxt(path, delimiter=",", skip_header=1, dtype=np.float64,
                         usecols=[i for i, h in enumerate(header) if h not in ("event", "applied")])
    names = [h for h in header if h not in ("event", "applied")]
    return {n: data[:, i] for i, n in enumerate(names)}


def test_mrclam_robot3_equals_the_command_line_log(mrclam6, locus_bin, tmp_path):
    out = tmp_path / "cli"
    subprocess.run([locus_bin, "replay", "mrclam", mrclam6, "--robot", "3", "--no-plots",
                    "--out", out], check=True, capture_output=True)
    cli = read_log_csv(out / "log.csv")
    r = locus.replay(mrclam6, robot=3)
    assert len(r.times) == len(cli["time_s"]) == 65506
    def close(a, b):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12, equal_nan=True)
    close(r.times, cli["time_s"])
    close(r.elapsed, cli["elapsed_s"])
    close(r.poses[:, 0], cli["x_m"])
    close(r.poses[:, 1], cli["y_m"])
    close(r.poses[:, 2], cli["theta_rad"])
    c = r.covariances
    for (i, j), col in {(0, 0): "var_x_m2", (0, 1): "cov_xy_m2", (0, 2): "cov_xtheta_mrad",
                        (1, 1): "var_y_m2", (1, 2): "cov_ytheta_mrad", (2, 2): "var_theta_rad2"}.items():
        close(c[:, i, j], cli[col])
        close(c[:, j, i], cli[col])
    close(r.dead_reckoning, np.column_stack([cli["odo_x_m"], cli["odo_y_m"], cli["odo_theta_rad"]]))
    close(r.truth, np.column_stack([cli["true_x_m"], cli["true_y_m"], cli["true_theta_rad"]]))
    close(r.nis, cli["nis"])
    # The same metrics.json, figure for figure (its layout aside).
    import json
    cli_metrics = json.loads((out / "metrics.json").read_text())
    for m in (cli_metrics, r.metrics):
        del m["timing"]  # the wall clock differs from run to run
    assert r.metrics == cli_metrics
    assert r.metrics["source"] == "replay"
    assert 0.9 < r.metrics["filter"]["within_3_sigma_x_share"] <= 1.0


def test_a_bad_line_raises_naming_the_file_and_line(tmp_path):
    log = tmp_path / "bad.csv"
    log.write_text("# Locus log v4\nlandmark,1,2.0,0.0\nodometry,0.0,0.1,0.0\n"
                   "odometry,0.1,zero,0.0\n")
    with pytest.raises(locus.LocusError, match=r"bad\.csv:4.*zero"):
        locus.replay(log)


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(locus.LocusError, match="nowhere.csv"):
        locus.replay(tmp_path / "nowhere.csv")


def test_wrong_shapes_raise_value_error_naming_the_argument():
    odo = np.array([[0.0, 0.1, 0.0], [0.1, 0.1, 0.0]])
    with pytest.raises(ValueError, match=r"odometry: expected shape \(N, 3\), got \(2, 2\)"):
        locus.replay({"odometry": odo[:, :2]})
    with pytest.raises(ValueError, match=r"sightings: expected shape \(N, 4\)"):
        locus.replay({"odometry": odo, "sightings": np.zeros((3, 3))})
    with pytest.raises(ValueError, match=r"odometry: row 1, column 1: NaN is not finite"):
        locus.replay({"odometry": np.array([[0.0, 0.1, 0.0], [0.1, np.nan, 0.0]])})
    with pytest.raises(ValueError, match=r"start: expected 3 numbers, got 2"):
        locus.replay({"odometry": odo, "start": [0.0, 0.0]})
    with pytest.raises(ValueError, match=r"gate: 1.5 is not in \(0, 1\)"):
        locus.replay({"odometry": odo, "start": [0, 0, 0]}, gate=1.5)
    with pytest.raises(TypeError, match="gaet"):
        locus.replay({"odometry": odo, "start": [0, 0, 0]}, gaet=0.9)


def test_arrays_replay_as_the_same_log_written_as_csv(tmp_path):
    """A log given as arrays replays as the same log read from a file."""
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 60.0, 0.05)
    v, w = 0.3 + 0.05 * np.sin(t / 7), 0.2 * np.sin(t / 5)
    odo = np.column_stack([t, v, w])
    marks = np.array([[1, 3.0, 0.0], [2, 0.0, 3.0], [3, -3.0, 0.5], [4, 1.0, -3.0]])
    # Truth by integrating the commanded motion.
    x = np.zeros((len(t), 3))
    for k in range(1, len(t)):
        dt = t[k] - t[k - 1]
        th = x[k - 1, 2]
        x[k] = x[k - 1] + dt * np.array([v[k - 1] * np.cos(th), v[k - 1] * np.sin(th), w[k - 1]])
    rows = []
    for k in range(0, len(t), 10):
        for lid, lx, ly in marks:
            dx, dy = lx - x[k, 0], ly - x[k, 1]
            rng_ = np.hypot(dx, dy) + rng.normal(0, 0.05)
            brg = np.arctan2(dy, dx) - x[k, 2] + rng.normal(0, 0.01)
            rows.append([t[k], lid, rng_, np.arctan2(np.sin(brg), np.cos(brg))])
    sight = np.array(rows)
    truth = np.column_stack([t, x])
    kw = dict(q_v=0.001, q_omega=0.001, sigma_range=0.05, sigma_bearing=0.01, estimate="nothing")
    a = locus.replay({"odometry": odo, "sightings": sight, "landmarks": marks, "truth": truth}, **kw)
    csv = tmp_path / "same.csv"
    with open(csv, "w") as f:
        f.write("# Locus log v4\n")
        for lid, lx, ly in marks:
            f.write(f"landmark,{int(lid)},{float(lx)!r},{float(ly)!r}\n")
        for r in odo:
            f.write("odometry," + ",".join(repr(float(v)) for v in r) + "\n")
        for r in sight:
            f.write(f"measurement,{float(r[0])!r},{int(r[1])},{float(r[2])!r},{float(r[3])!r}\n")
        for r in truth:
            f.write("truth," + ",".join(repr(float(v)) for v in r) + "\n")
    b = locus.replay(csv, **kw)
    np.testing.assert_array_equal(a.poses, b.poses)
    np.testing.assert_array_equal(a.covariances, b.covariances)
    assert a.metrics["filter"]["position_rmse_m"] < 0.1
    df = a.to_pandas()
    assert list(df["event"].unique()) == ["odometry", "sighting"]
    assert df["x_m"].to_numpy().tolist() == a.poses[:, 0].tolist()


def test_a_bag_whose_mapping_names_a_map_replays_against_it(laser_wall, locus_bin, tmp_path):
    """Paper 000's laser to a wall as a bag whose mapping names a walls file:
    the map is loaded, as `locus replay bag` loads it."""
    exported = tmp_path / "export.csv"
    subprocess.run([locus_bin, "replay", "laser-wall", laser_wall, "--export", exported,
                    "--no-estimate", "--q-v", "1e-4", "--q-omega", "1e-4", "--sigma-beam", "0.01",
                    "--no-plots", "--out", tmp_path / "exported"], check=True, capture_output=True)
    lines = exported.read_text().splitlines()
    walls = [l.split(",")[1:] for l in lines if l.startswith("wall,")]
    assert walls
    (tmp_path / "walls.txt").write_text("".join(" ".join(w) + "\n" for w in walls))
    kept = [l for l in lines if not l.startswith(("wall,", "start,"))]
    csv = tmp_path / "wall.csv"
    csv.write_text("map,walls.txt\n" + "\n".join(kept) + "\n")
    mapping = tmp_path / "wall.toml"
    root = pathlib.Path(__file__).resolve().parents[2]
    subprocess.run([sys.executable, root / "scripts" / "locus_csv_to_bag.py", csv,
                    tmp_path / "wall-bag", mapping], check=True, capture_output=True)
    assert "walls.txt" in mapping.read_text()
    bag = tmp_path / "wall-bag" / "wall-bag.mcap"

    kw = dict(q_v=1e-4, q_omega=1e-4, sigma_beam=0.01, estimate="nothing",
              start=[0.9844566829712001, 0.0, 0.0])
    out = tmp_path / "cli"
    said = subprocess.run([locus_bin, "replay", "bag", bag, "--topics", mapping, "--no-estimate",
                           "--q-v", "1e-4", "--q-omega", "1e-4", "--sigma-beam", "0.01",
                           "--start", "0.9844566829712001,0,0", "--no-plots", "--out", out],
                          check=True, capture_output=True, text=True).stdout
    assert "scans / beams in them" in said
    cli = read_log_csv(out / "log.csv")
    r = locus.replay(bag, topics=mapping, **kw)
    assert len(r.times) == len(cli["time_s"])
    np.testing.assert_allclose(r.poses[:, 0], cli["x_m"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.covariances[:, 0, 0], cli["var_x_m2"], rtol=0, atol=1e-12)
    # The beams corrected the estimate against the map: 6.7 mm, where the
    # odometry alone drifts to 0.28 m.
    assert r.metrics["counts"]["applied"] > 10000
    assert r.metrics["filter"]["position_rmse_m"] < 0.02 < r.metrics["odometry"]["position_rmse_m"]
    # A mapping whose map file is missing is an error naming it.
    (tmp_path / "walls.txt").unlink()
    with pytest.raises(locus.LocusError, match="walls.txt"):
        locus.replay(bag, topics=mapping, **kw)


def columns_equal(r, cli):
    """A Python replay's arrays equal the CLI's log.csv to 1e-12."""
    assert len(r.times) == len(cli["time_s"])
    for got, col in ((r.times, "time_s"), (r.poses[:, 0], "x_m"), (r.poses[:, 1], "y_m"),
                     (r.poses[:, 2], "theta_rad"), (r.covariances[:, 0, 0], "var_x_m2"),
                     (r.covariances[:, 2, 2], "var_theta_rad2")):
        np.testing.assert_allclose(got, cli[col], rtol=0, atol=1e-12, equal_nan=True)


def test_a_laser_wall_log_replays_as_the_command_line(laser_wall, locus_bin, tmp_path):
    flags = ["--no-estimate", "--q-v", "1e-4", "--q-omega", "1e-4", "--sigma-beam", "0.01"]
    subprocess.run([locus_bin, "replay", "laser-wall", laser_wall, *flags, "--no-plots",
                    "--out", tmp_path], check=True, capture_output=True)
    r = locus.replay(laser_wall, format="laser-wall", estimate="nothing", q_v=1e-4, q_omega=1e-4,
                     sigma_beam=0.01)
    columns_equal(r, read_log_csv(tmp_path / "log.csv"))
    assert r.metrics["counts"]["applied"] > 10000


def test_a_carmen_log_replays_against_its_map_as_the_command_line(intel_lab, locus_bin, tmp_path):
    log = intel_lab / "intel-corrected.log.gz"
    subprocess.run([locus_bin, "map", "--carmen", log, "--out", tmp_path / "map"],
                   check=True, capture_output=True)
    grid = tmp_path / "map" / "map.yaml"
    noise = dict(q_v=0.00902, q_omega=0.002, sigma_beam=0.04691, beam_bias_sigma=0.06473,
                 beam_bias_tau=28.75, odometry_delay=0.1, estimate="nothing")
    flags = [f"--{k.replace('_', '-')}={v}" for k, v in noise.items() if k != "estimate"]
    subprocess.run([locus_bin, "replay", "carmen", log, "--map", grid, *flags, "--no-estimate",
                    "--no-plots", "--out", tmp_path / "cli"], check=True, capture_output=True)
    r = locus.replay(log, map_file=grid, **noise)
    columns_equal(r, read_log_csv(tmp_path / "cli" / "log.csv"))
    assert r.metrics["filter"]["position_rmse_m"] < 0.5
    with pytest.raises(locus.LocusError, match="map=MAP"):
        locus.replay(log, **noise)
    with pytest.raises(locus.LocusError, match="nowhere.yaml"):
        locus.replay(log, map_file=tmp_path / "nowhere.yaml", **noise)


def test_smooth_gives_the_smoothed_track(mrclam6):
    r = locus.replay(mrclam6, robot=2, smooth=True)
    assert r.smoothed is not None
    assert r.smoothed.poses.shape == r.poses.shape
    s, f = r.metrics["smoother"]["position_rmse_m"], r.metrics["filter"]["position_rmse_m"]
    assert s < f
