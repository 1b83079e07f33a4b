//! A mapping proposed for a bag from its topics (`locus replay bag FILE
//! --list`): a starting point the user edits, not a guess the replay acts
//! on.

use crate::bag::Topic;
use crate::mapping::Defaults;

/// A proposed mapping for the decodable `topics` of a bag ([`topics`]):
/// the first velocity-like topic, the first pose-like topic whose name
/// says truth (`mocap`, `truth`, `ground`, `vicon`, `optitrack`), each
/// `LaserScan` and `Range` topic (with an empty `map`), and the first topic
/// of a type with `id` and `range` fields as the landmark sightings.
///
/// [`topics`]: crate::topics
#[must_use]
pub fn propose(topics: &[Topic]) -> String {
    let decodable: Vec<&Topic> = topics.iter().filter(|t| t.undecodable.is_none()).collect();
    let find = |pick: &dyn Fn(&Topic) -> bool| decodable.iter().copied().find(|t| pick(t));
    let mut out = String::new();
    let velocity =
        find(&|t| t.type_name.ends_with("/Twist") || t.type_name.ends_with("/TwistStamped"))
            .or_else(|| find(&|t| Defaults::velocity(&t.type_name).is_some()));
    match velocity {
        Some(t) => out.push_str(&format!("[velocity]\ntopic = \"{}\"  # {}\n", t.topic, t.type_name)),
        None => out.push_str("# no velocity topic found (Twist, TwistStamped or Odometry): set one\n[velocity]\ntopic = \"\"\n"),
    }
    let truthy = ["mocap", "truth", "ground", "vicon", "optitrack"];
    if let Some(t) = find(&|t| {
        Defaults::pose(&t.type_name).is_some()
            && truthy.iter().any(|w| t.topic.to_lowercase().contains(w))
    }) {
        out.push_str(&format!(
            "\n[truth]\ntopic = \"{}\"  # {}\n",
            t.topic, t.type_name
        ));
    }
    let mut beams = false;
    for t in &decodable {
        let table = match t.type_name.as_str() {
            "sensor_msgs/msg/LaserScan" => "[[scan]]",
            "sensor_msgs/msg/Range" => "[[range]]",
            _ => continue,
        };
        beams = true;
        out.push_str(&format!("\n{table}\ntopic = \"{}\"\n", t.topic));
    }
    if beams {
        out.insert_str(0, "map = \"\"  # the map the ranges are corrected against (docs/maps.md), relative to this file\n\n");
    }
    let has = |t: &Topic, name: &str| t.fields.iter().any(|f| f == name);
    if let Some(t) = find(&|t| has(t, "id") && has(t, "range")) {
        out.push_str(&format!(
            "\n[landmarks]\ntopic = \"{}\"  # {}\n\n# the landmark map: one entry per landmark\n# [[landmark]]\n# id = 1\n# x = 0.0\n# y = 0.0\n",
            t.topic, t.type_name
        ));
    }
    out
}
