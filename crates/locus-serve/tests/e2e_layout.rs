//! The teaching page fits the screens it is used on (issue 33): a class
//! projector (1024 x 768), common laptops (1280 x 800, 1366 x 768) and a
//! desktop (1920 x 1080), in real headless Chromium. At each size: no
//! horizontal scroll, every plot inside the viewport, every plot title
//! fully shown, the plots' axes and legends there before the first step,
//! and a few seconds of the square scenario still draw the estimate, the
//! ellipse and every plot.
//!
//! `LOCUS_SCREENSHOTS=docs/img` keeps two screenshots per size: the top of
//! the page (`ui-layout-WxH.png`) and the page scrolled to the plots
//! (`ui-layout-WxH-plots.png`).
#![allow(clippy::std_instead_of_core, clippy::std_instead_of_alloc)]

mod support;

use std::time::Duration;

use serde_json::json;
use support::browser::{ONE_BROWSER, browser, click, js, num, screenshot, start_driver, wait_for};

/// Viewport sizes (CSS px).
const SIZES: [(u32, u32); 4] = [(1024, 768), (1280, 800), (1366, 768), (1920, 1080)];

/// The plots' containers.
const CHARTS: [&str; 5] = [
    "chart-p",
    "chart-innov",
    "chart-nis",
    "chart-wheels",
    "chart-ir",
];

/// What the layout looks like now, as one JSON value: the page's scroll
/// width and the viewport's, and for each plot its canvas's right edge and
/// whether its title and its axes are shown whole.
const LAYOUT: &str = "(() => {
  const charts = [...document.querySelectorAll('.chart')].map((c) => {
    const canvas = c.querySelector('canvas');
    const title = c.querySelector('.u-title');
    const r = canvas.getBoundingClientRect();
    return {
      id: c.id,
      left: r.left, right: r.right, width: r.width,
      title: title ? title.textContent : null,
      titleClipped: title ? title.scrollWidth > title.clientWidth : true,
      axes: c.querySelectorAll('.u-axis').length,
      legend: c.querySelectorAll('.u-legend .u-series').length,
    };
  });
  const arena = document.getElementById('arena').getBoundingClientRect();
  return {
    scrollWidth: document.documentElement.scrollWidth,
    innerWidth: window.innerWidth,
    arenaRight: arena.right, arenaWidth: arena.width,
    charts,
  };
})()";

