//! End-to-end test of the teaching UI attached to a robot in real
//! headless Chromium (`support/browser.rs`): the page attached to a
//! simulated robot (`locus_simlink::run_robot`) over loopback UDP
//! (`locus serve --robot`).
#![allow(
    clippy::std_instead_of_core,
    clippy::std_instead_of_alloc,
    clippy::too_many_lines
)]

mod support;

use std::time::Duration;

use fantoccini::Locator;
use fantoccini::actions::{InputSource, KeyAction, KeyActions};
use serde_json::{Value, json};
use support::browser::{
    ONE_BROWSER, browser, click, js, num, screenshot, set_input, start_driver, text_of, wait_for,
};

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
