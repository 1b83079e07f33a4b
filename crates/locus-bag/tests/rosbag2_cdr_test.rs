//! A bag written by rosbag2 itself (`../shared/data/rosbag2_cdr_test`:
//! rosbag2's own test resource `cdr_test`, MCAP with CDR messages and the
//! `ros2msg` schemas inside), decoded field by field against the values it
//! holds: ROS 2's test fixtures as rosbag2's end-to-end play test asserts
//! them (`test_msgs/msg/BasicTypes`: `get_messages_basic_types()[0]`, all
//! zero, with `int32_value` 123; `test_msgs/msg/Arrays`: a default
//! `Arrays` with `bool_values` {true, false, true} and `string_values`
//! {"Complex Hello1", "Complex Hello2", "Complex Hello3"}; its
//! `*_default` arrays and its `Defaults` members hold the defaults that
//! test_msgs' `.msg` files declare). Then the same file damaged (cut
//! short, a byte flipped), and bags written here with the `mcap` crate
//! that a robot's recorder should never write (a schema that does not
//! parse, a count of a billion, an encoding that is not CDR): each is a
//! clear error naming the record, never a panic or a large allocation.
//! The data is read from `../shared/data`; the tests are skipped without
//! it.

extern crate alloc;

use alloc::collections::BTreeMap;
use std::path::{Path, PathBuf};

use locus_bag::{BagError, Value, read, topics};

