//! ROS 2 message definitions as rosbag2 stores them in an MCAP schema
//! (encoding `ros2msg`): the channel's own `.msg` text, then each message
//! type it depends on after a line of `=` and a line `MSG: pkg/Type`.
//!
//! A field line is `TYPE NAME [DEFAULT]`; a constant `TYPE NAME=VALUE` is
//! skipped (it is not serialised); `#` starts a comment. `TYPE` is a
//! primitive (`bool`, `byte`, `char`, `int8` ... `uint64`, `float32`,
//! `float64`), `string`, `wstring` (optionally bounded, `string<=N`), or a
//! message (`pkg/Type`, `pkg/msg/Type`, or `Type` in the same package),
//! with an optional array suffix: `[N]` (fixed), `[<=N]` (bounded) or `[]`.
//! `builtin_interfaces/Time` and `Duration` are known even when the schema
//! leaves them out.

use alloc::sync::Arc;
use std::collections::HashMap;

use crate::error::SchemaError;

/// A primitive type and its size in bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Primitive {
    /// `bool`: one byte.
    Bool,
    /// `int8`.
    I8,
    /// `byte`, `char`, `uint8`.
    U8,
    /// `int16`.
    I16,
    /// `uint16`.
    U16,
    /// `int32`.
    I32,
    /// `uint32`.
    U32,
    /// `int64`.
    I64,
    /// `uint64`.
    U64,
    /// `float32`.
    F32,
    /// `float64`.
    F64,
}

impl Primitive {
    /// The primitive named `name`, if it is one.
    fn named(name: &str) -> Option<Self> {
        Some(match name {
            "bool" => Self::Bool,
            "int8" => Self::I8,
            "byte" | "char" | "uint8" => Self::U8,
            "int16" => Self::I16,
            "uint16" => Self::U16,
            "int32" => Self::I32,
            "uint32" => Self::U32,
            "int64" => Self::I64,
            "uint64" => Self::U64,
            "float32" => Self::F32,
            "float64" => Self::F64,
            _ => return None,
        })
    }

    /// Size (and CDR alignment) in bytes.
    #[must_use]
    pub fn size(self) -> usize {
        match self {
            Self::Bool | Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }
}

/// A field's element type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Base {
    /// A primitive.
    Primitive(Primitive),
    /// `string` (UTF-8).
    String,
    /// `wstring` (not decoded: its wire form differs between middlewares).
    WString,
    /// A message type, by its full name `pkg/Type`.
    Message(Arc<str>),
}

/// Whether a field is one element or a sequence of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// One element.
    Single,
    /// `[N]`: exactly N elements, no length on the wire.
    Fixed(usize),
    /// `[<=N]` or `[]`: a length on the wire, then the elements (the bound
    /// `N`, if any).
    Sequence(Option<usize>),
}

/// One field of a message type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// Its name.
    pub name: Arc<str>,
    /// Its element type.
    pub base: Base,
    /// One element or several.
    pub shape: Shape,
}

/// A message type: its full name and fields in wire order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MessageType {
    /// `pkg/Type`.
    pub name: Arc<str>,
    /// The fields, in order.
    pub fields: Vec<Field>,
}

impl MessageType {
    /// The index of the field `name`.
    #[must_use]
    pub fn field(&self, name: &str) -> Option<usize> {
        self.fields.iter().position(|f| &*f.name == name)
    }
}

/// A channel's message definitions: the root type and every type it uses.
#[derive(Debug, Clone, PartialEq)]
pub struct Definitions {
    /// The channel's own type.
    pub root: Arc<MessageType>,
    types: HashMap<Arc<str>, Arc<MessageType>>,
    /// The same types in the schema's order.
    all: Vec<Arc<MessageType>>,
}

/// The longest fixed array or bound a schema may declare (a schema is
/// small text; a larger number is a corrupt or hostile file).
pub const MAX_DECLARED_LENGTH: usize = 1 << 24;

/// `pkg/msg/Type` or `pkg/Type` as `pkg/Type`.
fn normalise(name: &str) -> String {
    match name.split('/').collect::<Vec<_>>().as_slice() {
        [pkg, "msg", ty] => format!("{pkg}/{ty}"),
        _ => name.to_string(),
    }
}

