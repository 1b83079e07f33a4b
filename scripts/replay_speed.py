#!/usr/bin/env python3
"""Reference replay of one MRCLAM robot in plain Python, to time against
`locus replay mrclam` and to cross-check its figures.

Usage: python3 scripts/replay_speed.py DIR --robot 3

DIR is an MRCLAM dataset directory (e.g. shared/data/mrclam/MRCLAM_Dataset6);
each file may be plain or xz-compressed (NAME.dat or NAME.dat.xz). Python 3
standard library only.

What it does, as Locus does (crates/locus-logs, crates/locus-replay, with
the replay's default configuration):

* Reading: lines whose first non-blank character is '#', and blank lines,
  are skipped; fields are whitespace-separated. Measurement barcodes are
  mapped to subjects through Barcodes.dat; only sightings of landmarks
  (known subjects that are not robots 1-5) are kept. Odometry (commanded
  v, omega) is held from each record to the next.
* Events: odometry and sightings merged in time order, odometry before
  sightings at equal times, sightings at equal times by landmark, range,
  bearing.
* Start: the ground truth at the first odometry time; initial standard
  deviations 0.05 m, 0.05 m, 0.05 rad.
* Prediction (unicycle, exact arc): between events, over dt seconds, with
  white noise of power spectral densities q_v = 0.01 m^2/s and
  q_omega = 0.01 rad^2/s on v and omega, i.e. variances q/dt.
* Correction: range and bearing from the robot's centre (sigma 0.2 m and
  0.03 rad; no measurement within 1 mm of a landmark), Joseph-form update,
  a 99.9 % chi-square gate on 2 degrees of freedom (NIS <= 13.8155); after
  5 consecutive rejections the covariance is multiplied by 4 and the
  sighting tried once more (Locus's default recovery).
* Comparison: at every event, the ground truth interpolated linearly at the
  event's time (theta the short way round), unless the two samples around
  it are more than 0.25 s apart or the time is outside the track; the
  position RMSE is the root of the mean squared position error over those
  events (as `locus replay` reports it), for the filter and for dead
  reckoning from the same start.

Prints one JSON object on stdout: event counts, the load time (reading,
decompressing, parsing, merging) and the filter-loop time (prediction,
correction, ground-truth lookup, error sums) in seconds and in microseconds
per event, the final pose and standard deviations, and the RMSEs.
"""

import argparse
import bisect
import json
import lzma
import math
import os
import sys
import time

# The replay's default configuration (crates/locus-replay/src/config.rs).
Q_V = 0.01  # m^2/s
Q_OMEGA = 0.01  # rad^2/s
SIGMA_RANGE = 0.2  # m
SIGMA_BEARING = 0.03  # rad
GATE = 13.815510557964274  # chi-square 99.9 % point, 2 dof: -2 ln(0.001)
RECOVER_AFTER = 5  # consecutive rejections
INFLATION = 4.0
INITIAL_STD = (0.05, 0.05, 0.05)  # m, m, rad
TRUTH_MAX_GAP = 0.25  # s
MIN_RANGE = 1e-3  # m
ROBOTS = range(1, 6)
SERIES_BELOW = 0.05  # |omega dt / 2| below which sinc uses its series

PI = math.pi
TWO_PI = 2.0 * math.pi


def wrap(a):
    """An angle (rad) wrapped to (-pi, pi]."""
    r = a - TWO_PI * math.floor((a + PI) / TWO_PI)
    return r + TWO_PI if r <= -PI else r


def read_text(directory, name):
    """The text of DIR/NAME, or of DIR/NAME.xz decompressed."""
    plain = os.path.join(directory, name)
    if os.path.isfile(plain):
        with open(plain, "rb") as f:
            data = f.read()
    elif os.path.isfile(plain + ".xz"):
        with open(plain + ".xz", "rb") as f:
            data = lzma.decompress(f.read())
    else:
        sys.exit(f"{plain}: not found (nor {plain}.xz)")
    return data.decode("utf-8")


def records(text):
    """The whitespace-separated fields of each data line."""
    for line in text.splitlines():
        fields = line.split()
        if fields and not fields[0].startswith("#"):
            yield fields


