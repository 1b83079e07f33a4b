//! Headless Chromium for the end-to-end tests (Debian's `chromium` and
//! `chromium-driver` over WebDriver with fantoccini): the driver, a browser
//! session, and the page helpers. A missing browser or driver fails the
//! test with the command that installs them. Paths: `LOCUS_CHROMEDRIVER`
//! (default `/usr/bin/chromedriver`) and `LOCUS_CHROMIUM` (default
//! `/usr/bin/chromium`). With `LOCUS_SCREENSHOTS=DIR`, [`screenshot`]
//! writes PNGs into DIR (relative to the workspace root).
#![allow(dead_code, clippy::std_instead_of_core, clippy::std_instead_of_alloc)]

use std::os::unix::process::CommandExt as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use fantoccini::{Client, ClientBuilder, Locator};
use serde_json::{Value, json};

/// One browser at a time: the tests of this file hold it while they run.
pub static ONE_BROWSER: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

/// chromedriver, killed when dropped.
pub struct Driver {
    child: Child,
    url: String,
}

impl Drop for Driver {
    /// Ends chromedriver and the browser it started, also when the test
    /// failed before closing the session: both are in the process group
    /// chromedriver leads (its own, see `start_driver`).
    fn drop(&mut self) {
        let _ = Command::new("kill")
            .args(["-KILL", "--", &format!("-{}", self.child.id())])
            .status();
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

pub const INSTALL: &str = "install Debian's chromium and chromium-driver \
    (`apt-get install -y chromium chromium-driver`; scripts/test.sh does it)";

pub fn binary(var: &str, default: &str) -> PathBuf {
    let p = PathBuf::from(std::env::var(var).unwrap_or_else(|_| default.to_string()));
    assert!(
        p.is_file(),
        "end-to-end test: {} not found (set {var} to another path, or {INSTALL})",
        p.display()
    );
    p
}

/// Starts chromedriver on a free loopback port and waits for it.
pub fn start_driver() -> Driver {
    let driver = binary("LOCUS_CHROMEDRIVER", "/usr/bin/chromedriver");
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    let child = Command::new(&driver)
        .arg(format!("--port={port}"))
        .process_group(0)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("starting {}: {e} ({INSTALL})", driver.display()));
    let started = Instant::now();
    while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "chromedriver did not listen on port {port} within 20 s"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    Driver {
        child,
        url: format!("http://127.0.0.1:{port}"),
    }
}

pub async fn browser(driver: &Driver, downloads: &Path) -> Client {
    let chromium = binary("LOCUS_CHROMIUM", "/usr/bin/chromium");
    let caps = json!({
        "goog:chromeOptions": {
            "binary": chromium,
            "args": ["--headless=new", "--no-sandbox", "--disable-gpu",
                     "--disable-dev-shm-usage", "--window-size=1720,1160",
                     "--hide-scrollbars"],
            "prefs": {
                "download.default_directory": downloads,
                "download.prompt_for_download": false,
            },
        }
    });
    let Value::Object(caps) = caps else {
        unreachable!()
    };
    ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
        .capabilities(caps)
        .connect(&driver.url)
        .await
        .unwrap_or_else(|e| panic!("starting headless chromium through chromedriver: {e}"))
}

/// `return (expr);` evaluated in the page.
pub async fn js(c: &Client, expr: &str) -> Value {
    c.execute(&format!("return ({expr});"), vec![])
        .await
        .unwrap_or_else(|e| panic!("evaluating {expr}: {e}"))
}

pub async fn num(c: &Client, expr: &str) -> f64 {
    js(c, expr)
        .await
        .as_f64()
        .unwrap_or_else(|| panic!("{expr} is not a number"))
}

/// Waits until `expr` is true in the page.
pub async fn wait_for(c: &Client, expr: &str, timeout: Duration) {
    let start = Instant::now();
    loop {
        if js(c, expr).await == Value::Bool(true) {
            return;
        }
        assert!(
            start.elapsed() < timeout,
            "timed out after {timeout:?} waiting for {expr}; page state: {}",
            js(c, "JSON.stringify({frames: locus.frames, samples: locus.samples, errors: locus.errors, status: document.getElementById('status').textContent})").await
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// The text of element `id` now (read in the page: an element redrawn
/// every frame would be stale by the time WebDriver reads it).
pub async fn text_of(c: &Client, id: &str) -> String {
    js(c, &format!("document.getElementById('{id}').textContent"))
        .await
        .as_str()
        .unwrap_or_else(|| panic!("#{id} has no text"))
        .to_string()
}

pub async fn click(c: &Client, id: &str) {
    c.find(Locator::Id(id))
        .await
        .unwrap_or_else(|e| panic!("#{id}: {e}"))
        .click()
        .await
        .unwrap_or_else(|e| panic!("clicking #{id}: {e}"));
}

pub async fn set_input(c: &Client, id: &str, text: &str) {
    // Select all and type over it, as a user does (`clear()` would fire a
    // change event with an empty value).
    let el = c.find(Locator::Id(id)).await.expect(id);
    el.click().await.expect("focus");
    el.send_keys("\u{e009}a\u{e009}").await.expect("select all");
    el.send_keys(text).await.expect("type");
}

pub async fn screenshot(c: &Client, name: &str) {
    let Ok(dir) = std::env::var("LOCUS_SCREENSHOTS") else {
        return;
    };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(dir);
    std::fs::create_dir_all(&dir).expect("screenshot dir");
    let png = c.screenshot().await.expect("screenshot");
    std::fs::write(dir.join(name), png).expect("write screenshot");
}
