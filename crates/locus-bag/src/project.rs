//! A channel's numeric fields read straight from each message's CDR,
//! every other field skipped without building a value: the fast path of
//! [`crate::convert`] for the topics whose mapped fields are numbers at
//! fixed paths (velocities, truth poses, one sighting per message).
//!
//! A [`Projection`] is compiled once per channel from the field paths the
//! mapping reads. Paths through a list (`detections[0].id`) or to a
//! non-number do not compile: such a topic is read through the decoded
//! [`crate::Value`] instead. Skipping keeps the decoder's bounds: a count
//! is checked against the bytes left and the values a message may hold,
//! and nesting against [`crate::cdr::MAX_DEPTH`]. A string skipped is not
//! checked for UTF-8: it is not read. Single message fields are
//! flattened once into their fields' steps, each with its path for errors,
//! so reading a message is one loop that builds nothing.

use alloc::sync::Arc;

use crate::cdr::{Decoder, MAX_DEPTH, Step, primitive};
use crate::error::CdrError;
use crate::msgdef::{Base, Definitions, MessageType, Primitive, Shape};

/// What a field of a message gives the projection.
#[derive(Debug, Clone, PartialEq)]
enum Want {
    /// Nothing: skipped.
    Skip,
    /// A number, into this slot.
    Leaf(usize, Primitive),
    /// Some of the fields of this single message field, of this type.
    Inner(Arc<MessageType>, Node),
}

/// The wanted fields of one message type, by field index.
#[derive(Debug, Clone, PartialEq)]
struct Node(Vec<Want>);

/// One step of reading a message, its single message fields flattened
/// into their fields (their layout is fixed by the schema).
#[derive(Debug, Clone, PartialEq)]
enum Op {
    /// A number into a slot.
    Number(usize, Primitive),
    /// A primitive skipped.
    Skip(Primitive),
    /// A string skipped.
    SkipString,
    /// The byte of a message type with no fields.
    EmptyMessage,
    /// An array or a sequence skipped, element by element where it must.
    SkipList(Base, Shape),
    /// A `wstring`: refused, as the full decoder refuses it.
    WString,
    /// Consecutive primitives read and skipped as one: aligned to `align`
    /// (the largest of theirs), `size` bytes, the numbers wanted at their
    /// offsets in it; each primitive's type and path, to name the one a
    /// short message cuts.
    Block {
        align: usize,
        size: usize,
        reads: Vec<(usize, usize, Primitive)>,
        parts: Vec<(Primitive, String)>,
    },
}

/// `ops` with each run of primitives that share the first one's
/// alignment or less merged into one [`Op::Block`]: the offsets in a run
/// are fixed once its start is aligned. The run's path (for an error) is
/// its first field's.
fn blocks(ops: Vec<(Op, String)>) -> Vec<(Op, String)> {
    let mut out: Vec<(Op, String)> = Vec::with_capacity(ops.len());
    for (op, path) in ops {
        let (p, slot) = match op {
            Op::Number(slot, p) => (p, Some(slot)),
            Op::Skip(p) => (p, None),
            other => {
                out.push((other, path));
                continue;
            }
        };
        let n = p.size();
        if let Some((
            Op::Block {
                align,
                size,
                reads,
                parts,
            },
            _,
        )) = out.last_mut()
            && n <= *align
        {
            let offset = size.next_multiple_of(n);
            if let Some(slot) = slot {
                reads.push((offset, slot, p));
            }
            *size = offset + n;
            parts.push((p, path));
            continue;
        }
        let reads = slot.map(|slot| vec![(0, slot, p)]).unwrap_or_default();
        let parts = vec![(p, path.clone())];
        out.push((
            Op::Block {
                align: n,
                size: n,
                reads,
                parts,
            },
            path,
        ));
    }
    out
}

/// The numeric fields at fixed paths of a channel's messages.
#[derive(Debug, Clone, PartialEq)]
pub struct Projection {
    /// The steps, each with its field's path (for errors).
    ops: Vec<(Op, String)>,
    /// Each path's primitive type, by slot.
    kinds: Vec<Primitive>,
}