def load(directory, robot):
    """Landmarks {subject: (x, y)}, odometry [(t, v, omega)], landmark
    sightings [(t, subject, range, bearing)] and ground truth
    ([t], [(x, y, theta)]) of one robot."""
    subject_of = {}
    for f in records(read_text(directory, "Barcodes.dat")):
        subject_of[int(f[1])] = int(f[0])
    landmarks = {}
    for f in records(read_text(directory, "Landmark_Groundtruth.dat")):
        landmarks[int(f[0])] = (float(f[1]), float(f[2]))
    odometry = [
        (float(f[0]), float(f[1]), float(f[2]))
        for f in records(read_text(directory, f"Robot{robot}_Odometry.dat"))
    ]
    sightings = []
    for f in records(read_text(directory, f"Robot{robot}_Measurement.dat")):
        subject = subject_of.get(int(f[1]))
        if subject is not None and subject not in ROBOTS:
            sightings.append((float(f[0]), subject, float(f[2]), float(f[3])))
    truth_t = []
    truth_pose = []
    for f in records(read_text(directory, f"Robot{robot}_Groundtruth.dat")):
        truth_t.append(float(f[0]))
        truth_pose.append((float(f[1]), float(f[2]), float(f[3])))
    return landmarks, odometry, sightings, truth_t, truth_pose


def timeline(odometry, sightings):
    """Events in canonical order: (time, 0, index, v, omega) for odometry
    (log order kept at equal times), (time, 1, landmark, range, bearing)
    for sightings."""
    events = [(t, 0, i, v, w) for i, (t, v, w) in enumerate(odometry)]
    events.extend((t, 1, lm, r, b) for t, lm, r, b in sightings)
    events.sort()
    return events


def truth_at(truth_t, truth_pose, t):
    """The ground truth (x, y, theta) at t, or None (outside the track or in
    a gap wider than TRUTH_MAX_GAP)."""
    i = bisect.bisect_right(truth_t, t)
    if i == 0:
        return None
    ta = truth_t[i - 1]
    a = truth_pose[i - 1]
    if ta == t:
        return a
    if i == len(truth_t):
        return None
    dt = truth_t[i] - ta
    if dt > TRUTH_MAX_GAP:
        return None
    b = truth_pose[i]
    w = (t - ta) / dt
    return (
        a[0] + w * (b[0] - a[0]),
        a[1] + w * (b[1] - a[1]),
        wrap(a[2] + w * wrap(b[2] - a[2])),
    )


def sinc_and_derivative(h):
    """sin(h)/h and its derivative."""
    if abs(h) < SERIES_BELOW:
        h2 = h * h
        s = 1.0 - h2 / 6.0 * (1.0 - h2 / 20.0 * (1.0 - h2 / 42.0))
        ds = -h / 3.0 * (1.0 - h2 / 10.0 * (1.0 - h2 / 28.0 * (1.0 - h2 / 54.0)))
        return s, ds
    sn, cs = math.sin(h), math.cos(h)
    return sn / h, (h * cs - sn) / (h * h)


