//! Shards of a sweep, the result CSV (floats in shortest round-trip form)
//! and the merge of shards into the whole grid.

use core::fmt;

use super::{Cell, CellResult, DoaConfig, DoaError, GridConfig, MAX_GRID_CELLS};

/// A deterministic slice `index / count` of a sweep (0-based index).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard (0-based, `< count`).
    pub index: usize,
    /// Number of shards (>= 1).
    pub count: usize,
}

impl Shard {
    /// The whole sweep (`0/1`).
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N` (0-based `I < N`).
    pub fn parse(spec: &str) -> Result<Self, DoaError> {
        let bad = |message: &str| DoaError::Shard {
            spec: spec.to_owned(),
            message: message.to_owned(),
        };
        let (i, n) = spec
            .split_once('/')
            .ok_or_else(|| bad("expected I/N, e.g. 0/8"))?;
        let index: usize = i
            .trim()
            .parse()
            .map_err(|_| bad("I is not a whole number"))?;
        let count: usize = n
            .trim()
            .parse()
            .map_err(|_| bad("N is not a whole number"))?;
        if count == 0 {
            return Err(bad("N must be >= 1"));
        }
        if index >= count {
            return Err(bad("I must be < N (0-based)"));
        }
        Ok(Self { index, count })
    }

    /// True if cell `index` belongs to this shard.
    pub fn contains(&self, cell_index: usize) -> bool {
        cell_index % self.count == self.index
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The results of a sweep or a shard of it.
#[derive(Debug, Clone, PartialEq)]
pub struct DoaResult {
    /// [`DoaConfig::hash`](super::DoaConfig::hash) of the study.
    pub config_hash: u64,
    /// Rows of the grid.
    pub v_g_count: usize,
    /// Columns of the grid.
    pub alpha_count: usize,
    /// The shard these results are (`None`: the whole grid).
    pub shard: Option<Shard>,
    /// The cells, by increasing index.
    pub cells: Vec<CellResult>,
}

const CSV_MAGIC: &str = "# locus-doa v1";
const CSV_HEADER: &str = "index,i_vg,i_alpha,v_g,alpha,m_zeta,evaluations,settle_time_s";

impl DoaResult {
    /// The CSV form: a comment line with the configuration hash, grid and
    /// shard, the header, then one line per cell (floats in shortest
    /// round-trip form; an empty settling time means some vertex did not
    /// converge).
    pub fn to_csv(&self) -> String {
        let shard = self.shard.map_or("all".to_owned(), |s| s.to_string());
        let mut out = format!(
            "{CSV_MAGIC} config={:016x} grid={}x{} shard={shard}\n{CSV_HEADER}\n",
            self.config_hash, self.v_g_count, self.alpha_count
        );
        for r in &self.cells {
            let c = &r.cell;
            let settle = r.settle.map_or(String::new(), |s| s.to_string());
            out.push_str(&format!(
                "{},{},{},{},{},{},{},{}\n",
                c.index, c.i_vg, c.i_alpha, c.v_g, c.alpha, r.m_zeta, r.evaluations, settle
            ));
        }
        out
    }

    /// Parses [`to_csv`](Self::to_csv)'s form; `file` names it in errors.
    /// Every cell must lie in the grid of the header (at most
    /// [`MAX_GRID_CELLS`] cells) at its row-major index, with finite `v_g`
    /// and `alpha`, `m_zeta` finite and `>= 0`, and a settling time (if any)
    /// finite and `>= 0`.
    pub fn from_csv(text: &str, file: &str) -> Result<Self, DoaError> {
        Self::parse_csv(text, file, None)
    }

    /// [`from_csv`](Self::from_csv) for shards of the study `config`: the
    /// header's grid must be the configuration's and every cell's `v_g` and
    /// `alpha` exactly the configuration's values at its row and column.
    pub fn from_csv_of(text: &str, file: &str, config: &DoaConfig) -> Result<Self, DoaError> {
        Self::parse_csv(text, file, Some(&config.grid))
    }

    fn parse_csv(text: &str, file: &str, grid_of: Option<&GridConfig>) -> Result<Self, DoaError> {
        let err = |line: usize, field: &str, message: String| DoaError::Csv {
            file: file.to_owned(),
            line,
            field: field.to_owned(),
            message,
        };
        let mut lines = text.lines().enumerate();
        let (_, first) = lines
            .next()
            .ok_or_else(|| err(1, "header", "empty file".into()))?;
        let rest = first.strip_prefix(CSV_MAGIC).ok_or_else(|| {
            err(
                1,
                "header",
                format!("expected `{CSV_MAGIC} ...`, got `{first}`"),
            )
        })?;
        let (mut hash, mut grid, mut shard) = (None, None, None);
        for kv in rest.split_whitespace() {
            match kv.split_once('=') {
                Some(("config", v)) => hash = u64::from_str_radix(v, 16).ok(),
                Some(("grid", v)) => {
                    grid = v
                        .split_once('x')
                        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
                }
                Some(("shard", "all")) => shard = Some(None),
                Some(("shard", v)) => shard = Shard::parse(v).ok().map(Some),
                _ => {}
            }
        }
        let config_hash = hash.ok_or_else(|| err(1, "config", "missing or malformed".into()))?;
        let (v_g_count, alpha_count): (usize, usize) =
            grid.ok_or_else(|| err(1, "grid", "missing or malformed".into()))?;
        let shard = shard.ok_or_else(|| err(1, "shard", "missing or malformed".into()))?;
        let total = v_g_count
            .checked_mul(alpha_count)
            .filter(|&n| n <= MAX_GRID_CELLS)
            .ok_or_else(|| {
                err(
                    1,
                    "grid",
                    format!(
                        "{v_g_count}x{alpha_count} is more than the {MAX_GRID_CELLS} cells a study may have"
                    ),
                )
            })?;
        if let Some(g) = grid_of {
            if (g.v_g_count, g.alpha_count) != (v_g_count, alpha_count) {
                return Err(err(
                    1,
                    "grid",
                    format!(
                        "{v_g_count}x{alpha_count}, but the configuration's grid is {}x{}",
                        g.v_g_count, g.alpha_count
                    ),
                ));
            }
        }
        match lines.next() {
            Some((_, h)) if h == CSV_HEADER => {}
            _ => return Err(err(2, "header", format!("expected `{CSV_HEADER}`"))),
        }
        let names: Vec<&str> = CSV_HEADER.split(',').collect();
        let mut cells = Vec::new();
        for (i, line) in lines {
            let n = i + 1;
            if line.trim().is_empty() {
                continue;
            }
            let f: Vec<&str> = line.split(',').collect();
            if f.len() != names.len() {
                return Err(err(
                    n,
                    "line",
                    format!("expected {} fields, got {}", names.len(), f.len()),
                ));
            }
            let int = |k: usize| {
                f[k].parse::<usize>()
                    .map_err(|e| err(n, names[k], format!("`{}`: {e}", f[k])))
            };
            let float = |k: usize| {
                f[k].parse::<f64>()
                    .map_err(|e| err(n, names[k], format!("`{}`: {e}", f[k])))
            };
            let evaluations = f[6]
                .parse::<u32>()
                .map_err(|e| err(n, names[6], format!("`{}`: {e}", f[6])))?;
            let settle = if f[7].is_empty() {
                None
            } else {
                Some(float(7)?)
            };
            let result = CellResult {
                cell: Cell {
                    index: int(0)?,
                    i_vg: int(1)?,
                    i_alpha: int(2)?,
                    v_g: float(3)?,
                    alpha: float(4)?,
                },
                m_zeta: float(5)?,
                evaluations,
                settle,
            };
            check_cell(&result, (v_g_count, alpha_count, total), grid_of)
                .map_err(|(k, message)| err(n, names[k], message))?;
            cells.push(result);
        }
        Ok(Self {
            config_hash,
            v_g_count,
            alpha_count,
            shard,
            cells,
        })
    }

    /// The cell at `(i_vg, i_alpha)`, if present.
    pub fn get(&self, i_vg: usize, i_alpha: usize) -> Option<&CellResult> {
        self.cells
            .iter()
            .find(|r| r.cell.i_vg == i_vg && r.cell.i_alpha == i_alpha)
    }
}

/// Whether the parsed cell `r` fits a `(rows, columns, cells)` grid and
/// (if given) the configuration's grid `g`; else the CSV column (index in
/// the header) and what is wrong.
fn check_cell(
    r: &CellResult,
    (rows, columns, total): (usize, usize, usize),
    g: Option<&GridConfig>,
) -> Result<(), (usize, String)> {
    let c = &r.cell;
    if c.i_vg >= rows {
        return Err((
            1,
            format!("{} is outside the {rows} rows of the grid", c.i_vg),
        ));
    }
    if c.i_alpha >= columns {
        return Err((
            2,
            format!("{} is outside the {columns} columns of the grid", c.i_alpha),
        ));
    }
    if c.index >= total || c.index != c.i_vg * columns + c.i_alpha {
        return Err((
            0,
            format!(
                "{} is not the row-major index of cell ({}, {})",
                c.index, c.i_vg, c.i_alpha
            ),
        ));
    }
    if !c.v_g.is_finite() {
        return Err((3, format!("must be finite, got {}", c.v_g)));
    }
    if !c.alpha.is_finite() {
        return Err((4, format!("must be finite, got {}", c.alpha)));
    }
    if !(r.m_zeta.is_finite() && r.m_zeta >= 0.0) {
        return Err((5, format!("must be finite and >= 0, got {}", r.m_zeta)));
    }
    if let Some(s) = r.settle {
        if !(s.is_finite() && s >= 0.0) {
            return Err((7, format!("must be finite and >= 0 or empty, got {s}")));
        }
    }
    if let Some(g) = g {
        let (v_g, alpha) = (g.v_g(c.i_vg), g.alpha(c.i_alpha));
        if c.v_g.to_bits() != v_g.to_bits() {
            return Err((
                3,
                format!(
                    "{} is not the configuration's v_g of row {} ({v_g})",
                    c.v_g, c.i_vg
                ),
            ));
        }
        if c.alpha.to_bits() != alpha.to_bits() {
            return Err((
                4,
                format!(
                    "{} is not the configuration's alpha of column {} ({alpha})",
                    c.alpha, c.i_alpha
                ),
            ));
        }
    }
    Ok(())
}

/// The whole grid from the CSV texts of all its shards, each given with
/// the name its errors use (`locus doa merge`, `locus.doa`): each parsed
/// ([`DoaResult::from_csv`], or [`DoaResult::from_csv_of`] the study
/// `config` when given, with the name of its file), then [`merge`]d, and
/// the merged configuration hash checked against `config`'s.
///
/// # Errors
/// A shard that does not parse or does not fit the configuration's grid
/// (its name, line and field); shards that do not merge ([`merge`]);
/// shards of another configuration than `config`.
pub fn merge_csv<'a>(
    shards: impl IntoIterator<Item = (&'a str, &'a str)>,
    config: Option<(&DoaConfig, &str)>,
) -> Result<DoaResult, DoaError> {
    let parts = shards
        .into_iter()
        .map(|(name, text)| match config {
            Some((c, _)) => DoaResult::from_csv_of(text, name, c),
            None => DoaResult::from_csv(text, name),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let merged = merge(parts)?;
    if let Some((c, name)) = config
        && c.hash() != merged.config_hash
    {
        return Err(DoaError::Merge(format!(
            "the shards were computed with another configuration than {name}"
        )));
    }
    Ok(merged)
}

/// Joins shards into the whole grid: every part must have the same
/// configuration hash and grid, and together they must hold every cell
/// exactly once. The result equals the unsharded sweep.
pub fn merge(parts: Vec<DoaResult>) -> Result<DoaResult, DoaError> {
    let first = parts
        .first()
        .ok_or_else(|| DoaError::Merge("no shards given".into()))?;
    let (hash, nv, na) = (first.config_hash, first.v_g_count, first.alpha_count);
    let total = nv * na;
    let mut slots: Vec<Option<CellResult>> = vec![None; total];
    for (k, part) in parts.iter().enumerate() {
        if part.config_hash != hash {
            return Err(DoaError::Merge(format!(
                "shard {k} has configuration {:016x}, shard 0 has {hash:016x}",
                part.config_hash
            )));
        }
        if (part.v_g_count, part.alpha_count) != (nv, na) {
            return Err(DoaError::Merge(format!(
                "shard {k} has a {}x{} grid, shard 0 has {nv}x{na}",
                part.v_g_count, part.alpha_count
            )));
        }
        for r in &part.cells {
            let i = r.cell.index;
            if i >= total || r.cell.i_vg * na + r.cell.i_alpha != i {
                return Err(DoaError::Merge(format!(
                    "shard {k}: cell index {i} does not fit the grid"
                )));
            }
            if slots[i].replace(*r).is_some() {
                return Err(DoaError::Merge(format!("cell {i} appears twice")));
            }
        }
    }
    let missing: Vec<usize> = (0..total).filter(|&i| slots[i].is_none()).collect();
    if !missing.is_empty() {
        return Err(DoaError::Merge(format!(
            "{} cells missing (first: {:?})",
            missing.len(),
            &missing[..missing.len().min(5)]
        )));
    }
    Ok(DoaResult {
        config_hash: hash,
        v_g_count: nv,
        alpha_count: na,
        shard: None,
        cells: slots.into_iter().flatten().collect(),
    })
}