/// Appends the steps of reading `ty` as `node` wants (`None`: skipping all
/// of it) to `ops`, paths under `prefix`; `None` if single message fields
/// nest beyond [`MAX_DEPTH`] (a type that contains itself).
fn flatten(
    defs: &Definitions,
    ty: &MessageType,
    node: Option<&Node>,
    prefix: &str,
    depth: usize,
    ops: &mut Vec<(Op, String)>,
) -> Option<()> {
    if depth > MAX_DEPTH {
        return None;
    }
    if ty.fields.is_empty() {
        ops.push((Op::EmptyMessage, prefix.trim_end_matches('.').to_string()));
    }
    for (i, f) in ty.fields.iter().enumerate() {
        let path = format!("{prefix}{}", f.name);
        match (node.map(|n| &n.0[i]), &f.base, f.shape) {
            (Some(Want::Leaf(slot, p)), _, _) => ops.push((Op::Number(*slot, *p), path)),
            (Some(Want::Inner(t, inner)), _, _) => {
                flatten(defs, t, Some(inner), &format!("{path}."), depth + 1, ops)?;
            }
            (_, Base::Primitive(p), Shape::Single) => ops.push((Op::Skip(*p), path)),
            (_, Base::String, Shape::Single) => ops.push((Op::SkipString, path)),
            (_, Base::WString, Shape::Single) => ops.push((Op::WString, path)),
            (_, Base::Message(name), Shape::Single) => {
                let t = defs.resolve(name)?;
                flatten(defs, t, None, &format!("{path}."), depth + 1, ops)?;
            }
            (_, base, shape) => ops.push((Op::SkipList(base.clone(), shape), path)),
        }
    }
    Some(())
}

impl Projection {
    /// The projection reading `paths` (`pose.position.x`; slot `i` is
    /// `paths[i]`) of the root type of `defs`; `None` if a path goes
    /// through a list or a sequence, names no field, or does not end at a
    /// number.
    #[must_use]
    pub fn compile(defs: &Definitions, paths: &[&str]) -> Option<Self> {
        let mut root = Node(vec![Want::Skip; defs.root.fields.len()]);
        let mut kinds = Vec::with_capacity(paths.len());
        for (slot, path) in paths.iter().enumerate() {
            let mut ty: &Arc<MessageType> = &defs.root;
            let mut node = &mut root;
            let mut names = path.split('.').peekable();
            loop {
                let name = names.next()?;
                let i = ty.field(name)?;
                let field = &ty.fields[i];
                if field.shape != Shape::Single {
                    return None;
                }
                if names.peek().is_none() {
                    let Base::Primitive(p) = field.base else {
                        return None;
                    };
                    if node.0[i] != Want::Skip {
                        return None;
                    }
                    node.0[i] = Want::Leaf(slot, p);
                    kinds.push(p);
                    break;
                }
                let Base::Message(inner) = &field.base else {
                    return None;
                };
                ty = defs.resolve(inner)?;
                if node.0[i] == Want::Skip {
                    node.0[i] = Want::Inner(ty.clone(), Node(vec![Want::Skip; ty.fields.len()]));
                }
                let Want::Inner(_, next) = &mut node.0[i] else {
                    return None;
                };
                node = next;
            }
        }
        let mut ops = Vec::new();
        flatten(defs, &defs.root, Some(&root), "", 0, &mut ops)?;
        Some(Self {
            ops: blocks(ops),
            kinds,
        })
    }

    /// The primitive type of slot `slot`.
    #[must_use]
    pub fn kind(&self, slot: usize) -> Option<Primitive> {
        self.kinds.get(slot).copied()
    }

    /// Reads the CDR `bytes` of one message of the root type of `defs`,
    /// each wanted number into its slot of `out` (as [`crate::Value::as_f64`]
    /// gives it).
    ///
    /// # Errors
    /// As [`crate::cdr::decode`] for the fields it reads or skips.
    pub fn read(&self, defs: &Definitions, bytes: &[u8], out: &mut [f64]) -> Result<(), CdrError> {
        let mut d = Decoder::new(defs, bytes)?;
        for (op, path) in &self.ops {
            let done = match op {
                Op::Number(slot, p) => d.number(*p).map(|v| {
                    if let Some(o) = out.get_mut(*slot) {
                        *o = v;
                    }
                }),
                Op::Skip(p) => d.take(p.size(), p.size()).map(|_| ()),
                Op::SkipString => d.skip_element(&Base::String, 0),
                Op::EmptyMessage => d.take(1, 1).map(|_| ()),
                Op::SkipList(base, shape) => d.skip_field(base, *shape, 0),
                Op::WString => d.skip_element(&Base::WString, 0),
                Op::Block {
                    align,
                    size,
                    reads,
                    parts,
                } => {
                    let (little, start) = (d.little, d.pos);
                    match d.take(*size, *align) {
                        Ok(b) => {
                            for &(offset, slot, p) in reads {
                                let v = primitive(&b[offset..offset + p.size()], p, little);
                                if let Some(o) = out.get_mut(slot) {
                                    *o = v.as_f64().unwrap_or(f64::NAN);
                                }
                            }
                            Ok(())
                        }
                        // Cut short: the primitive it cuts, named as alone.
                        Err(e) => {
                            d.pos = start;
                            for (p, path) in parts {
                                d.take(p.size(), p.size())
                                    .map_err(|e| e.within(Step::Field(path)))?;
                            }
                            Err(e)
                        }
                    }
                }
            };
            done.map_err(|e| e.within(Step::Field(path)))?;
        }
        Ok(())
    }
}

