//! What flows along edges (port types), what a node is configured with (params),
//! and the texture formats the plan assigns.

use std::fmt;

use serde::{Deserialize, Deserializer, Serialize, Serializer, de};

/// The type of data carried by a port. An edge is allowed when the input port
/// accepts the output port's type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum PortType {
    /// Linear, scene-referred RGB radiance (any non-negative value).
    HdrColor,
    /// Display-encoded RGB in \[0, 1\] (sRGB transfer function applied).
    LdrColor,
    /// Linear surface albedo in \[0, 1\].
    Albedo,
    /// World-space unit shading normal.
    Normal,
    /// Linear depth along the camera ray.
    Depth,
    /// Per-pixel variance estimate of a color signal.
    Variance,
    /// One value per pixel, of any meaning: a depth, a matte, a luminance read from a file.
    Scalar,
    /// Up to four values per pixel that are not colour: motion (`u`, `v`), a normal or a
    /// position read from a file.
    Vector,
}

impl PortType {
    /// Every port type, for documentation and menus.
    pub const ALL: [Self; 8] = [
        Self::HdrColor,
        Self::LdrColor,
        Self::Albedo,
        Self::Normal,
        Self::Depth,
        Self::Variance,
        Self::Scalar,
        Self::Vector,
    ];

    /// Short name used in messages and docs.
    pub fn name(self) -> &'static str {
        match self {
            Self::HdrColor => "hdr_color",
            Self::LdrColor => "ldr_color",
            Self::Albedo => "albedo",
            Self::Normal => "normal",
            Self::Depth => "depth",
            Self::Variance => "variance",
            Self::Scalar => "scalar",
            Self::Vector => "vector",
        }
    }

    /// One-line description for docs and tooltips.
    pub fn doc(self) -> &'static str {
        match self {
            Self::HdrColor => "linear scene-referred RGB, unbounded",
            Self::LdrColor => "display-encoded RGB in [0, 1] (sRGB transfer)",
            Self::Albedo => "linear surface albedo",
            Self::Normal => "world-space unit shading normal",
            Self::Depth => "linear depth along the camera ray",
            Self::Variance => "per-pixel variance of a color signal",
            Self::Scalar => "one value per pixel (a depth, a matte, a luminance)",
            Self::Vector => "up to four values per pixel that are not colour (motion, a normal)",
        }
    }

    /// The texture format a texture of this type is stored in.
    pub fn format(self) -> TexFormat {
        match self {
            Self::HdrColor | Self::Albedo | Self::Normal | Self::Variance | Self::Vector => {
                TexFormat::Rgba32Float
            }
            Self::LdrColor => TexFormat::Rgba8Unorm,
            Self::Depth | Self::Scalar => TexFormat::R32Float,
        }
    }
}

impl fmt::Display for PortType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Storage format of a planned texture. The render crate maps these to GPU formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TexFormat {
    /// Four 32-bit floats per pixel.
    Rgba32Float,
    /// Four 8-bit unsigned normalized channels.
    Rgba8Unorm,
    /// One 32-bit float per pixel.
    R32Float,
}

impl TexFormat {
    /// Bytes per pixel.
    pub fn bytes_per_pixel(self) -> u64 {
        match self {
            Self::Rgba32Float => 16,
            Self::Rgba8Unorm | Self::R32Float => 4,
        }
    }

    /// Short name used in plans.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rgba32Float => "rgba32f",
            Self::Rgba8Unorm => "rgba8",
            Self::R32Float => "r32f",
        }
    }
}

/// Width and height of an image in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Extent {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Extent {
    /// A new extent.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height }
    }

    /// Number of pixels.
    pub fn pixels(self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }
}

impl fmt::Display for Extent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

/// The declared type of a node parameter, with its default and valid range.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum ParamType {
    /// A real number in `[min, max]`.
    Float {
        /// Value when the file does not set one.
        default: f64,
        /// Smallest allowed value.
        min: f64,
        /// Largest allowed value.
        max: f64,
    },
    /// An integer in `[min, max]`.
    Int {
        /// Value when the file does not set one.
        default: i64,
        /// Smallest allowed value.
        min: i64,
        /// Largest allowed value.
        max: i64,
    },
    /// On or off.
    Bool {
        /// Value when the file does not set one.
        default: bool,
    },
    /// One of a fixed set of names.
    Enum {
        /// Value when the file does not set one.
        default: &'static str,
        /// The allowed names, each with a one-line description.
        options: &'static [(&'static str, &'static str)],
    },
    /// A file path; relative paths are resolved against the graph file's folder
    /// (inputs) or the output folder (outputs, which must stay inside it:
    /// [`crate::outputs`]).
    Path {
        /// Value when the file does not set one.
        default: &'static str,
        /// File extensions the node understands, lower case, without the dot.
        extensions: &'static [&'static str],
    },
    /// Any text, empty included (a layer's or a view's name).
    Text {
        /// Value when the file does not set one.
        default: &'static str,
    },
}

impl ParamType {
    /// The default value.
    pub fn default_value(&self) -> ParamValue {
        match self {
            Self::Float { default, .. } => ParamValue::Float(*default),
            Self::Int { default, .. } => ParamValue::Int(*default),
            Self::Bool { default } => ParamValue::Bool(*default),
            Self::Enum { default, .. } | Self::Path { default, .. } | Self::Text { default } => {
                ParamValue::Str((*default).to_owned())
            }
        }
    }

