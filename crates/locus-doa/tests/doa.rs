//! The domain-of-attraction study of paper 002 (spec section 4): run rules,
//! the M_zeta search, the alpha effect at the largest v_g, configuration
//! errors, and exact merging of shards. Reduced grids keep each test short.

use locus_doa::{
    Cell, Divergence, DoaConfig, DoaError, DoaResult, RunOutcome, SearchConfig, SettleTracker,
    Shard, Study, merge, merge_csv, search_m_zeta, vertex,
};

fn study() -> Study {
    Study::new(DoaConfig::default()).unwrap()
}

#[test]
fn defaults_are_the_specs_values() {
    let c = DoaConfig::default();
    let g = &c.grid;
    assert_eq!((g.v_g_count, g.alpha_count), (12, 25));
    assert_eq!(g.v_g(0), 1e-4);
    assert!((g.v_g(11) - 5.51e-2).abs() < 1e-15);
    assert_eq!((g.alpha(0), g.alpha(24)), (5.0, 125.0));
    assert_eq!(
        (c.run.dt, c.run.horizon, c.run.threshold),
        (0.005, 3.0, 0.0087)
    );
    assert_eq!(c.run.steps(), 600);
    let s = &c.search;
    assert_eq!(
        (s.m_start, s.m_step, s.m_cap, s.tolerance, s.settle_m_zeta),
        (0.05, 0.05, 2.0, 0.01, 0.1)
    );
    assert_eq!(c.geometry.min_depth, 0.05);
    assert_eq!(c.noise.pixel_sigma, 2.0);
    assert_eq!(c.noise.q_diag[0], 0.1 * 0.1);
    assert_eq!(c.noise.q_diag[5], 0.1396 * 0.1396);
    // An empty file is the defaults.
    assert_eq!(DoaConfig::from_toml_str("", "empty.toml").unwrap(), c);
}

#[test]
fn settling_time_is_the_last_time_above_the_threshold() {
    let mut t = SettleTracker::new(0.0087);
    // Below at step 2, above again at step 3 (a late swing), below after.
    for (k, norm) in [0.1, 0.05, 0.001, 0.02, 0.008, 0.0, 0.0]
        .into_iter()
        .enumerate()
    {
        t.observe(k, norm);
    }
    assert_eq!(t.settle_time(0.005), 3.0 * 0.005);
    // Exactly the threshold is not below it.
    let mut t = SettleTracker::new(0.0087);
    t.observe(4, 0.0087);
    t.observe(5, 0.0086);
    assert_eq!(t.settle_time(1.0), 4.0);
    // Never above: 0.
    let mut t = SettleTracker::new(0.0087);
    t.observe(1, 0.001);
    assert_eq!(t.settle_time(1.0), 0.0);
}

