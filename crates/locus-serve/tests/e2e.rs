//! End-to-end tests of the teaching UI in real headless Chromium (Debian's
//! `chromium` and `chromium-driver`, driven over WebDriver with
//! fantoccini). The server runs in-process on 127.0.0.1:0.
//!
//! A missing browser or driver FAILS the test with the command that
//! installs them (`scripts/test.sh` installs them first). Paths:
//! `LOCUS_CHROMEDRIVER` (default `/usr/bin/chromedriver`) and
//! `LOCUS_CHROMIUM` (default `/usr/bin/chromium`).
//!
//! `page_attached_to_a_robot_in_headless_chromium` attaches the page to a
//! simulated robot (`locus_sim::link_robot::run_robot`) over loopback UDP
//! (`locus serve --robot`). The two tests take turns with the browser
//! ([`ONE_BROWSER`]): two Chromiums at once are too much for a small
//! machine.
//!
//! With `LOCUS_SCREENSHOTS=DIR` the test also writes docs/serve.md's
//! screenshots into DIR (e.g. `LOCUS_SCREENSHOTS=docs/img`, relative to
//! the workspace root).
#![allow(
    clippy::std_instead_of_core,
    clippy::std_instead_of_alloc,
    clippy::too_many_lines
)]

mod support;

use std::os::unix::process::CommandExt as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use fantoccini::actions::{InputSource, KeyAction, KeyActions};
use fantoccini::{Client, ClientBuilder, Locator};
use serde_json::{Value, json};

/// One browser at a time: the tests of this file hold it while they run.
static ONE_BROWSER: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