/// For each plot, before any data: whether the scale of every axis has a
/// finite range (uPlot then draws the axis with its ticks) and how many
/// series its legend lists.
const EMPTY_PLOTS: &str = "Object.entries(locus.charts).map(([id, u]) => ({
  id,
  ranged: u.axes.every((a) => { const s = u.scales[a.scale]; return Number.isFinite(s.min) && Number.isFinite(s.max); }),
  legend: u.root.querySelectorAll('.u-legend .u-series').length,
}))";

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_fits_a_projector_a_laptop_and_a_desktop() {
    let _browser = ONE_BROWSER.lock().await;
    let driver = start_driver();
    let downloads = std::env::temp_dir().join(format!("locus-e2e-layout-{}", std::process::id()));
    std::fs::create_dir_all(&downloads).expect("download dir");
    let scenario = locus_sim::SquareConfig {
        laps: 20,
        max_time: 3000.0,
        ..locus_sim::SquareConfig::default()
    };
    let config = locus_serve::Config::new("square", scenario).expect("config");
    let addr = support::start_server(config).await;
    let c = browser(&driver, &downloads).await;
    let long = Duration::from_secs(30);
    // Every size is tried and screenshot before anything is asserted, so a
    // failure lists every size it fails at.
    let mut failed: Vec<String> = Vec::new();
    for (w, h) in SIZES {
        // The window's outer size is set; the viewport is what the page sees.
        c.set_window_size(w, h).await.expect("window size");
        c.goto(&format!("http://{addr}/")).await.expect("load");
        wait_for(
            &c,
            "locus.connected && locus.hello !== null && locus.params !== null",
            long,
        )
        .await;
        let inner = num(&c, "window.innerWidth").await;
        if (inner - f64::from(w)).abs() > 20.0 {
            failed.push(format!("{w}x{h}: the viewport is {inner} px wide"));
        }
        // Before the first step: every plot has its axes (every scale a
        // finite range, so the axes are drawn with ticks) and its legend.
        let empty = js(&c, EMPTY_PLOTS).await;
        for chart in empty.as_array().expect("charts") {
            if chart["ranged"] != json!(true) || chart["legend"].as_u64().unwrap_or(0) < 2 {
                failed.push(format!("{w}x{h}: no axes or legend before data: {chart}"));
            }
        }
        // A few seconds of the square scenario.
        click(&c, "reset").await;
        click(&c, "start").await;
        wait_for(&c, "locus.samples > 200 && locus.ellipse !== null", long).await;
        tokio::time::sleep(Duration::from_secs(2)).await;
        screenshot(&c, &format!("ui-layout-{w}x{h}.png")).await;
        let layout = js(&c, LAYOUT).await;
        // And scrolled down to the plots (the viewport's width unchanged).
        js(
            &c,
            "(document.getElementById('chart-p').scrollIntoView(), true)",
        )
        .await;
        screenshot(&c, &format!("ui-layout-{w}x{h}-plots.png")).await;
        js(&c, "(window.scrollTo(0, 0), true)").await;
        click(&c, "stop").await;
        let inner = layout["innerWidth"].as_f64().expect("innerWidth");
        let scroll = layout["scrollWidth"].as_f64().expect("scrollWidth");
        if scroll > inner {
            failed.push(format!(
                "{w}x{h}: the page is {scroll} px wide in a {inner} px viewport"
            ));
        }
        if layout["arenaRight"].as_f64().unwrap() > inner
            || layout["arenaWidth"].as_f64().unwrap() < 300.0
        {
            failed.push(format!("{w}x{h}: the arena: {layout}"));
        }
        let charts = layout["charts"].as_array().expect("charts");
        assert_eq!(charts.len(), CHARTS.len(), "{layout}");
        for chart in charts {
            let (left, right) = (
                chart["left"].as_f64().unwrap(),
                chart["right"].as_f64().unwrap(),
            );
            if left < 0.0 || right > inner || chart["width"].as_f64().unwrap() < 200.0 {
                failed.push(format!("{w}x{h}: a plot outside the viewport: {chart}"));
            }
            if chart["titleClipped"] != json!(false) {
                failed.push(format!("{w}x{h}: a plot title cut: {chart}"));
            }
        }
        // The run still draws: the estimate, the ellipse and every plot.
        let e = js(&c, "locus.ellipse").await;
        if e["rx_px"].as_f64().unwrap_or(0.0) <= 0.5 {
            failed.push(format!("{w}x{h}: no ellipse: {e}"));
        }
        let est = num(&c, "locus.estPoints || 0").await;
        if est <= 10.0 {
            failed.push(format!("{w}x{h}: the estimate's path has {est} points"));
        }
        for chart in CHARTS {
            let n = num(&c, &format!("locus.charts['{chart}'].data[0].length")).await;
            if n <= 100.0 {
                failed.push(format!("{w}x{h}: {chart} has {n} points"));
            }
        }
    }
    // Large text, on the projector: still no horizontal scroll, titles
    // whole, taller plots.
    c.set_window_size(1024, 768).await.expect("window size");
    let height = num(&c, "locus.charts['chart-p'].height").await;
    click(&c, "big").await;
    wait_for(&c, "document.body.classList.contains('big')", long).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    screenshot(&c, "ui-layout-1024x768-large-text.png").await;
    let layout = js(&c, LAYOUT).await;
    if layout["scrollWidth"].as_f64() > layout["innerWidth"].as_f64()
        || layout["charts"]
            .as_array()
            .expect("charts")
            .iter()
            .any(|c| c["titleClipped"] != json!(false))
        || num(&c, "locus.charts['chart-p'].height").await <= height
    {
        failed.push(format!("large text at 1024x768: {layout}"));
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
    let _ = std::fs::remove_dir_all(&downloads);
}
