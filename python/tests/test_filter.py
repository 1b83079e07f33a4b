"""locus.Filter and the models: against filterpy, against finite
differences, and what a bad input does."""

import subprocess
import sys

import numpy as np
import pytest

import locus
from conftest import ROOT


@pytest.fixture(scope="module")
def filterpy_runs(tmp_path_factory):
    """filterpy's paper-001 runs (scripts/filterpy_crosscheck.py: the
    models written from the spec's text, filterpy's EKF)."""
    out = tmp_path_factory.mktemp("filterpy")
    subprocess.run([sys.executable, ROOT / "scripts" / "filterpy_crosscheck.py", "--out", out,
                    "--steps", "400", "--only", "001"], check=True, capture_output=True)
    return out


def load(path):
    with open(path) as f:
        init = [float(v) for v in f.readline().split(",")[1:]]
        header = f.readline().strip().split(",")
        rows = [dict(zip(header, line.strip().split(","))) for line in f]
    return np.array(init[:3]), np.array(init[3:]).reshape(3, 3), rows


@pytest.mark.parametrize("run", ["run1_centred.csv", "run2_offset.csv"])
def test_one_step_at_a_time_equals_filterpy(filterpy_runs, run):
    x0, p0, rows = load(filterpy_runs / run)
    r0 = rows[0]
    f = locus.Filter(locus.DiffDrive(0.1, 1e-8, 1e-8),
                     locus.IrPair(float(r0["L"]), float(r0["Lw"]), float(r0["R11"]), float(r0["R22"]),
                                  lateral=float(r0["e"]), forward=float(r0["c"])),
                     x0=tuple(x0), P0=p0)
    updates = 0
    for r in rows:
        f.motion = locus.DiffDrive(float(r["b"]), float(r["Q11"]), float(r["Q22"]))
        f.predict((float(r["d1"]), float(r["d2"])))
        if r["has_obs"] == "1":
            nis, applied = f.update((float(r["ds1"]), float(r["ds2"])), r["wall"])
            assert applied and nis >= 0
            updates += 1
        want_x = np.array([float(r["x"]), float(r["y"]), float(r["theta"])])
        dx = f.x - want_x
        dx[2] = (dx[2] + np.pi) % (2 * np.pi) - np.pi
        np.testing.assert_allclose(dx, 0, atol=1e-12)
        want_p = np.array([float(r[f"P{i}{j}"]) for i in range(3) for j in range(3)]).reshape(3, 3)
        np.testing.assert_allclose(f.P, want_p, rtol=1e-9, atol=1e-15)
    assert updates > 100


def test_the_version_is_the_workspaces():
    cargo = (ROOT / "Cargo.toml").read_text()
    assert f'version = "{locus.__version__}"' in cargo


def paper001_filter():
    return locus.Filter(locus.DiffDrive(0.112, 2.6e-8, 8.3e-6),
                        locus.IrPair(0.1, 1.0, 6.4e-5, 8.1e-5, lateral=0.03, forward=0.02),
                        x0=(-0.84, -0.862, 0.03), P0=np.diag([4e-4, 4e-4, 2.5e-3]))


def test_run_equals_the_steps_one_at_a_time(filterpy_runs):
    _, _, rows = load(filterpy_runs / "run2_offset.csv")
    u = np.array([[float(r["d1"]), float(r["d2"])] for r in rows])
    z = np.array([[float(r["ds1"]), float(r["ds2"])] if r["has_obs"] == "1" else [np.nan, np.nan]
                  for r in rows])
    walls = {"x+": 0, "x-": 1, "y+": 2, "y-": 3}
    at = np.array([walls.get(r["wall"], -1) for r in rows], dtype=np.int64)
    batch = paper001_filter().run(u, z, at)
    # Into the arrays of an earlier run: the same numbers, in place.
    reused = {k: np.full_like(v, 7.0) for k, v in batch.items()}
    again = paper001_filter().run(u, z, at, out=reused)
    assert again is reused
    for k in batch:
        np.testing.assert_array_equal(reused[k], batch[k])
    with pytest.raises(ValueError, match=r"out: nis: expected shape \[400\], got \[3\]"):
        paper001_filter().run(u, z, at, out={**reused, "nis": np.zeros(3)})
    f = paper001_filter()
    for i in range(len(rows)):
        nis = f.step(tuple(u[i]), None if np.isnan(z[i, 0]) else tuple(z[i]), int(at[i]))
        assert np.array_equal(f.x, batch["poses"][i])
        assert np.array_equal(f.P, batch["covariances"][i])
        assert (nis is None and np.isnan(batch["nis"][i])) or nis == batch["nis"][i]


