//! ROS map_server maps: a small hand-written map (YAML and PGM written here)
//! whose pixel values exercise each rule, round trips through the writer, and
//! bad files refused with the file and field named.

mod common;

use std::path::Path;

use common::{Rng, temp_dir};
use locus_map::{Grid, GridGeometry, Map, MapError, Occupancy, Thresholds, ros};

/// Image rows, top first (row 0 = highest y). With thresholds 0.65 / 0.196:
/// 0 and 89 occupied (p = 1, 0.651), 90 unknown (0.647), 205 unknown
/// (0.19608), 206 free (0.1922), 254 and 255 free, 128 and 100 unknown, 50
/// occupied (0.804). Negated (p = v / 255), 50 is unknown (0.19608).
const PIXELS: [[u8; 4]; 3] = [[0, 89, 90, 205], [206, 254, 255, 128], [100, 50, 0, 255]];

fn p2(pixels: &[[u8; 4]; 3]) -> String {
    let mut s = String::from("P2\n# written by hand\n4 3\n# max\n255\n");
    for row in pixels {
        let line: Vec<String> = row.iter().map(u8::to_string).collect();
        s += &line.join(" ");
        s += "\n";
    }
    s
}

fn p5(pixels: &[[u8; 4]; 3]) -> Vec<u8> {
    let mut v = b"P5\n4 3\n255\n".to_vec();
    v.extend(pixels.iter().flatten());
    v
}

