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
//! checked for UTF-8: it is not read. An error's field path is written as
//! the error goes up, so reading builds nothing.

use alloc::sync::Arc;

use crate::cdr::{Decoder, MAX_DEPTH, Step};
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

/// The numeric fields at fixed paths of a channel's messages.
#[derive(Debug, Clone, PartialEq)]
pub struct Projection {
    root: Node,
    /// Each path's primitive type, by slot.
    kinds: Vec<Primitive>,
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
        Some(Self { root, kinds })
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
        d.project(&defs.root, &self.root, 0, out)
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

    /// The fields of `ty` that `node` wants, into `out`; the others skipped.
    fn project(
        &mut self,
        ty: &Arc<MessageType>,
        node: &Node,
        depth: usize,
        out: &mut [f64],
    ) -> Result<(), CdrError> {
        if depth > MAX_DEPTH {
            return Err(self.error(format!("message types nested deeper than {MAX_DEPTH}")));
        }
        self.spend()?;
        if ty.fields.is_empty() {
            self.take(1, 1)?;
        }
        for (f, want) in ty.fields.iter().zip(&node.0) {
            match want {
                Want::Skip => self.skip_field(&f.base, f.shape, depth),
                Want::Leaf(slot, p) => self.number(*p).map(|v| {
                    if let Some(o) = out.get_mut(*slot) {
                        *o = v;
                    }
                }),
                Want::Inner(t, inner) => self.project(t, inner, depth + 1, out),
            }
            .map_err(|e| e.within(Step::Field(&f.name)))?;
        }
        Ok(())
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
        self.spend()?;
        let smallest = Self::smallest(base);
        if n.saturating_mul(smallest) > self.left() || n > self.budget {
            return Err(self.error(format!(
                "{n} elements cannot fit in the {} bytes left",
                self.left()
            )));
        }
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