def test_a_nan_raises_and_keeps_the_belief():
    f = paper001_filter()
    f.step((0.01, 0.01))
    x, p = f.x.copy(), f.P.copy()
    with pytest.raises(ValueError, match=r"u: NaN is not finite"):
        f.predict((np.nan, 0.01))
    with pytest.raises(ValueError, match=r"z: inf is not finite"):
        f.step((0.01, 0.01), (np.inf, 0.1), "x+")
    with pytest.raises(ValueError, match=r"at: \"z\+\" is not a wall"):
        f.update((0.1, 0.1), "z+")
    with pytest.raises(ValueError, match=r"u: expected 2 numbers, got 3"):
        f.predict([0.01, 0.01, 0.1])
    assert np.array_equal(f.x, x) and np.array_equal(f.P, p)
    u = np.full((5, 2), 0.01)
    u[3, 0] = np.inf
    with pytest.raises(locus.LocusError, match=r"step 3: predict: non-finite .* belief is unchanged"):
        f.run(u)
    assert np.array_equal(f.x, x) and np.array_equal(f.P, p)
    with pytest.raises(ValueError, match=r"u: expected shape \(N, 2\), got \(5, 3\)"):
        f.run(np.zeros((5, 3)))
    with pytest.raises(ValueError, match=r"P0: expected shape \(3, 3\), got \(2, 2\)"):
        locus.Filter(locus.Unicycle(0.01, 0.01), P0=np.eye(2))


def numeric_jacobian(fun, x, eps=1e-6):
    x = np.asarray(x, dtype=float)
    cols = []
    for i in range(len(x)):
        d = np.zeros_like(x)
        d[i] = eps
        cols.append((np.asarray(fun(x + d)) - np.asarray(fun(x - d))) / (2 * eps))
    return np.column_stack(cols)


@pytest.mark.parametrize("motion,u", [
    (locus.DiffDrive(0.112, 1e-6, 1e-5), (0.012, 0.009)),
    (locus.Unicycle(0.01, 0.02), (0.4, 0.3, 0.1)),
    (locus.SkidSteer(0.3, 0.01, 0.01), (0.2, 0.3, 0.05)),
])
def test_motion_jacobians_match_finite_differences(motion, u):
    x = np.array([0.3, -0.2, 0.7])
    a, w = motion.jacobians(x, u)
    np.testing.assert_allclose(a, numeric_jacobian(lambda s: motion.f(s, u), x), atol=1e-7)
    assert w.shape == (3, 2)
    assert motion.noise(u).shape == (2, 2)


@pytest.mark.parametrize("sensor,at", [
    (locus.RangeBearing(np.array([[7, 2.0, 1.0]]), 0.1, 0.01, sensor=(0.1, 0.05)), 7),
    (locus.IrPair(0.1, 1.0, 1e-4, 1e-4), "y-"),
    (locus.LaserRange(np.array([[2.0, -1.0, -1.0, 2.0]]), 1e-4, mount=(0.17, 0.0, 0.0)), None),
])
def test_sensor_jacobians_match_finite_differences(sensor, at):
    x = np.array([0.3, -0.2, 0.3])
    h = sensor.jacobian(x, at)
    np.testing.assert_allclose(h, numeric_jacobian(lambda s: sensor.h(s, at), x), atol=1e-7)


