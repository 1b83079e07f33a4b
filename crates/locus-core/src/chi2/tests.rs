//! The chi-square functions against statrs (an independent implementation),
//! table values, edge cases and round trips.

use super::*;
use statrs::distribution::{ChiSquared, Continuous, ContinuousCDF};

const PROBS: [f64; 8] = [0.001, 0.025, 0.05, 0.5, 0.95, 0.975, 0.99, 0.999];

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn table_values() {
    let cases = [
        (0.95, 1, 3.841_458_820_694_124),
        (0.95, 2, 5.991_464_547_107_979),
        (0.99, 2, 9.210_340_371_976_184),
        (0.99, 1, 6.634_896_601_021_214),
        (0.95, 3, 7.814_727_903_251_178),
        (0.999, 1, 10.827_566_170_662_733),
        (0.05, 1, 0.003_932_140_000_019_522),
        (0.5, 2, 1.386_294_361_119_890_6), // 2 ln 2
        (0.95, 10, 18.307_038_053_275_146),
    ];
    for (p, k, expected) in cases {
        let q = quantile(p, k).unwrap();
        assert!(
            rel(q, expected) < 1e-12,
            "quantile({p}, {k}) = {q}, expected {expected}"
        );
        assert!((cdf(expected, k) - p).abs() < 1e-14, "cdf({expected}, {k})");
    }
    // Closed forms: dof 2 is exponential with mean 2.
    for x in [1e-8, 0.01, 0.5, 1.0, 3.0, 10.0, 50.0, 700.0] {
        let exact_sf = libm::exp(-0.5 * x);
        assert!(
            rel(cdf(x, 2), -libm::expm1(-0.5 * x)) < 1e-14,
            "cdf({x}, 2)"
        );
        assert!(rel(sf(x, 2), exact_sf) < 1e-13, "sf({x}, 2)");
    }
    // dof 1: P(1/2, x/2) = erf(sqrt(x/2)).
    for x in [1e-10, 1e-3, 0.3, 1.0, 2.5, 9.0, 30.0] {
        assert!(
            rel(cdf(x, 1), libm::erf(libm::sqrt(0.5 * x))) < 1e-14,
            "cdf({x}, 1)"
        );
        assert!(
            rel(sf(x, 1), libm::erfc(libm::sqrt(0.5 * x))) < 1e-13,
            "sf({x}, 1)"
        );
    }
}

#[test]
fn cdf_matches_statrs() {
    for k in 1..=300u32 {
        let dist = ChiSquared::new(f64::from(k)).unwrap();
        for &p in &PROBS {
            let x = quantile(p, k).unwrap();
            for xx in [0.5 * x, x, 1.5 * x] {
                let ours = cdf(xx, k);
                let theirs = dist.cdf(xx);
                assert!(
                    (ours - theirs).abs() <= 1e-9 * theirs + 1e-15,
                    "cdf({xx}, {k}): ours {ours}, statrs {theirs}"
                );
                let (ours_sf, theirs_sf) = (sf(xx, k), dist.sf(xx));
                assert!(
                    (ours_sf - theirs_sf).abs() <= 1e-9 * theirs_sf + 1e-15,
                    "sf({xx}, {k}): ours {ours_sf}, statrs {theirs_sf}"
                );
                assert!(
                    (ours + ours_sf - 1.0).abs() < 1e-15,
                    "cdf + sf != 1 at ({xx}, {k})"
                );
            }
        }
    }
}

/// `(F(x) - p) / F'(x)` with statrs' CDF `F` and a central-difference slope:
/// the distance from `x` to the true `p`-quantile, to first order.
fn implied_error(dist: &ChiSquared, x: f64, p: f64) -> f64 {
    let h = 1e-4 * x;
    let slope = (dist.cdf(x + h) - dist.cdf(x - h)) / (2.0 * h);
    (dist.cdf(x) - p) / slope
}

