//! CDR (OMG DDS-XTypes, encoding version 1, as ROS 2's middlewares write
//! it) decoded with a message's [`Definitions`].
//!
//! A message starts with a 4-byte encapsulation header: the representation
//! (`0x0000` big-endian CDR, `0x0001` little-endian; others are refused)
//! and 2 option bytes. Each primitive is aligned to its size (8 at most),
//! counted from the end of the header. A string is a `uint32` length that
//! counts its terminating NUL, then its bytes. A sequence is a `uint32`
//! element count, then its elements; a fixed array has no count. A message
//! field is its fields in order; one with no fields (only constants) is one
//! byte, the member rosidl adds to it.
//!
//! Hostile input cannot make the decoder allocate beyond the message's
//! size: a count is checked against the bytes left (each element takes at
//! least its smallest wire size), and the values built are bounded by
//! [`value_budget`]; nesting is bounded by [`MAX_DEPTH`].

use alloc::sync::Arc;

use crate::error::CdrError;
use crate::msgdef::{Base, Definitions, MessageType, Primitive, Shape};
use crate::value::{Message, Value};

/// Deepest nesting of message types decoded (a schema that contains itself
/// is refused when a message reaches this depth).
pub const MAX_DEPTH: usize = 64;

/// The most values a message of `len` bytes may decode to: every value but
/// a message or an empty list takes at least a byte, and each message
/// wraps at least one other value or none.
#[must_use]
pub fn value_budget(len: usize) -> usize {
    2 * len + 4096
}

/// The name of an encapsulation kind, for errors.
fn representation(kind: u16) -> &'static str {
    match kind {
        0x0002 => "PL_CDR big-endian",
        0x0003 => "PL_CDR little-endian",
        0x0006 => "XCDR2 big-endian",
        0x0007 => "XCDR2 little-endian",
        0x0008 => "delimited XCDR2 big-endian",
        0x0009 => "delimited XCDR2 little-endian",
        0x000a => "PL_CDR2 big-endian",
        0x000b => "PL_CDR2 little-endian",
        _ => "unknown",
    }
}

/// Decodes the CDR `bytes` of one message of the root type of `defs`.
///
/// # Errors
/// An encapsulation other than plain CDR; a message shorter than its
/// fields; a count beyond the bytes left or a declared bound; a string
/// that is not UTF-8; a `wstring`; nesting beyond [`MAX_DEPTH`]. The error
/// names the field's path and the byte offset.
pub fn decode(defs: &Definitions, bytes: &[u8]) -> Result<Value, CdrError> {
    let mut value = Value::Bool(false);
    decode_into(defs, bytes, &mut value)?;
    Ok(value)
}

/// As [`decode`], into `out`: the strings, lists and messages `out` holds
/// from an earlier message of the same type are reused, so a channel's
/// messages decode with no allocation once the first has. On an error,
/// `out` holds part of the message.
///
/// # Errors
/// As [`decode`].
pub fn decode_into(defs: &Definitions, bytes: &[u8], out: &mut Value) -> Result<(), CdrError> {
    let mut d = Decoder::new(defs, bytes)?;
    d.message(&defs.root, 0, out)
}

impl CdrError {
    /// The error inside `step` of its path: the step written before the
    /// field named so far.
    pub(crate) fn within(mut self, step: Step<'_>) -> Self {
        let head = match step {
            Step::Field(name) if self.field.is_empty() || self.field.starts_with('[') => {
                name.to_string()
            }
            Step::Field(name) => format!("{name}."),
            Step::Index(i) if self.field.is_empty() || self.field.starts_with('[') => {
                format!("[{i}]")
            }
            Step::Index(i) => format!("[{i}]."),
        };
        self.field.insert_str(0, &head);
        self
    }
}