    /// Short name of the type for messages and docs.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Float { .. } => "float",
            Self::Int { .. } => "int",
            Self::Bool { .. } => "bool",
            Self::Enum { .. } => "enum",
            Self::Path { .. } => "path",
            Self::Text { .. } => "text",
        }
    }

    /// Checks `value` against this type and returns it in canonical form
    /// (an integer given for a float parameter becomes a float).
    ///
    /// # Errors
    /// A message saying what was expected when the value does not fit.
    pub fn check(&self, value: &ParamValue) -> Result<ParamValue, String> {
        match (self, value) {
            // A number written as a frame expression: its value at the default frame (a
            // sequence writes each frame's number in first, `crate::expr::substitute`).
            (Self::Float { .. }, ParamValue::Str(text)) => {
                let v = crate::expr::evaluate(text, crate::expr::DEFAULT_FRAME)
                    .map_err(|e| format!("expected float or a frame expression: {e}"))?;
                self.check(&ParamValue::Float(v))
                    .map_err(|e| format!("{text:?} gives {v}: {e}"))
            }
            (Self::Int { .. }, ParamValue::Str(text)) => {
                let v = crate::expr::evaluate(text, crate::expr::DEFAULT_FRAME)
                    .map_err(|e| format!("expected integer or a frame expression: {e}"))?
                    .round();
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "a finite value, range-checked as an integer below"
                )]
                let i = v.clamp(i64::MIN as f64, i64::MAX as f64) as i64;
                self.check(&ParamValue::Int(i))
                    .map_err(|e| format!("{text:?} gives {v}: {e}"))
            }
            (Self::Float { min, max, .. }, ParamValue::Float(_) | ParamValue::Int(_)) => {
                let v = value.as_f64().unwrap_or(f64::NAN);
                if !v.is_finite() {
                    return Err(format!("expected a finite number, found {v}"));
                }
                if v < *min || v > *max {
                    return Err(format!("{v} is out of range [{min}, {max}]"));
                }
                Ok(ParamValue::Float(v))
            }
            (Self::Int { min, max, .. }, ParamValue::Int(v)) => {
                if v < min || v > max {
                    return Err(format!("{v} is out of range [{min}, {max}]"));
                }
                Ok(value.clone())
            }
            (Self::Bool { .. }, ParamValue::Bool(_)) => Ok(value.clone()),
            (Self::Enum { options, .. }, ParamValue::Str(s)) => {
                if options.iter().any(|(name, _)| name == s) {
                    Ok(value.clone())
                } else {
                    let names: Vec<_> = options.iter().map(|(n, _)| format!("\"{n}\"")).collect();
                    Err(format!("\"{s}\" is not one of {}", names.join(", ")))
                }
            }
            (Self::Path { .. }, ParamValue::Str(s)) => {
                if s.is_empty() {
                    Err("the path is empty".to_owned())
                } else {
                    Ok(value.clone())
                }
            }
            (Self::Text { .. }, ParamValue::Str(_)) => Ok(value.clone()),
            _ => Err(format!(
                "expected {}, found {}",
                self.name(),
                value.type_name()
            )),
        }
    }
}

/// A parameter value as written in a graph file.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// `true` or `false`.
    Bool(bool),
    /// An integer literal.
    Int(i64),
    /// A real literal.
    Float(f64),
    /// A string: enum names and paths.
    Str(String),
}

impl ParamValue {
    /// The value as a float, when it is a number.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            #[expect(clippy::cast_precision_loss, reason = "params are small integers")]
            Self::Int(v) => Some(*v as f64),
            Self::Float(v) => Some(*v),
            _ => None,
        }
    }

    /// Short name of the value's type for messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            Self::Bool(_) => "bool",
            Self::Int(_) => "int",
            Self::Float(_) => "float",
            Self::Str(_) => "string",
        }
    }

    /// Parses a value written as in a graph file (`1.5`, `true`, `"aces"`); a bare word
    /// that is not a number or bool is taken as a string, so `--set tonemap.operator=aces` works.
    ///
    /// # Errors
    /// When the text is not a single value.
    pub fn parse(text: &str) -> Result<Self, String> {
        let text = text.trim();
        match ron::from_str::<Self>(text) {
            Ok(v) => Ok(v),
            Err(_) if !text.is_empty() && !text.contains(['"', ',', '(', '[', '{']) => {
                Ok(Self::Str(text.to_owned()))
            }
            Err(e) => Err(format!("cannot parse `{text}` as a value: {}", e.code)),
        }
    }
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Bool(v) => write!(f, "{v}"),
            Self::Int(v) => write!(f, "{v}"),
            Self::Float(v) => write!(f, "{v:?}"),
            Self::Str(v) => write!(f, "{v:?}"),
        }
    }
}

impl Serialize for ParamValue {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Bool(v) => s.serialize_bool(*v),
            Self::Int(v) => s.serialize_i64(*v),
            Self::Float(v) => s.serialize_f64(*v),
            Self::Str(v) => s.serialize_str(v),
        }
    }
}

impl<'de> Deserialize<'de> for ParamValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl de::Visitor<'_> for Visitor {
            type Value = ParamValue;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a bool, a number or a string")
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<ParamValue, E> {
                Ok(ParamValue::Bool(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ParamValue, E> {
                Ok(ParamValue::Int(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ParamValue, E> {
                i64::try_from(v)
                    .map(ParamValue::Int)
                    .map_err(|_| E::custom("integer too large"))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<ParamValue, E> {
                Ok(ParamValue::Float(v))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<ParamValue, E> {
                Ok(ParamValue::Str(v.to_owned()))
            }
        }
        d.deserialize_any(Visitor)
    }
}
