//! Byte-stream framing (COBS, `framing.rs`): round trip of any packet, the
//! published COBS examples, a streaming decoder that agrees with a
//! split-on-zero reference decoder on arbitrary bytes and accounts for
//! every byte, frames that survive garbage, damaged bytes that cost at most
//! the packet they fall in, independence from how the stream is chunked,
//! and no allocation.

use locus_link::{
    DELIMITER, FrameCounters, FrameDecoder, FrameError, MAX_BEAMS, MAX_FRAME, MAX_PACKET, Receiver,
    Telemetry, encode_frame, frame_len, max_frame_len,
};
use proptest::prelude::*;

/// One decoder event, owned.
type Event = Result<Vec<u8>, FrameError>;

/// `packet` framed by `encode_frame`, with the checks every frame must pass:
/// the length is `frame_len`, within `max_frame_len`, delimited at both ends
/// and free of `0x00` inside.
fn frame(packet: &[u8]) -> Vec<u8> {
    let mut out = vec![0xAA; max_frame_len(packet.len())];
    let n = encode_frame(packet, &mut out).unwrap();
    assert_eq!(n, frame_len(packet));
    out.truncate(n);
    assert_eq!(out[0], DELIMITER);
    assert_eq!(out[n - 1], DELIMITER);
    assert!(!out[1..n - 1].contains(&DELIMITER), "{out:x?}");
    out
}

/// Every event of `bytes` pushed one at a time into `d`.
fn push_all<const N: usize>(d: &mut FrameDecoder<N>, bytes: &[u8]) -> Vec<Event> {
    let mut events = Vec::new();
    for &b in bytes {
        if let Some(e) = d.push(b) {
            events.push(e.map(<[u8]>::to_vec));
        }
    }
    events
}

/// The accounting identity: every pushed byte is in exactly one place.
fn accounted<const N: usize>(d: &FrameDecoder<N>, pushed: usize) -> bool {
    let c = d.counters();
    c.frame_bytes + c.discarded + c.empty + d.pending() == pushed as u64
}

/// A reference decoder written differently from the streaming one: split the
/// stream on `0x00`, throw away what precedes the first delimiter, and decode
/// each complete piece as a whole. A piece whose decoded bytes exceed `cap`
/// is oversize (the streaming decoder finds that before the delimiter, so
/// an unterminated last piece can be oversize too); a piece whose last code
/// byte points past its end is malformed. Returns the events and the
/// counters the streaming decoder must report.
fn reference(bytes: &[u8], cap: usize) -> (Vec<Event>, FrameCounters, u64) {
    let mut events = Vec::new();
    let mut c = FrameCounters::default();
    let mut pending = 0;
    let pieces: Vec<&[u8]> = bytes.split(|&b| b == DELIMITER).collect();
    let last = pieces.len() - 1;
    for (k, piece) in pieces.iter().enumerate() {
        let terminated = k < last;
        let n = piece.len() as u64;
        if k == 0 {
            // Before the first delimiter: discarded (an empty piece ended
            // by a delimiter is an empty frame).
            if terminated && piece.is_empty() {
                c.empty += 1;
            } else {
                c.discarded += n + u64::from(terminated);
            }
            continue;
        }
        if piece.is_empty() {
            c.empty += u64::from(terminated);
            continue;
        }
        let (out, complete) = cobs_decode(piece);
        if out.len() > cap {
            c.oversize += 1;
            c.discarded += n + u64::from(terminated);
            events.push(Err(FrameError::Oversize { capacity: cap }));
        } else if !terminated {
            pending = n;
        } else if !complete {
            c.malformed += 1;
            c.discarded += n + 1;
            events.push(Err(FrameError::Malformed));
        } else {
            c.frames += 1;
            c.frame_bytes += n + 1;
            events.push(Ok(out));
        }
    }
    (events, c, pending)
}

