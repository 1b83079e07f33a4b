//! The load test, short: 50 concurrent clients for 3 s on loopback (the
//! 30 s version: `cargo bench -p locus-serve --bench load`).
#![allow(clippy::std_instead_of_core)]

mod support;

use std::time::Duration;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fifty_clients_for_three_seconds() {
    let secs = std::env::var("LOCUS_LOAD_TEST_SECS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let r = support::load::run(50, Duration::from_secs(secs), 1.0).await;
    support::load::print(&r);
    assert_eq!(r.errors, 0, "errors during the load test");
    assert_eq!(r.sessions_after, 0, "sessions left open");
    // Every client streams: 20 frames/s each at least half the time.
    #[allow(clippy::cast_precision_loss)]
    let expected = 50.0 * 20.0 * r.seconds * 0.5;
    assert!(
        r.received as f64 > expected,
        "{} messages, expected > {expected}",
        r.received
    );
    // ~100 steps/s of simulated time per client at speed 1.
    #[allow(clippy::cast_precision_loss)]
    let steps = r.samples as f64 / r.seconds / 50.0;
    assert!(steps > 50.0, "{steps:.0} steps/s per client");
    let growth_mb = r.rss_peak_kb.saturating_sub(r.rss_before_kb) / 1024;
    assert!(growth_mb < 128, "RSS grew by {growth_mb} MB");
}
