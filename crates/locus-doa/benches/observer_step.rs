//! One Euler step of paper 002's continuous-time observer (eq. 12-17) on the
//! four-mark camera at the spec's default DOA configuration, and one whole
//! 3-s run (600 steps) of one vertex of one grid cell: the unit of work of
//! `locus doa`.

use core::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use locus_core::MeasurementModel;
use locus_doa::{DoaConfig, Study, vertex};
use locus_models::observer::ObserverState;

fn bench(c: &mut Criterion) {
    let study = Study::new(DoaConfig::default()).expect("default configuration is valid");
    let config = study.config().clone();
    let model = config.model();
    let nominal = config.nominal();
    let y = model.h(&nominal).expect("nominal pose sees every mark");
    let observer = study.observer(50.0);
    let (v_g, m) = (0.0151, 0.1);
    let state = ObserverState::new(nominal + vertex(5, m), config.noise_q() * v_g);
    c.bench_function("observer step (002, 4 marks, f64)", |b| {
        b.iter(|| {
            observer
                .step(black_box(&state), &model, black_box(&y))
                .expect("a valid step")
        })
    });
    c.bench_function(
        "one vertex run (600 steps, v_g 0.0151, alpha 50, m 0.1)",
        |b| b.iter(|| study.run(&observer, black_box(v_g), &vertex(5, black_box(m)))),
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
