//! A decoded message: a tree of values typed by its schema, read by field
//! path (`twist.twist.linear.x`, `ranges[3]`, `transforms[0].child_frame_id`).

use alloc::sync::Arc;

use crate::msgdef::MessageType;

/// One decoded value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// `bool`.
    Bool(bool),
    /// A signed integer (`int8` to `int64`).
    Int(i64),
    /// An unsigned integer (`byte`, `char`, `uint8` to `uint64`).
    UInt(u64),
    /// `float32` (exactly) or `float64`.
    Float(f64),
    /// `string`.
    Str(String),
    /// An array or a sequence.
    List(Vec<Value>),
    /// A message: its type and its fields' values in the type's order.
    Message(Message),
}

/// A decoded message of a known type.
#[derive(Debug, Clone, PartialEq)]
pub struct Message {
    /// Its type.
    pub ty: Arc<MessageType>,
    /// Its fields' values, in the order of `ty.fields`.
    pub fields: Vec<Value>,
}

impl Message {
    /// The value of the field `name`.
    #[must_use]
    pub fn field(&self, name: &str) -> Option<&Value> {
        self.ty.field(name).map(|i| &self.fields[i])
    }
}

impl Value {
    /// The value at `path`: field names separated by `.`, each optionally
    /// followed by `[index]`s; `None` if a step does not exist.
    #[must_use]
    pub fn get(&self, path: &str) -> Option<&Value> {
        let mut at = self;
        let bytes = path.as_bytes();
        let mut i = 0;
        while i < bytes.len() {
            // A field's name runs to the next `.` or `[`.
            let start = i;
            while i < bytes.len() && bytes[i] != b'.' && bytes[i] != b'[' {
                i += 1;
            }
            if i > start {
                let Value::Message(m) = at else { return None };
                at = m.field(&path[start..i])?;
            }
            while i < bytes.len() && bytes[i] == b'[' {
                let close = i + path[i..].find(']')?;
                let k: usize = path[i + 1..close].parse().ok()?;
                let Value::List(items) = at else { return None };
                at = items.get(k)?;
                i = close + 1;
            }
            if i < bytes.len() {
                if bytes[i] != b'.' || i + 1 == bytes.len() {
                    return None;
                }
                i += 1;
            }
        }
        Some(at)
    }

    /// The value as a number, for any numeric or boolean value.
    #[must_use]
    #[allow(clippy::cast_precision_loss)]
    pub fn as_f64(&self) -> Option<f64> {
        match *self {
            Value::Float(v) => Some(v),
            Value::Int(v) => Some(v as f64),
            Value::UInt(v) => Some(v as f64),
            Value::Bool(v) => Some(f64::from(u8::from(v))),
            _ => None,
        }
    }

    /// The value as text, for a string.
    #[must_use]
    pub fn as_str(&self) -> Option<&str> {
        match self {
            Value::Str(s) => Some(s),
            _ => None,
        }
    }

    /// The elements, for an array or a sequence.
    #[must_use]
    pub fn as_list(&self) -> Option<&[Value]> {
        match self {
            Value::List(v) => Some(v),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgdef::Definitions;

    #[test]
    fn a_path_reads_fields_and_elements_and_nothing_else() {
        let d = Definitions::parse("p/T", "P[] pts\nfloat64 s\n===\nMSG: p/P\nfloat64[2] xy\n")
            .unwrap();
        let p = d.get("p/P").unwrap().clone();
        let point = |a: f64, b: f64| {
            Value::Message(Message {
                ty: p.clone(),
                fields: vec![Value::List(vec![Value::Float(a), Value::Float(b)])],
            })
        };
        let v = Value::Message(Message {
            ty: d.root.clone(),
            fields: vec![
                Value::List(vec![point(1.0, 2.0), point(3.0, 4.0)]),
                Value::Float(5.0),
            ],
        });
        assert_eq!(v.get("s"), Some(&Value::Float(5.0)));
        assert_eq!(v.get("pts[1].xy[0]"), Some(&Value::Float(3.0)));
        assert_eq!(
            v.get("pts[0].xy")
                .and_then(Value::as_list)
                .map(<[Value]>::len),
            Some(2)
        );
        assert_eq!(v.get(""), Some(&v));
        for bad in [
            "s.", "pts[2]", "pts[x]", "pts[0", "pts..xy", "q", "s[0]", "pts[0]xy", "pts.xy",
        ] {
            assert_eq!(v.get(bad), None, "{bad}");
        }
    }
}