def test_a_landmark_filter_converges_on_a_simulated_circle():
    rng = np.random.default_rng(3)
    marks = np.array([[1, 4.0, 0.0], [2, 0.0, 4.0], [3, -4.0, 0.0], [4, 0.0, -4.0]])
    f = locus.Filter(locus.Unicycle(1e-4, 1e-4), locus.RangeBearing(marks, 0.05, 0.01),
                     x0=(0.2, -0.1, 0.1), P0=np.diag([0.1, 0.1, 0.05]), gate=0.999)
    x = np.zeros(3)
    errors = []
    for k in range(2000):
        v, w, dt = 0.5, 0.25, 0.05
        x = x + np.array([v * dt * np.cos(x[2] + w * dt / 2), v * dt * np.sin(x[2] + w * dt / 2), w * dt])
        f.predict((v + rng.normal(0, 0.01), w + rng.normal(0, 0.01), dt))
        if k % 5 == 0:
            lid, lx, ly = marks[k // 5 % 4]
            r = np.hypot(lx - x[0], ly - x[1]) + rng.normal(0, 0.05)
            b = np.arctan2(ly - x[1], lx - x[0]) - x[2] + rng.normal(0, 0.01)
            f.update((r, np.arctan2(np.sin(b), np.cos(b))), int(lid))
        errors.append(np.hypot(*(f.x[:2] - x[:2])))
    assert np.mean(errors[-500:]) < 0.05


@pytest.mark.parametrize("motion,sensor,u,reading", [
    # Forward 0.5 m/s for 0.05 s steps, a landmark at (3, 1) seen every third step.
    (locus.Unicycle(1e-4, 1e-4), locus.RangeBearing(np.array([[7, 3.0, 1.0]]), 0.05, 0.01),
     (0.5, 0.05, 0.05), lambda x: (np.hypot(3 - x[0], 1 - x[1]), np.arctan2(1 - x[1], 3 - x[0]) - x[2])),
    # Tread speeds towards a wall at x = 4, its laser 0.17 m ahead of the centre.
    (locus.SkidSteer(0.3, 1e-4, 1e-4), locus.LaserRange(np.array([[4.0, -5.0, 4.0, 5.0]]), 1e-4,
                                                      mount=(0.17, 0.0, 0.0)),
     (0.3, 0.31, 0.05), lambda x: ((4 - 0.17 * np.cos(x[2]) - x[0]) / np.cos(x[2]),)),
    (locus.DiffDrive(0.112, 1e-6, 1e-5), None, (0.012, 0.011), None),
])
def test_a_batch_run_equals_its_steps_one_by_one(motion, sensor, u, reading):
    """`run` is the loop of `step`, for each motion and sensor: the same
    beliefs, bit for bit, after every step."""
    n = 60
    x = np.zeros(3)
    us, zs, ats = np.tile(np.asarray(u, dtype=float), (n, 1)), [], []
    for k in range(n):
        x = x + np.array([0.025 * np.cos(x[2]), 0.025 * np.sin(x[2]), 0.002])
        seen = sensor is not None and k % 3 == 0
        zs.append(np.asarray(reading(x)) + 0.001 if seen else None)
        ats.append(7 if seen else 0)
    kw = dict(x0=(0.01, -0.01, 0.01), P0=np.diag([1e-3, 1e-3, 1e-3]))
    one = locus.Filter(motion, sensor, **kw)
    poses, covs = [], []
    for k in range(n):
        if zs[k] is None:
            one.step(us[k])
        else:
            one.step(us[k], zs[k], ats[k] if isinstance(sensor, locus.RangeBearing) else None)
        poses.append(one.x.copy())
        covs.append(one.P.copy())
    batch = locus.Filter(motion, sensor, **kw)
    if sensor is None:
        out = batch.run(us)
    else:
        m = 1 if isinstance(sensor, locus.LaserRange) else 2
        z = np.array([np.full(m, np.nan) if r is None else r for r in zs])
        out = batch.run(us, z, np.array(ats, dtype=np.int64))
        assert np.sum(out["applied"]) == n // 3
    np.testing.assert_array_equal(out["poses"], np.array(poses))
    np.testing.assert_array_equal(out["covariances"], np.array(covs))
    np.testing.assert_array_equal(batch.x, one.x)