/// Whole-piece COBS decoding: the bytes decoded and whether the last block
/// was complete.
fn cobs_decode(piece: &[u8]) -> (Vec<u8>, bool) {
    let mut out = Vec::new();
    let mut i = 0;
    while i < piece.len() {
        let code = usize::from(piece[i]);
        let end = i + code;
        out.extend_from_slice(&piece[i + 1..end.min(piece.len())]);
        if end > piece.len() {
            return (out, false);
        }
        if code < 0xFF && end < piece.len() {
            out.push(0);
        }
        i = end;
    }
    (out, true)
}

/// Bytes with many zeros and many runs (so every COBS case is common).
fn bytes_with_zeros(max: usize) -> impl Strategy<Value = Vec<u8>> {
    proptest::collection::vec(prop_oneof![3 => Just(0u8), 10 => any::<u8>()], 0..=max)
}

fn telemetry() -> impl Strategy<Value = Telemetry> {
    (
        any::<u64>(),
        any::<[u32; 2]>(),
        proptest::option::of([0f32..4.0, 0f32..4.0]),
        proptest::collection::vec(0f32..10.0, 0..=MAX_BEAMS),
    )
        .prop_map(|(ts, counts, ir, beams)| {
            let mut t = Telemetry::new(0, ts);
            t.counts = counts;
            t.ir = ir;
            t.set_beams(&beams).unwrap();
            t
        })
}

/// `t` encoded and framed.
fn framed(t: &Telemetry) -> Vec<u8> {
    let mut packet = [0u8; MAX_PACKET];
    let n = t.encode(&mut packet).unwrap();
    frame(&packet[..n])
}

/// The examples of the COBS article (Wikipedia, "Consistent Overhead Byte
/// Stuffing"), each as `encode_frame` writes it: a leading `0x00` and the
/// article's encoding with its trailing `0x00`.
#[test]
fn published_examples_byte_for_byte() {
    let seq = |a: u8, b: u8| (a..=b).collect::<Vec<u8>>();
    let cat = |parts: &[&[u8]]| parts.concat();
    let cases: Vec<(Vec<u8>, Vec<u8>)> = vec![
        (vec![], vec![0x01, 0x00]),
        (vec![0x00], vec![0x01, 0x01, 0x00]),
        (vec![0x00, 0x00], vec![0x01, 0x01, 0x01, 0x00]),
        (vec![0x00, 0x11, 0x00], vec![0x01, 0x02, 0x11, 0x01, 0x00]),
        (
            vec![0x11, 0x22, 0x00, 0x33],
            vec![0x03, 0x11, 0x22, 0x02, 0x33, 0x00],
        ),
        (
            vec![0x11, 0x22, 0x33, 0x44],
            vec![0x05, 0x11, 0x22, 0x33, 0x44, 0x00],
        ),
        (
            vec![0x11, 0x00, 0x00, 0x00],
            vec![0x02, 0x11, 0x01, 0x01, 0x01, 0x00],
        ),
        (seq(0x01, 0xFE), cat(&[&[0xFF], &seq(0x01, 0xFE), &[0x00]])),
        (
            cat(&[&[0x00], &seq(0x01, 0xFE)]),
            cat(&[&[0x01, 0xFF], &seq(0x01, 0xFE), &[0x00]]),
        ),
        (
            seq(0x01, 0xFF),
            cat(&[&[0xFF], &seq(0x01, 0xFE), &[0x02, 0xFF, 0x00]]),
        ),
        (
            cat(&[&seq(0x02, 0xFF), &[0x00]]),
            cat(&[&[0xFF], &seq(0x02, 0xFF), &[0x01, 0x01, 0x00]]),
        ),
        (
            cat(&[&seq(0x03, 0xFF), &[0x00, 0x01]]),
            cat(&[&[0xFE], &seq(0x03, 0xFF), &[0x02, 0x01, 0x00]]),
        ),
    ];
    for (packet, cobs) in cases {
        let f = frame(&packet);
        assert_eq!(f[0], DELIMITER);
        assert_eq!(&f[1..], &cobs[..], "packet {packet:x?}");
        let mut d = FrameDecoder::<300>::new();
        assert_eq!(push_all(&mut d, &f), vec![Ok(packet)]);
    }
    // The bound is reached by packets without zeros, and MAX_FRAME is it.
    assert_eq!(frame(&seq(0x01, 0xFE)).len(), max_frame_len(254));
    assert_eq!(frame(&seq(0x01, 0xFF)).len(), max_frame_len(255));
    assert_eq!(MAX_FRAME, MAX_PACKET + 3);
    assert_eq!(frame(&[7; MAX_PACKET]).len(), MAX_FRAME);
}

