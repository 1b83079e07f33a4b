//! A bag and its mapping file read as one Locus log ([`read_log`]): what
//! `locus replay bag` and the Python package's `locus.replay` both read.

use std::path::Path;

use locus_logs::locus_csv::LocusLog;
use locus_logs::wall::MapPath;

use crate::convert::to_locus;
use crate::error::BagError;
use crate::mapping::Mapping;

/// The bag at `bag` read as a Locus log by the mapping in the TOML file
/// `mapping_file` ([`Mapping`], [`to_locus`]).
///
/// The mapping's `map` file is relative to the mapping file. The log's
/// `map` record holds it resolved ([`MapPath::resolve`]), so that the log
/// names the file wherever it is read or exported; nothing of the map is
/// read here.
///
/// # Errors
/// The mapping file cannot be read ([`BagError::Io`]) or does not parse
/// ([`BagError::MappingFile`], its line named); it gives the map both as a
/// file and as `[[wall]]` entries, or a map path a log cannot record
/// ([`BagError::Mapping`]); and [`to_locus`]'s errors.
pub fn read_log(bag: &Path, mapping_file: &Path) -> Result<LocusLog, BagError> {
    let text = std::fs::read_to_string(mapping_file).map_err(|source| BagError::Io {
        file: mapping_file.to_path_buf(),
        source,
    })?;
    let shown = mapping_file.display().to_string();
    let mapping = Mapping::from_toml(&text, &shown).map_err(BagError::MappingFile)?;
    let mut log = to_locus(bag, &mapping, &shown)?;
    let map_error = |reason: &str| BagError::Mapping {
        file: shown.clone(),
        key: "map".to_string(),
        reason: reason.to_string(),
    };
    log.map = match mapping.map.as_deref() {
        None => None,
        Some(_) if !mapping.walls.is_empty() => {
            return Err(map_error(
                "give the map as `map` or as [[wall]] entries, not both",
            ));
        }
        Some(given) => {
            let relative = MapPath::new(given).ok_or_else(|| {
                map_error("a map path must not be empty, nor hold a comma or a line break, nor start or end with a blank")
            })?;
            let resolved = relative.resolve(mapping_file);
            Some(resolved.to_str().and_then(MapPath::new).ok_or_else(|| {
                map_error(&format!(
                    "{} cannot be recorded in a log (not UTF-8, or too long)",
                    resolved.display()
                ))
            })?)
        }
    };
    Ok(log)
}
