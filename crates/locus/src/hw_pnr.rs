//! `locus hw --pnr DIR`: the placed-and-routed row of the Verilog core
//! (`scripts/hw_pnr.sh`, nextpnr-ecp5's `report.json` in DIR) beside the
//! papers' core: cycles (the cycle-level model with the built units'
//! latencies), Fmax, time per correction, LUT4, flip-flops, the area in
//! LE-equivalents and the multipliers. Without DIR, or without the
//! report, the row reads "n/a" with the reason.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{Context as _, Result, anyhow};
use serde::Deserialize;

use crate::table::with_header;

/// One resource of nextpnr's report: used of available.
#[derive(Debug, Deserialize)]
struct Resource {
    used: u64,
}

/// One clock's Fmax in nextpnr's report, MHz.
#[derive(Debug, Deserialize)]
struct Clock {
    achieved: f64,
}

/// What `locus hw` reads of nextpnr's `--report` JSON.
#[derive(Debug, Deserialize)]
struct Report {
    utilization: HashMap<String, Resource>,
    fmax: HashMap<String, Clock>,
}

/// The placed-and-routed figures of a flow run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placed {
    /// LUT4 (nextpnr's `TRELLIS_COMB`).
    pub lut4: u64,
    /// Flip-flops (`TRELLIS_FF`).
    pub ff: u64,
    /// 18x18 multipliers (`MULT18X18D`).
    pub mult18: u64,
    /// The core clock's Fmax, MHz (the slowest clock's if there are
    /// several).
    pub fmax_mhz: f64,
}

impl Placed {
    /// The figures of nextpnr's report text `json` (named `file` in
    /// errors).
    ///
    /// # Errors
    /// Text that is not such a report, or one with no clock.
    pub fn from_report(json: &str, file: &str) -> Result<Self> {
        let r: Report =
            serde_json::from_str(json).with_context(|| format!("{file}: not a nextpnr report"))?;
        let used = |k: &str| r.utilization.get(k).map_or(0, |x| x.used);
        let fmax_mhz = r
            .fmax
            .values()
            .map(|c| c.achieved)
            .fold(f64::INFINITY, f64::min);
        if !fmax_mhz.is_finite() || fmax_mhz <= 0.0 {
            return Err(anyhow!("{file}: fmax: no clock with a positive Fmax"));
        }
        Ok(Self {
            lut4: used("TRELLIS_COMB"),
            ff: used("TRELLIS_FF"),
            mult18: used("MULT18X18D"),
            fmax_mhz,
        })
    }

    /// The area in Cyclone IV logic elements' terms: an element is one
    /// LUT4 and one flip-flop, so the flip-flops beyond the LUT4 count.
    #[must_use]
    pub fn le_equivalent(&self) -> u64 {
        self.lut4 + self.ff.saturating_sub(self.lut4)
    }
}

/// Prints the placed-and-routed row for `dir` (a `scripts/hw_pnr.sh`
/// output directory) at `cycles` per correction, beside the papers' row.
///
/// # Errors
/// A report that exists but cannot be read or parsed.
pub fn print(dir: Option<&Path>, cycles: u64) -> Result<()> {
    let placed = match dir {
        None => Err(
            "not given: run `bash scripts/hw_pnr.sh` (about 25 minutes), then `locus hw --pnr target/hw-pnr`"
                .to_owned(),
        ),
        Some(d) => {
            let file = d.join("report.json");
            if file.is_file() {
                let text = std::fs::read_to_string(&file)
                    .with_context(|| format!("reading {}", file.display()))?;
                Ok(Placed::from_report(&text, &file.display().to_string())?)
            } else {
                Err(format!(
                    "{} is missing: run `bash scripts/hw_pnr.sh {}`",
                    file.display(),
                    d.display()
                ))
            }
        }
    };
    println!("Placed and routed (LFE5U-85F-6 CABGA381, scripts/hw_pnr.sh):");
    let mut table = with_header([
        "",
        "cycles",
        "Fmax [MHz]",
        "time [us]",
        "LUT4",
        "flip-flops",
        "LE-equivalent",
        "multipliers",
    ]);
    match placed {
        Ok(p) => table.add_row(vec![
            "this core (nextpnr-ecp5)".to_owned(),
            cycles.to_string(),
            format!("{:.2}", p.fmax_mhz),
            format!("{:.2}", cycles as f64 / p.fmax_mhz),
            p.lut4.to_string(),
            p.ff.to_string(),
            p.le_equivalent().to_string(),
            format!("{} MULT18X18D", p.mult18),
        ]),
        Err(reason) => table.add_row(vec![
            "this core".to_owned(),
            cycles.to_string(),
            format!("n/a: {reason}"),
            "n/a".to_owned(),
            "n/a".to_owned(),
            "n/a".to_owned(),
            "n/a".to_owned(),
            "n/a".to_owned(),
        ]),
    };
    table.add_row(vec![
        "papers 000/003 (EP4CE115, Quartus II)".to_owned(),
        "104".to_owned(),
        "49.08".to_owned(),
        "2.08".to_owned(),
        "-".to_owned(),
        "-".to_owned(),
        "22089 LEs".to_owned(),
        "175 9x9 (about 87 18x18)".to_owned(),
    ]);
    println!("{table}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shape of nextpnr 0.11's `--report` (trimmed).
    const REPORT: &str = r#"{"critical_paths": [], "fmax": {"$glbnet$clk$TRELLIS_IO_IN":
        {"achieved": 19.027685165405273, "constraint": 50}}, "utilization": {
        "MULT18X18D": {"available": 156, "used": 36}, "TRELLIS_COMB": {"available": 83640,
        "used": 55724}, "TRELLIS_FF": {"available": 83640, "used": 8628}}}"#;

    #[test]
    fn a_nextpnr_report_gives_the_row() {
        let p = Placed::from_report(REPORT, "report.json").unwrap();
        assert_eq!((p.lut4, p.ff, p.mult18), (55_724, 8_628, 36));
        assert!((p.fmax_mhz - 19.0277).abs() < 1e-4);
        assert_eq!(p.le_equivalent(), 55_724);
        let more_ff = Placed { ff: 60_000, ..p };
        assert_eq!(more_ff.le_equivalent(), 60_000);
    }

    #[test]
    fn a_report_without_a_clock_or_malformed_is_an_error_naming_the_file() {
        let e = Placed::from_report(r#"{"fmax": {}, "utilization": {}}"#, "r.json").unwrap_err();
        assert!(e.to_string().contains("r.json: fmax"), "{e}");
        let e = Placed::from_report("{", "r.json").unwrap_err();
        assert!(
            e.to_string().contains("r.json: not a nextpnr report"),
            "{e}"
        );
    }
}