/// The primitive `p` in its `p.size()` bytes `b`, little-endian or not.
pub(crate) fn primitive(b: &[u8], p: Primitive, little: bool) -> Value {
    macro_rules! num {
        ($t:ty) => {{
            let a = b.try_into().unwrap_or_default();
            if little {
                <$t>::from_le_bytes(a)
            } else {
                <$t>::from_be_bytes(a)
            }
        }};
    }
    match p {
        Primitive::Bool => Value::Bool(b[0] != 0),
        Primitive::I8 => Value::Int(i64::from(num!(i8))),
        Primitive::U8 => Value::UInt(u64::from(b[0])),
        Primitive::I16 => Value::Int(i64::from(num!(i16))),
        Primitive::U16 => Value::UInt(u64::from(num!(u16))),
        Primitive::I32 => Value::Int(i64::from(num!(i32))),
        Primitive::U32 => Value::UInt(u64::from(num!(u32))),
        Primitive::I64 => Value::Int(num!(i64)),
        Primitive::U64 => Value::UInt(num!(u64)),
        Primitive::F32 => Value::Float(f64::from(num!(f32))),
        Primitive::F64 => Value::Float(num!(f64)),
    }
}

/// One step of a field's path: a field's name or an element's index.
#[derive(Clone, Copy)]
pub(crate) enum Step<'a> {
    Field(&'a str),
    Index(usize),
}

/// The decoder's position in one message.
pub(crate) struct Decoder<'a> {
    pub(crate) defs: &'a Definitions,
    /// The bytes after the encapsulation header.
    pub(crate) data: &'a [u8],
    pub(crate) pos: usize,
    pub(crate) little: bool,
    pub(crate) budget: usize,
    /// The field path, for errors (written out only for one).
    pub(crate) path: Vec<Step<'a>>,
}

impl<'a> Decoder<'a> {
    /// A decoder after the encapsulation header of `bytes`.
    pub(crate) fn new(defs: &'a Definitions, bytes: &'a [u8]) -> Result<Self, CdrError> {
        let Some(header) = bytes.get(..4) else {
            return Err(CdrError {
                field: String::new(),
                offset: 0,
                reason: format!(
                    "{} bytes: shorter than the 4-byte encapsulation header",
                    bytes.len()
                ),
            });
        };
        let kind = u16::from_be_bytes([header[0], header[1]]);
        let little = match kind {
            0x0000 => false,
            0x0001 => true,
            _ => {
                return Err(CdrError {
                    field: String::new(),
                    offset: 0,
                    reason: format!(
                        "encapsulation {kind:#06x} ({}) is not plain CDR (0x0000 or 0x0001)",
                        representation(kind)
                    ),
                });
            }
        };
        Ok(Decoder {
            defs,
            data: &bytes[4..],
            pos: 0,
            little,
            budget: value_budget(bytes.len()),
            path: Vec::new(),
        })
    }

    pub(crate) fn error(&self, reason: String) -> CdrError {
        let mut field = String::new();
        for step in &self.path {
            match step {
                Step::Field(name) if field.is_empty() => field.push_str(name),
                Step::Field(name) => {
                    field.push('.');
                    field.push_str(name);
                }
                Step::Index(i) => field.push_str(&format!("[{i}]")),
            }
        }
        CdrError {
            field,
            offset: self.pos + 4,
            reason,
        }
    }

    pub(crate) fn spend(&mut self) -> Result<(), CdrError> {
        if self.budget == 0 {
            return Err(self.error(format!(
                "more values than a message of {} bytes can hold",
                self.data.len() + 4
            )));
        }
        self.budget -= 1;
        Ok(())
    }