impl Definitions {
    /// Parses the `ros2msg` schema `text` of the type `name` (as the MCAP
    /// schema record names it, e.g. `nav_msgs/msg/Odometry`).
    ///
    /// # Errors
    /// A line that is not a field, a constant or a comment; an unknown or
    /// undefined type; a type defined twice; a field with a length beyond
    /// [`MAX_DECLARED_LENGTH`]. Each error names the schema and its line.
    pub fn parse(name: &str, text: &str) -> Result<Self, SchemaError> {
        let err = |line: usize, reason: String| SchemaError {
            schema: name.to_string(),
            line,
            reason,
        };
        let root_name = normalise(name);
        if !root_name.contains('/') {
            return Err(err(0, format!("type name {name:?} has no package")));
        }
        let mut sections: Vec<Section<'_>> = vec![(root_name.clone(), 1, Vec::new())];
        let mut after_rule = false;
        for (k, line) in text.lines().enumerate() {
            let n = k + 1;
            let t = line.trim();
            if t.len() >= 3 && t.bytes().all(|b| b == b'=') {
                after_rule = true;
                continue;
            }
            if after_rule {
                if t.is_empty() {
                    continue;
                }
                let Some(ty) = t.strip_prefix("MSG:") else {
                    return Err(err(
                        n,
                        format!("expected \"MSG: pkg/Type\" after a rule, found {t:?}"),
                    ));
                };
                sections.push((normalise(ty.trim()), n, Vec::new()));
                after_rule = false;
                continue;
            }
            if let Some(last) = sections.last_mut() {
                last.2.push((n, line));
            }
        }
        let mut raw: Vec<(String, usize, Vec<RawField>)> = Vec::new();
        for (ty, at, lines) in sections {
            let package = ty.split('/').next().unwrap_or_default().to_string();
            let mut fields = Vec::new();
            for (n, line) in lines {
                if let Some(f) = field_line(line, &package).map_err(|r| err(n, r))? {
                    fields.push((n, f));
                }
            }
            if raw.iter().any(|(t, _, _)| *t == ty) {
                return Err(err(at, format!("type {ty} is defined twice")));
            }
            raw.push((ty, at, fields));
        }
        for (builtin, fields) in [
            ("builtin_interfaces/Time", ["sec", "nanosec"]),
            ("builtin_interfaces/Duration", ["sec", "nanosec"]),
        ] {
            if !raw.iter().any(|(t, _, _)| t == builtin) {
                let f =
                    |name: &str, p| (0, (name.to_string(), BaseName::Primitive(p), Shape::Single));
                raw.push((
                    builtin.to_string(),
                    0,
                    vec![f(fields[0], Primitive::I32), f(fields[1], Primitive::U32)],
                ));
            }
        }
        let names: Vec<String> = raw.iter().map(|(t, _, _)| t.clone()).collect();
        // One Arc per type name, shared by the type and every field of
        // it, so that the decoder finds a field's type by pointer.
        let interned: Vec<Arc<str>> = names.iter().map(|n| Arc::from(n.as_str())).collect();
        let mut types = HashMap::new();
        let mut all = Vec::with_capacity(raw.len());
        for (k, (_, _, fields)) in raw.into_iter().enumerate() {
            let mut out = Vec::with_capacity(fields.len());
            for (n, (fname, base, shape)) in fields {
                let base = match base {
                    BaseName::Primitive(p) => Base::Primitive(p),
                    BaseName::String => Base::String,
                    BaseName::WString => Base::WString,
                    BaseName::Message(m) => {
                        let Some(i) = names.iter().position(|t| *t == m) else {
                            return Err(err(
                                n,
                                format!("field {fname}: type {m} is not defined in the schema"),
                            ));
                        };
                        Base::Message(interned[i].clone())
                    }
                };
                out.push(Field {
                    name: fname.into(),
                    base,
                    shape,
                });
            }
            let name = interned[k].clone();
            let ty = Arc::new(MessageType { name, fields: out });
            all.push(ty.clone());
            types.insert(interned[k].clone(), ty);
        }
        let root = types[root_name.as_str()].clone();
        Ok(Self { root, types, all })
    }

    /// The message type `name` (`pkg/Type`).
    #[must_use]
    pub fn get(&self, name: &str) -> Option<&Arc<MessageType>> {
        self.types.get(name)
    }

    /// The type a field's [`Base::Message`] names: found by pointer among
    /// the schema's few types (its name is the type's own `Arc`), with no
    /// hashing, else by name.
    #[must_use]
    pub fn resolve(&self, name: &Arc<str>) -> Option<&Arc<MessageType>> {
        self.all
            .iter()
            .find(|t| Arc::ptr_eq(&t.name, name))
            .or_else(|| self.get(name))
    }
}

/// A type's section of a schema: its name, the line it starts on, and its
/// lines with their numbers.
type Section<'a> = (String, usize, Vec<(usize, &'a str)>);

/// A field's element type before the names are checked.
enum BaseName {
    Primitive(Primitive),
    String,
    WString,
    Message(String),
}

type RawField = (usize, (String, BaseName, Shape));

