//! Fuzzes the decoder: no input panics; an input that decodes re-encodes to
//! exactly its bytes (so every other input is an error); the receiver
//! counts every packet in exactly one class.
#![no_main]

use libfuzzer_sys::fuzz_target;
use locus_link::{MAX_PACKET, Packet, Receiver, decode};

fuzz_target!(|data: &[u8]| {
    let mut rx = Receiver::new();
    match decode(data) {
        Ok(p) => {
            let mut buf = [0u8; MAX_PACKET];
            let n = match p {
                Packet::Telemetry(t) => t.encode(&mut buf).unwrap(),
                Packet::Command(c) => c.encode(&mut buf).unwrap(),
            };
            assert_eq!(&buf[..n], data, "accepted input is not canonical");
            if let Packet::Telemetry(_) = p {
                rx.receive_telemetry(data).unwrap();
                assert_eq!(rx.counters().applied, 1);
            }
        }
        Err(e) => {
            assert!(rx.receive_telemetry(data).is_err());
            let c = rx.counters();
            assert_eq!(c.corrupt + c.malformed, 1);
            assert_eq!(c.corrupt == 1, e.is_corrupt());
        }
    }
});
