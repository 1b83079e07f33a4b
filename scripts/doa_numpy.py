#!/usr/bin/env python3
"""The observer of paper 002 (eq. 12-17, explicit Euler) in numpy, for one
cell of the domain-of-attraction grid, run side by side with the Rust one.

The same study as `locus doa` (spec MODELS.md section 4, its defaults): the
camera with four marks (eq. 5-10, pinhole + radial distortion), the nominal
pose T = (0, 0, 2.5) m, noise-free y = h(x_n), Q = diag(0.1^2 x3, 0.1396^2
x3), Theta = 2^2 I, dt = 0.005 s, 3 s. For one cell (v_g, alpha) and one
amplitude m it runs the 64 vertices zeta0 = m (+-1, ..., +-1), vectorised over
the vertices (the fair way to write it in numpy), and reports the worst
settling time (the time after which max|x^ - x_n| stays below 0.0087), or
`none` if a vertex does not converge (diverged: a mark at z_c <= 0.05 m or a
non-finite value; or a final error not below 0.0087).

It then runs the Rust twin (`cargo run --release -p locus-doa --example
doa_cell`), checks that both give the same worst settling time and prints the
time per cell of each and the ratio.

    python3 scripts/doa_numpy.py [V_G ALPHA M_ZETA]      # default 0.0151 50 0.1
"""

import os
import re
import subprocess
import sys
import time

import numpy as np

DT = 0.005
STEPS = 600
THRESHOLD = 0.0087
MIN_DEPTH = 0.05
MARKS = np.array([[0.30, 0.0, 0.0], [-0.30, 0.0, 0.0], [0.0, 0.20, 0.0], [0.0, -0.10, 0.15]])
FOCAL = np.array([1865.33, 1868.57])
PRINCIPAL = np.array([510.68, 619.68])
KC1 = -0.19457
SIGMA_P = 2.0
Q = np.diag([0.1**2] * 3 + [0.1396**2] * 3)
NOMINAL = np.array([0.0, 0.0, 2.5, 0.0, 0.0, 0.0])


def rotations(x):
    """Rx, Ry, Rz and R = Rz Ry Rx (eq. 3) for a batch of states (B, 6)."""
    b = x.shape[0]
    sp, cp = np.sin(x[:, 3]), np.cos(x[:, 3])
    st, ct = np.sin(x[:, 4]), np.cos(x[:, 4])
    ss, cs = np.sin(x[:, 5]), np.cos(x[:, 5])
    o, z = np.ones(b), np.zeros(b)
    rx = np.stack([o, z, z, z, cp, -sp, z, sp, cp], axis=1).reshape(b, 3, 3)
    ry = np.stack([ct, z, st, z, o, z, -st, z, ct], axis=1).reshape(b, 3, 3)
    rz = np.stack([cs, -ss, z, ss, cs, z, z, z, o], axis=1).reshape(b, 3, 3)
    return rx, ry, rz, rz @ (ry @ rx)


def measure(x):
    """h(x) (B, 8), C = dh/dx (B, 8, 6) (eq. 18-19) and the mark depths (B, 4)."""
    b = x.shape[0]
    rx, ry, rz, r = rotations(x)
    rxo = np.einsum("bij,mj->bmi", r, MARKS)  # R X_O, (B, 4, 3)
    xc = x[:, None, :3] + rxo  # X_C = T + R X_O (eq. 7)
    inv_z = 1.0 / xc[..., 2]
    nx, ny = xc[..., 0] * inv_z, xc[..., 1] * inv_z  # eq. 8
    k = 1.0 + KC1 * (nx * nx + ny * ny)  # eq. 9
    y = np.stack([FOCAL[0] * k * nx + PRINCIPAL[0], FOCAL[1] * k * ny + PRINCIPAL[1]], axis=2)
    # d(u, v)/dX_C = diag(l) * distortion Jacobian * pinhole Jacobian.
    off = 2.0 * KC1 * nx * ny
    ld = np.empty((b, 4, 2, 2))
    ld[..., 0, 0] = FOCAL[0] * (1.0 + 3.0 * KC1 * nx * nx + KC1 * ny * ny)
    ld[..., 0, 1] = FOCAL[0] * off
    ld[..., 1, 0] = FOCAL[1] * off
    ld[..., 1, 1] = FOCAL[1] * (1.0 + KC1 * nx * nx + 3.0 * KC1 * ny * ny)
    jn = np.zeros((b, 4, 2, 3))
    jn[..., 0, 0] = inv_z
    jn[..., 1, 1] = inv_z
    jn[..., 0, 2] = -nx * inv_z
    jn[..., 1, 2] = -ny * inv_z
    jp = ld @ jn  # (B, 4, 2, 3)
    # Columns of [I3 | dR/dphi X_O | dR/dtheta X_O | dR/dpsi X_O] (eq. 19, spec fix).
    e1x = np.stack([np.zeros(4), -MARKS[:, 2], MARKS[:, 1]], axis=1)  # e1 x X_O
    d_phi = np.einsum("bij,mj->bmi", r, e1x)
    w = np.einsum("bij,mj->bmi", rx, MARKS)
    e2w = np.stack([w[..., 2], np.zeros_like(w[..., 0]), -w[..., 0]], axis=2)
    d_theta = np.einsum("bij,bmj->bmi", rz @ ry, e2w)
    d_psi = np.stack([-rxo[..., 1], rxo[..., 0], np.zeros_like(rxo[..., 0])], axis=2)
    c = np.empty((b, 4, 2, 6))
    c[..., :3] = jp
    c[..., 3] = np.einsum("bmij,bmj->bmi", jp, d_phi)
    c[..., 4] = np.einsum("bmij,bmj->bmi", jp, d_theta)
    c[..., 5] = np.einsum("bmij,bmj->bmi", jp, d_psi)
    return y.reshape(b, 8), c.reshape(b, 8, 6), xc[..., 2]


