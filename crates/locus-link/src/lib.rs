#![doc = include_str!("../README.md")]
#![no_std]
#![forbid(unsafe_code)]

pub mod clock;
pub mod error;
pub mod framing;
pub mod packet;
pub mod receiver;

pub use clock::{ClockEstimator, ClockFit};
pub use error::{Error, FrameError};
pub use framing::{
    DELIMITER, FrameCounters, FrameDecoder, MAX_FRAME, encode_frame, frame_len, max_frame_len,
};
pub use packet::{
    COMMAND_LEN, CommandPacket, MAGIC, MAX_BEAMS, MAX_PACKET, NO_ACK, Packet, TELEMETRY_MIN_LEN,
    Telemetry, VERSION, decode,
};
pub use receiver::{Counters, Receiver, Status};
