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
        if path.is_empty() {
            return Some(at);
        }
        for step in path.split('.') {
            let (name, mut indices) = match step.find('[') {
                Some(i) => (&step[..i], &step[i..]),
                None => (step, ""),
            };
            if !name.is_empty() {
                let Value::Message(m) = at else { return None };
                at = m.field(name)?;
            }
            while let Some(rest) = indices.strip_prefix('[') {
                let close = rest.find(']')?;
                let i: usize = rest[..close].parse().ok()?;
                let Value::List(items) = at else { return None };
                at = items.get(i)?;
                indices = &rest[close + 1..];
            }
            if !indices.is_empty() {
                return None;
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