def worst_settle(v_g, alpha, m):
    """Worst settling time (s) over the 64 vertices, or None."""
    signs = np.array([[-1.0 if (v >> i) & 1 else 1.0 for i in range(6)] for v in range(64)])
    x = NOMINAL + m * signs
    p = np.broadcast_to(Q * v_g, (64, 6, 6)).copy()
    y_meas, _, _ = measure(NOMINAL[None, :])
    alive = np.ones(64, dtype=bool)
    last_above = np.zeros(64, dtype=int)
    w = 1.0 / SIGMA_P  # Theta^-1/2 for Theta = sigma^2 I
    for k in range(STEPS):
        y_hat, c, depth = measure(x)
        ok = (depth > MIN_DEPTH).all(axis=1) & np.isfinite(depth).all(axis=1)
        alive &= ok
        if not alive.any():
            return None
        cw = c * w
        nuw = (y_meas - y_hat) * w
        g = cw @ p  # (B, 8, 6)
        x_new = x + DT * np.einsum("bki,bk->bi", g, nuw)
        p_new = p + DT * (2.0 * alpha * p - np.swapaxes(g, 1, 2) @ g + Q)
        p_new = 0.5 * (p_new + np.swapaxes(p_new, 1, 2))
        finite = np.isfinite(x_new).all(axis=1) & np.isfinite(p_new).all(axis=(1, 2))
        alive &= finite
        # Diverged vertices are frozen (their values no longer matter).
        x = np.where(alive[:, None], x_new, x)
        p = np.where(alive[:, None, None], p_new, p)
        norm = np.abs(x - NOMINAL).max(axis=1)
        last_above = np.where(norm < THRESHOLD, last_above, k + 1)
        if not alive.all():
            return None
    _, _, depth = measure(x)
    if not (depth > MIN_DEPTH).all():
        return None
    if not (np.abs(x - NOMINAL).max(axis=1) < THRESHOLD).all():
        return None
    return float(last_above.max()) * DT


def main():
    args = [float(a) for a in sys.argv[1:4]]
    v_g, alpha, m = (args + [0.0151, 50.0, 0.1][len(args):])[:3]
    best = float("inf")
    result = None
    for _ in range(3):
        t = time.perf_counter()
        result = worst_settle(v_g, alpha, m)
        best = min(best, time.perf_counter() - t)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = subprocess.run(
        ["cargo", "run", "--quiet", "--release", "-p", "locus-doa", "--example", "doa_cell",
         "--", str(v_g), str(alpha), str(m), "5"],
        cwd=root, check=True, capture_output=True, text=True,
    ).stdout
    fields = dict(re.findall(r"(\w+)=(\S+)", out))
    rust_settle = None if fields["worst_settle_s"] == "none" else float(fields["worst_settle_s"])
    rust_s = float(fields["seconds_per_cell"])
    print(f"cell v_g={v_g} alpha={alpha} m_zeta={m}: 64 vertices x {STEPS} steps = {64 * STEPS} observer steps")
    print(f"worst settling time: numpy {result} s, Rust {rust_settle} s")
    print(f"numpy (vectorised over the 64 vertices): {best * 1e3:.1f} ms per cell, {best / (64 * STEPS) * 1e6:.2f} us per vertex-step")
    print(f"Rust (one thread, vertex by vertex):     {rust_s * 1e3:.1f} ms per cell, {rust_s / (64 * STEPS) * 1e6:.3f} us per vertex-step")
    print(f"ratio numpy / Rust: {best / rust_s:.1f}x")
    same = (result is None and rust_settle is None) or (
        result is not None and rust_settle is not None and abs(result - rust_settle) < 1e-12)
    if not same:
        print("MISMATCH: the two implementations disagree", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
