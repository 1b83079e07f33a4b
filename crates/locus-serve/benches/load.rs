//! The full load test of the teaching UI's server: 50 concurrent WebSocket
//! clients for 30 s on loopback (`LOCUS_LOAD_CLIENTS`, `LOCUS_LOAD_SECS`,
//! `LOCUS_LOAD_SPEED` change them), each running its own session, changing
//! R every second and teleoperating. Prints messages per second and the
//! memory, and exits non-zero on any error, a session left open, or RSS
//! growth above the sessions' bound (every session's log full, + 64 MB).
//!
//! `cargo bench -p locus-serve --bench load` (the test suite runs a 3 s
//! version: tests/load.rs).
#![allow(clippy::std_instead_of_core)]

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Duration;

fn env<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    // `cargo bench` passes `--bench`; nothing else to parse.
    let clients = env("LOCUS_LOAD_CLIENTS", 50usize);
    let secs = env("LOCUS_LOAD_SECS", 30u64);
    let speed = env("LOCUS_LOAD_SPEED", 1.0f64);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .expect("runtime");
    let report = runtime.block_on(support::load::run(
        clients,
        Duration::from_secs(secs),
        speed,
    ));
    support::load::print(&report);
    // The memory bound: every session's log full (the largest thing a
    // session keeps), plus 64 MB for buffers and the runtime.
    let per_session = locus_serve::session::MAX_LOG_STEPS
        * std::mem::size_of::<locus_sim::StepRecord>()
        / (1024 * 1024);
    let bound_mb = clients * per_session + 64;
    let growth_mb = report.rss_peak_kb.saturating_sub(report.rss_before_kb) / 1024;
    println!(
        "RSS growth {growth_mb} MB; bound {bound_mb} MB ({clients} sessions x {per_session} MB of log at most, + 64 MB)"
    );
    #[allow(clippy::cast_possible_truncation)]
    if report.errors > 0 || report.sessions_after != 0 || growth_mb > bound_mb as u64 {
        eprintln!("load test FAILED");
        std::process::exit(1);
    }
    println!("load test passed");
}
