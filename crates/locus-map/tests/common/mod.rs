//! Shared by the tests: a seeded generator and random wall maps.

#![allow(dead_code)]

use std::path::PathBuf;

use locus_map::Segment;

/// SplitMix64: small, seeded, the same on every machine.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// `n` random walls (0.5 to 4 m long, any direction) inside a `size` x
/// `size` m square at the origin, plus its four sides.
pub fn random_walls(rng: &mut Rng, n: usize, size: f64) -> Vec<Segment> {
    let mut out = vec![
        Segment::new([0.0, 0.0], [size, 0.0]),
        Segment::new([size, 0.0], [size, size]),
        Segment::new([size, size], [0.0, size]),
        Segment::new([0.0, size], [0.0, 0.0]),
    ];
    while out.len() < n + 4 {
        let a = [rng.range(0.5, size - 0.5), rng.range(0.5, size - 0.5)];
        let len = rng.range(0.5, 4.0);
        let th = rng.range(-core::f64::consts::PI, core::f64::consts::PI);
        let b = [a[0] + len * th.cos(), a[1] + len * th.sin()];
        if b.iter().all(|&x| x > 0.2 && x < size - 0.2) {
            out.push(Segment::new(a, b));
        }
    }
    out
}

/// The nearest crossing `(range, index)` over every segment, written
/// independently of the crate (parametric solve by Cramer's rule).
pub fn brute_cast(
    walls: &[Segment],
    o: [f64; 2],
    angle: f64,
    max_range: f64,
) -> Option<(f64, usize)> {
    let d = [angle.cos(), angle.sin()];
    let mut best: Option<(f64, usize)> = None;
    for (i, w) in walls.iter().enumerate() {
        // o + t d = a + s (b - a)  <=>  [d, a - b] [t, s]^T = a - o
        let m = [[d[0], w.a[0] - w.b[0]], [d[1], w.a[1] - w.b[1]]];
        let r = [w.a[0] - o[0], w.a[1] - o[1]];
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        if det == 0.0 {
            continue;
        }
        let t = (r[0] * m[1][1] - m[0][1] * r[1]) / det;
        let s = (m[0][0] * r[1] - r[0] * m[1][0]) / det;
        if (0.0..=1.0).contains(&s)
            && t >= 0.0
            && t <= max_range
            && best.is_none_or(|(bt, _)| t < bt)
        {
            best = Some((t, i));
        }
    }
    best
}

/// A fresh empty folder under the system's temporary folder.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("locus-map-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temporary folder");
    dir
}

/// The angle (rad) between two unit vectors.
pub fn angle_between(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] * b[1] - a[1] * b[0])
        .atan2(a[0] * b[0] + a[1] * b[1])
        .abs()
}
