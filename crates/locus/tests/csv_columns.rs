//! Issue 31: one column convention for every step log: `locus run`'s
//! scenarios, the teaching UI's export (the `square` record) and `locus
//! replay`'s `log.csv` and `smoothed.csv`.

/// One CSV column convention for every step log (`locus run`'s scenarios,
/// the teaching UI's export, `locus replay`): snake case, the unit as a
/// suffix (`_s`, `_m`, `_rad`, `_m2`, ...), no brackets; the columns the
/// simulator and the replay share are named alike.
#[test]
fn every_step_log_names_its_columns_one_way() {
    use locus_eval::Record;
    let headers = [
        ("square", locus_sim::StepRecord::csv_header()),
        ("wall45", locus_sim::wall45::Wall45Record::csv_header()),
        (
            "tricycle-slip",
            locus_sim::tricycle_slip::TricycleSlipRecord::csv_header(),
        ),
        ("hover", locus_sim::hover::HoverRecord::csv_header()),
        ("replay", locus_replay::Step::csv_header().to_string()),
        (
            "replay smoothed",
            locus_replay::Step::smoothed_csv_header().to_string(),
        ),
    ];
    for (name, header) in &headers {
        for column in header.split(',') {
            assert!(
                !column.is_empty()
                    && column
                        .chars()
                        .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_'),
                "{name}: column `{column}` in {header}"
            );
        }
    }
    let replay: Vec<&str> = headers[4].1.split(',').collect();
    for (name, header) in &headers[..3] {
        for shared in [
            "time_s",
            "true_x_m",
            "true_y_m",
            "true_theta_rad",
            "var_x_m2",
            "var_y_m2",
            "var_theta_rad2",
            "cov_xy_m2",
        ] {
            assert!(header.split(',').any(|c| c == shared), "{name}: {header}");
            assert!(replay.contains(&shared), "replay: {shared}");
        }
    }
}
