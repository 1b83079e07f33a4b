//! Occupancy grids in ROS map_server's format: a YAML file naming an 8-bit
//! PGM image (P5 binary or P2 ascii), read and written as map_server and
//! map_saver do, so that a map made with ROS tools loads as it is.
//!
//! The YAML keys (ROS 1 map_server; nav2's map_io reads the same):
//! `image` (the PGM, relative to the YAML file's folder unless absolute),
//! `resolution` (m/cell), `origin` (`[x, y, yaw]`, the world pose of the
//! lower-left pixel's corner; m, m, rad), `negate` (0/1 or false/true),
//! `occupied_thresh`, `free_thresh`, and optionally `mode` (`trinary`, the
//! default, `scale` or `raw`). Other keys are ignored.
//!
//! Row 0 of the image is the top of the map (the highest y). A pixel of
//! value `v` (0..=255) has occupancy probability `p = (255 - v) / 255`, or
//! `v / 255` if `negate` is set. Trinary and scale: occupied if `p >
//! occupied_thresh`, free if `p < free_thresh`, unknown otherwise; trinary
//! keeps no probability for an unknown cell, scale keeps `p`. Raw: the
//! value (after `negate`, as ROS 1 map_server) is the occupancy in percent,
//! `p = v / 100` for `v <= 100` (then classified by the thresholds), unknown
//! above. A colour image (P6) is read as the mean of its channels, as
//! map_server does.

use std::io::BufReader;
use std::path::{Path, PathBuf};

use image::ImageDecoder as _;
use image::codecs::pnm::{PnmDecoder, PnmEncoder, PnmSubtype, SampleEncoding};
use serde::Deserialize;

use crate::{Grid, GridGeometry, MapError, Occupancy, Thresholds};

/// How pixel values map to occupancy (the YAML's `mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Occupied, free or unknown by the thresholds (map_server's default).
    #[default]
    Trinary,
    /// As trinary, but a cell between the thresholds keeps its probability.
    Scale,
    /// The pixel value is the occupancy in percent (0..=100, above: unknown).
    Raw,
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Self::Trinary => "trinary",
            Self::Scale => "scale",
            Self::Raw => "raw",
        }
    }
}

/// The YAML half of a ROS map, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct MapYaml {
    /// The image file, resolved against the YAML file's folder.
    pub image: PathBuf,
    /// Cell size (m).
    pub resolution: f64,
    /// World pose (m, m, rad) of the lower-left pixel's lower-left corner.
    pub origin: [f64; 3],
    /// Whether white means occupied.
    pub negate: bool,
    /// `occupied_thresh` and `free_thresh`.
    pub thresholds: Thresholds,
    /// The `mode`.
    pub mode: Mode,
}

/// `negate` as map_server files write it: 0/1 or a boolean.
#[derive(Deserialize)]
#[serde(untagged)]
enum Flag {
    Bool(bool),
    Int(i64),
}

#[derive(Deserialize)]
struct RawYaml {
    image: String,
    resolution: f64,
    origin: Vec<f64>,
    negate: Flag,
    occupied_thresh: f64,
    free_thresh: f64,
    #[serde(default)]
    mode: Option<String>,
}

/// Reads a ROS map: the YAML file at `path` and the image it names.
///
/// # Errors
/// [`MapError::Io`] for a file that cannot be read, [`MapError::Syntax`]
/// (with the line) for YAML that does not parse or lacks a key,
/// [`MapError::Field`] for a value that is not allowed, [`MapError::Image`]
/// for an image that is not an 8-bit PNM.
pub fn load(path: &Path) -> Result<Grid, MapError> {
    let src = std::fs::read_to_string(path).map_err(|source| MapError::Io {
        file: path.into(),
        source,
    })?;
    let yaml = parse_yaml(&src, path)?;
    let (width, height, pixels) = read_pgm(&yaml.image)?;
    grid_from_pixels(width, height, &pixels, &yaml)
}

