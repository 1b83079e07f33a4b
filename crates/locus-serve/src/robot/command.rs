//! The pages' commands to the host thread, checked before they reach it.

use locus_net::host::Host;

use crate::params::{self, Invalid, ParamPatch};
use crate::protocol::ClientMsg;

/// A page's command to the host thread, validated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Resume the path controller.
    Start,
    /// Zero wheel speeds (the operator's twist ends too).
    Stop,
    /// The operator's body twist (m/s, rad/s) for [`TELEOP_TIMEOUT`](crate::session::TELEOP_TIMEOUT).
    Teleop {
        /// Linear speed (m/s).
        v: f64,
        /// Turn rate (rad/s).
        w: f64,
    },
    /// Back to the controller (or to zero speeds if stopped).
    TeleopOff,
    /// Show the host's next IR correction step by step (the robot keeps
    /// its drive: it runs live).
    NextCorrection,
    /// Live settings (a patch: the fields given).
    Settings(Settings),
}

pub use crate::params::Settings;

/// The live settings of `values` for a robot: the patch checked, and
/// `ir_sigma` (the simulator's injected noise) refused.
///
/// # Errors
/// [`Invalid`] naming the first bad field.
pub fn robot_settings(values: &ParamPatch) -> Result<Settings, Invalid> {
    let s = values.checked()?;
    if s.ir_sigma.is_some() {
        return Err(Invalid::new(
            "ir_sigma",
            "is the simulator's injected noise: a robot's IR noise is its own",
        ));
    }
    Ok(s)
}

impl Settings {
    /// Applies the settings to `host` from its next packet on. Values
    /// within [`params::LIMITS`] are always accepted (every limit is
    /// inside the host's domain), so a patch is applied whole.
    ///
    /// # Errors
    /// The host's [`locus_net::Error`] for a value outside its domain (the
    /// noise, then the gate, then the controller are set in that order).
    pub fn apply(&self, host: &mut Host) -> Result<(), locus_net::Error> {
        let c = *host.config();
        let l = c.localiser;
        if self.q11.is_some() || self.q22.is_some() || self.r11.is_some() || self.r22.is_some() {
            host.set_noise(
                self.q11.unwrap_or(l.q11),
                self.q22.unwrap_or(l.q22),
                self.r11.unwrap_or(l.r11),
                self.r22.unwrap_or(l.r22),
            )?;
        }
        if let Some(g) = self.gate {
            host.set_gate((g > 0.0).then_some(g))?;
        }
        if let Some(on) = self.use_ir {
            host.set_use_ir(on);
        }
        let k = c.control;
        let control = locus_control::Config {
            v_ref: self.v_ref.unwrap_or(k.v_ref),
            w_ref: self.w_ref.unwrap_or(k.w_ref),
            k_cross: self.k_cross.unwrap_or(k.k_cross),
            k_heading: self.k_heading.unwrap_or(k.k_heading),
            k_pos: self.k_pos.unwrap_or(k.k_pos),
            ..k
        };
        if control != k {
            host.set_control(control)?;
        }
        Ok(())
    }
}

/// A page's message as a host command, validated.
///
/// # Errors
/// [`Invalid`]: a bad value, or a message a live robot cannot do
/// ([`UNAVAILABLE`](super::UNAVAILABLE)), named by its type.
pub fn command(msg: ClientMsg) -> Result<Command, Invalid> {
    let unavailable = |what: &str| {
        Err(Invalid::new(
            what,
            "is not available when attached to a robot (it runs live, in real time, and sends no ground truth)",
        ))
    };
    match msg {
        ClientMsg::Start {} => Ok(Command::Start),
        ClientMsg::Stop {} => Ok(Command::Stop),
        ClientMsg::Teleop { v, w } => Ok(Command::Teleop {
            v: params::checked("teleop_v", &v)?,
            w: params::checked("teleop_w", &w)?,
        }),
        ClientMsg::TeleopOff {} => Ok(Command::TeleopOff),
        ClientMsg::Params { values } => robot_settings(&values).map(Command::Settings),
        ClientMsg::Step {} => unavailable("step"),
        ClientMsg::StepCorrection {} => Ok(Command::NextCorrection),
        ClientMsg::Reset {} => unavailable("reset"),
        ClientMsg::Speed { .. } => unavailable("speed"),
        ClientMsg::Scenario { .. } => unavailable("scenario"),
        ClientMsg::Preset { .. } => unavailable("preset"),
        ClientMsg::Initial { .. } => unavailable("initial"),
        ClientMsg::Export {} => unavailable("export"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{Value, json};

    use crate::robot::UNAVAILABLE;

    fn host() -> Host {
        let mut cfg = locus_simlink::host_config(&locus_sim::SquareConfig::default());
        cfg.laps = usize::MAX;
        Host::new(&cfg).unwrap()
    }

    fn values(v: Value) -> ParamPatch {
        serde_json::from_value(v).unwrap()
    }

    #[test]
    fn settings_are_checked_whole_and_applied_to_the_host() {
        for (v, field) in [
            (json!({"r11": 1e-3, "ir_sigma": 0.01}), "ir_sigma"),
            (json!({"r11": 1e-3, "q22": "1e999"}), "q22"),
            (json!({"gate": 1.5}), "gate"),
            (json!({"use_ir": "maybe"}), "use_ir"),
            (json!({"q11": null}), "q11"),
        ] {
            assert_eq!(
                robot_settings(&values(v.clone())).unwrap_err().field,
                field,
                "{v}"
            );
        }
        let mut h = host();
        let before = *h.config();
        let s = robot_settings(&values(
            json!({"r22": "4e-4", "gate": 0, "use_ir": false, "k_pos": 2}),
        ))
        .unwrap();
        s.apply(&mut h).unwrap();
        let c = h.config();
        assert_eq!(c.localiser.r22, 4e-4);
        assert_eq!(
            c.localiser.r11, before.localiser.r11,
            "fields not given are kept"
        );
        assert_eq!(c.localiser.gate_confidence, None, "gate 0: no gate");
        assert!(!c.use_ir);
        assert_eq!(c.control.k_pos, 2.0);
        assert_eq!(c.control.v_ref, before.control.v_ref);
    }

    /// An unknown key is refused when the message is read, naming it: the
    /// host thread never sees it.
    #[test]
    fn an_unknown_key_is_refused_naming_it() {
        for key in ["start_x", "q12", "speed"] {
            let text = json!({"type": "params", "values": {"r11": 1e-3, key: 1}});
            let e = serde_json::from_value::<ClientMsg>(text).unwrap_err();
            assert!(
                e.to_string().contains(&format!("unknown field `{key}`")),
                "{key}: {e}"
            );
        }
    }

    #[test]
    fn what_a_live_robot_cannot_do_is_refused_by_name() {
        for kind in UNAVAILABLE {
            let text = match kind {
                "speed" => json!({"type": kind, "factor": 2}),
                "scenario" => json!({"type": kind, "name": "square"}),
                "preset" => json!({"type": kind, "step": "a"}),
                "initial" => json!({"type": kind, "values": {}}),
                _ => json!({"type": kind}),
            };
            let msg: ClientMsg = serde_json::from_value(text).unwrap();
            let e = command(msg).unwrap_err();
            assert_eq!(e.field, kind);
            assert!(e.reason.contains("not available when attached to a robot"));
        }
        let msg: ClientMsg =
            serde_json::from_value(json!({"type": "teleop", "v": 0.1, "w": -1})).unwrap();
        assert_eq!(command(msg), Ok(Command::Teleop { v: 0.1, w: -1.0 }));
    }
}
