//! What a telemetry packet may say: the limits its content must respect
//! before the host lets it touch the filter (`docs/protocol.md`,
//! "Plausibility"). The rules are the ones the replay applies to a log's
//! records, kept in one place: [`locus_models::plausible`].
//!
//! A packet can pass the CRC and still be impossible: a bit flip the CRC
//! missed, a forged packet, a robot whose encoder counter was reset. Such a
//! packet is refused whole and counted; because the encoder counts are
//! cumulative, the next plausible packet's difference still covers the
//! travel, so a refused packet loses nothing.

pub use locus_models::plausible::{Implausible, Limits};
