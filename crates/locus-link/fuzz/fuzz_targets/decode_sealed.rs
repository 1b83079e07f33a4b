//! Fuzzes the decoder past the CRC: the input gets a valid CRC-32 appended,
//! so the header, length, reserved-field and value checks are reached. No
//! input panics; an input that decodes re-encodes to exactly its bytes; every
//! rejection is a malformed (not corrupt) error.
#![no_main]

use libfuzzer_sys::fuzz_target;
use locus_link::{MAX_PACKET, Packet, decode};

const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

fuzz_target!(|data: &[u8]| {
    if data.len() > 2 * MAX_PACKET {
        return;
    }
    let mut packet = [0u8; 2 * MAX_PACKET + 4];
    let n = data.len();
    packet[..n].copy_from_slice(data);
    packet[n..n + 4].copy_from_slice(&CRC.checksum(data).to_le_bytes());
    let packet = &packet[..n + 4];
    match decode(packet) {
        Ok(p) => {
            let mut buf = [0u8; MAX_PACKET];
            let m = match p {
                Packet::Telemetry(t) => t.encode(&mut buf).unwrap(),
                Packet::Command(c) => c.encode(&mut buf).unwrap(),
            };
            assert_eq!(&buf[..m], packet, "accepted input is not canonical");
        }
        Err(e) => assert!(!e.is_corrupt(), "sealed input reported corrupt: {e:?}"),
    }
});