fn yaml(image: &str, negate: &str, mode: Option<&str>) -> String {
    let mut s = format!(
        "image: {image}\nresolution: 0.5\norigin: [-1.0, 2.0, 0.0]\nnegate: {negate}\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    );
    if let Some(m) = mode {
        s += &format!("mode: {m}\n");
    }
    s
}

fn load(dir: &Path, name: &str, yaml_text: &str) -> Result<Grid, MapError> {
    let path = dir.join(name);
    std::fs::write(&path, yaml_text).unwrap();
    ros::load(&path)
}

/// States by image row (top first), as `#` occupied, `.` free, `?` unknown.
fn picture(g: &Grid) -> Vec<String> {
    let (w, h) = (g.geometry().width(), g.geometry().height());
    (0..h)
        .map(|row| {
            (0..w)
                .map(|ix| match g.state(ix, h - 1 - row).unwrap() {
                    Occupancy::Occupied => '#',
                    Occupancy::Free => '.',
                    Occupancy::Unknown => '?',
                })
                .collect()
        })
        .collect()
}

#[test]
fn hand_written_map_follows_map_server() {
    let dir = temp_dir("ros-hand");
    std::fs::write(dir.join("ascii.pgm"), p2(&PIXELS)).unwrap();
    std::fs::write(dir.join("binary.pgm"), p5(&PIXELS)).unwrap();

    // Trinary, P2 and P5 alike; row 0 of the image is the top.
    let a = load(&dir, "a.yaml", &yaml("ascii.pgm", "0", None)).unwrap();
    let b = load(&dir, "b.yml", &yaml("binary.pgm", "false", Some("trinary"))).unwrap();
    assert_eq!(a, b);
    assert_eq!(picture(&a), ["##??", "...?", "?##."]);
    assert_eq!(a.probability(0, 2), Some(1.0));
    assert!((a.probability(1, 2).unwrap() - 166.0 / 255.0).abs() < 1e-6);
    assert_eq!(
        a.probability(2, 2),
        None,
        "trinary keeps no probability for unknown"
    );
    assert_eq!(a.probability(2, 1), Some(0.0));
    let g = a.geometry();
    assert_eq!(
        (g.width(), g.height(), g.resolution(), g.origin()),
        (4, 3, 0.5, [-1.0, 2.0, 0.0])
    );
    assert_eq!(g.cell_center(0, 2), [-0.75, 3.25]);
    assert_eq!(g.cell_of([-0.9, 2.1]), Some([0, 0]));

    // negate: white is occupied, p = v / 255.
    let n = load(&dir, "n.yaml", &yaml("binary.pgm", "1", None)).unwrap();
    assert_eq!(picture(&n), [".??#", "###?", "??.#"]);

    // scale: between the thresholds the probability is kept.
    let s = load(&dir, "s.yaml", &yaml("binary.pgm", "0", Some("scale"))).unwrap();
    assert_eq!(picture(&s), picture(&a));
    assert!((s.probability(3, 1).unwrap() - 127.0 / 255.0).abs() < 1e-6);
    assert!((s.probability(3, 2).unwrap() - 50.0 / 255.0).abs() < 1e-6);

    // raw: the value is the occupancy in percent, above 100 unknown.
    let r = load(&dir, "r.yaml", &yaml("binary.pgm", "0", Some("raw"))).unwrap();
    assert_eq!(picture(&r), [".##?", "????", "#?.?"]);
    assert_eq!(r.probability(1, 0), Some(0.5));
    assert_eq!(r.probability(3, 0), None);

    // An absolute image path, a quoted name, other keys ignored.
    let abs = dir.join("binary.pgm");
    let text = yaml(&format!("\"{}\"", abs.display()), "0", None) + "comment: ignored\n";
    assert_eq!(load(&dir, "abs.yaml", &text).unwrap(), a);
    // Through the Map front.
    assert!(matches!(
        Map::load(&dir.join("a.yaml")).unwrap(),
        Map::Grid(_)
    ));
}

/// A grid with occupied, free and unknown cells, a rotated origin and an
/// odd resolution survives the writer: trinary keeps every state, scale
/// every probability to half a grey level, raw to half a percent.
#[test]
fn written_maps_read_back() {
    let dir = temp_dir("ros-round");
    let g = GridGeometry::new(37, 23, 0.073, [-3.25, 1.125, 0.4]).unwrap();
    let mut rng = Rng::new(2);
    let probs: Vec<_> = (0..g.len())
        .map(|_| match rng.next_u64() % 4 {
            0 => None,
            1 => Some(1.0),
            2 => Some(0.0),
            _ => Some(rng.unit()),
        })
        .collect();
    let grid = Grid::from_probabilities(g, Thresholds::default(), &probs).unwrap();
    let path = dir.join("map.yaml");
    Map::from(grid.clone()).save(&path).unwrap();
    assert!(dir.join("map.pgm").exists());
    assert!(
        std::fs::read(dir.join("map.pgm"))
            .unwrap()
            .starts_with(b"P5")
    );
    let back = ros::load(&path).unwrap();
    assert_eq!(back.geometry(), grid.geometry());
    assert_eq!(back.thresholds(), grid.thresholds());
    assert_eq!(picture(&back), picture(&grid));
    // A path that would make the YAML its own image is refused.
    assert!(ros::save(&grid, &dir.join("map.pgm"), ros::Mode::Trinary).is_err());

    for (mode, tol) in [(ros::Mode::Scale, 0.5 / 255.0), (ros::Mode::Raw, 0.005)] {
        ros::save(&grid, &path, mode).unwrap();
        let back = ros::load(&path).unwrap();
        for iy in 0..g.height() {
            for ix in 0..g.width() {
                match (grid.probability(ix, iy), back.probability(ix, iy)) {
                    (Some(p), Some(q)) => assert!((p - q).abs() <= tol + 1e-6, "{mode:?} {p} {q}"),
                    // Scale cannot say "no probability" without alpha: the
                    // state stays unknown.
                    (None, q) => {
                        assert!(mode == ros::Mode::Scale || q.is_none());
                        assert_eq!(back.state(ix, iy), Some(Occupancy::Unknown));
                    }
                    (p, None) => panic!("{mode:?}: {p:?} lost"),
                }
            }
        }
    }
}

fn error_of(dir: &Path, name: &str, text: &str) -> MapError {
    load(dir, name, text).unwrap_err()
}

#[test]
fn bad_maps_name_file_and_field() {
    let dir = temp_dir("ros-bad");
    std::fs::write(dir.join("ok.pgm"), p5(&PIXELS)).unwrap();
    let good = yaml("ok.pgm", "0", None);

    // A missing key: the parser names it, with the line.
    let err = error_of(&dir, "m.yaml", &good.replace("resolution: 0.5\n", ""));
    let MapError::Syntax {
        file,
        line,
        message,
    } = &err
    else {
        panic!("{err:?}")
    };
    assert!(file.ends_with("m.yaml"));
    assert!(message.contains("resolution"), "{message}");
    assert!(line.is_some(), "{err}");

    let field_of = |err: MapError| match err {
        MapError::Field { field, .. } => field,
        other => panic!("{other:?}"),
    };
    let cases = [
        ("resolution: 0.5", "resolution: -0.5", "resolution"),
        ("origin: [-1.0, 2.0, 0.0]", "origin: [-1.0, 2.0]", "origin"),
        ("negate: 0", "negate: 2", "negate"),
        (
            "occupied_thresh: 0.65",
            "occupied_thresh: 1.65",
            "occupied_thresh",
        ),
        ("free_thresh: 0.196", "free_thresh: 0.7", "free_thresh"),
        ("image: ok.pgm", "image: \"\"", "image"),
    ];
    for (from, to, field) in cases {
        assert_eq!(
            field_of(error_of(&dir, "f.yaml", &good.replace(from, to))),
            field,
            "{to}"
        );
    }
    assert_eq!(
        field_of(error_of(&dir, "f.yaml", &(good.clone() + "mode: fancy\n"))),
        "mode"
    );
    let err = error_of(&dir, "f.yaml", &good.replace("negate: 0", "negate: 2"));
    assert!(
        err.to_string()
            .contains("f.yaml: negate: 2: must be 0 or 1"),
        "{err}"
    );

    // Not YAML at all.
    assert!(matches!(
        error_of(&dir, "y.yaml", "image: [unclosed\n"),
        MapError::Syntax { .. }
    ));

    // The image: missing, not a PNM, 16-bit.
    let err = error_of(&dir, "i.yaml", &good.replace("ok.pgm", "gone.pgm"));
    let MapError::Io { file, .. } = &err else {
        panic!("{err:?}")
    };
    assert!(file.ends_with("gone.pgm"));
    std::fs::write(dir.join("junk.pgm"), b"GIF89a").unwrap();
    let err = error_of(&dir, "i.yaml", &good.replace("ok.pgm", "junk.pgm"));
    let MapError::Image { file, .. } = &err else {
        panic!("{err:?}")
    };
    assert!(file.ends_with("junk.pgm"));
    std::fs::write(dir.join("deep.pgm"), b"P5\n1 1\n65535\n\x01\x02").unwrap();
    let err = error_of(&dir, "i.yaml", &good.replace("ok.pgm", "deep.pgm"));
    assert!(matches!(err, MapError::Image { .. }), "{err:?}");
    std::fs::write(dir.join("short.pgm"), b"P5\n4 3\n255\n\x01\x02").unwrap();
    let err = error_of(&dir, "i.yaml", &good.replace("ok.pgm", "short.pgm"));
    assert!(matches!(err, MapError::Image { .. }), "{err:?}");
}
