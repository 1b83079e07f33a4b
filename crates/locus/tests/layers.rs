//! Dependencies point down: every workspace crate's normal dependencies on
//! other workspace crates, from `cargo metadata`, against ARCHITECTURE.md's
//! layer list (a crate may depend on lower layers only) and its dependency
//! arrows (which must be exactly the real ones). Both are read from the
//! document, so it and the workspace cannot drift apart.

extern crate alloc;

use alloc::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// The repository's root (two levels above this crate).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The lines of the fenced block of ARCHITECTURE.md opened by
/// "```" followed by `tag`.
fn block(doc: &str, tag: &str) -> Vec<String> {
    let open = format!("```{tag}");
    let mut lines = doc.lines().skip_while(|l| l.trim() != open);
    assert!(
        lines.next().is_some(),
        "ARCHITECTURE.md has no ```{tag} block"
    );
    lines
        .take_while(|l| l.trim() != "```")
        .map(str::to_string)
        .collect()
}

/// `a, b, c` as names (`(none)`: none).
fn names(list: &str) -> BTreeSet<String> {
    let list = list.trim();
    if list == "(none)" {
        return BTreeSet::new();
    }
    list.split(',').map(|n| n.trim().to_string()).collect()
}

/// The layer list: each crate's layer number (1: lowest).
///
/// # Panics
/// On a malformed line or a crate listed twice.
fn parse_layers(lines: &[String]) -> BTreeMap<String, usize> {
    let mut layer = BTreeMap::new();
    for (i, line) in lines.iter().enumerate() {
        let (n, crates) = line
            .split_once('.')
            .unwrap_or_else(|| panic!("layer line {line:?} is not `N. crate, crate`"));
        let n: usize = n.trim().parse().expect("layer number");
        assert_eq!(n, i + 1, "layers are numbered 1, 2, ... in order");
        for c in names(crates) {
            assert!(layer.insert(c.clone(), n).is_none(), "{c} is listed twice");
        }
    }
    layer
}

/// The arrows: each crate's workspace dependencies as documented.
fn parse_arrows(lines: &[String]) -> BTreeMap<String, BTreeSet<String>> {
    lines
        .iter()
        .map(|line| {
            let (name, deps) = line
                .split_once("->")
                .unwrap_or_else(|| panic!("arrow line {line:?} is not `crate -> crate, crate`"));
            (name.trim().to_string(), names(deps))
        })
        .collect()
}

/// Each workspace crate's normal (not dev, not build) dependencies on
/// workspace crates, from `cargo metadata`.
fn workspace_deps() -> BTreeMap<String, BTreeSet<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(root())
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: Value = serde_json::from_slice(&out.stdout).expect("cargo metadata's JSON");
    let packages = meta["packages"].as_array().expect("packages");
    let members: BTreeSet<String> = packages
        .iter()
        .map(|p| p["name"].as_str().expect("name").to_string())
        .collect();
    packages
        .iter()
        .map(|p| {
            let deps = p["dependencies"]
                .as_array()
                .expect("dependencies")
                .iter()
                .filter(|d| d["kind"].is_null())
                .filter_map(|d| d["name"].as_str())
                .filter(|n| members.contains(*n))
                .map(str::to_string)
                .collect();
            (p["name"].as_str().expect("name").to_string(), deps)
        })
        .collect()
}

/// The layer rule over `deps`: every breach, as `crate (layer) -> dep
/// (layer)`, and every crate missing from the list.
fn breaches(
    layer: &BTreeMap<String, usize>,
    deps: &BTreeMap<String, BTreeSet<String>>,
) -> Vec<String> {
    let mut out = Vec::new();
    for (krate, ds) in deps {
        let Some(&l) = layer.get(krate) else {
            out.push(format!("{krate} is in no layer of ARCHITECTURE.md"));
            continue;
        };
        for d in ds {
            match layer.get(d) {
                Some(&ld) if ld < l => {}
                Some(&ld) => out.push(format!(
                    "{krate} (layer {l}) depends on {d} (layer {ld}): not below it"
                )),
                None => out.push(format!("{d} is in no layer of ARCHITECTURE.md")),
            }
        }
    }
    out
}

fn architecture() -> String {
    std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md")
}

#[test]
fn dependencies_point_down_the_layer_list() {
    let doc = architecture();
    let layer = parse_layers(&block(&doc, "layers"));
    let deps = workspace_deps();
    let bad = breaches(&layer, &deps);
    assert!(bad.is_empty(), "layering broken:\n{}", bad.join("\n"));
    for krate in layer.keys() {
        assert!(
            deps.contains_key(krate),
            "ARCHITECTURE.md's layer list names {krate}, which is not a workspace crate"
        );
    }
}

#[test]
fn the_documented_arrows_are_the_real_dependencies() {
    let arrows = parse_arrows(&block(&architecture(), "arrows"));
    let deps = workspace_deps();
    assert_eq!(
        arrows.keys().collect::<Vec<_>>(),
        deps.keys().collect::<Vec<_>>(),
        "ARCHITECTURE.md's arrows name every workspace crate once"
    );
    for (krate, real) in &deps {
        assert_eq!(
            &arrows[krate], real,
            "ARCHITECTURE.md's arrow of {krate} (left) is not its real dependencies (right)"
        );
    }
}

/// The rule itself: the simulator depending on the host (its layer-mate)
/// or on a crate above it, and a crate outside the list, are breaches.
#[test]
fn a_dependency_sideways_or_up_is_a_breach() {
    let layer = parse_layers(&block(&architecture(), "layers"));
    let mut deps = workspace_deps();
    assert!(breaches(&layer, &deps).is_empty());
    let sim = deps.get_mut("locus-sim").expect("locus-sim");
    sim.insert("locus-net".to_string());
    sim.insert("locus-serve".to_string());
    let bad = breaches(&layer, &deps);
    assert_eq!(bad.len(), 2, "{bad:?}");
    assert!(bad[0].starts_with("locus-sim (layer 4) depends on locus-net (layer 4)"));
    deps.insert("locus-new".to_string(), BTreeSet::new());
    assert!(
        breaches(&layer, &deps)
            .contains(&"locus-new is in no layer of ARCHITECTURE.md".to_string())
    );
}