/// The YAML text `src` of the map file `file` (which names it in errors and
/// anchors a relative `image`).
///
/// # Errors
/// [`MapError::Syntax`] if it does not parse or lacks a key;
/// [`MapError::Field`] for `resolution` not finite and positive, `origin`
/// not three finite numbers, `negate` not 0/1/false/true, a threshold
/// outside 0..=1, `free_thresh` above `occupied_thresh`, or an unknown
/// `mode`.
pub fn parse_yaml(src: &str, file: &Path) -> Result<MapYaml, MapError> {
    let raw: RawYaml = yaml_serde::from_str(src).map_err(|e| MapError::Syntax {
        file: file.into(),
        line: e.location().map(|l| l.line()),
        message: e.to_string(),
    })?;
    let field = |field: &str, reason: String| MapError::Field {
        file: file.into(),
        field: field.to_string(),
        reason,
    };
    if !(raw.resolution.is_finite() && raw.resolution > 0.0) {
        return Err(field(
            "resolution",
            format!("{}: must be finite and positive (m/cell)", raw.resolution),
        ));
    }
    let origin: [f64; 3] = match raw.origin[..] {
        [x, y, yaw] if [x, y, yaw].iter().all(|v| v.is_finite()) => [x, y, yaw],
        _ => {
            return Err(field(
                "origin",
                format!("{:?}: must be [x, y, yaw], finite (m, m, rad)", raw.origin),
            ));
        }
    };
    let negate = match raw.negate {
        Flag::Bool(b) => b,
        Flag::Int(0) => false,
        Flag::Int(1) => true,
        Flag::Int(n) => return Err(field("negate", format!("{n}: must be 0 or 1"))),
    };
    for (name, v) in [
        ("occupied_thresh", raw.occupied_thresh),
        ("free_thresh", raw.free_thresh),
    ] {
        if !(0.0..=1.0).contains(&v) {
            return Err(field(name, format!("{v}: must be in 0..=1")));
        }
    }
    if raw.free_thresh > raw.occupied_thresh {
        return Err(field(
            "free_thresh",
            format!(
                "{} is above occupied_thresh {}",
                raw.free_thresh, raw.occupied_thresh
            ),
        ));
    }
    let mode = match raw.mode.as_deref().map(str::trim) {
        None | Some("trinary") => Mode::Trinary,
        Some("scale") => Mode::Scale,
        Some("raw") => Mode::Raw,
        Some(other) => {
            return Err(field(
                "mode",
                format!("{other:?}: must be trinary, scale or raw"),
            ));
        }
    };
    if raw.image.trim().is_empty() {
        return Err(field("image", "empty: must name the PGM file".into()));
    }
    let image = Path::new(&raw.image);
    let image = if image.is_absolute() {
        image.to_path_buf()
    } else {
        file.parent().unwrap_or(Path::new("")).join(image)
    };
    Ok(MapYaml {
        image,
        resolution: raw.resolution,
        origin,
        negate,
        thresholds: Thresholds {
            occupied: raw.occupied_thresh,
            free: raw.free_thresh,
        },
        mode,
    })
}

/// Reads an 8-bit PNM image as grey levels: `(width, height, pixels)`,
/// row-major, row 0 at the top.
///
/// # Errors
/// [`MapError::Io`] if it cannot be opened; [`MapError::Image`] if it does
/// not decode or is not 8-bit grey or colour.
pub fn read_pgm(path: &Path) -> Result<(usize, usize, Vec<u8>), MapError> {
    let file = std::fs::File::open(path).map_err(|source| MapError::Io {
        file: path.into(),
        source,
    })?;
    let image_err = |reason: String| MapError::Image {
        file: path.into(),
        reason,
    };
    let decoder = PnmDecoder::new(BufReader::new(file)).map_err(|e| image_err(e.to_string()))?;
    let (w, h) = decoder.dimensions();
    let colour = decoder.color_type();
    let mut buf = vec![0u8; decoder.total_bytes() as usize];
    decoder
        .read_image(&mut buf)
        .map_err(|e| image_err(e.to_string()))?;
    let pixels = match colour {
        image::ColorType::L8 => buf,
        image::ColorType::Rgb8 => buf
            .chunks_exact(3)
            .map(|c| ((u16::from(c[0]) + u16::from(c[1]) + u16::from(c[2])) / 3) as u8)
            .collect(),
        other => {
            return Err(image_err(format!(
                "{other:?} pixels: a map image must be 8-bit grey (or colour)"
            )));
        }
    };
    Ok((w as usize, h as usize, pixels))
}

