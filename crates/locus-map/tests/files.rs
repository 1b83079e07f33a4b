//! Wall files (plain text and TOML): round trips to the bit, and bad files
//! refused with the file, the line and the field named.

mod common;

use std::path::Path;

use common::{Rng, random_walls, temp_dir};
use locus_map::{Map, MapError, Segment, text, walls_toml};

fn walls() -> Vec<Segment> {
    let mut rng = Rng::new(17);
    let mut w = random_walls(&mut rng, 30, 12.5);
    // Awkward numbers: tiny, huge, negative zero, a zero-length wall.
    w.push(Segment::new([1e-300, -0.0], [1.0 / 3.0, 1e17]));
    w.push(Segment::new([2.5, 2.5], [2.5, 2.5]));
    w
}

#[test]
fn text_and_toml_round_trip_bit_for_bit() {
    let dir = temp_dir("walls");
    let walls = walls();
    for name in ["walls.txt", "walls.toml"] {
        let path = dir.join(name);
        let map = Map::from(locus_map::SegmentMap::new(walls.clone()).unwrap());
        map.save(&path).unwrap();
        let Map::Segments(back) = Map::load(&path).unwrap() else {
            panic!("{name}: not walls")
        };
        assert_eq!(back.segments().len(), walls.len());
        for (a, b) in back.segments().iter().zip(&walls) {
            assert_eq!(
                a.to_array().map(f64::to_bits),
                b.to_array().map(f64::to_bits),
                "{name}"
            );
        }
    }
}

#[test]
fn text_format_comments_and_blank_lines() {
    let src = "# arena\n\n0 0 4 0\n  4\t0 4 3   # east wall\n#\n";
    let w = text::parse(src, Path::new("a.txt")).unwrap();
    assert_eq!(
        w,
        vec![
            Segment::new([0.0, 0.0], [4.0, 0.0]),
            Segment::new([4.0, 0.0], [4.0, 3.0])
        ]
    );
    assert!(text::parse("", Path::new("e.txt")).unwrap().is_empty());
}

/// The error's file, line and field.
fn line_error(src: &str) -> (usize, String, String) {
    match text::parse(src, Path::new("bad.txt")).unwrap_err() {
        MapError::Line {
            file,
            line,
            field,
            reason,
        } => {
            assert_eq!(file, Path::new("bad.txt"));
            (line, field, reason)
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_text_files_name_line_and_field() {
    assert_eq!(line_error("0 0 1 1\n# c\n1 2 3\n").0, 3);
    assert_eq!(line_error("0 0 1 1\n# c\n1 2 3\n").1, "y2");
    let (line, field, reason) = line_error("1 2 x 4");
    assert_eq!((line, field.as_str()), (1, "x2"));
    assert!(reason.contains("\"x\""), "{reason}");
    assert_eq!(line_error("1 2 3 4 5").1, "line");
    assert_eq!(line_error("\n1 NaN 3 4").1, "y1");
    assert_eq!(line_error("\n1 NaN 3 4").0, 2);
    assert_eq!(line_error("inf 2 3 4").1, "x1");
    let shown = text::parse("1 2 3", Path::new("dir/bad.txt"))
        .unwrap_err()
        .to_string();
    assert_eq!(
        shown,
        "dir/bad.txt:1: y2: missing: a wall is `x1 y1 x2 y2` (m)"
    );
    let missing = Map::load(Path::new("/nonexistent/walls.txt")).unwrap_err();
    assert!(matches!(missing, MapError::Io { .. }));
    assert!(
        missing.to_string().starts_with("/nonexistent/walls.txt: "),
        "{missing}"
    );
}

#[test]
fn bad_toml_files_name_line_and_field() {
    let file = Path::new("bad.toml");
    let err = walls_toml::parse(
        "[[wall]]\nfrom = [0, 0]\nto = [1, 1]\n\n[[wall]]\nfrom = [0, 0]\n",
        file,
    )
    .unwrap_err();
    let MapError::Syntax { line, message, .. } = &err else {
        panic!("{err:?}")
    };
    assert!(message.contains("missing field `to`"), "{message}");
    assert_eq!(*line, Some(5), "{err}");
    let err = walls_toml::parse("[[wall]]\nfrom = [0, 0]\nto = [1, \"a\"]\n", file).unwrap_err();
    let MapError::Syntax { line, .. } = &err else {
        panic!("{err:?}")
    };
    assert_eq!(*line, Some(3), "{err}");
    let err =
        walls_toml::parse("[[wall]]\nfrom = [0, 0]\nto = [1, 1]\nheight = 2\n", file).unwrap_err();
    assert!(err.to_string().contains("height"), "{err}");
    let err = walls_toml::parse(
        "[[wall]]\nfrom = [0, 0]\nto = [1, 1]\n[[wall]]\nfrom = [0, inf]\nto = [1, 1]\n",
        file,
    )
    .unwrap_err();
    let MapError::Field { field, .. } = &err else {
        panic!("{err:?}")
    };
    assert_eq!(field, "wall[1].from");
    assert_eq!(
        err.to_string(),
        "bad.toml: wall[1].from: [0.0, inf]: coordinates must be finite"
    );
    assert!(walls_toml::parse("# nothing\n", file).unwrap().is_empty());
}