/// Each failure mode on its own, with the exact counters, and the frame
/// after each failure decodes.
#[test]
fn errors_are_dropped_counted_and_the_next_frame_decodes() {
    let good = frame(&[1, 2, 0, 3]);
    let mut d = FrameDecoder::<8>::new();
    // Power-up in the middle of a frame: discarded up to the first 0x00.
    assert_eq!(push_all(&mut d, &[0x33, 0x44, 0x00]), vec![]);
    assert_eq!(d.counters().discarded, 3);
    // Oversize: 9 decoded bytes into 8, reported at the 9th, the rest
    // discarded up to the delimiter.
    let long = frame(&[9; 9]);
    let events = push_all(&mut d, &long);
    assert_eq!(events, vec![Err(FrameError::Oversize { capacity: 8 })]);
    // Malformed: the code 0x05 promises 4 bytes, the delimiter comes after 2.
    let events = push_all(&mut d, &[0x00, 0x05, 0x11, 0x22, 0x00]);
    assert_eq!(events, vec![Err(FrameError::Malformed)]);
    // Two delimiters in a row: an empty frame, skipped.
    assert_eq!(push_all(&mut d, &[0x00, 0x00]), vec![]);
    assert_eq!(push_all(&mut d, &good), vec![Ok(vec![1, 2, 0, 3])]);
    let c = d.counters();
    assert_eq!(
        c,
        FrameCounters {
            frames: 1,
            frame_bytes: good.len() as u64 - 1,
            oversize: 1,
            malformed: 1,
            // The leading 0x00 of long, of the malformed frame, of good,
            // and the pair.
            empty: 5,
            discarded: 3 + (long.len() as u64 - 1) + 4,
        }
    );
    assert_eq!(c.dropped(), 2);
    let pushed = 3 + long.len() + 5 + 2 + good.len();
    assert!(accounted(&d, pushed));
    // A stream without any 0x00 is all discarded, and nothing is handed out.
    let mut d = FrameDecoder::<MAX_PACKET>::new();
    assert_eq!(push_all(&mut d, &[0x55; 1000]), vec![]);
    assert_eq!(d.counters().discarded, 1000);
    assert_eq!(d.pending(), 0);
}

/// A flipped data byte keeps the COBS structure: the framing hands the frame
/// out, and the packet decoder's CRC catches it (the Receiver counts it as
/// corrupt).
#[test]
fn a_flipped_data_byte_is_corrupt_for_the_receiver() {
    let mut t = Telemetry::new(5, 1_000);
    t.counts = [10, 20];
    let mut f = framed(&t);
    // f[1] is the first code byte; f[2] the first data byte, 'L'.
    assert_eq!(f[2], b'L');
    f[2] ^= 0x01;
    let mut d = FrameDecoder::<MAX_PACKET>::new();
    let events = push_all(&mut d, &f);
    assert_eq!(d.counters().frames, 1);
    assert_eq!(d.counters().dropped(), 0);
    let mut rx = Receiver::new();
    let e = rx
        .receive_telemetry(events[0].as_ref().unwrap())
        .unwrap_err();
    assert!(e.is_corrupt(), "{e:?}");
    assert_eq!(rx.counters().corrupt, 1);
}

