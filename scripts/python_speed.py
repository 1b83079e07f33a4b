#!/usr/bin/env python3
"""Speed of the Python package against its peers, side by side in one run.

Usage:
    pip install ./python                      # the release wheel (maturin)
    pip install -r scripts/requirements-crosscheck.txt
    python3 scripts/python_speed.py [--steps 20000] [--rounds 7] [--locus target/release/locus]

What it measures: in each of --rounds rounds each peer runs --repeats times
back to back (the first run warms the caches and branch predictors that the
peer before it cooled), and each figure is the best run of all rounds. The
peers take turns, so that they see the same machine state; the Rust floor is
likewise the best of 7 back-to-back runs. `--repeats 1` gives the figures
right after another peer has run.

1. paper 001's EKF step (differential-drive predict, then the IR-pair wall
   correction when a reading arrived), the step of the Rust peer benchmark
   (crates/locus-core/benches/ekf_step.rs), on a seeded run of
   scripts/filterpy_crosscheck.py:
   * filterpy 2.0.0's ExtendedKalmanFilter with the models written in numpy
     from the spec (the cross-check's DiffDriveEKF), two calls per step;
   * locus.Filter driven from Python, one call per step (`step`);
   * locus.Filter.run, the whole run in one call: into new arrays, and
     into the arrays of an earlier run (`out=`; no memory for the kernel
     to map: 112 bytes of results per step cost about as much as the
     step itself when they are fresh pages).
   The three give the same posterior (checked to 1e-9 before timing).
   Beside them, the floor: the batch's loop in plain Rust on the same
   steps (crates/locus-models/examples/batch_floor.rs, built and run with
   cargo when it is on the PATH).
2. locus.replay of MRCLAM dataset 6 robot 3 against `locus replay` (the
   command-line engine, --no-plots), per event; both settle the noise from
   the log, replay, and judge against the truth.

3. With --doa: paper 002's domain of attraction (the default 12 x 25 grid)
   on a dask.distributed LocalCluster of 1 and of 2 single-threaded worker
   processes, and here on 1 thread: the cluster's speed-up on this
   machine's cores. Each grid's CSV is checked equal to the one-thread one.

Prints a table of times and ratios; `--json FILE` also writes them.
"""

import os

# numpy's OpenBLAS threads spin after each call and take the other core
# from the peer that runs next; filterpy's 3 x 3 products use one thread.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import importlib.util
import json
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import locus

ROOT = pathlib.Path(__file__).resolve().parents[1]