/// The grid of an image (`width x height` grey levels, row 0 at the top)
/// under the YAML's rules (see the module's documentation).
///
/// # Errors
/// [`MapError::Image`] if the pixel count is not `width * height`, or the
/// image is empty or too large; [`MapError::Invalid`] for thresholds that
/// [`Thresholds::check`] refuses.
pub fn grid_from_pixels(
    width: usize,
    height: usize,
    pixels: &[u8],
    yaml: &MapYaml,
) -> Result<Grid, MapError> {
    if pixels.len() != width * height || width == 0 || height == 0 {
        return Err(MapError::Image {
            file: yaml.image.clone(),
            reason: format!("{} pixels for {width} x {height}", pixels.len()),
        });
    }
    let geometry = GridGeometry::new(width, height, yaml.resolution, yaml.origin).map_err(|e| {
        MapError::Image {
            file: yaml.image.clone(),
            reason: e.to_string(),
        }
    })?;
    let th = yaml.thresholds;
    let mut probs = vec![None; width * height];
    for (row, line) in pixels.chunks_exact(width).enumerate() {
        let iy = height - 1 - row;
        for (ix, &v) in line.iter().enumerate() {
            let v = if yaml.negate { 255 - v } else { v };
            let p = match yaml.mode {
                Mode::Raw => (v <= 100).then(|| f64::from(v) / 100.0),
                Mode::Trinary | Mode::Scale => {
                    let p = f64::from(255 - v) / 255.0;
                    let known =
                        yaml.mode == Mode::Scale || th.classify(Some(p)) != Occupancy::Unknown;
                    known.then_some(p)
                }
            };
            probs[geometry.index(ix, iy)] = p;
        }
    }
    Grid::from_probabilities(geometry, th, &probs)
}

/// map_saver's pixel values: occupied, free, unknown.
const OCCUPIED: u8 = 0;
const FREE: u8 = 254;
const UNKNOWN: u8 = 205;

