//! Codec properties: round trip of every valid packet, and arbitrary bytes
//! never panic the decoder (every input that is not a valid packet is an
//! error, and every accepted input re-encodes to the same bytes).

use locus_link::{
    COMMAND_LEN, CommandPacket, Error, MAX_BEAMS, MAX_PACKET, Packet, Receiver, Telemetry, decode,
};
use proptest::prelude::*;

fn telemetry() -> impl Strategy<Value = Telemetry> {
    (
        any::<u32>(),
        any::<u64>(),
        any::<[u32; 2]>(),
        proptest::option::of([-1e6f32..1e6, -1e6f32..1e6]),
        proptest::collection::vec(-1e6f32..1e6, 0..=MAX_BEAMS),
    )
        .prop_map(|(seq, ts, counts, ir, beams)| {
            let mut t = Telemetry::new(seq, ts);
            t.counts = counts;
            t.ir = ir;
            t.set_beams(&beams).unwrap();
            t
        })
}

fn command() -> impl Strategy<Value = CommandPacket> {
    (any::<u32>(), any::<u32>(), -1e3f32..1e3, -1e3f32..1e3).prop_map(
        |(sequence, ack, right, left)| CommandPacket {
            sequence,
            ack,
            right,
            left,
        },
    )
}

/// Re-encodes a decoded packet.
fn encode(p: &Packet, buf: &mut [u8]) -> usize {
    match p {
        Packet::Telemetry(t) => t.encode(buf).unwrap(),
        Packet::Command(c) => c.encode(buf).unwrap(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn telemetry_round_trip(t in telemetry()) {
        let mut buf = [0u8; MAX_PACKET];
        let n = t.encode(&mut buf).unwrap();
        prop_assert_eq!(n, t.encoded_len());
        prop_assert_eq!(Telemetry::decode(&buf[..n]), Ok(t));
        prop_assert_eq!(decode(&buf[..n]), Ok(Packet::Telemetry(t)));
    }

    #[test]
    fn command_round_trip(c in command()) {
        let mut buf = [0u8; COMMAND_LEN];
        prop_assert_eq!(c.encode(&mut buf), Ok(COMMAND_LEN));
        prop_assert_eq!(CommandPacket::decode(&buf), Ok(c));
    }

    /// Any single bit flipped in a valid packet is a CRC error (CRC-32
    /// detects every 1-bit error).
    #[test]
    fn a_flipped_bit_is_corrupt(t in telemetry(), bit in 0usize..8 * MAX_PACKET) {
        let mut buf = [0u8; MAX_PACKET];
        let n = t.encode(&mut buf).unwrap();
        let bit = bit % (8 * n);
        buf[bit / 8] ^= 1 << (bit % 8);
        let mut rx = Receiver::new();
        let e = rx.receive_telemetry(&buf[..n]).unwrap_err();
        prop_assert!(e.is_corrupt(), "{e:?}");
        prop_assert_eq!(rx.counters().corrupt, 1);
    }

    /// Arbitrary bytes: no panic; whatever decodes is canonical (encodes
    /// back to exactly the input), so every other input is an error.
    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2 * MAX_PACKET)) {
        if let Ok(p) = decode(&bytes) {
            let mut buf = [0u8; MAX_PACKET];
            let n = encode(&p, &mut buf);
            prop_assert_eq!(&buf[..n], &bytes[..]);
        }
    }

    /// Bytes with a valid CRC (so the later checks are reached): no panic,
    /// canonical when accepted, and a typed malformed error otherwise.
    #[test]
    fn sealed_arbitrary_bytes_never_panic(
        mut bytes in proptest::collection::vec(any::<u8>(), 4..2 * MAX_PACKET),
        header in any::<bool>(),
        kind in 0u8..4,
    ) {
        if header && bytes.len() >= 12 {
            bytes[0] = b'L';
            bytes[1] = b'K';
            bytes[2] = 1;
            bytes[3] = kind;
        }
        let n = bytes.len() - 4;
        let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&bytes[..n]);
        bytes[n..].copy_from_slice(&crc.to_le_bytes());
        match decode(&bytes) {
            Ok(p) => {
                let mut buf = [0u8; MAX_PACKET];
                let m = encode(&p, &mut buf);
                prop_assert_eq!(&buf[..m], &bytes[..]);
            }
            Err(e) => prop_assert!(!e.is_corrupt(), "{e:?}"),
        }
    }
}

#[test]
fn typed_errors() {
    let mut buf = [0u8; MAX_PACKET];
    let mut t = Telemetry::new(3, 4);
    t.set_beams(&[1.0, 2.0]).unwrap();
    let n = t.encode(&mut buf).unwrap();
    assert_eq!(decode(&buf[..3]), Err(Error::TooShort { len: 3 }));
    // Re-seal after each edit so the check after the CRC is reached.
    let reseal = |b: &mut [u8]| {
        let m = b.len() - 4;
        let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&b[..m]);
        b[m..].copy_from_slice(&crc.to_le_bytes());
    };
    let mut b = buf;
    b[2] = 9;
    reseal(&mut b[..n]);
    assert_eq!(decode(&b[..n]), Err(Error::BadVersion { version: 9 }));
    let mut b = buf;
    b[0] = b'X';
    reseal(&mut b[..n]);
    assert_eq!(decode(&b[..n]), Err(Error::BadMagic));
    let mut b = buf;
    b[3] = 7;
    reseal(&mut b[..n]);
    assert_eq!(decode(&b[..n]), Err(Error::BadKind { kind: 7 }));
    let mut b = buf;
    b[25] = 3;
    reseal(&mut b[..n]);
    assert_eq!(
        decode(&b[..n]),
        Err(Error::BadLength {
            expected: 52,
            len: 48
        })
    );
    let mut b = buf;
    b[25] = 17;
    reseal(&mut b[..n]);
    assert_eq!(decode(&b[..n]), Err(Error::TooManyBeams { count: 17 }));
    let mut b = buf;
    b[36..40].copy_from_slice(&f32::NAN.to_le_bytes());
    reseal(&mut b[..n]);
    assert_eq!(decode(&b[..n]), Err(Error::NonFinite));
    let mut b = buf;
    b[26] = 1;
    reseal(&mut b[..n]);
    assert_eq!(decode(&b[..n]), Err(Error::Reserved));
    assert_eq!(
        t.encode(&mut buf[..10]),
        Err(Error::BufferTooSmall {
            needed: 48,
            len: 10
        })
    );
    assert_eq!(
        t.set_beams(&[0.0; 17]),
        Err(Error::TooManyBeams { count: 17 })
    );
    assert_eq!(
        CommandPacket::decode(&buf[..n]),
        Err(Error::BadKind { kind: 1 })
    );
}