#[test]
fn a_small_initial_error_converges() {
    let s = study();
    let obs = s.observer(50.0);
    match s.run(&obs, 0.0051, &vertex(0, 0.05)) {
        RunOutcome::Converged {
            settle,
            final_error,
        } => {
            assert!(final_error < 0.0087);
            assert!(settle > 0.0 && settle <= 0.1, "settle {settle}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_run_that_ends_above_the_threshold_has_not_converged() {
    // Two steps are too short to bring 0.05 below 0.0087: finite, not diverged,
    // not converged.
    let mut c = DoaConfig::default();
    c.run.horizon = 0.01;
    let s = Study::new(c).unwrap();
    let obs = s.observer(50.0);
    match s.run(&obs, 0.0051, &vertex(0, 0.05)) {
        RunOutcome::NotConverged { final_error } => assert!(final_error >= 0.0087),
        other => panic!("{other:?}"),
    }
}

#[test]
fn divergence_rules_mark_at_the_camera_plane_and_non_finite() {
    let s = study();
    let obs = s.observer(50.0);
    // The observer test of locus-models pins this run: a mark passes behind
    // the camera at step 27.
    assert_eq!(
        s.run(&obs, 0.0051, &vertex(0, 2.0)),
        RunOutcome::Diverged {
            step: 27,
            reason: Divergence::MarkAtCameraPlane
        }
    );
    // A start behind the camera diverges at once.
    let mut zeta = vertex(0, 0.0);
    zeta[2] = -2.46; // tz = 0.04 m: the marks at z = 0.04 <= 0.05
    assert_eq!(
        s.run(&obs, 0.0051, &zeta),
        RunOutcome::Diverged {
            step: 0,
            reason: Divergence::MarkAtCameraPlane
        }
    );
    // A non-finite value diverges.
    let mut zeta = vertex(0, 0.01);
    zeta[4] = f64::NAN;
    assert_eq!(
        s.run(&obs, 0.0051, &zeta),
        RunOutcome::Diverged {
            step: 0,
            reason: Divergence::NonFinite
        }
    );
}

#[test]
fn stepping_then_bisection_finds_a_known_threshold() {
    let search = SearchConfig::default();
    // Monotone phi with the threshold 0.437: steps 0.05..0.40 pass (8), 0.45
    // fails, then 0.425 pass, 0.4375 fail, 0.43125 pass: bracket 0.00625.
    let mut tried = Vec::new();
    let r = search_m_zeta(&search, |m| {
        tried.push(m);
        m <= 0.437
    });
    assert!((r.value - 0.43125).abs() < 1e-12, "{r:?}");
    assert!((r.failure.unwrap() - 0.4375).abs() < 1e-12);
    assert!(r.failure.unwrap() - r.value <= 0.01);
    assert!(r.value <= 0.437 && 0.437 - r.value <= 0.01);
    assert_eq!(r.evaluations, 12);
    assert_eq!(tried.len(), 12);
    // Not monotone: success again above the first failure is not explored.
    let r = search_m_zeta(&search, |m| !(0.22..0.3).contains(&m));
    assert!(r.value < 0.22 && r.value >= 0.21, "{r:?}");
    // Never fails: the cap.
    let r = search_m_zeta(&search, |_| true);
    assert_eq!((r.value, r.failure, r.evaluations), (2.0, None, 40));
    // Fails at once: bisect below m_start down to 0.
    let r = search_m_zeta(&search, |m| m < 0.02);
    assert!(r.value <= 0.02 && 0.02 - r.value <= 0.01, "{r:?}");
}

#[test]
fn at_the_largest_v_g_a_larger_alpha_widens_the_doa() {
    let s = study();
    let g = s.config().grid.clone();
    let v_g = g.v_g(g.v_g_count - 1);
    let cell = |j: usize| Cell {
        index: 0,
        i_vg: g.v_g_count - 1,
        i_alpha: j,
        v_g,
        alpha: g.alpha(j),
    };
    let small = s.solve(cell(0)).m_zeta; // alpha = 5
    let large = s.solve(cell(g.alpha_count - 1)).m_zeta; // alpha = 125
    println!("v_g = {v_g}: M_zeta(alpha 5) = {small}, M_zeta(alpha 125) = {large}");
    assert!(large > small + 0.1, "alpha 125: {large}, alpha 5: {small}");
}

fn small_config() -> DoaConfig {
    let mut c = DoaConfig::default();
    c.grid.v_g_count = 2;
    c.grid.v_g_step = 0.05;
    c.grid.alpha_count = 3;
    c.grid.alpha_step = 50.0;
    c.run.horizon = 1.0;
    c.search.m_cap = 0.3;
    c
}

#[test]
fn merged_shards_equal_the_unsharded_sweep_exactly() {
    let study = Study::new(small_config()).unwrap();
    let whole = study.sweep(Shard::ALL, &|_| {});
    assert_eq!(whole.cells.len(), 6);
    let parts: Vec<DoaResult> = (0..4)
        .map(|i| {
            let part = study.sweep(Shard { index: i, count: 4 }, &|_| {});
            // Through the CSV file form and back.
            DoaResult::from_csv(&part.to_csv(), "part.csv").unwrap()
        })
        .collect();
    assert_eq!(parts[0].cells.len(), 2); // cells 0 and 4
    let merged = merge(parts.clone()).unwrap();
    assert_eq!(merged, whole);
    assert_eq!(merged.to_csv(), whole.to_csv());
    // The sweep found something non-trivial to compare.
    assert!(whole.cells.iter().any(|c| c.m_zeta > 0.0));

    // Missing and duplicated shards are refused.
    assert!(matches!(
        merge(parts[..3].to_vec()),
        Err(DoaError::Merge(_))
    ));
    let mut dup = parts.clone();
    dup.push(parts[1].clone());
    assert!(matches!(merge(dup), Err(DoaError::Merge(_))));
    // A shard of another configuration is refused.
    let mut other = parts.clone();
    other[2].config_hash ^= 1;
    assert!(matches!(merge(other), Err(DoaError::Merge(_))));
}

/// What `locus doa merge` and `locus.doa` join: shard CSVs, checked
/// against the configuration when it is given.
#[test]
fn shard_csvs_merge_checked_against_their_configuration() {
    let config = small_config();
    let study = Study::new(config.clone()).unwrap();
    let whole = study.sweep(Shard::ALL, &|_| {});
    let texts: Vec<(String, String)> = (0..3)
        .map(|i| {
            let part = study.sweep(Shard { index: i, count: 3 }, &|_| {});
            (format!("part{i}.csv"), part.to_csv())
        })
        .collect();
    let shards = || texts.iter().map(|(n, t)| (n.as_str(), t.as_str()));
    assert_eq!(merge_csv(shards(), None).unwrap().to_csv(), whole.to_csv());
    let given = merge_csv(shards(), Some((&config, "small.toml"))).unwrap();
    assert_eq!(given.to_csv(), whole.to_csv());

    // The same grid, another horizon: refused, naming the configuration.
    let mut other = config.clone();
    other.run.horizon = 2.0;
    let e = merge_csv(shards(), Some((&other, "other.toml")))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("the shards were computed with another configuration than other.toml"),
        "{e}"
    );
    // Another grid: refused, naming the shard.
    let mut wider = config;
    wider.grid.alpha_count = 4;
    let e = merge_csv(shards(), Some((&wider, "wider.toml")))
        .unwrap_err()
        .to_string();
    assert!(e.contains("part0.csv"), "{e}");
    // No shards.
    assert!(matches!(
        merge_csv(core::iter::empty(), None),
        Err(DoaError::Merge(_))
    ));
}

#[test]
fn configuration_errors_name_file_line_and_field() {
    let e =
        DoaConfig::from_toml_str("[grid]\nv_g_count = 3\nalpha_cout = 4\n", "a.toml").unwrap_err();
    match e {
        DoaError::Parse {
            file, line, field, ..
        } => assert_eq!(
            (file.as_str(), line, field.as_str()),
            ("a.toml", 3, "grid.alpha_cout")
        ),
        other => panic!("{other:?}"),
    }
    let e = DoaConfig::from_toml_str("[run]\n\ndt = \"fast\"\n", "b.toml").unwrap_err();
    match e {
        DoaError::Parse {
            file, line, field, ..
        } => assert_eq!(
            (file.as_str(), line, field.as_str()),
            ("b.toml", 3, "run.dt")
        ),
        other => panic!("{other:?}"),
    }
    let e = DoaConfig::from_toml_str(
        "[search]\ntolerance = 0.01\n[run]\nhorizon = -1.0\n",
        "c.toml",
    )
    .unwrap_err();
    match &e {
        DoaError::Invalid {
            file, line, field, ..
        } => assert_eq!(
            (file.as_str(), *line, field.as_str()),
            ("c.toml", 4, "run.horizon")
        ),
        other => panic!("{other:?}"),
    }
    assert!(
        e.to_string().starts_with("c.toml:4: field `run.horizon`"),
        "{e}"
    );
    let e =
        DoaConfig::from_toml_str("[geometry]\nmarks = [[0.3, 0.0, 0.0]]\n", "d.toml").unwrap_err();
    assert!(matches!(e, DoaError::Invalid { line: 2, .. }), "{e:?}");
    assert!(Shard::parse("3/3").is_err());
    assert!(Shard::parse("x/3").is_err());
    assert_eq!(Shard::parse("2/3").unwrap(), Shard { index: 2, count: 3 });
}