/// Writes `grid` as a ROS map: the YAML at `path` and, beside it, a P5 PGM
/// of the same stem (`map.yaml` -> `map.pgm`), named relative in the YAML.
/// Trinary: occupied cells 0, free 254, unknown 205, as map_saver (205 is
/// replaced by a value between the thresholds if the grid's thresholds
/// would not read it back as unknown). Scale: `round(255 (1 - p))`, a cell
/// without probability as trinary's unknown. Raw: `round(100 p)`, 255 for a
/// cell without probability. The grid's thresholds are written.
///
/// # Errors
/// [`MapError::Io`] or [`MapError::Image`] if a file cannot be written;
/// [`MapError::Invalid`] if `path` has no file name or ends in `.pgm`, or
/// the thresholds leave no pixel value that reads back as each trinary
/// state.
pub fn save(grid: &Grid, path: &Path, mode: Mode) -> Result<(), MapError> {
    let stem = path.file_stem().and_then(|s| s.to_str()).ok_or_else(|| {
        MapError::invalid("map path", format!("{}: no file name", path.display()))
    })?;
    let image_name = format!("{stem}.pgm");
    let image_path = path.with_file_name(&image_name);
    if image_path == path {
        return Err(MapError::invalid(
            "map path",
            format!("{}: the YAML would overwrite its own image", path.display()),
        ));
    }
    let g = grid.geometry();
    let th = grid.thresholds();
    let unknown = if mode == Mode::Raw {
        255
    } else {
        unknown_pixel(th)?
    };
    if mode == Mode::Trinary
        && (th.classify(Some(1.0)) != Occupancy::Occupied
            || th.classify(Some(f64::from(255 - FREE) / 255.0)) != Occupancy::Free)
    {
        return Err(MapError::invalid(
            "thresholds",
            format!(
                "free {} and occupied {}: pixels 0 and 254 would not read back as occupied and free",
                th.free, th.occupied
            ),
        ));
    }
    let (w, h) = (g.width(), g.height());
    let mut pixels = Vec::with_capacity(w * h);
    for row in 0..h {
        let iy = h - 1 - row;
        for ix in 0..w {
            let p = grid.probability(ix, iy);
            let v = match mode {
                Mode::Trinary => match grid.state(ix, iy) {
                    Some(Occupancy::Occupied) => OCCUPIED,
                    Some(Occupancy::Free) => FREE,
                    _ => unknown,
                },
                Mode::Scale => p.map_or(unknown, |p| (255.0 * (1.0 - p)).round() as u8),
                Mode::Raw => p.map_or(255, |p| (100.0 * p).round() as u8),
            };
            pixels.push(v);
        }
    }
    write_pgm(&image_path, w, h, &pixels)?;
    // map_saver's layout (origin as a flow list); the image name quoted as
    // YAML needs it; numbers that read back bit for bit.
    let name = yaml_serde::to_string(&image_name).map_err(|e| MapError::Syntax {
        file: path.into(),
        line: None,
        message: e.to_string(),
    })?;
    let o = g.origin();
    let text = format!(
        "image: {}\nmode: {}\nresolution: {:?}\norigin: [{:?}, {:?}, {:?}]\nnegate: 0\noccupied_thresh: {:?}\nfree_thresh: {:?}\n",
        name.trim_end(),
        mode.name(),
        g.resolution(),
        o[0],
        o[1],
        o[2],
        th.occupied,
        th.free
    );
    std::fs::write(path, text).map_err(|source| MapError::Io {
        file: path.into(),
        source,
    })
}

/// A pixel value that the thresholds read as unknown: map_saver's 205 if it
/// is, else the one nearest the middle of the thresholds.
fn unknown_pixel(th: Thresholds) -> Result<u8, MapError> {
    let reads_unknown = |v: u8| th.classify(Some(f64::from(255 - v) / 255.0)) == Occupancy::Unknown;
    if reads_unknown(UNKNOWN) {
        return Ok(UNKNOWN);
    }
    let mid = 0.5 * (th.free + th.occupied);
    let v = (255.0 * (1.0 - mid)).round() as u8;
    if reads_unknown(v) {
        Ok(v)
    } else {
        Err(MapError::invalid(
            "thresholds",
            format!(
                "free {} and occupied {}: no pixel value reads back as unknown",
                th.free, th.occupied
            ),
        ))
    }
}

/// Writes an 8-bit binary PGM (P5), row 0 at the top.
///
/// # Errors
/// [`MapError::Io`] or [`MapError::Image`].
pub fn write_pgm(path: &Path, width: usize, height: usize, pixels: &[u8]) -> Result<(), MapError> {
    let file = std::fs::File::create(path).map_err(|source| MapError::Io {
        file: path.into(),
        source,
    })?;
    let mut out = std::io::BufWriter::new(file);
    let image_err = |reason: String| MapError::Image {
        file: path.into(),
        reason,
    };
    let (w, h) = (
        u32::try_from(width).map_err(|e| image_err(e.to_string()))?,
        u32::try_from(height).map_err(|e| image_err(e.to_string()))?,
    );
    PnmEncoder::new(&mut out)
        .with_subtype(PnmSubtype::Graymap(SampleEncoding::Binary))
        .encode(pixels, w, h, image::ColorType::L8)
        .map_err(|e| image_err(e.to_string()))?;
    std::io::Write::flush(&mut out).map_err(|source| MapError::Io {
        file: path.into(),
        source,
    })
}