#[test]
fn quantile_matches_statrs() {
    let mut compared = 0;
    for k in 1..=300u32 {
        let dist = ChiSquared::new(f64::from(k)).unwrap();
        for &p in &PROBS {
            let q = quantile(p, k).unwrap();
            // The x-error implied by statrs' CDF at our quantile (its density
            // overflows to inf for dof > ~200, so take a central difference).
            let implied = implied_error(&dist, q, p);
            assert!(
                implied.abs() < 1e-12 * q,
                "quantile({p}, {k}) = {q}: off by {implied}"
            );
            // Our density agrees with statrs' where the latter is finite.
            let their_pdf = dist.pdf(q);
            if their_pdf.is_finite() {
                let our_pdf = pdf(q, 0.5 * f64::from(k));
                assert!(rel(our_pdf, their_pdf) < 1e-9, "pdf({q}, {k})");
            }
            // statrs' own inverse (8 bisections + at most 4 Newton steps) does
            // not always converge (NaN for p = 0.001, dof = 1; 323.37 instead
            // of 322.56 for p = 0.999, dof = 248): compare with it wherever its
            // answer passes the same CDF check.
            let theirs = dist.inverse_cdf(p);
            if implied_error(&dist, theirs, p).abs() < 1e-12 * theirs {
                compared += 1;
                assert!(
                    rel(q, theirs) < 1e-9,
                    "quantile({p}, {k}): ours {q}, statrs {theirs}"
                );
            }
            // Round trip through our own CDF / survival function.
            let back = if p > 0.5 { 1.0 - sf(q, k) } else { cdf(q, k) };
            assert!(
                (back - p).abs() < 1e-13 * p.max(1e-3),
                "round trip ({p}, {k})"
            );
        }
    }
    assert!(
        compared > 2000,
        "statrs' inverse usable in only {compared} of 2400 cases"
    );
}

#[test]
fn regularized_gamma_large_shape() {
    // Around the mode of Gamma(a, 1) the CDF is ~ 1/2: compare with statrs'
    // implementation and check the round trip through the quantile.
    for a in [500.0, 1e3, 1e4, 1e5, 2.5e5] {
        for z in [-4.0, -1.0, 0.0, 0.5, 3.0] {
            let x = a + z * libm::sqrt(a);
            let ours = regularized_lower_gamma(a, x);
            let theirs = statrs::function::gamma::gamma_lr(a, x);
            assert!(
                (ours - theirs).abs() <= 1e-9 * theirs.min(1.0 - theirs),
                "P({a}, {x}): ours {ours}, statrs {theirs}"
            );
            assert!(
                (ours + regularized_upper_gamma(a, x) - 1.0).abs() < 1e-15,
                "P + Q != 1 at ({a}, {x})"
            );
        }
        let dof = (2.0 * a) as u32;
        for &p in &PROBS {
            let q = quantile(p, dof).unwrap();
            let back = if p > 0.5 {
                1.0 - sf(q, dof)
            } else {
                cdf(q, dof)
            };
            assert!(
                (back - p).abs() < 1e-12 * p.min(1.0 - p),
                "({p}, {dof}): {back}"
            );
        }
    }
    // Shape a = n gives Q(n, x) = e^-x sum_{j<n} x^j / j! (Poisson tail).
    let (n, x) = (20u32, 17.0);
    let mut term = libm::exp(-x);
    let mut sum = term;
    for j in 1..n {
        term *= x / f64::from(j);
        sum += term;
    }
    assert!(rel(regularized_upper_gamma(f64::from(n), x), sum) < 1e-14);
}

