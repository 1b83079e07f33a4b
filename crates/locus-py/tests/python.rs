//! The Python package's tests (pytest, `python/tests`) against the
//! extension module this build made: the module (`deps/lib_locus.so`, built by
//! cargo beside this test with the workspace's features and profile, so
//! nothing is compiled twice) and the package's Python sources are staged
//! as an importable `locus` package, and pytest runs each test file.
//! The interpreter is `$LOCUS_PYTHON`, else `python3`, with the packages of
//! `python/requirements-test.txt` (scripts/test.sh installs them).
//! `pip install ./python` builds the same package with maturin.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The repository's root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `target/<profile>`: this test is `target/<profile>/deps/python-<hash>`.
fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's path");
    exe.parent()
        .and_then(Path::parent)
        .expect("target/<profile>")
        .to_path_buf()
}

/// The staged package's directory (on `PYTHONPATH`), staged once.
fn staged() -> &'static Path {
    static STAGED: OnceLock<PathBuf> = OnceLock::new();
    STAGED.get_or_init(|| {
        let profile_dir = profile_dir();
        // A cdylib's file name carries no hash: the last build of the
        // module, in any profile, is here (`cargo build` of the crate in
        // another profile replaces it).
        let module = profile_dir.join("deps/lib_locus.so");
        assert!(
            module.is_file(),
            "{} is missing: cargo builds it with this test",
            module.display()
        );
        let stage = profile_dir.join("python-stage");
        let package = stage.join("locus");
        let _ = std::fs::remove_dir_all(&stage);
        std::fs::create_dir_all(&package).expect("creating the stage");
        for entry in std::fs::read_dir(root().join("python/locus")).expect("python/locus") {
            let entry = entry.expect("an entry of python/locus");
            if entry.file_type().expect("its type").is_file() {
                std::fs::copy(entry.path(), package.join(entry.file_name()))
                    .expect("staging a source");
            }
        }
        std::fs::copy(&module, package.join("_locus.abi3.so")).expect("staging the module");
        stage
    })
}

/// Runs pytest on `python/tests/<file>`; fails with pytest's output.
fn pytest(file: &str) {
    let python = std::env::var("LOCUS_PYTHON").unwrap_or_else(|_| "python3".to_string());
    let out = Command::new(&python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(root().join("python/tests").join(file))
        .env("PYTHONPATH", staged())
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .env("LOCUS_BIN", profile_dir().join("locus"))
        .current_dir(root())
        .output()
        .expect("running pytest");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    println!("{text}");
    assert!(out.status.success(), "pytest {file} failed:\n{text}");
}

#[test]
fn replay() {
    pytest("test_replay.py");
}

#[test]
fn filter() {
    pytest("test_filter.py");
}

#[test]
fn doa_cluster() {
    pytest("test_doa_cluster.py");
}

#[test]
fn notebooks() {
    pytest("test_notebooks.py");
}

#[test]
fn interrupt() {
    pytest("test_interrupt.py");
}