def run(landmarks, events, truth_t, truth_pose, start):
    """The filter over `events` from `start` (t, x, y, theta); returns the
    figures of the JSON report (times excluded)."""
    t_now, x, y, th = start
    th = wrap(th)
    sx, sy, st = INITIAL_STD
    # Covariance entries (symmetric 3x3).
    pxx, pxy, pxt, pyy, pyt, ptt = sx * sx, 0.0, 0.0, sy * sy, 0.0, st * st
    v = w = 0.0
    dx_, dy_, dth_ = x, y, th  # dead reckoning
    var_r = SIGMA_RANGE * SIGMA_RANGE
    var_b = SIGMA_BEARING * SIGMA_BEARING
    rejections = 0
    applied = gated = inflations = no_measurement = 0
    compared = 0
    sq_ekf = sq_dead = 0.0
    for ev in events:
        t = ev[0]
        dt = t - t_now
        if dt > 0.0:
            h = w * dt * 0.5
            s, ds = sinc_and_derivative(h)
            d = v * dt * s
            a = th + h
            sn, cs = math.sin(a), math.cos(a)
            # Jacobians: F = [[1, 0, f02], [0, 1, f12], [0, 0, 1]],
            # G = [[g00, g01], [g10, g11], [0, dt]].
            f02 = -d * sn
            f12 = d * cs
            half = dt * 0.5
            dd_dw = v * dt * ds * half
            g00 = dt * s * cs
            g01 = dd_dw * cs - d * half * sn
            g10 = dt * s * sn
            g11 = dd_dw * sn + d * half * cs
            qv = Q_V / dt
            qw = Q_OMEGA / dt
            # F P F^T
            a00 = pxx + 2.0 * f02 * pxt + f02 * f02 * ptt
            a01 = pxy + f02 * pyt + f12 * pxt + f02 * f12 * ptt
            a02 = pxt + f02 * ptt
            a11 = pyy + 2.0 * f12 * pyt + f12 * f12 * ptt
            a12 = pyt + f12 * ptt
            # + G Q G^T
            pxx = a00 + qv * g00 * g00 + qw * g01 * g01
            pxy = a01 + qv * g00 * g10 + qw * g01 * g11
            pxt = a02 + qw * g01 * dt
            pyy = a11 + qv * g10 * g10 + qw * g11 * g11
            pyt = a12 + qw * g11 * dt
            ptt = ptt + qw * dt * dt
            x += d * cs
            y += d * sn
            th = wrap(th + w * dt)
            # Dead reckoning with the same input.
            ad = dth_ + h
            dx_ += d * math.cos(ad)
            dy_ += d * math.sin(ad)
            dth_ = wrap(dth_ + w * dt)
            t_now = t
        if ev[1] == 0:
            v, w = ev[3], ev[4]
        else:
            lx, ly = landmarks[ev[2]]
            zr, zb = ev[3], ev[4]
            tried_inflation = False
            while True:
                ex = lx - x
                ey = ly - y
                r = math.sqrt(ex * ex + ey * ey)
                if not (r > MIN_RANGE):
                    no_measurement += 1
                    break
                r2 = r * r
                # H = [[h00, h01, 0], [h10, h11, -1]]
                h00, h01 = -ex / r, -ey / r
                h10, h11 = ey / r2, -ex / r2
                nu0 = zr - r
                nu1 = wrap(zb - wrap(math.atan2(ey, ex) - th))
                # P H^T, columns c0 (range) and c1 (bearing).
                c00 = pxx * h00 + pxy * h01
                c10 = pxy * h00 + pyy * h01
                c20 = pxt * h00 + pyt * h01
                c01 = pxx * h10 + pxy * h11 - pxt
                c11 = pxy * h10 + pyy * h11 - pyt
                c21 = pxt * h10 + pyt * h11 - ptt
                s00 = h00 * c00 + h01 * c10 + var_r
                s01 = h00 * c01 + h01 * c11
                s11 = h10 * c01 + h11 * c11 - c21 + var_b
                det = s00 * s11 - s01 * s01
                i00, i01, i11 = s11 / det, -s01 / det, s00 / det
                y0 = i00 * nu0 + i01 * nu1
                y1 = i01 * nu0 + i11 * nu1
                nis = nu0 * y0 + nu1 * y1
                if nis <= GATE:
                    # Gain K = P H^T S^-1.
                    k00 = c00 * i00 + c01 * i01
                    k01 = c00 * i01 + c01 * i11
                    k10 = c10 * i00 + c11 * i01
                    k11 = c10 * i01 + c11 * i11
                    k20 = c20 * i00 + c21 * i01
                    k21 = c20 * i01 + c21 * i11
                    x += c00 * y0 + c01 * y1
                    y += c10 * y0 + c11 * y1
                    th += c20 * y0 + c21 * y1
                    # Joseph form: (I - K H) P (I - K H)^T + K R K^T.
                    m00 = 1.0 - k00 * h00 - k01 * h10
                    m01 = -k00 * h01 - k01 * h11
                    m02 = k01
                    m10 = -k10 * h00 - k11 * h10
                    m11 = 1.0 - k10 * h01 - k11 * h11
                    m12 = k11
                    m20 = -k20 * h00 - k21 * h10
                    m21 = -k20 * h01 - k21 * h11
                    m22 = 1.0 + k21
                    # MP = M P (rows of M times P).
                    b00 = m00 * pxx + m01 * pxy + m02 * pxt
                    b01 = m00 * pxy + m01 * pyy + m02 * pyt
                    b02 = m00 * pxt + m01 * pyt + m02 * ptt
                    b10 = m10 * pxx + m11 * pxy + m12 * pxt
                    b11 = m10 * pxy + m11 * pyy + m12 * pyt
                    b12 = m10 * pxt + m11 * pyt + m12 * ptt
                    b20 = m20 * pxx + m21 * pxy + m22 * pxt
                    b21 = m20 * pxy + m21 * pyy + m22 * pyt
                    b22 = m20 * pxt + m21 * pyt + m22 * ptt
                    pxx = b00 * m00 + b01 * m01 + b02 * m02 + var_r * k00 * k00 + var_b * k01 * k01
                    pxy = b00 * m10 + b01 * m11 + b02 * m12 + var_r * k00 * k10 + var_b * k01 * k11
                    pxt = b00 * m20 + b01 * m21 + b02 * m22 + var_r * k00 * k20 + var_b * k01 * k21
                    pyy = b10 * m10 + b11 * m11 + b12 * m12 + var_r * k10 * k10 + var_b * k11 * k11
                    pyt = b10 * m20 + b11 * m21 + b12 * m22 + var_r * k10 * k20 + var_b * k11 * k21
                    ptt = b20 * m20 + b21 * m21 + b22 * m22 + var_r * k20 * k20 + var_b * k21 * k21
                    rejections = 0
                    applied += 1
                    break
                rejections += 1
                if rejections >= RECOVER_AFTER and not tried_inflation:
                    pxx, pxy, pxt = pxx * INFLATION, pxy * INFLATION, pxt * INFLATION
                    pyy, pyt, ptt = pyy * INFLATION, pyt * INFLATION, ptt * INFLATION
                    inflations += 1
                    tried_inflation = True
                    continue
                gated += 1
                break
        truth = truth_at(truth_t, truth_pose, t)
        if truth is not None:
            compared += 1
            sq_ekf += (truth[0] - x) ** 2 + (truth[1] - y) ** 2
            sq_dead += (truth[0] - dx_) ** 2 + (truth[1] - dy_) ** 2
    return {
        "applied": applied,
        "gated": gated,
        "inflations": inflations,
        "no_measurement": no_measurement,
        "compared": compared,
        "final_pose": {"time_s": t_now, "x_m": x, "y_m": y, "theta_rad": th},
        "final_std": {
            "x_m": math.sqrt(pxx),
            "y_m": math.sqrt(pyy),
            "theta_rad": math.sqrt(ptt),
        },
        "position_rmse_m": math.sqrt(sq_ekf / compared) if compared else None,
        "dead_reckoning_position_rmse_m": math.sqrt(sq_dead / compared) if compared else None,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dir", help="MRCLAM dataset directory")
    parser.add_argument("--robot", type=int, default=3, help="robot number (1-5)")
    args = parser.parse_args()
    if args.robot not in ROBOTS:
        sys.exit(f"no robot {args.robot}: the dataset has robots 1-5")

    t0 = time.perf_counter()
    landmarks, odometry, sightings, truth_t, truth_pose = load(args.dir, args.robot)
    events = timeline(odometry, sightings)
    load_s = time.perf_counter() - t0
    if not odometry:
        sys.exit("the log has no odometry")
    first = odometry[0][0]
    pose = truth_at(truth_t, truth_pose, first)
    if pose is None:
        sys.exit(f"no ground truth at the first odometry time {first} s")

    t0 = time.perf_counter()
    figures = run(landmarks, events, truth_t, truth_pose, (first,) + pose)
    filter_s = time.perf_counter() - t0

    n = len(events)
    report = {
        "robot": args.robot,
        "events": n,
        "odometry": len(odometry),
        "sightings": len(sightings),
        "load_s": load_s,
        "load_us_per_event": load_s / n * 1e6,
        "filter_s": filter_s,
        "filter_us_per_event": filter_s / n * 1e6,
        "python": sys.version.split()[0],
    }
    report.update(figures)
    json.dump(report, sys.stdout, indent=2)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