/// chromedriver, killed when dropped.
struct Driver {
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

const INSTALL: &str = "install Debian's chromium and chromium-driver \
    (`apt-get install -y chromium chromium-driver`; scripts/test.sh does it)";

fn binary(var: &str, default: &str) -> PathBuf {
    let p = PathBuf::from(std::env::var(var).unwrap_or_else(|_| default.to_string()));
    assert!(
        p.is_file(),
        "end-to-end test: {} not found (set {var} to another path, or {INSTALL})",
        p.display()
    );
    p
}

/// Starts chromedriver on a free loopback port and waits for it.
fn start_driver() -> Driver {
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

async fn browser(driver: &Driver, downloads: &Path) -> Client {
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
async fn js(c: &Client, expr: &str) -> Value {
    c.execute(&format!("return ({expr});"), vec![])
        .await
        .unwrap_or_else(|e| panic!("evaluating {expr}: {e}"))
}

async fn num(c: &Client, expr: &str) -> f64 {
    js(c, expr)
        .await
        .as_f64()
        .unwrap_or_else(|| panic!("{expr} is not a number"))
}

/// Waits until `expr` is true in the page.
async fn wait_for(c: &Client, expr: &str, timeout: Duration) {
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
async fn text_of(c: &Client, id: &str) -> String {
    js(c, &format!("document.getElementById('{id}').textContent"))
        .await
        .as_str()
        .unwrap_or_else(|| panic!("#{id} has no text"))
        .to_string()
}

async fn click(c: &Client, id: &str) {
    c.find(Locator::Id(id))
        .await
        .unwrap_or_else(|e| panic!("#{id}: {e}"))
        .click()
        .await
        .unwrap_or_else(|e| panic!("clicking #{id}: {e}"));
}

async fn set_input(c: &Client, id: &str, text: &str) {
    // Select all and type over it, as a user does (`clear()` would fire a
    // change event with an empty value).
    let el = c.find(Locator::Id(id)).await.expect(id);
    el.click().await.expect("focus");
    el.send_keys("\u{e009}a\u{e009}").await.expect("select all");
    el.send_keys(text).await.expect("type");
}

async fn screenshot(c: &Client, name: &str) {
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

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn teaching_ui_in_headless_chromium() {
    let _browser = ONE_BROWSER.lock().await;
    let driver = start_driver();
    let downloads = std::env::temp_dir().join(format!("locus-e2e-{}", std::process::id()));
    std::fs::create_dir_all(&downloads).expect("download dir");
    // Twenty laps (about 1400 s simulated), so the run is still going at
    // the end of the test whatever the speed factors and the machine's load.
    let scenario = locus_sim::SquareConfig {
        laps: 20,
        max_time: 3000.0,
        ..locus_sim::SquareConfig::default()
    };
    let config = locus_serve::Config::new("square", scenario).expect("config");
    let addr = support::start_server(config).await;
    let c = browser(&driver, &downloads).await;
    let long = Duration::from_secs(30);

    // Load the page: connected, the square scenario.
    c.goto(&format!("http://{addr}/"))
        .await
        .expect("load the page");
    wait_for(
        &c,
        "locus.connected && locus.hello !== null && locus.params !== null",
        long,
    )
    .await;
    assert_eq!(js(&c, "locus.hello.scenario").await, json!("square"));
    assert_eq!(
        js(&c, "typeof uPlot").await,
        json!("function"),
        "uPlot loaded from the embedded asset"
    );

    // Start square at 5x: the plots fill, the ellipse is drawn and changes.
    set_input(&c, "speed", "5").await;
    c.find(Locator::Id("speed"))
        .await
        .unwrap()
        .send_keys("\u{e007}")
        .await
        .unwrap();
    wait_for(&c, "locus.params.values.speed === 5", long).await;
    click(&c, "start").await;
    wait_for(&c, "locus.samples > 300 && locus.ellipse !== null", long).await;
    let points1 = num(&c, "locus.charts['chart-p'].data[0].length").await;
    let e1 = js(&c, "locus.ellipse").await;
    assert!(e1["rx_px"].as_f64().unwrap() > 0.5, "ellipse drawn: {e1}");
    assert!((e1["p"].as_f64().unwrap() - 0.95).abs() < 1e-9);
    assert!(
        (e1["k"].as_f64().unwrap() - 2.4477).abs() < 1e-3,
        "95 % is k = 2.45 sigma: {e1}"
    );
    tokio::time::sleep(Duration::from_secs(2)).await;
    let points2 = num(&c, "locus.charts['chart-p'].data[0].length").await;
    let e2 = js(&c, "locus.ellipse").await;
    assert!(
        points2 > points1 + 100.0,
        "plots update: {points1} -> {points2}"
    );
    assert_ne!(
        e1["rx_m"], e2["rx_m"],
        "the ellipse changes as the run goes"
    );
    for chart in ["chart-innov", "chart-nis", "chart-wheels", "chart-ir"] {
        let n = num(&c, &format!("locus.charts['{chart}'].data[0].length")).await;
        assert!(n > 100.0, "{chart} has {n} points");
    }
    // Some corrections happened, with a finite NIS.
    wait_for(
        &c,
        "locus.charts['chart-nis'].data[1].filter(x => x !== null).length > 50",
        long,
    )
    .await;
    screenshot(&c, "ui-running.png").await;

    // Change R from the panel: R = 1e-2 m^2 (10 cm) against 5 mm of real
    // noise: the NIS of the corrections after the change collapses (S is
    // dominated by R, the gain vanishes).
    let mean_nis = |after: f64| {
        format!(
            "(() => {{ const v = locus.nisLog.filter(e => e.t > {after}).map(e => e.nis).slice(-100); \
             return v.length >= 30 ? v.reduce((a, b) => a + b, 0) / v.length : -1; }})()"
        )
    };
    let nis_before = num(&c, &mean_nis(0.0)).await;
    assert!(nis_before > 0.0, "corrections before the change");
    set_input(&c, "p-r11", "1e-2").await;
    set_input(&c, "p-r22", "1e-2").await;
    click(&c, "apply-params").await;
    wait_for(
        &c,
        "locus.params.values.r11 === 0.01 && locus.params.values.r22 === 0.01",
        long,
    )
    .await;
    let changed_at = num(&c, "locus.state.time").await + 0.1;
    assert_eq!(
        js(&c, "document.getElementById('inuse-r11').textContent").await,
        json!("in use: 0.01")
    );
    wait_for(
        &c,
        &format!("{} > 0", mean_nis(changed_at)),
        Duration::from_secs(60),
    )
    .await;
    let nis_after = num(&c, &mean_nis(changed_at)).await;
    assert!(
        nis_before > 10.0 * nis_after,
        "mean NIS with R = 25e-6: {nis_before}, with R = 1e-2: {nis_after}"
    );

    // Invalid value: a visible error, the run keeps its last good values.
    set_input(&c, "p-r11", "abc").await;
    click(&c, "apply-params").await;
    wait_for(&c, "!document.getElementById('err-r11').hidden", long).await;
    let err = c.find(Locator::Id("err-r11")).await.unwrap();
    assert!(err.is_displayed().await.unwrap());
    let text = err.text().await.unwrap();
    assert!(text.contains("must be a number"), "error text: {text}");
    assert!(
        c.find(Locator::Id("errors"))
            .await
            .unwrap()
            .is_displayed()
            .await
            .unwrap()
    );
    assert_eq!(
        js(&c, "locus.params.values.r11").await,
        json!(0.01),
        "last good value kept"
    );
    let steps = num(&c, "locus.state.steps").await;
    wait_for(&c, &format!("locus.state.steps > {steps} + 50"), long).await;
    screenshot(&c, "ui-error.png").await;

    // Keyboard teleoperation: hold the left arrow 1.5 s (speed 1: about 1.5
    // rad of turn in place), with the arena focused.
    set_input(&c, "p-r11", "2.5e-5").await;
    click(&c, "apply-params").await;
    set_input(&c, "speed", "1").await;
    c.find(Locator::Id("speed"))
        .await
        .unwrap()
        .send_keys("\u{e007}")
        .await
        .unwrap();
    wait_for(
        &c,
        "locus.params.values.speed === 1 && locus.params.values.r11 === 2.5e-5",
        long,
    )
    .await;
    click(&c, "arena").await;
    assert_eq!(
        js(&c, "locus.state.running").await,
        json!(true),
        "still running"
    );
    let theta0 = num(&c, "locus.lastSample.truth[2]").await;
    let teleop0 = num(&c, "locus.teleopFrames").await;
    let keys = KeyActions::new("keyboard".to_string())
        .then(KeyAction::Down { value: '\u{e012}' })
        .then(KeyAction::Pause {
            duration: Duration::from_millis(1500),
        })
        .then(KeyAction::Up { value: '\u{e012}' });
    c.perform_actions(keys).await.expect("arrow key");
    let theta1 = num(&c, "locus.lastSample.truth[2]").await;
    let teleop1 = num(&c, "locus.teleopFrames").await;
    assert!(
        teleop1 > teleop0 + 10.0,
        "frames while driving: {teleop0} -> {teleop1}"
    );
    let turned = (theta1 - theta0 + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
        - std::f64::consts::PI;
    assert!(turned > 0.5, "left arrow turns left: {turned} rad");
    wait_for(&c, "locus.state.teleop === false", long).await;

    // Step-through of one correction: prediction, H, S, K, innovation, gate.
    click(&c, "step-correction").await;
    wait_for(
        &c,
        "locus.state.running === false && locus.lastCorrection !== null",
        long,
    )
    .await;
    let detail = c
        .find(Locator::Id("detail"))
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    for part in [
        "prediction",
        "H = ",
        "S = ",
        "K = ",
        "innovation",
        "gate",
        "ACCEPTED",
    ] {
        assert!(detail.contains(part), "step-through shows {part}: {detail}");
    }

    // Export the CSV and parse it.
    let steps = num(&c, "locus.state.steps").await;
    click(&c, "export").await;
    wait_for(&c, "locus.lastCsv !== null", long).await;
    let name = js(&c, "locus.lastCsv.filename").await;
    let file = downloads.join(name.as_str().unwrap());
    let start = Instant::now();
    while !file.is_file() || std::fs::metadata(&file).map(|m| m.len()).unwrap_or(0) == 0 {
        assert!(
            start.elapsed() < long,
            "download {} did not appear",
            file.display()
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    tokio::time::sleep(Duration::from_millis(300)).await;
    let csv = std::fs::read_to_string(&file).expect("read the export");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header, locus_sim::StepRecord::CSV_COLUMNS);
    let mut last_time = 0.0;
    let mut rows = 0.0;
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), header.len(), "row {line}");
        let t: f64 = f[1].parse().expect("time");
        assert!(t > last_time, "time increases: {t} after {last_time}");
        last_time = t;
        for v in [f[2], f[5], f[8]] {
            assert!(v.parse::<f64>().expect("number").is_finite());
        }
        rows += 1.0;
    }
    // One row per step run, up to the session's log bound (a slow,
    // loaded machine lets the run pass it before the export): then the
    // export says it was cut, which the page shows as a second error.
    #[allow(clippy::cast_precision_loss)]
    let bound = locus_serve::session::MAX_LOG_STEPS as f64;
    let truncated = steps > bound;
    assert_eq!(
        rows,
        steps.min(bound),
        "one row per step run, up to the bound"
    );
    assert_eq!(
        js(&c, "locus.lastCsv.truncated").await,
        json!(truncated),
        "the export says whether it was cut"
    );
    assert_eq!(
        js(&c, "locus.errors.length").await,
        json!(1 + usize::from(truncated)),
        "only the error we provoked (and the cut export's): {}",
        js(&c, "JSON.stringify(locus.errors)").await
    );

    // Guide preset f: the criterion beside the live figure.
    click(&c, "preset-f").await;
    wait_for(
        &c,
        "locus.params.preset === 'f' && locus.state.steps === 0",
        long,
    )
    .await;
    set_input(&c, "speed", "10").await;
    c.find(Locator::Id("speed"))
        .await
        .unwrap()
        .send_keys("\u{e007}")
        .await
        .unwrap();
    click(&c, "start").await;
    wait_for(&c, "locus.state.steps > 2500", long).await;
    let figure = c
        .find(Locator::Id("figure"))
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    assert!(
        figure.contains("criterion: RMSE below c's, d's and e's"),
        "{figure}"
    );
    assert!(figure.contains("live: RMSE"), "{figure}");
    click(&c, "step-correction").await;
    wait_for(&c, "locus.state.running === false", long).await;
    screenshot(&c, "ui-guide-step.png").await;
    js(
        &c,
        "(document.getElementById('detail').scrollIntoView(), true)",
    )
    .await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    screenshot(&c, "ui-correction.png").await;

    c.close().await.expect("close the browser");
    let _ = std::fs::remove_dir_all(&downloads);
}

/// Robot seconds per wall second for the attached page: quick, and a held
/// arrow key of 0.6 s turns the robot about 1.8 rad (less than pi, so the
/// turn is read unambiguously from two headings).
const ROBOT_TIME_SCALE: f64 = 3.0;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn page_attached_to_a_robot_in_headless_chromium() {
    let _browser = ONE_BROWSER.lock().await;
    let driver = start_driver();
    let downloads = std::env::temp_dir().join(format!("locus-e2e-robot-{}", std::process::id()));
    std::fs::create_dir_all(&downloads).expect("download dir");
    let robot = support::spawn_robot(ROBOT_TIME_SCALE);
    let addr = support::start_robot_server(robot).await;
    let c = browser(&driver, &downloads).await;
    let long = Duration::from_secs(30);

    // Attached: the link named, no ground truth said, the simulation's
    // controls off.
    c.goto(&format!("http://{addr}/"))
        .await
        .expect("load the page");
    wait_for(
        &c,
        "locus.connected && locus.robot !== null && locus.params !== null && locus.link !== null",
        long,
    )
    .await;
    assert_eq!(
        js(&c, "locus.robot.link").await,
        json!(format!("udp {robot}"))
    );
    let panel = c.find(Locator::Id("robot-panel")).await.unwrap();
    assert!(panel.is_displayed().await.unwrap());
    let text = panel.text().await.unwrap();
    assert!(
        text.contains("No ground truth from this robot"),
        "robot panel: {text}"
    );
    for id in ["step", "reset", "export", "presets", "p-ir_sigma"] {
        let el = c.find(Locator::Id(id)).await.unwrap();
        assert!(!el.is_displayed().await.unwrap(), "#{id} is hidden");
    }
    assert_eq!(
        js(&c, "document.getElementById('step').disabled").await,
        json!(true)
    );

    // Stopped until Start, the link counting packets.
    wait_for(&c, "locus.link.applied > 100", long).await;
    let status = c
        .find(Locator::Id("status"))
        .await
        .unwrap()
        .text()
        .await
        .unwrap();
    assert!(status.contains("stopped"), "status: {status}");
    let x0 = js(&c, "locus.lastSample.ekf").await;

    // Start: the estimate moves; there is no truth in the samples.
    click(&c, "start").await;
    wait_for(
        &c,
        &format!(
            "Math.hypot(locus.lastSample.ekf[0] - ({}), locus.lastSample.ekf[1] - ({})) > 0.05",
            x0[0], x0[1]
        ),
        long,
    )
    .await;
    assert_eq!(js(&c, "locus.lastSample.truth").await, Value::Null);
    assert_eq!(js(&c, "locus.ellipse !== null").await, json!(true));

    // R x 100 from the panel, applied in the host: the mean NIS the page
    // shows (last 50 corrections) falls.
    wait_for(&c, "locus.nisLog.length >= 100", long).await;
    let nis_before: f64 = text_of(&c, "nis-mean")
        .await
        .parse()
        .expect("the mean NIS shown");
    let r11 = num(&c, "locus.params.values.r11").await;
    let r = format!("{:e}", 100.0 * r11);
    set_input(&c, "p-r11", &r).await;
    set_input(&c, "p-r22", &r).await;
    click(&c, "apply-params").await;
    wait_for(
        &c,
        &format!(
            "locus.params.values.r11 === {} && locus.params.values.r22 === {}",
            100.0 * r11,
            100.0 * r11
        ),
        long,
    )
    .await;
    assert_eq!(
        js(&c, "document.getElementById('inuse-r11').textContent").await,
        json!(format!("in use: {}", 100.0 * r11))
    );
    let changed_at = num(&c, "locus.state.time").await + 0.1;
    wait_for(
        &c,
        &format!("locus.nisLog.filter(e => e.t > {changed_at}).length >= 60"),
        long,
    )
    .await;
    // A frame redraws the figure: wait for one after the 60th correction.
    let frames = num(&c, "locus.frames").await;
    wait_for(&c, &format!("locus.frames > {frames} + 1"), long).await;
    let nis_after: f64 = text_of(&c, "nis-mean")
        .await
        .parse()
        .expect("the mean NIS shown");
    println!("mean NIS shown: {nis_before} with R, {nis_after} with 100 R");
    assert!(
        nis_after < nis_before / 5.0,
        "mean NIS shown with R: {nis_before}, with 100 R: {nis_after}"
    );

    // Next correction: the host's next one, shown step by step while the
    // robot runs on (its posterior is a sample's estimate).
    let frames = num(&c, "locus.frames").await;
    click(&c, "step-correction").await;
    wait_for(
        &c,
        &format!("locus.frames > {frames} && locus.lastCorrection !== undefined && locus.lastCorrection !== null"),
        long,
    )
    .await;
    let detail = text_of(&c, "detail").await;
    assert!(
        detail.contains("K = P⁻ Hᵀ S⁻¹")
            && (detail.contains("ACCEPTED") || detail.contains("REJECTED")),
        "detail: {detail}"
    );
    assert_eq!(
        js(&c, "locus.state.running").await,
        json!(true),
        "the robot runs on"
    );
    assert_eq!(
        js(
            &c,
            "locus.lastCorrection.x_post.every((v, i) => Number.isFinite(v))"
        )
        .await,
        json!(true)
    );

    // The arrow keys steer: stop the path first (the heading then moves
    // only under the keys), hold the left arrow 0.6 s.
    click(&c, "stop").await;
    wait_for(&c, "locus.link.drive === 'stopped'", long).await;
    tokio::time::sleep(Duration::from_millis(500)).await;
    click(&c, "arena").await;
    let theta0 = num(&c, "locus.lastSample.ekf[2]").await;
    let teleop0 = num(&c, "locus.teleopFrames").await;
    let keys = KeyActions::new("keyboard".to_string())
        .then(KeyAction::Down { value: '\u{e012}' })
        .then(KeyAction::Pause {
            duration: Duration::from_millis(600),
        })
        .then(KeyAction::Up { value: '\u{e012}' });
    c.perform_actions(keys).await.expect("arrow key");
    wait_for(
        &c,
        "locus.state.teleop === false && locus.link.drive === 'stopped'",
        long,
    )
    .await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    let theta1 = num(&c, "locus.lastSample.ekf[2]").await;
    let teleop1 = num(&c, "locus.teleopFrames").await;
    assert!(
        teleop1 > teleop0 + 3.0,
        "frames while steering: {teleop0} -> {teleop1}"
    );
    let turned = (theta1 - theta0 + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
        - std::f64::consts::PI;
    println!("heading estimate turned {turned:.3} rad under the left arrow");
    assert!(
        turned > 0.5,
        "the left arrow turns the heading estimate left: {turned} rad"
    );

    // The link's counters on the page.
    for id in [
        "applied",
        "lost",
        "duplicate",
        "late",
        "corrupt",
        "malformed",
        "suspect",
        "implausible",
        "frames_malformed",
        "frames_oversize",
    ] {
        // The table is redrawn every frame: read its text, not an element.
        let t = text_of(&c, &format!("link-{id}")).await;
        let n: u64 = t.parse().unwrap_or_else(|_| panic!("link-{id}: {t}"));
        if id == "applied" {
            assert!(n > 1000, "packets applied shown: {n}");
        }
    }
    let latency = text_of(&c, "link-latency").await;
    assert!(latency.contains("µs"), "latency: {latency}");
    let clock = text_of(&c, "link-clock").await;
    assert!(clock.contains("ppm"), "clock: {clock}");
    screenshot(&c, "ui-robot.png").await;
    assert_eq!(
        js(&c, "locus.errors.length").await,
        json!(0),
        "no errors: {}",
        js(&c, "JSON.stringify(locus.errors)").await
    );

    c.close().await.expect("close the browser");
    let _ = std::fs::remove_dir_all(&downloads);
}