    pub(crate) fn left(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    /// `n` bytes at alignment `align`.
    pub(crate) fn take(&mut self, n: usize, align: usize) -> Result<&[u8], CdrError> {
        // Alignments are 1, 2, 4 or 8: a mask, not a division.
        debug_assert!(align.is_power_of_two());
        let start = (self.pos + align - 1) & !(align - 1);
        let end = start.checked_add(n).filter(|&e| e <= self.data.len());
        let Some(end) = end else {
            return Err(self.error(format!(
                "needs {n} bytes, the message has {} left",
                self.data.len().saturating_sub(start)
            )));
        };
        self.pos = end;
        Ok(&self.data[start..end])
    }

    pub(crate) fn u32(&mut self) -> Result<u32, CdrError> {
        let b: [u8; 4] = self.take(4, 4)?.try_into().unwrap_or_default();
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn primitive(&mut self, p: Primitive, out: &mut Value) -> Result<(), CdrError> {
        *out = self.scalar(p)?;
        Ok(())
    }

    /// The primitive `p` at the position, aligned to its size.
    pub(crate) fn scalar(&mut self, p: Primitive) -> Result<Value, CdrError> {
        self.spend()?;
        let little = self.little;
        let b = self.take(p.size(), p.size())?;
        Ok(primitive(b, p, little))
    }

    fn string(&mut self, out: &mut Value) -> Result<(), CdrError> {
        self.spend()?;
        let n = self.u32()? as usize;
        let b = self.take(n, 1)?;
        let text = b.strip_suffix(&[0]).unwrap_or(b);
        let text = match core::str::from_utf8(text) {
            Ok(t) => t,
            Err(e) => return Err(self.error(format!("string is not UTF-8: {e}"))),
        };
        if let Value::Str(s) = out {
            s.clear();
            s.push_str(text);
        } else {
            *out = Value::Str(text.to_string());
        }
        Ok(())
    }

    /// One element of type `base`.
    fn element(&mut self, base: &'a Base, depth: usize, out: &mut Value) -> Result<(), CdrError> {
        match base {
            Base::Primitive(p) => self.primitive(*p, out),
            Base::String => self.string(out),
            Base::WString => Err(self.error(
                "wstring fields are not decoded (their wire form differs between middlewares)"
                    .into(),
            )),
            Base::Message(name) => {
                let defs: &'a Definitions = self.defs;
                let ty = defs
                    .resolve(name)
                    .ok_or_else(|| self.error(format!("type {name} is not defined")))?;
                self.message(ty, depth + 1, out)
            }
        }
    }

    /// Spends a value on a list of `n` elements of `base`, refusing a
    /// count that cannot fit in the bytes left or the values a message
    /// may hold: nothing is allocated or looped over for it.
    pub(crate) fn list_count(&mut self, base: &Base, n: usize) -> Result<(), CdrError> {
        self.spend()?;
        let smallest = Self::smallest(base);
        if n.saturating_mul(smallest) > self.left() || n > self.budget {
            return Err(self.error(format!(
                "{n} elements cannot fit in the {} bytes left",
                self.left()
            )));
        }
        Ok(())
    }

    /// The fewest bytes an element of `base` takes on the wire (0 for a
    /// message: its fields may be empty sequences).
    fn smallest(base: &Base) -> usize {
        match base {
            Base::Primitive(p) => p.size(),
            Base::String | Base::WString => 4,
            Base::Message(_) => 0,
        }
    }

    fn message(
        &mut self,
        ty: &'a Arc<MessageType>,
        depth: usize,
        out: &mut Value,
    ) -> Result<(), CdrError> {
        if depth > MAX_DEPTH {
            return Err(self.error(format!("message types nested deeper than {MAX_DEPTH}")));
        }
        self.spend()?;
        if ty.fields.is_empty() {
            // rosidl gives a message with no fields one `uint8` member
            // (`structure_needs_at_least_one_member`), which is on the wire.
            self.take(1, 1)?;
        }
        // The message `out` holds, if of this type, is reused.
        let reuse = matches!(out, Value::Message(m) if Arc::ptr_eq(&m.ty, ty));
        if !reuse {
            *out = Value::Message(Message {
                ty: ty.clone(),
                fields: vec![Value::Bool(false); ty.fields.len()],
            });
        }
        let Value::Message(m) = out else {
            return Err(self.error("internal: not a message".into()));
        };
        for (f, value) in ty.fields.iter().zip(m.fields.iter_mut()) {
            self.path.push(Step::Field(&f.name));
            match f.shape {
                Shape::Single => self.element(&f.base, depth, value)?,
                Shape::Fixed(n) => self.list(&f.base, n, depth, value)?,
                Shape::Sequence(bound) => {
                    let n = self.u32()? as usize;
                    if let Some(b) = bound
                        && n > b
                    {
                        return Err(self.error(format!("{n} elements, beyond the bound {b}")));
                    }
                    self.list(&f.base, n, depth, value)?;
                }
            }
            self.path.pop();
        }
        Ok(())
    }

    fn list(
        &mut self,
        base: &'a Base,
        n: usize,
        depth: usize,
        out: &mut Value,
    ) -> Result<(), CdrError> {
        self.list_count(base, n)?;
        if !matches!(out, Value::List(_)) {
            *out = Value::List(Vec::new());
        }
        let Value::List(items) = out else {
            return Err(self.error("internal: not a list".into()));
        };
        items.truncate(n);
        items.resize(n, Value::Bool(false));
        for (i, item) in items.iter_mut().enumerate() {
            self.path.push(Step::Index(i));
            self.element(base, depth, item)?;
            self.path.pop();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn defs(text: &str) -> Definitions {
        Definitions::parse("p/T", text).unwrap()
    }

    #[test]
    fn alignment_counts_from_the_end_of_the_header_in_both_byte_orders() {
        let d = defs("uint8 a\nfloat64 b\nstring s\nint16[] v\n");
        // Little-endian: a at 0, b at 8 (aligned), s at 16, v at 24.
        let mut le = vec![0, 1, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0];
        le.extend_from_slice(&1.5f64.to_le_bytes());
        le.extend_from_slice(&3u32.to_le_bytes());
        le.extend_from_slice(b"hi\0");
        le.push(0); // pad to 4
        le.extend_from_slice(&2u32.to_le_bytes());
        le.extend_from_slice(&(-2i16).to_le_bytes());
        le.extend_from_slice(&5i16.to_le_bytes());
        let mut be = vec![0, 0, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0];
        be.extend_from_slice(&1.5f64.to_be_bytes());
        be.extend_from_slice(&3u32.to_be_bytes());
        be.extend_from_slice(b"hi\0");
        be.push(0);
        be.extend_from_slice(&2u32.to_be_bytes());
        be.extend_from_slice(&(-2i16).to_be_bytes());
        be.extend_from_slice(&5i16.to_be_bytes());
        for bytes in [le, be] {
            let v = decode(&d, &bytes).unwrap();
            assert_eq!(v.get("a"), Some(&Value::UInt(7)));
            assert_eq!(v.get("b"), Some(&Value::Float(1.5)));
            assert_eq!(v.get("s").and_then(Value::as_str), Some("hi"));
            assert_eq!(v.get("v[0]"), Some(&Value::Int(-2)));
            assert_eq!(v.get("v[1]"), Some(&Value::Int(5)));
            assert_eq!(v.get("v[2]"), None);
        }
    }

    #[test]
    fn hostile_messages_are_refused_without_allocating() {
        let d = defs("float64[] v\n");
        // A billion elements claimed in a 12-byte message.
        let mut b = vec![0, 1, 0, 0];
        b.extend_from_slice(&1_000_000_000u32.to_le_bytes());
        b.extend_from_slice(&[0; 4]);
        let e = decode(&d, &b).unwrap_err();
        assert_eq!((e.field.as_str(), e.offset), ("v", 8), "{e}");
        assert!(e.reason.contains("1000000000 elements cannot fit"), "{e}");
        // Truncated.
        let e = decode(&defs("float64 x\n"), &[0, 1, 0, 0, 1, 2]).unwrap_err();
        assert!(e.reason.contains("needs 8 bytes"), "{e}");
        // Not plain CDR.
        let e = decode(&d, &[0, 7, 0, 0]).unwrap_err();
        assert!(e.reason.contains("XCDR2 little-endian"), "{e}");
        // A sequence of a billion empty messages: no bytes, still refused.
        let d = defs("E[] v\n===\nMSG: p/E\n");
        let e = decode(&d, &b).unwrap_err();
        assert!(e.reason.contains("cannot fit"), "{e}");
        // A type that contains itself.
        let d = defs("T[] t\n");
        let mut b = vec![0, 1, 0, 0];
        for _ in 0..100 {
            b.extend_from_slice(&1u32.to_le_bytes());
        }
        let e = decode(&d, &b).unwrap_err();
        assert!(e.reason.contains("nested deeper than 64"), "{e}");
        // Not UTF-8.
        let d = defs("string s\n");
        let e = decode(&d, &[0, 1, 0, 0, 2, 0, 0, 0, 0xff, 0]).unwrap_err();
        assert!(e.reason.contains("UTF-8"), "{e}");
    }
}
