//! `locus replay bag FILE --list`: a bag's topics, their types and message
//! counts and time spans (as `ros2 bag info` lists them), which of them
//! Locus can decode, and a proposed mapping (docs/bags.md) to start from.

use std::path::Path;

use anyhow::Result;

use crate::table::with_header;

/// The listing of the bag at `file`: a table and a proposed mapping.
///
/// # Errors
/// The bag cannot be read (`locus_bag::read`).
pub fn list(file: &Path) -> Result<String> {
    let topics = locus_bag::topics(file)?;
    let mut t = with_header([
        "topic",
        "type",
        "messages [count]",
        "first [s]",
        "last [s]",
        "decodable",
    ]);
    #[allow(clippy::cast_precision_loss)]
    let s = |ns: u64| format!("{:.3}", ns as f64 * 1e-9);
    for topic in &topics {
        t.add_row(vec![
            topic.topic.clone(),
            topic.type_name.clone(),
            topic.count.to_string(),
            s(topic.first_ns),
            s(topic.last_ns),
            topic
                .undecodable
                .as_ref()
                .map_or_else(|| "yes".to_string(), |why| format!("no: {why}")),
        ]);
    }
    let messages: u64 = topics.iter().map(|t| t.count).sum();
    Ok(format!(
        "{}: {} topics, {messages} messages\n{t}\n\nA mapping to start from (save it, complete it, and pass it with --topics; docs/bags.md):\n\n{}",
        file.display(),
        topics.len(),
        locus_bag::propose::propose(&topics)
    ))
}
