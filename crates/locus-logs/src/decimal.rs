//! Numbers as log text, fast: `f64` written exactly as Rust's `Display`
//! writes it (`{}`: the shortest digits that read back to the same value,
//! plain decimal notation, never an exponent; `1` not `1.0`, `-0` for
//! negative zero), but by the `ryu` algorithm, about three times as fast,
//! straight into the caller's `String` without allocating.
//!
//! Both give the shortest digits that read back to the value, the closest
//! to it where several are as short. They differ in layout (ryu writes
//! `1.0`, `-0.0`, `1e-7`, `1e21`), which [`push_f64`] converts, and in one
//! rare case: a value exactly halfway between the two closest shortest
//! candidates (e.g. 154000748790168.625, between ...168.62 and ...168.63),
//! where ryu rounds to the even digit and `Display` up. [`push_f64`] detects
//! those ties exactly and writes them by `Display`.

use core::fmt::Write as _;

/// Appends `x` to `out` as `format!("{x}")` would (so `x.to_string()`
/// parses back to `x` bit for bit). Non-finite values are written by
/// `Display` itself (`NaN`, `inf`, `-inf`).
pub fn push_f64(out: &mut String, x: f64) {
    if !x.is_finite() {
        let _ = write!(out, "{x}");
        return;
    }
    let mut buffer = ryu::Buffer::new();
    let text = buffer.format_finite(x);
    if is_tie(x, text) {
        let _ = write!(out, "{x}");
        return;
    }
    match text.split_once('e') {
        // Plain notation: the same as Display but for a trailing ".0".
        None => out.push_str(text.strip_suffix(".0").unwrap_or(text)),
        Some((mantissa, exponent)) => {
            // ryu writes exponents as decimal integers.
            let exponent: i32 = exponent.parse().unwrap_or(0);
            push_plain(out, mantissa, exponent);
        }
    }
}

/// Appends `mantissa * 10^exponent` in plain notation, `mantissa` as ryu
/// writes it before an exponent (`-?D(.D+)?`, shortest digits, so no
/// trailing zeros after the point).
fn push_plain(out: &mut String, mantissa: &str, exponent: i32) {
    let (sign, unsigned) = match mantissa.strip_prefix('-') {
        Some(rest) => ("-", rest),
        None => ("", mantissa),
    };
    let (whole, fraction) = unsigned.split_once('.').unwrap_or((unsigned, ""));
    // Significant digits, and how many of them stand before the point.
    let digits = [whole, fraction];
    let count = whole.len() + fraction.len();
    let point = i64::try_from(whole.len()).unwrap_or(i64::MAX) + i64::from(exponent);
    out.push_str(sign);
    if point <= 0 {
        out.push_str("0.");
        push_zeros(out, point.unsigned_abs());
        digits.iter().for_each(|d| out.push_str(d));
    } else {
        let point = usize::try_from(point).unwrap_or(usize::MAX);
        if point >= count {
            digits.iter().for_each(|d| out.push_str(d));
            push_zeros(out, (point - count) as u64);
        } else {
            let joined = digits.iter().flat_map(|d| d.chars());
            for (i, c) in joined.enumerate() {
                if i == point {
                    out.push('.');
                }
                out.push(c);
            }
        }
    }
}