fn bag() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/rosbag2_cdr_test/cdr_test_0.mcap");
    if p.is_file() {
        Some(p)
    } else {
        eprintln!("skipped: {} not found", p.display());
        None
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("locus-bag-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every message of the bag at `path`, decoded: (topic, log time, value).
fn decoded(path: &Path) -> Result<Vec<(String, u64, Value)>, BagError> {
    let mut out = Vec::new();
    read(path, |c, m| {
        out.push((c.topic.clone(), m.log_time_ns, c.decode(path, m)?));
        Ok(())
    })?;
    Ok(out)
}

fn num(v: &Value, path: &str) -> f64 {
    v.get(path)
        .and_then(Value::as_f64)
        .unwrap_or_else(|| panic!("{path}"))
}

fn nums(v: &Value, path: &str) -> Vec<f64> {
    v.get(path)
        .and_then(Value::as_list)
        .unwrap_or_else(|| panic!("{path}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn strs(v: &Value, path: &str) -> Vec<String> {
    v.get(path)
        .and_then(Value::as_list)
        .unwrap_or_else(|| panic!("{path}"))
        .iter()
        .map(|x| x.as_str().unwrap().to_string())
        .collect()
}

const BASIC: [&str; 13] = [
    "bool_value",
    "byte_value",
    "char_value",
    "float32_value",
    "float64_value",
    "int8_value",
    "uint8_value",
    "int16_value",
    "uint16_value",
    "int32_value",
    "uint32_value",
    "int64_value",
    "uint64_value",
];

/// test_msgs' `Defaults.msg` defaults, in `BASIC`'s order.
#[allow(clippy::cast_precision_loss)]
const DEFAULTS: [f64; 13] = [
    1.0,
    50.0,
    100.0,
    1.125,
    1.125,
    -50.0,
    200.0,
    -1000.0,
    2000.0,
    -30000.0,
    60000.0,
    -40_000_000.0,
    50_000_000.0,
];

#[test]
fn a_bag_written_by_rosbag2_decodes_field_by_field() {
    let Some(path) = bag() else { return };
    let t = topics(&path).unwrap();
    let listed: Vec<_> = t
        .iter()
        .map(|t| (t.topic.as_str(), t.type_name.as_str(), t.count))
        .collect();
    assert_eq!(
        listed,
        [
            ("/test_topic", "test_msgs/msg/BasicTypes", 3),
            ("/array_topic", "test_msgs/msg/Arrays", 4)
        ]
    );
    assert!(t.iter().all(|t| t.undecodable.is_none()));
    assert_eq!(t[0].first_ns, 1_586_406_456_763_032_325);
    assert_eq!(t[1].last_ns, 1_586_406_456_914_169_506);

    let messages = decoded(&path).unwrap();
    assert_eq!(messages.len(), 7);
    for (topic, _, v) in &messages {
        if topic == "/test_topic" {
            for f in BASIC {
                let want = if f == "int32_value" { 123.0 } else { 0.0 };
                assert_eq!(num(v, f), want, "{f}");
            }
            assert_eq!(v.get("int32_value"), Some(&Value::Int(123)));
            continue;
        }
        assert_eq!(topic, "/array_topic");
        assert_eq!(
            v.get("bool_values"),
            Some(&Value::List(vec![
                Value::Bool(true),
                Value::Bool(false),
                Value::Bool(true)
            ]))
        );
        assert_eq!(
            strs(v, "string_values"),
            ["Complex Hello1", "Complex Hello2", "Complex Hello3"]
        );
        for f in &BASIC[1..] {
            let array = f.replace("_value", "_values");
            assert_eq!(nums(v, &array), [0.0; 3], "{array}");
        }
        for k in 0..3 {
            for f in BASIC {
                assert_eq!(num(v, &format!("basic_types_values[{k}].{f}")), 0.0);
                let d = num(v, &format!("defaults_values[{k}].{f}"));
                let i = BASIC.iter().position(|b| *b == f).unwrap();
                assert_eq!(d, DEFAULTS[i], "defaults_values[{k}].{f}");
            }
        }
        assert_eq!(
            v.get("constants_values")
                .and_then(Value::as_list)
                .map(<[Value]>::len),
            Some(3)
        );
        // The arrays' declared defaults (Arrays.msg).
        assert_eq!(nums(v, "bool_values_default"), [0.0, 1.0, 0.0]);
        assert_eq!(nums(v, "byte_values_default"), [0.0, 1.0, 255.0]);
        assert_eq!(nums(v, "char_values_default"), [0.0, 1.0, 127.0]);
        assert_eq!(nums(v, "float32_values_default"), [1.125, 0.0, -1.125]);
        // Arrays.msg declares 3.1415 (not pi).
        #[allow(clippy::approx_constant)]
        let declared = [3.1415, 0.0, -3.1415];
        assert_eq!(nums(v, "float64_values_default"), declared);
        assert_eq!(nums(v, "int8_values_default"), [0.0, 127.0, -128.0]);
        assert_eq!(nums(v, "uint8_values_default"), [0.0, 1.0, 255.0]);
        assert_eq!(nums(v, "int16_values_default"), [0.0, 32767.0, -32768.0]);
        assert_eq!(nums(v, "uint16_values_default"), [0.0, 1.0, 65535.0]);
        assert_eq!(
            v.get("int32_values_default[2]"),
            Some(&Value::Int(i64::from(i32::MIN)))
        );
        assert_eq!(
            v.get("uint32_values_default[2]"),
            Some(&Value::UInt(u64::from(u32::MAX)))
        );
        assert_eq!(
            v.get("int64_values_default[1]"),
            Some(&Value::Int(i64::MAX))
        );
        assert_eq!(
            v.get("int64_values_default[2]"),
            Some(&Value::Int(i64::MIN))
        );
        assert_eq!(
            v.get("uint64_values_default[2]"),
            Some(&Value::UInt(u64::MAX))
        );
        assert_eq!(
            strs(v, "string_values_default"),
            ["", "max value", "min value"]
        );
        assert_eq!(v.get("alignment_check"), Some(&Value::Int(0)));
    }
}

#[test]
fn a_damaged_bag_is_an_error_naming_the_record() {
    let Some(path) = bag() else { return };
    let bytes = std::fs::read(&path).unwrap();
    let dir = scratch("damaged");

    // Cut short in the middle of its chunk.
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = decoded(&cut).unwrap_err().to_string();
    assert!(
        e.contains("cut.mcap: record ") && e.contains("ended in the middle of a record"),
        "{e}"
    );

    // rosbag2 wrote this file without CRCs (they are 0, "not computed");
    // a byte flipped in a bag with CRCs is in the hostile test below.

    // Not an MCAP file at all.
    let text = dir.join("text.mcap");
    std::fs::write(&text, "time,x,y\n0,1,2\n").unwrap();
    let e = decoded(&text).unwrap_err().to_string();
    assert!(e.contains("text.mcap: record 1"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A bag of one channel written with the `mcap` crate (zstd chunks with
/// CRCs, its default): its type `name`, schema `text`, message encoding and
/// messages.
fn write_bag(path: &Path, name: &str, text: &str, encoding: &str, messages: &[Vec<u8>]) {
    write_bag_with(
        path,
        name,
        text,
        encoding,
        messages,
        mcap::WriteOptions::new(),
    );
}

/// As [`write_bag`], with the writer's `options`.
fn write_bag_with(
    path: &Path,
    name: &str,
    text: &str,
    encoding: &str,
    messages: &[Vec<u8>],
    options: mcap::WriteOptions,
) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::Writer::with_options(file, options).unwrap();
    let schema = w.add_schema(name, "ros2msg", text.as_bytes()).unwrap();
    let channel = w
        .add_channel(schema, "/odom", encoding, &BTreeMap::new())
        .unwrap();
    for (i, m) in messages.iter().enumerate() {
        let t = 1_000_000_000 + 100_000_000 * i as u64;
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: u32::try_from(i).unwrap(),
            log_time: t,
            publish_time: t,
        };
        w.write_to_known_channel(&header, m).unwrap();
    }
    w.finish().unwrap();
}

#[test]
fn hostile_bags_are_errors_naming_the_record_and_the_field() {
    let dir = scratch("hostile");
    let good = {
        let mut b = vec![0, 1, 0, 0];
        b.extend_from_slice(&2u32.to_le_bytes());
        b.extend_from_slice(&[0; 4]);
        b.extend_from_slice(&1.5f64.to_le_bytes());
        b.extend_from_slice(&2.5f64.to_le_bytes());
        b
    };
    // A good one first: two messages, the second read back.
    let p = dir.join("good.mcap");
    let mut second = good.clone();
    second[20..28].copy_from_slice(&2.75f64.to_le_bytes());
    write_bag(
        &p,
        "p/msg/V",
        "float64[] v\n",
        "cdr",
        &[good.clone(), second],
    );
    let m = decoded(&p).unwrap();
    assert_eq!(m.len(), 2);
    assert_eq!(nums(&m[0].2, "v"), [1.5, 2.5]);
    assert_eq!(nums(&m[1].2, "v"), [1.5, 2.75]);

    // A count of a billion doubles in a 28-byte message.
    let mut huge = good.clone();
    huge[4..8].copy_from_slice(&1_000_000_000u32.to_le_bytes());
    let p = dir.join("huge.mcap");
    write_bag(&p, "p/msg/V", "float64[] v\n", "cdr", &[good.clone(), huge]);
    let e = decoded(&p).unwrap_err().to_string();
    assert!(e.contains("huge.mcap: record "), "{e}");
    assert!(
        e.contains("message on /odom at 1100000000 ns (p/msg/V): field v at byte 8: 1000000000 elements cannot fit"),
        "{e}"
    );

    // A schema that does not parse: listed as undecodable, refused when
    // decoded, with the schema's line.
    let p = dir.join("schema.mcap");
    write_bag(
        &p,
        "p/msg/V",
        "float64[] v\nnot_a_type!\n",
        "cdr",
        core::slice::from_ref(&good),
    );
    let t = topics(&p).unwrap();
    let why = t[0].undecodable.clone().unwrap();
    assert!(why.contains("schema p/msg/V, line 2"), "{why}");
    let e = decoded(&p).unwrap_err().to_string();
    assert!(
        e.contains("schema.mcap: topic /odom: schema p/msg/V, line 2"),
        "{e}"
    );

    // A byte of a message flipped in a bag whose chunks carry CRCs (the
    // `mcap` crate writes them), uncompressed so the byte can be found.
    let p = dir.join("plain.mcap");
    write_bag_with(
        &p,
        "p/msg/V",
        "float64[] v\n",
        "cdr",
        core::slice::from_ref(&good),
        mcap::WriteOptions::new().compression(None),
    );
    assert_eq!(decoded(&p).unwrap().len(), 1);
    let mut bytes = std::fs::read(&p).unwrap();
    let at = bytes
        .windows(8)
        .position(|w| w == 2.5f64.to_le_bytes())
        .unwrap();
    bytes[at] ^= 0x01;
    let p = dir.join("crc.mcap");
    std::fs::write(&p, &bytes).unwrap();
    let e = decoded(&p).unwrap_err().to_string();
    assert!(
        e.contains("crc.mcap: record ") && e.contains("Chunk CRC failed"),
        "{e}"
    );

    // A channel that is not CDR.
    let p = dir.join("json.mcap");
    write_bag(
        &p,
        "p/msg/V",
        "float64[] v\n",
        "json",
        &[b"{\"v\": [1]}".to_vec()],
    );
    let e = decoded(&p).unwrap_err().to_string();
    assert!(
        e.contains("json.mcap: topic /odom: message encoding \"json\""),
        "{e}"
    );

    // A message in another CDR representation (XCDR2).
    let mut xcdr2 = good;
    xcdr2[1] = 0x07;
    let p = dir.join("xcdr2.mcap");
    write_bag(&p, "p/msg/V", "float64[] v\n", "cdr", &[xcdr2]);
    let e = decoded(&p).unwrap_err().to_string();
    assert!(
        e.contains("encapsulation 0x0007 (XCDR2 little-endian)"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A velocity topic's messages after the first go through the projection
/// of its mapped numbers: the same figures as the full decoder's, and a
/// damaged later message is still an error naming its record and field,
/// whether the field is read or skipped.
#[test]
fn later_messages_of_a_mapped_topic_read_alike_and_fail_alike() {
    let dir = scratch("fast");
    let schema = "std_msgs/Header header\nfloat64[] v\nfloat64 speed\nfloat64 turn\n\
        ===\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n";
    let msg = |sec: i32, ns: u32, speed: f64, turn: f64, count: u32| {
        let mut b = vec![0, 1, 0, 0];
        b.extend_from_slice(&sec.to_le_bytes());
        b.extend_from_slice(&ns.to_le_bytes());
        b.extend_from_slice(&5u32.to_le_bytes());
        b.extend_from_slice(b"base\0");
        b.extend_from_slice(&[0, 0, 0]);
        b.extend_from_slice(&count.to_le_bytes());
        b.extend_from_slice(&speed.to_le_bytes());
        b.extend_from_slice(&turn.to_le_bytes());
        b
    };
    let mapping = locus_bag::Mapping::from_toml(
        "base_frame = \"base\"\n[velocity]\ntopic = \"/odom\"\nlinear = \"speed\"\nangular = \"turn\"\n",
        "m.toml",
    )
    .unwrap();
    let good: Vec<Vec<u8>> = (0..4)
        .map(|i| msg(10 + i, 250_000_000, 0.1 * f64::from(i), -0.3, 0))
        .collect();
    let p = dir.join("fast.mcap");
    write_bag(&p, "p/msg/V", schema, "cdr", &good);
    let log = locus_bag::convert::to_locus(&p, &mapping, "m.toml").unwrap();
    let want: Vec<(f64, f64, f64)> = (0..4)
        .map(|i| (f64::from(10 + i) + 0.25, 0.1 * f64::from(i), -0.3))
        .collect();
    let got: Vec<(f64, f64, f64)> = log
        .odometry
        .iter()
        .map(|o| (o.time, o.v, o.omega))
        .collect();
    assert_eq!(got, want);
    // A skipped sequence claiming a billion elements, in the third message.
    let mut bad = good.clone();
    bad[2] = msg(12, 0, 0.0, 0.0, 1_000_000_000);
    write_bag(&p, "p/msg/V", schema, "cdr", &bad);
    let e = locus_bag::convert::to_locus(&p, &mapping, "m.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("message on /odom at 1200000000 ns (p/msg/V): field v at byte 28: 1000000000 elements cannot fit"), "{e}");
    // A read field cut short.
    let mut bad = good.clone();
    let cut = bad[3].len() - 4;
    bad[3].truncate(cut);
    write_bag(&p, "p/msg/V", schema, "cdr", &bad);
    let e = locus_bag::convert::to_locus(&p, &mapping, "m.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("field turn at byte 36: needs 8 bytes"), "{e}");
    // A velocity going back in time, named by the time it has.
    let mut bad = good;
    bad[3] = msg(11, 0, 0.0, 0.0, 0);
    write_bag(&p, "p/msg/V", schema, "cdr", &bad);
    let e = locus_bag::convert::to_locus(&p, &mapping, "m.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("velocity at 11 s is before the one before it"),
        "{e}"
    );
}

#[test]
fn a_mapping_file_names_its_map_relative_to_itself() {
    let dir = scratch("read_log");
    let twist = |speed: f64, turn: f64| {
        let mut b = vec![0, 1, 0, 0];
        for x in [speed, 0.0, 0.0, 0.0, 0.0, turn] {
            b.extend_from_slice(&x.to_le_bytes());
        }
        b
    };
    let schema = "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n\
        ===\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";
    let bag = dir.join("run.mcap");
    write_bag(
        &bag,
        "geometry_msgs/msg/Twist",
        schema,
        "cdr",
        &[twist(0.1, 0.0), twist(0.2, -0.1)],
    );
    let robot = dir.join("robot");
    std::fs::create_dir_all(&robot).unwrap();
    let mapping = robot.join("mapping.toml");
    let velocity = "[velocity]\ntopic = \"/odom\"\n";

    std::fs::write(&mapping, format!("map = \"maps/lab.txt\"\n{velocity}")).unwrap();
    let log = locus_bag::read_log(&bag, &mapping).unwrap();
    assert_eq!(log.odometry.len(), 2);
    assert_eq!(
        Path::new(log.map.as_ref().unwrap().as_str()),
        robot.join("maps/lab.txt")
    );

    std::fs::write(&mapping, velocity).unwrap();
    assert!(locus_bag::read_log(&bag, &mapping).unwrap().map.is_none());

    let both =
        format!("map = \"lab.txt\"\n{velocity}[[wall]]\nx1 = 0.0\ny1 = 0.0\nx2 = 1.0\ny2 = 0.0\n");
    std::fs::write(&mapping, both).unwrap();
    let e = locus_bag::read_log(&bag, &mapping).unwrap_err().to_string();
    assert!(
        e.contains("mapping.toml: map: give the map as `map` or as [[wall]] entries, not both"),
        "{e}"
    );

    std::fs::write(&mapping, format!("map = \"a,b.txt\"\n{velocity}")).unwrap();
    let e = locus_bag::read_log(&bag, &mapping).unwrap_err().to_string();
    assert!(e.contains("mapping.toml: map: a map path must not"), "{e}");

    std::fs::write(&mapping, format!("{velocity}topics = 3\n")).unwrap();
    let e = locus_bag::read_log(&bag, &mapping).unwrap_err().to_string();
    assert!(e.contains("mapping.toml:3:"), "{e}");

    let missing = robot.join("none.toml");
    let e = locus_bag::read_log(&bag, &missing).unwrap_err().to_string();
    assert!(e.contains("none.toml"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
