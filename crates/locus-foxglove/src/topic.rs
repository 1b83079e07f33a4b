//! The topics Locus publishes, each with its schema: Foxglove's published
//! JSON Schemas where one fits (`schemas/foxglove/`, @foxglove/schemas
//! 2.1.0, unchanged) and Locus's own for the two plottable series
//! (`schemas/locus/`).

/// A JSON Schema as MCAP and the WebSocket protocol carry it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Schema {
    /// The schema's name (its `title`), e.g. `foxglove.PoseInFrame`.
    pub name: &'static str,
    /// The JSON Schema itself.
    pub data: &'static str,
}

const POSE_IN_FRAME: Schema = Schema {
    name: "foxglove.PoseInFrame",
    data: include_str!("../schemas/foxglove/PoseInFrame.json"),
};
const FRAME_TRANSFORM: Schema = Schema {
    name: "foxglove.FrameTransform",
    data: include_str!("../schemas/foxglove/FrameTransform.json"),
};
const SCENE_UPDATE: Schema = Schema {
    name: "foxglove.SceneUpdate",
    data: include_str!("../schemas/foxglove/SceneUpdate.json"),
};
const GRID: Schema = Schema {
    name: "foxglove.Grid",
    data: include_str!("../schemas/foxglove/Grid.json"),
};
const LOG: Schema = Schema {
    name: "foxglove.Log",
    data: include_str!("../schemas/foxglove/Log.json"),
};
const ERRORS: Schema = Schema {
    name: "locus.Errors",
    data: include_str!("../schemas/locus/Errors.json"),
};
const NIS: Schema = Schema {
    name: "locus.Nis",
    data: include_str!("../schemas/locus/Nis.json"),
};

/// What Locus publishes, one topic each.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Topic {
    /// The filter's estimate (`foxglove.PoseInFrame`, frame `map`).
    Estimate,
    /// The truth, when the run has one.
    Truth,
    /// Odometry alone (dead reckoning), when the run has it.
    Odometry,
    /// `map` -> `base_link` at the estimate (`foxglove.FrameTransform`), so
    /// that the 3D panel can follow the robot.
    Transform,
    /// The covariance ellipse of the position and the heading's bounds
    /// (`foxglove.SceneUpdate`).
    Ellipse,
    /// The walls and landmarks (`foxglove.SceneUpdate`), once.
    Map,
    /// An occupancy-grid map (`foxglove.Grid`), once.
    Grid,
    /// Errors and 3-sigma bands (`locus.Errors`).
    Errors,
    /// Each correction's NIS (`locus.Nis`).
    Nis,
    /// The summary (`foxglove.Log`), at the end.
    Summary,
}

impl Topic {
    /// Every topic, in the order channels are numbered.
    pub const ALL: [Self; 10] = [
        Self::Estimate,
        Self::Truth,
        Self::Odometry,
        Self::Transform,
        Self::Ellipse,
        Self::Map,
        Self::Grid,
        Self::Errors,
        Self::Nis,
        Self::Summary,
    ];

    /// The topic's name.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::Estimate => "/locus/estimate",
            Self::Truth => "/locus/truth",
            Self::Odometry => "/locus/odometry",
            Self::Transform => "/tf",
            Self::Ellipse => "/locus/covariance",
            Self::Map => "/locus/map",
            Self::Grid => "/locus/grid",
            Self::Errors => "/locus/errors",
            Self::Nis => "/locus/nis",
            Self::Summary => "/locus/summary",
        }
    }

    /// Its schema.
    #[must_use]
    pub const fn schema(self) -> Schema {
        match self {
            Self::Estimate | Self::Truth | Self::Odometry => POSE_IN_FRAME,
            Self::Transform => FRAME_TRANSFORM,
            Self::Ellipse | Self::Map => SCENE_UPDATE,
            Self::Grid => GRID,
            Self::Errors => ERRORS,
            Self::Nis => NIS,
            Self::Summary => LOG,
        }
    }

    /// Its index in [`Topic::ALL`].
    #[must_use]
    pub const fn index(self) -> usize {
        self as usize
    }
}

/// The messages' encoding (MCAP's and the WebSocket protocol's name).
pub const MESSAGE_ENCODING: &str = "json";
/// The schemas' encoding.
pub const SCHEMA_ENCODING: &str = "jsonschema";
/// The fixed frame every pose is in.
pub const WORLD_FRAME: &str = "map";
/// The robot's frame, at the estimate.
pub const ROBOT_FRAME: &str = "base_link";