/// Encoding and decoding a stream of framed telemetry allocates nothing.
#[test]
fn framing_does_not_allocate() {
    let control = allocation_counter::measure(|| {
        core::hint::black_box(Vec::<u8>::with_capacity(1));
    });
    assert_eq!(
        control.count_total, 1,
        "the counting allocator is not active"
    );
    let mut packet = [0u8; MAX_PACKET];
    let mut out = [0u8; MAX_FRAME];
    let mut d = FrameDecoder::<MAX_PACKET>::new();
    let mut rx = Receiver::new();
    let mut applied = 0u32;
    let info = allocation_counter::measure(|| {
        for k in 0..10_000u32 {
            let mut t = Telemetry::new(k, u64::from(k) * 10_000);
            t.counts = [k.wrapping_mul(7), k.wrapping_mul(5)];
            t.ir = (k % 2 == 0).then_some([0.1, 0.2]);
            t.set_beams(&[1.0, 2.0, 3.0][..(k % 4) as usize]).unwrap();
            let n = t.encode(&mut packet).unwrap();
            let m = encode_frame(&packet[..n], &mut out).unwrap();
            if k % 10 == 3 {
                out[m / 2] = 0; // cut the frame in two
            }
            // Byte by byte for half the stream, in one slice for the rest.
            if k % 2 == 0 {
                for &b in &out[..m] {
                    if let Some(Ok(f)) = d.push(b) {
                        applied += u32::from(rx.receive_telemetry(f).is_ok());
                    }
                }
            } else {
                d.feed_all(&out[..m], |f| {
                    if let Ok(f) = f {
                        applied += u32::from(rx.receive_telemetry(f).is_ok());
                    }
                });
            }
        }
    });
    assert_eq!(applied, 9_000);
    assert_eq!(d.counters().frames + d.counters().dropped(), 11_000);
    assert_eq!(
        info.count_total, 0,
        "{} allocations in the framing loop",
        info.count_total
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Any packet of 0..=MAX_PACKET bytes, zeros included, frames and
    /// decodes back exactly, alone and back to back with another.
    #[test]
    fn round_trip_any_packet(a in bytes_with_zeros(MAX_PACKET), b in bytes_with_zeros(MAX_PACKET)) {
        let (fa, fb) = (frame(&a), frame(&b));
        prop_assert!(fa.len() <= MAX_FRAME);
        let mut d = FrameDecoder::<MAX_PACKET>::new();
        prop_assert_eq!(push_all(&mut d, &fa), vec![Ok(a.clone())]);
        prop_assert_eq!(push_all(&mut d, &fb), vec![Ok(b)]);
        let c = d.counters();
        prop_assert_eq!((c.frames, c.dropped(), c.discarded, c.empty), (2, 0, 0, 2));
        prop_assert!(accounted(&d, fa.len() + fb.len()));
        // Too small a buffer is an error and writes nothing.
        let mut small = vec![0xAA; fa.len() - 1];
        prop_assert!(encode_frame(&a, &mut small).is_err());
        prop_assert!(small.iter().all(|&x| x == 0xAA));
    }

    /// Long packets (several 254-byte blocks) round-trip through a decoder
    /// sized for them, and are oversize for one a byte too small.
    #[test]
    fn round_trip_long_packets(
        packet in proptest::collection::vec(prop_oneof![1 => Just(0u8), 60 => 1u8..], 0..=1200),
    ) {
        let f = frame(&packet);
        prop_assert!(f.len() <= max_frame_len(packet.len()));
        let mut d = FrameDecoder::<1200>::new();
        prop_assert_eq!(push_all(&mut d, &f), vec![Ok(packet.clone())]);
        if !packet.is_empty() {
            let mut d = FrameDecoder::<1199>::new();
            let events = push_all(&mut d, &f);
            if packet.len() == 1200 {
                prop_assert_eq!(events, vec![Err(FrameError::Oversize { capacity: 1199 })]);
            } else {
                prop_assert_eq!(events, vec![Ok(packet)]);
            }
        }
    }

    /// Arbitrary bytes never panic the decoder; its events and counters are
    /// those of the split-on-zero reference, and every byte is accounted for
    /// (in a decoded frame, discarded, an empty frame, or pending).
    #[test]
    fn any_stream_is_decoded_as_the_reference_and_every_byte_counted(
        bytes in bytes_with_zeros(700),
    ) {
        let mut small = FrameDecoder::<16>::new();
        let mut big = FrameDecoder::<MAX_PACKET>::new();
        let events = push_all(&mut small, &bytes);
        let (expected, counters, pending) = reference(&bytes, 16);
        prop_assert_eq!(&events, &expected);
        prop_assert_eq!(small.counters(), counters);
        prop_assert_eq!(small.pending(), pending);
        prop_assert!(accounted(&small, bytes.len()));
        let events = push_all(&mut big, &bytes);
        let (expected, counters, _) = reference(&bytes, MAX_PACKET);
        prop_assert_eq!(&events, &expected);
        prop_assert_eq!(big.counters(), counters);
        prop_assert!(accounted(&big, bytes.len()));
        prop_assert!(events.iter().flatten().all(|f| f.len() <= MAX_PACKET));
    }

    /// A framed packet survives arbitrary garbage before and after it: the
    /// leading delimiter ends whatever came before, the trailing one ends the
    /// frame before whatever comes after. It is decoded exactly once and the
    /// Receiver applies it.
    #[test]
    fn a_frame_survives_garbage_before_and_after(
        t in telemetry(),
        before in bytes_with_zeros(300),
        after in bytes_with_zeros(300),
    ) {
        let f = framed(&t);
        let stream = [&before[..], &f, &after].concat();
        let mut d = FrameDecoder::<MAX_PACKET>::new();
        let mut rx = Receiver::new();
        let mut got = Vec::new();
        for e in push_all(&mut d, &stream).into_iter().flatten() {
            if let Ok((p, _)) = rx.receive_telemetry(&e) {
                got.push(p);
            }
        }
        prop_assert_eq!(got, vec![t]);
        prop_assert!(accounted(&d, stream.len()));
    }

    /// The guarantee without the leading delimiter, stated exactly: garbage
    /// that does not end in 0x00 joins the frame after it (which may be
    /// lost), but never the one after that; garbage that ends in 0x00 costs
    /// nothing.
    #[test]
    fn without_the_leading_delimiter_garbage_takes_at_most_the_next_frame(
        a in telemetry(),
        b in telemetry(),
        garbage in bytes_with_zeros(300),
        last in 1u8..,
    ) {
        let (fa, fb) = (framed(&a), framed(&b));
        let decoded = |stream: &[u8]| {
            let mut d = FrameDecoder::<MAX_PACKET>::new();
            push_all(&mut d, stream)
                .into_iter()
                .flatten()
                .filter_map(|f| Telemetry::decode(&f).ok())
                .collect::<Vec<_>>()
        };
        // Garbage not ending in 0x00, then `a` without its leading 0x00,
        // then `b`: `b` is decoded; `a` may be lost.
        let stream = [&garbage[..], &[last], &fa[1..], &fb].concat();
        let got = decoded(&stream);
        prop_assert_eq!(got.last(), Some(&b));
        prop_assert!(got.len() <= 2);
        // Garbage ending in 0x00: `a` is decoded too.
        let stream = [&garbage[..], &[0], &fa[1..], &fb].concat();
        prop_assert_eq!(decoded(&stream), vec![a, b]);
    }

    /// Lost, flipped and zeroed bytes in a stream of N framed telemetry
    /// packets: every packet the Receiver accepts is the one sent with that
    /// sequence number, in order, at least N - k arrive for k damaged bytes,
    /// and at most 2k frames are dropped by the framing or rejected by the
    /// packet decoder (a byte that becomes 0x00 splits a frame in two).
    #[test]
    fn damaged_bytes_cost_at_most_the_packets_they_touch(
        ts in proptest::collection::vec(telemetry(), 1..=20),
        damage in proptest::collection::vec((any::<prop::sample::Index>(), 0u8..3, 1u8..), 1..=3),
    ) {
        let sent: Vec<Telemetry> = ts
            .into_iter()
            .zip(0u32..)
            .map(|(mut t, k)| {
                t.sequence = k;
                t
            })
            .collect();
        let mut stream: Vec<u8> = sent.iter().flat_map(framed).collect();
        for (at, kind, mask) in &damage {
            let i = at.index(stream.len());
            match kind {
                0 => {
                    stream.remove(i);
                }
                1 => stream[i] ^= mask,
                _ => stream[i] = 0,
            }
        }
        let k = damage.len() as u64;
        let mut d = FrameDecoder::<MAX_PACKET>::new();
        let mut rx = Receiver::new();
        let mut got = Vec::new();
        for e in push_all(&mut d, &stream).into_iter().flatten() {
            if let Ok((p, _)) = rx.receive_telemetry(&e) {
                got.push(p);
            }
        }
        for p in &got {
            prop_assert_eq!(p, &sent[p.sequence as usize]);
        }
        prop_assert!(got.windows(2).all(|w| w[0].sequence < w[1].sequence));
        prop_assert!(got.len() as u64 + k >= sent.len() as u64, "{} of {}", got.len(), sent.len());
        let rejected = d.counters().dropped() + rx.counters().corrupt + rx.counters().malformed;
        prop_assert!(rejected <= 2 * k, "{rejected} frames rejected for {k} damaged bytes");
        prop_assert!(accounted(&d, stream.len()));
    }

    /// The same stream fed in arbitrary chunks (through `feed` and
    /// `feed_all`) gives the same events and counters as byte by byte.
    #[test]
    fn chunking_does_not_change_the_frames(
        ts in proptest::collection::vec(telemetry(), 0..=8),
        garbage in bytes_with_zeros(100),
        cuts in proptest::collection::vec(0usize..40, 0..60),
    ) {
        let mut stream = garbage;
        for t in &ts {
            stream.extend(framed(t));
        }
        let mut one = FrameDecoder::<MAX_PACKET>::new();
        let expected = push_all(&mut one, &stream);
        let mut fed = FrameDecoder::<MAX_PACKET>::new();
        let mut all = FrameDecoder::<MAX_PACKET>::new();
        let (mut via_feed, mut via_all) = (Vec::new(), Vec::new());
        let mut rest = &stream[..];
        for cut in cuts.iter().chain(core::iter::once(&usize::MAX)) {
            let (chunk, tail) = rest.split_at((*cut).min(rest.len()));
            rest = tail;
            all.feed_all(chunk, |e| via_all.push(e.map(<[u8]>::to_vec)));
            let mut c = chunk;
            while !c.is_empty() {
                let (used, e) = fed.feed(c);
                prop_assert!(used >= 1 && used <= c.len());
                if let Some(e) = e {
                    via_feed.push(e.map(<[u8]>::to_vec));
                }
                c = &c[used..];
            }
        }
        prop_assert_eq!(&via_feed, &expected);
        prop_assert_eq!(&via_all, &expected);
        prop_assert_eq!(fed.counters(), one.counters());
        prop_assert_eq!(all.counters(), one.counters());
        prop_assert_eq!(fed.pending(), one.pending());
        let sent: Vec<_> = expected.iter().flatten().filter_map(|f| Telemetry::decode(f).ok()).collect();
        prop_assert!(sent.ends_with(&ts));
    }
}