impl<'a> Decoder<'a> {
    /// The number `p` at the position, as [`crate::Value::as_f64`] gives
    /// the value the full decoder builds.
    fn number(&mut self, p: Primitive) -> Result<f64, CdrError> {
        self.scalar(p).map(|v| v.as_f64().unwrap_or(f64::NAN))
    }

    fn message_type(&self, base: &Base) -> Result<&'a Arc<MessageType>, CdrError> {
        let defs: &'a Definitions = self.defs;
        match base {
            Base::Message(name) => defs
                .resolve(name)
                .ok_or_else(|| self.error(format!("type {name} is not defined"))),
            _ => Err(self.error("internal: not a message field".into())),
        }
    }

    fn skip_field(&mut self, base: &Base, shape: Shape, depth: usize) -> Result<(), CdrError> {
        match shape {
            Shape::Single => self.skip_element(base, depth),
            Shape::Fixed(n) => self.skip_list(base, n, depth),
            Shape::Sequence(bound) => {
                let n = self.u32()? as usize;
                if let Some(b) = bound
                    && n > b
                {
                    return Err(self.error(format!("{n} elements, beyond the bound {b}")));
                }
                self.skip_list(base, n, depth)
            }
        }
    }

    fn skip_element(&mut self, base: &Base, depth: usize) -> Result<(), CdrError> {
        match base {
            Base::Primitive(p) => {
                self.spend()?;
                self.take(p.size(), p.size()).map(|_| ())
            }
            Base::String => {
                self.spend()?;
                let n = self.u32()? as usize;
                self.take(n, 1).map(|_| ())
            }
            Base::WString => Err(self.error(
                "wstring fields are not decoded (their wire form differs between middlewares)"
                    .into(),
            )),
            Base::Message(_) => {
                let ty = self.message_type(base)?;
                if depth + 1 > MAX_DEPTH {
                    return Err(self.error(format!("message types nested deeper than {MAX_DEPTH}")));
                }
                self.spend()?;
                if ty.fields.is_empty() {
                    self.take(1, 1)?;
                }
                for f in &ty.fields {
                    self.skip_field(&f.base, f.shape, depth + 1)
                        .map_err(|e| e.within(Step::Field(&f.name)))?;
                }
                Ok(())
            }
        }
    }

    fn skip_list(&mut self, base: &Base, n: usize, depth: usize) -> Result<(), CdrError> {
        self.list_count(base, n)?;
        if let Base::Primitive(p) = base {
            // Aligned once, the elements follow each other with no padding.
            self.budget -= n;
            return self.take(n * p.size(), p.size()).map(|_| ());
        }
        for i in 0..n {
            self.skip_element(base, depth)
                .map_err(|e| e.within(Step::Index(i)))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cdr::decode;

    const SCHEMA: &str = "std_msgs/Header header\nstring[] names\nint16[3] v\nP pose\nfloat32 f\n\
        ===\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\
        ===\nMSG: p/P\nfloat64 x\nint64 big\nuint8 u\n";

    fn message(little: bool) -> Vec<u8> {
        let mut b: Vec<u8> = vec![0, u8::from(little), 0, 0];
        let put = |b: &mut Vec<u8>, bytes: &[u8], align: usize| {
            while (b.len() - 4) % align != 0 {
                b.push(0);
            }
            b.extend_from_slice(bytes);
        };
        macro_rules! e {
            ($v:expr) => {
                if little {
                    $v.to_le_bytes()
                } else {
                    $v.to_be_bytes()
                }
            };
        }
        put(&mut b, &e!(-7i32), 4);
        put(&mut b, &e!(123_456_789u32), 4);
        put(&mut b, &e!(5u32), 4);
        put(&mut b, b"base\0", 1);
        put(&mut b, &e!(2u32), 4);
        for s in ["ab\0", "c\0"] {
            put(&mut b, &e!(u32::try_from(s.len()).unwrap()), 4);
            put(&mut b, s.as_bytes(), 1);
        }
        for v in [1i16, -2, 3] {
            put(&mut b, &e!(v), 2);
        }
        put(&mut b, &e!(2.5f64), 8);
        put(&mut b, &e!(-9_007_199_254_740_993i64), 8);
        put(&mut b, &[200], 1);
        put(&mut b, &e!(0.1f32), 4);
        b
    }

    #[test]
    fn a_projection_reads_what_the_full_decoder_reads() {
        let d = Definitions::parse("p/T", SCHEMA).unwrap();
        let paths = [
            "header.stamp.sec",
            "header.stamp.nanosec",
            "pose.x",
            "pose.big",
            "pose.u",
            "f",
        ];
        let p = Projection::compile(&d, &paths).unwrap();
        for little in [true, false] {
            let bytes = message(little);
            let full = decode(&d, &bytes).unwrap();
            let mut out = [f64::NAN; 6];
            p.read(&d, &bytes, &mut out).unwrap();
            for (path, got) in paths.iter().zip(out) {
                let want = full.get(path).and_then(crate::Value::as_f64).unwrap();
                assert_eq!(got.to_bits(), want.to_bits(), "{path}");
            }
        }
        // Paths through lists, to non-numbers or to nothing do not compile.
        for bad in [
            "names",
            "v",
            "header.frame_id",
            "pose",
            "pose.q",
            "x",
            "header.stamp",
        ] {
            assert!(Projection::compile(&d, &[bad]).is_none(), "{bad}");
        }
    }

    #[test]
    fn a_projection_keeps_the_decoders_bounds() {
        let d = Definitions::parse("p/T", "float64[] v\nstring s\nfloat64 x\n").unwrap();
        let p = Projection::compile(&d, &["x"]).unwrap();
        let mut b = vec![0, 1, 0, 0];
        b.extend_from_slice(&1_000_000_000u32.to_le_bytes());
        b.extend_from_slice(&[0; 4]);
        let e = p.read(&d, &b, &mut [0.0]).unwrap_err();
        assert_eq!(e.field, "v");
        assert!(e.reason.contains("1000000000 elements cannot fit"), "{e}");
        // Truncated inside a skipped string.
        let mut b = vec![0, 1, 0, 0];
        b.extend_from_slice(&0u32.to_le_bytes());
        b.extend_from_slice(&100u32.to_le_bytes());
        let e = p.read(&d, &b, &mut [0.0]).unwrap_err();
        assert_eq!(e.field, "s");
        // The error names the field skipped, through lists and messages.
        let d = Definitions::parse(
            "p/T",
            "P[] pts\nfloat64 x\n===\nMSG: p/P\nuint8 k\nstring s\n",
        )
        .unwrap();
        let p = Projection::compile(&d, &["x"]).unwrap();
        let mut b = vec![0, 1, 0, 0];
        b.extend_from_slice(&2u32.to_le_bytes());
        b.extend_from_slice(&[7, 0, 0, 0]);
        b.extend_from_slice(&2u32.to_le_bytes());
        b.extend_from_slice(b"a\0");
        b.extend_from_slice(&[9, 0]);
        b.extend_from_slice(&50u32.to_le_bytes());
        let e = p.read(&d, &b, &mut [0.0]).unwrap_err();
        assert_eq!(e.field, "pts[1].s", "{e}");
        // A type that contains itself.
        let d = Definitions::parse("p/T", "T[] t\nfloat64 x\n").unwrap();
        let p = Projection::compile(&d, &["x"]).unwrap();
        let mut b = vec![0, 1, 0, 0];
        for _ in 0..100 {
            b.extend_from_slice(&1u32.to_le_bytes());
        }
        let e = p.read(&d, &b, &mut [0.0]).unwrap_err();
        assert!(e.reason.contains("nested deeper than 64"), "{e}");
    }
}