#[test]
fn regularized_gamma_matches_high_precision_reference() {
    // (a, x, P(a, x), Q(a, x)), computed with mpmath at 50 digits, at
    // x = a + z sqrt(a) for z in {-5, -1, 0, 2, 6} (x = a / 50 if negative).
    let reference = [
        (0.5, 0.01, 0.1124629160182849, 0.8875370839817152),
        (0.5, 0.5, 0.6826894921370859, 0.3173105078629141),
        (
            0.5,
            1.9142135623730951,
            0.9496098015056764,
            0.050390198494323586,
        ),
        (
            0.5,
            4.742640687119285,
            0.997928731546161,
            0.0020712684538389528,
        ),
        (7.5, 0.15, 4.131083688733391e-11, 0.9999999999586892),
        (
            7.5,
            4.76138721247417,
            0.15136226672351397,
            0.8486377332764861,
        ),
        (7.5, 7.5, 0.5485827887742748, 0.45141721122572526),
        (
            7.5,
            12.97722557505166,
            0.9614958288432045,
            0.03850417115679545,
        ),
        (
            7.5,
            23.931676725154983,
            0.9999732464380138,
            2.6753561986255085e-05,
        ),
        (
            150.0,
            88.76275643042055,
            2.0324910786867335e-09,
            0.9999999979675089,
        ),
        (
            150.0,
            137.7525512860841,
            0.1583697790721707,
            0.8416302209278294,
        ),
        (150.0, 150.0, 0.5108582297493597, 0.4891417702506403),
        (
            150.0,
            174.49489742783177,
            0.9730303880547668,
            0.02696961194523313,
        ),
        (
            150.0,
            223.48469228349535,
            0.9999999266488517,
            7.335114827481498e-08,
        ),
        (10000.0, 9500.0, 1.862454651795155e-07, 0.9999998137545348),
        (10000.0, 9900.0, 0.15865119219356466, 0.8413488078064354),
        (10000.0, 10000.0, 0.5013298083399552, 0.4986701916600448),
        (10000.0, 10200.0, 0.9767126778664011, 0.023287322133598805),
        (10000.0, 10600.0, 0.9999999980378075, 1.962192482133047e-09),
        (
            100000.0,
            98418.8611699158,
            2.510055744605881e-07,
            0.9999997489944256,
        ),
        (
            100000.0,
            99683.77223398317,
            0.1586548497379081,
            0.8413451502620919,
        ),
        (100000.0, 100000.0, 0.5004205221103651, 0.4995794778896348),
        (
            100000.0,
            100632.45553203368,
            0.9770794042218464,
            0.022920595778153613,
        ),
        (
            100000.0,
            101897.36659610103,
            0.9999999987656912,
            1.2343088093960284e-09,
        ),
    ];
    for (a, x, p, q) in reference {
        let (ours_p, ours_q) = (regularized_lower_gamma(a, x), regularized_upper_gamma(a, x));
        assert!(
            rel(ours_p, p) < 2e-14,
            "P({a}, {x}) = {ours_p}, expected {p}"
        );
        assert!(
            rel(ours_q, q) < 2e-14,
            "Q({a}, {x}) = {ours_q}, expected {q}"
        );
    }
}

#[test]
fn edge_cases() {
    assert!(regularized_lower_gamma(f64::NAN, 1.0).is_nan());
    assert!(regularized_lower_gamma(1.0, f64::NAN).is_nan());
    assert!(regularized_lower_gamma(0.0, 1.0).is_nan());
    assert!(regularized_lower_gamma(-1.0, 1.0).is_nan());
    assert_eq!(regularized_lower_gamma(2.0, 0.0), 0.0);
    assert_eq!(regularized_lower_gamma(2.0, -3.0), 0.0);
    assert_eq!(regularized_lower_gamma(2.0, f64::INFINITY), 1.0);
    assert_eq!(regularized_lower_gamma(3.0, 1e6), 1.0);
    assert_eq!(regularized_upper_gamma(2.0, f64::INFINITY), 0.0);
    assert_eq!(regularized_upper_gamma(2.0, 0.0), 1.0);
    assert!(cdf(f64::NAN, 3).is_nan());
    assert_eq!(cdf(-1.0, 3), 0.0);
    assert_eq!(cdf(f64::INFINITY, 3), 1.0);
    assert_eq!(cdf(0.0, 0), 1.0);
    assert_eq!(cdf(-1.0, 0), 0.0);
    assert_eq!(sf(0.0, 0), 0.0);
    for p in [
        0.0,
        1.0,
        -0.5,
        1.5,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ] {
        assert!(
            matches!(quantile(p, 2), Err(Error::InvalidParameter(_))),
            "quantile({p}, 2) must fail"
        );
    }
    assert!(matches!(quantile(0.5, 0), Err(Error::InvalidParameter(_))));
    // Extreme but valid probabilities still round-trip.
    for (p, k) in [
        (1e-150, 1),
        (1e-300, 2),
        (1e-12, 4),
        (1.0 - 1e-12, 1),
        (1e-9, 300),
    ] {
        let q = quantile(p, k).unwrap();
        assert!(q > 0.0 && q.is_finite());
        let back = if p > 0.5 { sf(q, k) } else { cdf(q, k) };
        let target = if p > 0.5 { 1.0 - p } else { p };
        assert!(rel(back, target) < 1e-10, "({p}, {k}): {back} vs {target}");
    }
    // A quantile below the smallest f64 underflows to 0 instead of failing.
    let q = quantile(1e-300, 1).unwrap();
    assert!((0.0..1e-300).contains(&q), "{q}");
    // Monotone in p and in dof.
    let mut prev = 0.0;
    for &p in &PROBS {
        let q = quantile(p, 7).unwrap();
        assert!(q > prev);
        prev = q;
    }
    assert!(quantile(0.95, 8).unwrap() > quantile(0.95, 7).unwrap());
}