/// Whether the finite `x` lies exactly halfway between two decimals of as
/// few significant digits as `text`, ryu's shortest form of `x` (the case
/// where ryu's and `Display`'s digits may differ).
///
/// With `D` the digits of `text` (an integer, trailing zeros dropped) and
/// `10^e` the weight of its last digit, the tie is `|x| = (D + 1/2) 10^e`,
/// i.e. `m 2^q = N 5^e 2^(e-1)` for `|x| = m 2^q`, `m` odd, and the odd
/// `N = 2D + 1`: `q = e - 1` and `m = N 5^e` (or `m 5^-e = N` for `e < 0`),
/// checked in exact integer arithmetic. Two candidates `10^e` apart can
/// only both read back to `x` if `10^e` is below its spacing, 2^-52 of a
/// normal `x`, so `D` has at least 16 digits; with `N < 2^58` and
/// `m < 2^53`, that leaves `-25 <= e <= 22`, so `-26 <= q <= 21`. Most
/// computed values have lower bits set (`q` far below -26) and are settled
/// by that test alone, before `text` is read.
fn is_tie(x: f64, text: &str) -> bool {
    let bits = x.abs().to_bits();
    let (m, q) = match bits >> 52 {
        0 => (bits, -1074),
        biased => (
            (bits & ((1 << 52) - 1)) | (1 << 52),
            i32::try_from(biased).unwrap_or(0) - 1075,
        ),
    };
    if m == 0 {
        return false;
    }
    let q = q + i32::try_from(m.trailing_zeros()).unwrap_or(0);
    let m = u128::from(m >> m.trailing_zeros());
    if !(-26..=21).contains(&q) {
        return false;
    }
    let (mantissa, exponent) = text.split_once('e').unwrap_or((text, "0"));
    let exponent: i32 = exponent.parse().unwrap_or(0);
    // D without its trailing zeros: zeros are held back until a nonzero
    // digit follows them. A text of this range has at most 23 digits.
    let mut digits: u128 = 0;
    let mut significant = 0u32;
    let mut held_zeros = 0u32;
    let mut after_point: i32 = 0;
    let mut seen_point = false;
    for b in mantissa.bytes() {
        match b {
            b'0' => {
                held_zeros += 1;
                after_point += i32::from(seen_point);
            }
            b'1'..=b'9' => {
                let started = digits != 0;
                for _ in 0..held_zeros {
                    digits *= 10;
                }
                digits = digits * 10 + u128::from(b - b'0');
                significant += 1 + if started { held_zeros } else { 0 };
                held_zeros = 0;
                after_point += i32::from(seen_point);
            }
            b'.' => seen_point = true,
            _ => {}
        }
    }
    if significant < 16 {
        return false;
    }
    let e = exponent - after_point + i32::try_from(held_zeros).unwrap_or(0);
    if q != e - 1 {
        return false;
    }
    let n = 2 * digits + 1;
    let five = 5u128.checked_pow(e.unsigned_abs());
    if e >= 0 {
        five.and_then(|p| n.checked_mul(p)) == Some(m)
    } else {
        five.and_then(|p| m.checked_mul(p)) == Some(n)
    }
}

/// Appends `n` zeros.
fn push_zeros(out: &mut String, n: u64) {
    out.extend(core::iter::repeat_n(
        '0',
        usize::try_from(n).unwrap_or(usize::MAX),
    ));
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn text(x: f64) -> String {
        let mut s = String::new();
        push_f64(&mut s, x);
        s
    }

    #[test]
    fn layouts_where_ryu_and_display_differ() {
        for (x, want) in [
            (0.0, "0"),
            (-0.0, "-0"),
            (1.0, "1"),
            (-2.0, "-2"),
            (1e-7, "0.0000001"),
            (-1.5e-7, "-0.00000015"),
            (1e21, "1000000000000000000000"),
            (1.25e22, "12500000000000000000000"),
            (1e15, "1000000000000000"),
            (1e16, "10000000000000000"),
            (123456.0, "123456"),
            (0.001, "0.001"),
            (0.1 + 0.2, "0.30000000000000004"),
            (1248444175.103, "1248444175.103"),
            // Ties, exactly halfway between two shortest candidates:
            // 154000748790168.625 and 1522906909470580.25.
            (4_928_023_961_285_396.0 / 32.0, "154000748790168.63"),
            (6_091_627_637_882_321.0 / 4.0, "1522906909470580.3"),
            (f64::NAN, "NaN"),
            (f64::INFINITY, "inf"),
            (f64::NEG_INFINITY, "-inf"),
        ] {
            assert_eq!(text(x), want, "{x:e}");
            assert_eq!(text(x), format!("{x}"), "{x:e}");
        }
    }

    #[test]
    fn every_power_of_ten_and_the_extremes_match_display() {
        let mut cases = vec![
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            f64::EPSILON,
            5e-324,
            -5e-324,
            f64::from_bits(0x000F_FFFF_FFFF_FFFF),
        ];
        for k in -330..=310 {
            let p: f64 = format!("1e{k}").parse().unwrap();
            cases.extend([p, -p, 1.5 * p, 9.999_999_999_999_999 * p, 3.0 * p]);
        }
        for x in cases {
            assert_eq!(text(x), format!("{x}"), "{x:e}");
        }
    }

    /// `m 2^q` for an odd `m` of up to 53 bits and `q` where ties can
    /// occur (`-27..=21`), and around.
    fn tie_prone() -> impl Strategy<Value = f64> {
        (1u64..(1 << 53), -40i32..=30, any::<bool>()).prop_map(|(m, q, negative)| {
            let x = (m | 1) as f64 * 2f64.powi(q);
            if negative { -x } else { x }
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(100_000))]

        #[test]
        fn tie_prone_values_write_as_display(x in tie_prone()) {
            prop_assert_eq!(text(x), format!("{}", x));
        }

        #[test]
        fn any_bits_write_as_display(bits in any::<u64>()) {
            let x = f64::from_bits(bits);
            prop_assert_eq!(text(x), format!("{}", x));
        }

        #[test]
        fn appends_to_what_is_there(x in any::<f64>(), head in "[a-z,]{0,8}") {
            let mut s = head.clone();
            push_f64(&mut s, x);
            prop_assert_eq!(s, format!("{head}{x}"));
        }
    }
}
