//! Speed of reading MRCLAM dataset 6's robot files (15 `.xz` files, about
//! 4 MB compressed, 28 MB of text; read from disk outside the timing):
//!
//! * `decode`: decompression alone, the pure-Rust `lzma-rs` decoder beside
//!   `liblzma` (xz's C library, built from source), each writing into a
//!   fresh buffer per file, as the reader does;
//! * `parse`: parsing alone, the decompressed text of every file through
//!   its `mrclam::parse_*` function;
//! * `read`: what the replay's load does, each robot's ground truth,
//!   odometry and measurements read through `Dataset` (decompression and
//!   parsing, file system included).

use core::hint::black_box;
use std::fs;
use std::io::Read as _;
use std::path::{Path, PathBuf};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use locus_logs::mrclam::{self, Dataset, ROBOTS};

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/mrclam/MRCLAM_Dataset6")
}

/// The compressed bytes of every robot file, in robot and kind order.
fn compressed() -> Vec<Vec<u8>> {
    ROBOTS
        .flat_map(|r| {
            ["Groundtruth", "Odometry", "Measurement"]
                .map(|kind| data_dir().join(format!("Robot{r}_{kind}.dat.xz")))
        })
        .map(|path| fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())))
        .collect()
}

fn lzma_rs(xz: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(xz.len().saturating_mul(32));
    lzma_rs::xz_decompress(&mut &xz[..], &mut out).expect("lzma-rs decodes");
    out
}

fn liblzma(xz: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(xz.len().saturating_mul(32));
    liblzma::read::XzDecoder::new(xz)
        .read_to_end(&mut out)
        .expect("liblzma decodes");
    out
}

fn bench(c: &mut Criterion) {
    let files = compressed();
    let text: Vec<Vec<u8>> = files.iter().map(|f| lzma_rs(f)).collect();
    for (xz, plain) in files.iter().zip(&text) {
        assert_eq!(&liblzma(xz), plain, "both decoders give the same text");
    }
    let out_bytes: usize = text.iter().map(Vec::len).sum();

    let mut group = c.benchmark_group(format!(
        "decode MRCLAM 6 robot files ({} xz files, {:.1} MB of text)",
        files.len(),
        out_bytes as f64 / 1e6
    ));
    group.sample_size(10);
    group.throughput(Throughput::Bytes(out_bytes as u64));
    group.bench_function("lzma-rs", |b| {
        b.iter(|| {
            files
                .iter()
                .map(|f| lzma_rs(black_box(f)).len())
                .sum::<usize>()
        });
    });
    group.bench_function("liblzma", |b| {
        b.iter(|| {
            files
                .iter()
                .map(|f| liblzma(black_box(f)).len())
                .sum::<usize>()
        });
    });
    group.finish();

    let texts: Vec<String> = text
        .iter()
        .map(|t| String::from_utf8(t.clone()).expect("text"))
        .collect();
    let mut group = c.benchmark_group("parse MRCLAM 6 robot files (mrclam::parse_*)");
    group.sample_size(10);
    group.throughput(Throughput::Bytes(out_bytes as u64));
    group.bench_function("ground truth, odometry, measurements", |b| {
        let path = Path::new("bench");
        b.iter(|| {
            // Files come in ground truth, odometry, measurement order.
            texts
                .chunks(3)
                .map(|t| {
                    let g = mrclam::parse_groundtruth(black_box(&t[0]), path).expect("truth");
                    let o = mrclam::parse_odometry(black_box(&t[1]), path).expect("odometry");
                    let m =
                        mrclam::parse_measurements(black_box(&t[2]), path).expect("measurements");
                    g.poses().len() + o.len() + m.len()
                })
                .sum::<usize>()
        });
    });
    group.finish();

    let dataset = Dataset::open(data_dir()).expect("MRCLAM dataset 6");
    let mut group = c.benchmark_group("read MRCLAM 6 robots 1-5 (locus_logs::mrclam)");
    group.sample_size(10);
    group.throughput(Throughput::Bytes(out_bytes as u64));
    group.bench_function("ground truth, odometry, measurements", |b| {
        b.iter(|| {
            ROBOTS
                .map(|r| {
                    let g = dataset.groundtruth(r).expect("ground truth");
                    let o = dataset.odometry(r).expect("odometry");
                    let m = dataset.measurements(r).expect("measurements");
                    g.poses().len() + o.len() + m.len()
                })
                .sum::<usize>()
        });
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
