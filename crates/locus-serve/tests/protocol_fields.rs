//! Issue 20 (hostile input): docs/ui.md says unknown fields are refused,
//! but the messages without fields (`start`, `stop`, `export`, ...)
//! accepted any extra field. Every message type must refuse them.

use locus_serve::protocol::ClientMsg;

#[test]
fn unknown_fields_are_refused_on_every_message_type() {
    for kind in [
        "start",
        "stop",
        "reset",
        "step",
        "step_correction",
        "teleop_off",
        "export",
    ] {
        let plain = format!(r#"{{"type":"{kind}"}}"#);
        assert!(
            serde_json::from_str::<ClientMsg>(&plain).is_ok(),
            "{plain} must be accepted"
        );
        let extra = format!(r#"{{"type":"{kind}","bogus":1}}"#);
        let err = serde_json::from_str::<ClientMsg>(&extra)
            .expect_err(&format!("{extra} must be refused"));
        assert!(err.to_string().contains("bogus"), "{kind}: {err}");
    }
    for extra in [
        r#"{"type":"speed","factor":2,"bogus":1}"#,
        r#"{"type":"scenario","name":"square","bogus":1}"#,
    ] {
        assert!(serde_json::from_str::<ClientMsg>(extra).is_err(), "{extra}");
    }
}