/// Whether `s` is a ROS identifier (a letter, then letters, digits, `_`).
fn identifier(s: &str) -> bool {
    let mut c = s.chars();
    c.next().is_some_and(|c| c.is_ascii_alphabetic())
        && c.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// The field of a line in package `package`, `None` for a blank line, a
/// comment or a constant.
fn field_line(line: &str, package: &str) -> Result<Option<(String, BaseName, Shape)>, String> {
    let t = line.trim();
    if t.is_empty() || t.starts_with('#') {
        return Ok(None);
    }
    let (ty, rest) = t
        .split_once(char::is_whitespace)
        .ok_or_else(|| format!("{t:?} is not \"TYPE NAME\""))?;
    let rest = rest.trim_start();
    let name_end = rest
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(rest.len());
    let name = &rest[..name_end];
    if !identifier(name) {
        return Err(format!("{name:?} is not a field name"));
    }
    if rest[name_end..].trim_start().starts_with('=') {
        return Ok(None);
    }
    let (base, shape) = match ty.find('[') {
        Some(open) => {
            let inner = ty[open..]
                .strip_prefix('[')
                .and_then(|s| s.strip_suffix(']'))
                .ok_or_else(|| format!("type {ty:?}: unclosed array"))?;
            let length = |s: &str| -> Result<usize, String> {
                let v: usize = s
                    .parse()
                    .map_err(|_| format!("type {ty:?}: {s:?} is not a length"))?;
                if v > MAX_DECLARED_LENGTH {
                    return Err(format!(
                        "type {ty:?}: length {v} is beyond {MAX_DECLARED_LENGTH}"
                    ));
                }
                Ok(v)
            };
            let shape = if inner.is_empty() {
                Shape::Sequence(None)
            } else if let Some(bound) = inner.strip_prefix("<=") {
                Shape::Sequence(Some(length(bound)?))
            } else {
                Shape::Fixed(length(inner)?)
            };
            (&ty[..open], shape)
        }
        None => (ty, Shape::Single),
    };
    let base = if let Some(p) = Primitive::named(base) {
        BaseName::Primitive(p)
    } else if base == "string" || base.starts_with("string<=") {
        BaseName::String
    } else if base == "wstring" || base.starts_with("wstring<=") {
        BaseName::WString
    } else if base == "Header" {
        BaseName::Message("std_msgs/Header".into())
    } else {
        let parts: Vec<&str> = base.split('/').collect();
        if !parts.iter().all(|p| identifier(p)) || parts.len() > 3 {
            return Err(format!("{base:?} is not a type"));
        }
        BaseName::Message(match parts.as_slice() {
            [ty] => format!("{package}/{ty}"),
            _ => normalise(base),
        })
    };
    Ok(Some((name.to_string(), base, shape)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_arrays_constants_defaults_and_dependencies_parse() {
        let text = "# a comment\nfloat64[3] v [1.0, 2.0, 3.0]\nint32 K=7\nuint8 MODE = 2\n\
                    string<=10 s\nPoint[<=4] pts # trailing\nstd_msgs/Header header\n\
                    builtin_interfaces/Time stamp\n\
                    ====\nMSG: p/Point\nfloat64 x\n====\nMSG: std_msgs/msg/Header\n\
                    builtin_interfaces/Time stamp\nstring frame_id\n";
        let d = Definitions::parse("p/msg/T", text).unwrap();
        let f = &d.root.fields;
        assert_eq!(d.root.name.as_ref(), "p/T");
        assert_eq!(f.len(), 5, "{f:?}");
        assert_eq!(f[0].shape, Shape::Fixed(3));
        assert_eq!(f[0].base, Base::Primitive(Primitive::F64));
        assert_eq!(
            (f[1].base.clone(), f[1].shape),
            (Base::String, Shape::Single)
        );
        assert_eq!(f[2].base, Base::Message("p/Point".into()));
        assert_eq!(f[2].shape, Shape::Sequence(Some(4)));
        assert_eq!(f[3].base, Base::Message("std_msgs/Header".into()));
        assert!(d.get("builtin_interfaces/Time").is_some());
    }

    #[test]
    fn a_bad_schema_is_refused_with_its_line() {
        let e = Definitions::parse("p/T", "float64 x\nfloat64\n").unwrap_err();
        assert_eq!(e.line, 2, "{e}");
        let e = Definitions::parse("p/T", "float64 x\nOther y\n").unwrap_err();
        assert!(e.to_string().contains("p/Other is not defined"), "{e}");
        let e = Definitions::parse("p/T", "uint8[99999999999] x\n").unwrap_err();
        assert!(e.to_string().contains("beyond"), "{e}");
        let e = Definitions::parse("p/T", "float64 x\n===\nnot a header\n").unwrap_err();
        assert!(e.to_string().contains("MSG:"), "{e}");
    }
}
