//! The firmware's robot end of the link ([`locus_fw_app::link`]), on the
//! host: the recorded run's telemetry frames decode to what the run
//! measured, the 20-bit counts extend across a wrap, commands come back
//! out of their frames and are counted, and the pacing rule.

use locus_fw_app::link::{LinkRobot, STEP_US, acknowledges};
use locus_fw_app::{Firmware, square_data};
use locus_link::framing::{FrameDecoder, MAX_FRAME, encode_frame};
use locus_link::{CommandPacket, NO_ACK, Telemetry};

/// Frames `c` as the host's serial transport sends it.
fn command_frame(c: &CommandPacket) -> Vec<u8> {
    let mut packet = [0u8; 64];
    let n = c.encode(&mut packet).unwrap();
    let mut frame = [0u8; MAX_FRAME];
    let len = encode_frame(&packet[..n], &mut frame).unwrap();
    frame[..len].to_vec()
}

#[test]
fn the_recorded_runs_telemetry_decodes_to_its_counts_and_readings() {
    let mut fw = Firmware::new(&square_data::CONFIG).unwrap();
    let mut robot = LinkRobot::new();
    let mut stream = Vec::new();
    let mut frame = [0u8; MAX_FRAME];
    let n = robot
        .telemetry_frame(0, fw.counts(), None, &mut frame)
        .unwrap();
    stream.extend_from_slice(&frame[..n]);
    for (k, (samples, ir)) in square_data::WAVEFORM
        .iter()
        .zip(square_data::IR.iter())
        .enumerate()
    {
        fw.step(*samples, *ir).unwrap();
        let n = robot
            .telemetry_frame(k as u32 + 1, fw.counts(), *ir, &mut frame)
            .unwrap();
        // 40 bytes of packet, 1 of COBS overhead, 2 delimiters.
        assert_eq!(n, 43);
        stream.extend_from_slice(&frame[..n]);
    }
    assert_eq!(robot.sent(), square_data::STEPS as u64 + 1);

    let mut decoder = FrameDecoder::<MAX_FRAME>::new();
    let mut packets = Vec::new();
    decoder.feed_all(&stream, |f| {
        packets.push(Telemetry::decode(f.unwrap()).unwrap());
    });
    assert_eq!(packets.len(), square_data::STEPS + 1);
    assert_eq!(decoder.counters().dropped(), 0);
    for (k, t) in packets.iter().enumerate() {
        assert_eq!(t.sequence, k as u32);
        assert_eq!(t.timestamp_us, k as u64 * STEP_US);
        let ir = if k == 0 { None } else { square_data::IR[k - 1] };
        assert_eq!(t.ir, ir, "telemetry {k}");
    }
    assert_eq!(packets[0].counts, [0, 0]);
    // The simulator's cumulative counts, as the link carries them.
    let last = packets.last().unwrap().counts;
    assert_eq!(last.map(i64::from), square_data::SIM_COUNTS);
    assert_eq!(robot.counts(), last);
    let readings = packets.iter().filter(|t| t.ir.is_some()).count();
    assert_eq!(readings, 1812);
}

#[test]
fn counts_extend_across_the_20_bit_wrap_both_ways() {
    let mut robot = LinkRobot::new();
    let top = (1u32 << 20) - 1;
    // Backwards from 0: the 20-bit counter wraps to its top, the link's
    // count to 2^32 - 1.
    assert_eq!(robot.extend([top, 3]), [u32::MAX, 3]);
    assert_eq!(robot.extend([top - 4, 7]), [u32::MAX - 4, 7]);
    // Forwards across the wrap again.
    assert_eq!(robot.extend([2, 7]), [2, 7]);
    // A whole turn of the 20-bit counter in steps of 2^18: the link's count
    // goes on past 2^20.
    let mut now = 2u32;
    for _ in 0..4 {
        now = (now + (1 << 18)) & top;
        robot.extend([now, 7]);
    }
    assert_eq!(robot.counts(), [2 + (1 << 20), 7]);
}

#[test]
fn commands_come_out_of_their_frames_and_are_counted() {
    let mut robot = LinkRobot::new();
    let c0 = CommandPacket {
        sequence: 0,
        ack: NO_ACK,
        right: 0.0,
        left: 0.0,
    };
    let c1 = CommandPacket {
        sequence: 1,
        ack: 0,
        right: 0.25,
        left: -0.125,
    };
    let mut got = Vec::new();
    let mut bytes = vec![0x55, 0x13]; // line noise before the first frame
    bytes.extend(command_frame(&c0));
    bytes.extend(command_frame(&c1));
    bytes.extend(command_frame(&c1)); // a duplicate
    let mut damaged = command_frame(&CommandPacket { sequence: 2, ..c1 });
    damaged[5] ^= 0x40; // a flipped bit: the CRC fails
    bytes.extend(damaged);
    for b in bytes {
        got.extend(robot.push(b));
    }
    assert_eq!(got, [c0, c1]);
    let c = robot.commands();
    assert_eq!((c.applied, c.duplicate, c.corrupt), (2, 1, 1));
    assert_eq!(robot.framing().frames, 4);
    // The noise and the delimiter that ended it (FrameCounters::discarded).
    assert_eq!(robot.framing().discarded, 3);
}

#[test]
fn a_command_paces_the_packet_it_acknowledges_and_those_before() {
    assert!(acknowledges(5, 5));
    assert!(acknowledges(6, 5));
    assert!(!acknowledges(4, 5));
    assert!(!acknowledges(NO_ACK, 5));
    assert!(acknowledges(1, u32::MAX - 1)); // across the wrap
    assert!(!acknowledges(5 + (1 << 31), 5));
}
