//! Locus results for Foxglove (issue 30).
//!
//! A run, simulated (`locus run`) or replayed (`locus replay`), as
//! messages of Foxglove's published schemas: the estimate, truth and
//! odometry alone as `foxglove.PoseInFrame`, the robot's transform, the
//! covariance ellipse and the map as `foxglove.SceneUpdate` (an occupancy
//! grid as `foxglove.Grid`), the errors with their 3-sigma bands and each
//! correction's NIS as plottable series, and the summary as a
//! `foxglove.Log` ([`frame`], [`scene`], [`summary`], [`topic`]). They go to an MCAP file
//! ([`McapOut`]) or, live, over the Foxglove WebSocket protocol ([`ws`]).
//!
//! **JSON, not protobuf.** Foxglove publishes both. JSON is chosen because
//! every message then validates against Foxglove's own JSON Schemas with
//! any validator (the tests do, against the published package), a file
//! reads with nothing but a JSON parser, and no protobuf code generation
//! enters the build. The cost is size: zstd chunks take most of it back
//! (docs/foxglove.md gives the figures).

extern crate alloc;

mod encode;
mod error;
mod mcap_out;
pub mod message;
pub mod topic;
pub mod ws;

pub use encode::{Frame, GridCells, Message, Scene, frame, nanos, scene, summary};
pub use error::Error;
pub use mcap_out::{McapOut, Written};
pub use topic::Topic;