def crosscheck():
    spec = importlib.util.spec_from_file_location("filterpy_crosscheck", ROOT / "scripts" / "filterpy_crosscheck.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def load_run(steps):
    out = pathlib.Path(tempfile.mkdtemp())
    subprocess.run([sys.executable, ROOT / "scripts" / "filterpy_crosscheck.py", "--out", out,
                    "--steps", str(steps), "--only", "001"], check=True, capture_output=True)
    with open(out / "run2_offset.csv") as f:
        init = [float(v) for v in f.readline().split(",")[1:]]
        header = f.readline().strip().split(",")
        rows = [dict(zip(header, line.strip().split(","))) for line in f]
    return np.array(init[:3]), np.array(init[3:]).reshape(3, 3), rows


def rust_floor(u, z, at):
    """ns per step of the batch's loop in plain Rust on the same steps, or
    None without cargo."""
    import shutil

    if shutil.which("cargo") is None:
        return None
    steps = pathlib.Path(tempfile.mkdtemp()) / "steps.bin"
    np.column_stack([u, z, at.astype(np.float64)]).astype("<f8").tofile(steps)
    out = subprocess.run(["cargo", "run", "--quiet", "--release", "--locked", "-p", "locus-models",
                          "--example", "batch_floor", "--", steps], cwd=ROOT, check=True,
                         capture_output=True, text=True)
    return float(out.stdout.strip())


def best(fn, rounds):
    times = []
    for _ in range(rounds):
        t = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t)
    return min(times), result


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--repeats", type=int, default=3,
                    help="back-to-back runs of each peer in a round (the first warms its caches)")
    ap.add_argument("--locus", default=str(ROOT / "target" / "release" / "locus"),
                    help="the command-line binary (cargo build --release -p locus)")
    ap.add_argument("--mrclam", default=str(ROOT.parent / "shared" / "data" / "mrclam" / "MRCLAM_Dataset6"))
    ap.add_argument("--json", help="also write the figures to this file")
    ap.add_argument("--doa", action="store_true", help="also time the DOA grid on LocalClusters of 1 and 2 workers")
    args = ap.parse_args()

    cc = crosscheck()
    x0, p0, rows = load_run(args.steps)
    r0 = rows[0]
    b, q11, q22 = float(r0["b"]), float(r0["Q11"]), float(r0["Q22"])
    L, e, c, lw = (float(r0[k]) for k in ("L", "e", "c", "Lw"))
    r11, r22 = float(r0["R11"]), float(r0["R22"])
    steps = [(float(r["d1"]), float(r["d2"]),
              (float(r["ds1"]), float(r["ds2"])) if r["has_obs"] == "1" else None, r["wall"])
             for r in rows]
    walls = {"x+": 0, "x-": 1, "y+": 2, "y-": 3}
    u = np.array([[d1, d2] for d1, d2, _, _ in steps])
    z = np.array([obs if obs else (np.nan, np.nan) for _, _, obs, _ in steps])
    at = np.array([walls.get(w, -1) for _, _, _, w in steps], dtype=np.int64)

    def run_filterpy():
        ekf = cc.DiffDriveEKF(x0, p0)
        for d1, d2, obs, wall in steps:
            ekf.predict_odometry(d1, d2, b, q11, q22)
            if obs:
                ekf.update_ir(wall, obs[0], obs[1], r11, r22, L, e, c, lw)
        return ekf.x[:, 0], ekf.P

    def new_filter():
        return locus.Filter(locus.DiffDrive(b, q11, q22), locus.IrPair(L, lw, r11, r22, lateral=e, forward=c),
                            x0=tuple(x0), P0=p0)

    def run_steps():
        f = new_filter()
        step = f.step
        for d1, d2, obs, wall in steps:
            if obs:
                step((d1, d2), obs, wall)
            else:
                step((d1, d2))
        return f.x, f.P

    def run_batch():
        f = new_filter()
        f.run(u, z, at)
        return f.x, f.P

    reused = new_filter().run(u, z, at)

    def run_batch_into():
        f = new_filter()
        f.run(u, z, at, out=reused)
        return f.x, f.P

    # The same posterior from all three before any timing.
    ref = run_filterpy()
    for name, fn in (("step", run_steps), ("run", run_batch), ("run_into", run_batch_into)):
        x, p = fn()
        dx = x - ref[0]
        dx[2] = (dx[2] + np.pi) % (2 * np.pi) - np.pi
        assert np.abs(dx).max() < 1e-9 and np.abs(p - ref[1]).max() < 1e-9, name

    t = {"filterpy": [], "step": [], "run": [], "run_into": []}
    for _ in range(args.rounds):
        for name, fn in (("filterpy", run_filterpy), ("step", run_steps), ("run", run_batch),
                         ("run_into", run_batch_into)):
            for _ in range(args.repeats):
                s = time.perf_counter()
                fn()
                t[name].append(time.perf_counter() - s)
    n = len(steps)
    per = {k: min(v) / n for k, v in t.items()}
    observed = sum(1 for s in steps if s[2])
    floor = rust_floor(u, z, at)
    if floor is not None:
        per["rust_floor"] = floor * 1e-9
    print(f"paper 001's EKF step, {n} steps ({observed} with an IR reading), best of {args.rounds} rounds")
    print(f"{'':32} {'per step':>12} {'filterpy / it':>14}")
    for k, label in (("filterpy", "filterpy 2.0.0 (numpy)"), ("step", "locus.Filter.step, per call"),
                     ("run", "locus.Filter.run, new arrays"), ("run_into", "locus.Filter.run, out= reused"),
                     ("rust_floor", "the same loop in plain Rust")):
        if k not in per:
            print(f"{label:32} n/a (cargo is not on the PATH)")
            continue
        print(f"{label:32} {per[k] * 1e9:9.0f} ns {per['filterpy'] / per[k]:13.1f}x")
    figures = {"steps": n, "per_step_ns": {k: v * 1e9 for k, v in per.items()},
               "speedup_over_filterpy": {k: per["filterpy"] / per[k] for k in per if k != "filterpy"}}

    mrclam = pathlib.Path(args.mrclam)
    binary = pathlib.Path(args.locus)
    if mrclam.is_dir() and binary.is_file():
        out = pathlib.Path(tempfile.mkdtemp())
        rt = {"cli": [], "python": []}
        events = None
        for _ in range(max(3, args.rounds // 2)):
            s = time.perf_counter()
            subprocess.run([binary, "replay", "mrclam", mrclam, "--robot", "3", "--no-plots", "--out", out],
                           check=True, capture_output=True)
            rt["cli"].append(time.perf_counter() - s)
            s = time.perf_counter()
            r = locus.replay(mrclam, robot=3)
            rt["python"].append(time.perf_counter() - s)
            events = len(r.times)
        cli, py = min(rt["cli"]), min(rt["python"])
        print(f"\nMRCLAM dataset 6 robot 3, {events} events, best of {len(rt['cli'])}")
        print(f"{'locus replay (command line)':32} {cli / events * 1e9:9.0f} ns per event ({cli:.2f} s)")
        print(f"{'locus.replay (Python)':32} {py / events * 1e9:9.0f} ns per event ({py:.2f} s), "
              f"{100 * (py / cli - 1):+.1f} % against the command line")
        figures["replay"] = {"events": events, "cli_s": cli, "python_s": py, "python_over_cli": py / cli}
    else:
        print(f"\nreplay: n/a ({binary} or {mrclam} is missing; cargo build --release -p locus)")
    if args.doa:
        figures["doa"] = doa_speed()
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(figures, indent=2))


def doa_speed():
    """The default DOA grid here on one thread, and on LocalClusters of 1
    and 2 single-threaded workers."""
    import locus.doa
    from dask.distributed import Client, LocalCluster

    s = time.perf_counter()
    one = locus.doa.grid(threads=1)
    here = time.perf_counter() - s
    cluster = {}
    for workers in (1, 2):
        with LocalCluster(n_workers=workers, threads_per_worker=1, host="127.0.0.1",
                          dashboard_address=None) as c, Client(c) as client:
            client.run(lambda: None)   # the workers up before the clock starts
            s = time.perf_counter()
            grid = locus.doa.grid(client=client)
            cluster[workers] = time.perf_counter() - s
            assert grid.csv == one.csv
    cells = one.m_zeta.size
    print(f"\nDOA, the default grid ({cells} cells)")
    print(f"{'here, 1 thread':32} {here:8.1f} s")
    print(f"{'LocalCluster, 1 worker':32} {cluster[1]:8.1f} s")
    print(f"{'LocalCluster, 2 workers':32} {cluster[2]:8.1f} s  (speed-up {cluster[1] / cluster[2]:.2f}x over 1 worker)")
    return {"cells": cells, "here_1_thread_s": here, "cluster_1_worker_s": cluster[1],
            "cluster_2_workers_s": cluster[2], "speedup_2_over_1": cluster[1] / cluster[2]}


if __name__ == "__main__":
    main()
