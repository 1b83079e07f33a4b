//! End-to-end test of the teaching UI in real headless Chromium (Debian's
//! `chromium` and `chromium-driver`, driven over WebDriver with
//! fantoccini). The server runs in-process on 127.0.0.1:0.
//!
//! A missing browser or driver FAILS the test with the command that
//! installs them (`scripts/test.sh` installs them first). Paths:
//! `LOCUS_CHROMEDRIVER` (default `/usr/bin/chromedriver`) and
//! `LOCUS_CHROMIUM` (default `/usr/bin/chromium`).
//!
//!
//! The page attached to a robot: `e2e_robot.rs`.
#![allow(
    clippy::std_instead_of_core,
    clippy::std_instead_of_alloc,
    clippy::too_many_lines
)]

mod support;

use std::time::{Duration, Instant};

use fantoccini::Locator;
use fantoccini::actions::{InputSource, KeyAction, KeyActions};
use serde_json::json;
use support::browser::{
    ONE_BROWSER, browser, click, js, num, screenshot, set_input, start_driver, wait_for,
};

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
