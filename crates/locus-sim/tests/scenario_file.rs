//! Scenario files: the committed examples load, overrides apply, and bad
//! files are reported with file, line, column and field.

use std::path::{Path, PathBuf};

use locus_sim::closed_loop::{NoiseModel, SquareConfig};
use locus_sim::scenario_file::{FileError, Scenario, ScenarioConfig, load, parse};

fn scenarios_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

#[test]
fn the_committed_examples_load_as_their_built_ins() {
    for name in ["square", "square-ideal"] {
        let path = scenarios_dir().join(format!("{name}.toml"));
        let cfg = load(&path).unwrap_or_else(|e| panic!("{e}"));
        let builtin: Scenario = name.parse().expect("built-in");
        assert_eq!(cfg, builtin.config(), "{name}");
    }
    // Every .toml under scenarios/ loads.
    let mut files = 0;
    for entry in std::fs::read_dir(scenarios_dir()).expect("scenarios/") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            load(&path).unwrap_or_else(|e| panic!("{e}"));
            files += 1;
        }
    }
    assert!(files >= 2, "{files} files");
}

#[test]
fn every_scenario_name_round_trips() {
    for s in Scenario::ALL {
        assert_eq!(s.to_string().parse::<Scenario>(), Ok(s), "{s}");
    }
    let names: Vec<String> = Scenario::ALL.iter().map(ToString::to_string).collect();
    assert_eq!(
        names,
        ["square", "square-ideal", "wall45", "tricycle-slip", "hover"]
    );
    let e = "circle".parse::<Scenario>().unwrap_err();
    assert_eq!(
        e.to_string(),
        "unknown scenario `circle`; supported scenarios: square, square-ideal, wall45, tricycle-slip, hover"
    );
    // Each name gives its own kind of configuration.
    for (s, kind) in
        Scenario::ALL
            .into_iter()
            .zip(["square", "square", "wall45", "tricycle-slip", "hover"])
    {
        assert_eq!(s.config().kind(), kind, "{s}");
    }
}

#[test]
fn printed_configurations_load_back() {
    for name in ["square", "square-ideal"] {
        let cfg = name.parse::<Scenario>().expect("built-in").config();
        let text = cfg.to_toml(name).expect("toml");
        assert_eq!(parse(&text, Path::new("x.toml")).expect("parse"), cfg);
    }
}

#[test]
fn keys_override_the_kinds_defaults_and_the_rest_stays() {
    let text = "scenario = \"square-ideal\"\nlaps = 1\nq22 = 4e-6\n[control]\nv_ref = 0.15\n";
    let ScenarioConfig::Square(cfg) = parse(text, Path::new("a.toml")).expect("parse") else {
        panic!("not a square scenario");
    };
    let ideal = SquareConfig::ideal();
    assert_eq!(cfg.laps, 1);
    assert_eq!(cfg.q22, 4e-6);
    assert_eq!(cfg.control.v_ref, 0.15);
    assert_eq!(cfg.control.w_ref, ideal.control.w_ref);
    assert_eq!(cfg.noise, NoiseModel::Ideal);
    assert_eq!(cfg.gate_confidence, None);
    assert_eq!(cfg.q11, ideal.q11);
    let text = "scenario = \"square\"\ngate_confidence = \"none\"\nencoder_gear = 2\n";
    let ScenarioConfig::Square(cfg) = parse(text, Path::new("b.toml")).expect("parse") else {
        panic!("not a square scenario");
    };
    assert_eq!(cfg.gate_confidence, None);
    assert_eq!(cfg.encoder_gear, 2.0);
    assert_eq!(cfg.noise, NoiseModel::Realistic);
}

/// `(line, column, field)` of a bad file's error, and its message.
fn bad(text: &str) -> (usize, usize, Option<String>, String) {
    let e = parse(text, Path::new("scenarios/bad.toml")).unwrap_err();
    let msg = e.to_string();
    match e {
        FileError::Invalid {
            line,
            column,
            field,
            ..
        } => (line, column, field, msg),
        e => panic!("not an Invalid error: {e}"),
    }
}

#[test]
fn bad_files_name_the_line_column_and_field() {
    // Unknown key.
    let (line, col, field, msg) = bad("scenario = \"square\"\nlaps = 1\nlapz = 2\n");
    assert_eq!((line, col, field.as_deref()), (3, 1, Some("lapz")), "{msg}");
    assert!(
        msg.starts_with("scenarios/bad.toml, line 3, column 1"),
        "{msg}"
    );
    assert!(msg.contains("unknown field"), "{msg}");
    // Wrong type.
    let (line, col, field, msg) = bad("scenario = \"square\"\n\ndt = \"fast\"\n");
    assert_eq!((line, col, field.as_deref()), (3, 6, Some("dt")), "{msg}");
    // Out of range (validate), nested key.
    let (line, col, field, msg) = bad("scenario = \"square\"\n[control]\n  v_ref = -0.1\n");
    assert_eq!(
        (line, col, field.as_deref()),
        (3, 3, Some("control.v_ref")),
        "{msg}"
    );
    assert!(msg.contains("must be in [1e-2, 5e-1] m/s"), "{msg}");
    // The shared limits (locus_models::settings): an IR noise the UI
    // refuses is refused here too.
    let (line, _, field, msg) = bad("scenario = \"square\"\nir_sigma = 0.2\n");
    assert_eq!((line, field.as_deref()), (2, Some("ir_sigma")), "{msg}");
    assert!(msg.contains("must be in [0e0, 1e-1] m"), "{msg}");
    let (line, _, field, msg) = bad("scenario = \"square\"\nq11 = 0.0\n");
    assert_eq!((line, field.as_deref()), (2, Some("q11")), "{msg}");
    // Unknown nested key.
    let (line, _, field, msg) = bad("scenario = \"square\"\n[control]\nv_rev = 1.0\n");
    assert_eq!(
        (line, field.as_deref()),
        (3, Some("control.v_rev")),
        "{msg}"
    );
    // Unknown or missing kind; TOML syntax.
    let (line, col, field, msg) = bad("laps = 1\nscenario = \"circle\"\n");
    assert_eq!(
        (line, col, field.as_deref()),
        (2, 12, Some("scenario")),
        "{msg}"
    );
    assert!(msg.contains("square-ideal"), "{msg}");
    let (_, _, field, _) = bad("laps = 1\n");
    assert_eq!(field.as_deref(), Some("scenario"));
    let (line, _, _, msg) = bad("scenario = \"square\"\nlaps = = 1\n");
    assert_eq!(line, 2, "{msg}");
}

#[test]
fn a_missing_file_names_it() {
    let err = load(Path::new("no/such/file.toml")).unwrap_err();
    assert!(err.to_string().contains("no/such/file.toml"), "{err}");
    assert!(core::error::Error::source(&err).is_some(), "{err}");
}
