//! Node kinds declared in a graph file (`kinds: [...]`, version 2): ports, params and a
//! WGSL function, made into registry kinds when the graph is loaded. The render crate
//! writes the shader around the function and validates it ([`Shader::Generated`]).
//!
//! A kind's names live as long as the program: the registry's kinds are `'static`
//! declarations, so names read from files are interned ([`intern`]), each distinct
//! string once.

use std::collections::HashSet;
use std::sync::{Arc, Mutex};

use serde::{Deserialize, Serialize};

use crate::registry::{Category, InputDef, NodeKind, OutputDef, ParamDef, Reach};
use crate::types::{ParamType, PortType};

/// The `'static` copy of `s`, made once per distinct string.
pub fn intern(s: &str) -> &'static str {
    static STRINGS: Mutex<Option<HashSet<&'static str>>> = Mutex::new(None);
    let mut guard = STRINGS
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let set = guard.get_or_insert_with(HashSet::new);
    if let Some(&found) = set.get(s) {
        return found;
    }
    let leaked: &'static str = Box::leak(s.to_owned().into_boxed_str());
    set.insert(leaked);
    leaked
}

/// The `'static` copy of a list of port types or enum options, made once per distinct list.
pub(crate) fn intern_slice<T: Clone + Eq + std::hash::Hash + Send + Sync + 'static>(
    items: Vec<T>,
) -> &'static [T] {
    use std::any::Any;
    static SLICES: Mutex<Vec<&'static (dyn Any + Send + Sync)>> = Mutex::new(Vec::new());
    let mut guard = SLICES
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    for s in guard.iter() {
        if let Some(found) = s.downcast_ref::<&'static [T]>()
            && **found == *items
        {
            return found;
        }
    }
    let slice: &'static [T] = Box::leak(items.into_boxed_slice());
    guard.push(Box::leak(Box::new(slice)));
    slice
}

/// The shader of a kind run by the generic post filter.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Shader {
    /// A file under `shaders/` (the built-in kinds).
    File(&'static str),
    /// A whole WGSL module made at run time, for a kind declared in a graph file.
    Generated(Arc<GeneratedShader>),
}

impl Shader {
    /// A name for messages and GPU labels: the file, or the kind and where it was declared.
    pub fn label(&self) -> &str {
        match self {
            Self::File(f) => f,
            Self::Generated(g) => &g.label,
        }
    }
}

impl std::fmt::Display for Shader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

/// WGSL made for a kind declared in a graph file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GeneratedShader {
    /// What it is, for messages and GPU labels.
    pub label: String,
    /// The module.
    pub text: String,
}

/// A param's type as a graph file declares it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ParamTypeDecl {
    /// A number in `[min, max]`.
    Float {
        /// Value when a node does not set one.
        default: f64,
        /// Smallest allowed value.
        min: f64,
        /// Largest allowed value.
        max: f64,
    },
    /// An integer in `[min, max]`.
    Int {
        /// Value when a node does not set one.
        default: i64,
        /// Smallest allowed value.
        min: i64,
        /// Largest allowed value.
        max: i64,
    },
    /// On or off.
    Bool {
        /// Value when a node does not set one.
        default: bool,
    },
    /// One of `options` (its index reaches the shader).
    Enum {
        /// Value when a node does not set one.
        default: String,
        /// The allowed names.
        options: Vec<String>,
    },
}

/// A param of a declared kind.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamDecl {
    /// Name: a WGSL identifier (it is a member of the shader's `params`).
    pub name: String,
    /// Type, default and range.
    #[serde(rename = "type")]
    pub ty: ParamTypeDecl,
    /// One line for docs and tooltips.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub doc: String,
}

/// An input port of a declared kind.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InputDecl {
    /// Name: a WGSL identifier (the shader reads it as a texture of that name).
    pub name: String,
    /// Port types accepted, by name (`"hdr_color"`); empty: `hdr_color`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub types: Vec<String>,
    /// Whether it may stay unconnected (the shader sees `params.has_<name>`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub optional: bool,
    /// One line for docs and tooltips.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub doc: String,
}

/// An output port of a declared kind.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputDecl {
    /// Name: a WGSL identifier.
    pub name: String,
    /// Port type by name (`"hdr_color"`, the default).
    #[serde(rename = "type", default = "hdr_color")]
    pub ty: String,
    /// One line for docs and tooltips.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub doc: String,
}

fn hdr_color() -> String {
    PortType::HdrColor.name().to_owned()
}

/// A node kind declared in a graph file: its ports and params, and the WGSL function
/// `node` that computes an output pixel, written in the file (`code`) or in a `.wgsl` file
/// beside it (`wgsl`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KindDecl {
    /// Name nodes use as their `kind`; not a built-in kind's.
    pub name: String,
    /// What it does, for docs and tooltips.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub doc: String,
    /// Menu category by name (`"Color"`); empty: `Custom`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub category: String,
    /// Input ports.
    #[serde(default)]
    pub inputs: Vec<InputDecl>,
    /// Output ports: at least one.
    pub outputs: Vec<OutputDecl>,
    /// Params.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub params: Vec<ParamDecl>,
    /// A `.wgsl` file holding the function, relative to the graph file's folder (or empty).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub wgsl: String,
    /// The function's WGSL, written in the graph file (or empty).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub code: String,
}

/// Whether `s` can name a port or param: a WGSL identifier of lower-case letters, digits
/// and `_`, not starting with a digit or `_`, and not one the generated code uses.
fn is_identifier(s: &str) -> bool {
    const TAKEN: &[&str] = &[
        "params", "main", "node", "size", "pixel", "id", "let", "var", "fn", "const", "if", "else",
        "for", "loop", "return", "struct", "true", "false", "switch", "case", "while", "break",
        "continue", "discard", "default", "override", "enable", "alias",
    ];
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_ascii_lowercase())
        && chars.all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        && !TAKEN.contains(&s)
        && s.len() <= 64
}

fn port_type(name: &str) -> Result<PortType, String> {
    PortType::ALL
        .into_iter()
        .find(|t| t.name() == name)
        .ok_or_else(|| {
            let known: Vec<&str> = PortType::ALL.iter().map(|t| t.name()).collect();
            format!("unknown port type \"{name}\" (known: {})", known.join(", "))
        })
}

impl KindDecl {
    /// The registry kind it declares, to be run by the generic post filter with `shader`.
    ///
    /// # Errors
    /// A name that is not an identifier, an unknown port type or category, no output,
    /// a bad range or default, both or neither of `wgsl` and `code`.
    pub fn to_kind(&self, shader: Shader) -> Result<NodeKind, String> {
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            return Err(format!(
                "kind name \"{}\" must be letters, digits and _",
                self.name
            ));
        }
        if self.outputs.is_empty() {
            return Err("a kind needs at least one output".into());
        }
        let category = if self.category.is_empty() {
            Category::Custom
        } else {
            let c = &self.category;
            Category::ALL
                .into_iter()
                .find(|k| k.name().eq_ignore_ascii_case(c))
                .ok_or_else(|| format!("unknown category \"{c}\""))?
        };
        let check = |what: &str, name: &str| {
            if is_identifier(name) {
                Ok(())
            } else {
                Err(format!(
                    "{what} name \"{name}\" must be a lower-case identifier (a-z, 0-9, _) \
                     that the generated shader does not use"
                ))
            }
        };
        let mut inputs = Vec::with_capacity(self.inputs.len());
        for i in &self.inputs {
            check("input", &i.name)?;
            let types: Vec<PortType> = if i.types.is_empty() {
                vec![PortType::HdrColor]
            } else {
                i.types
                    .iter()
                    .map(|t| port_type(t))
                    .collect::<Result<_, _>>()
                    .map_err(|e| format!("input \"{}\": {e}", i.name))?
            };
            let def = InputDef::new(intern(&i.name), intern_slice(types), intern(&i.doc));
            inputs.push(if i.optional { def.optional() } else { def });
        }
        let mut outputs = Vec::with_capacity(self.outputs.len());
        for o in &self.outputs {
            check("output", &o.name)?;
            let ty = port_type(&o.ty).map_err(|e| format!("output \"{}\": {e}", o.name))?;
            outputs.push(OutputDef::new(intern(&o.name), ty, intern(&o.doc)));
        }
        let params = self
            .params
            .iter()
            .map(|p| {
                check("param", &p.name)?;
                param_def(p).map_err(|m| format!("param \"{}\": {m}", p.name))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let taken: Vec<&str> = inputs
            .iter()
            .map(|i| i.name)
            .chain(outputs.iter().map(|o| o.name))
            .chain(params.iter().map(|p| p.name))
            .collect();
        for i in &inputs {
            let flag = format!("has_{}", i.name);
            if i.optional && taken.contains(&flag.as_str()) {
                return Err(format!(
                    "\"{flag}\" is taken: it tells whether \"{}\" is connected",
                    i.name
                ));
            }
        }
        if self.wgsl.is_empty() == self.code.trim().is_empty() {
            return Err(
                "give the shader function as `wgsl` (a file) or `code`, one of them".into(),
            );
        }
        Ok(NodeKind {
            name: intern(&self.name),
            category,
            doc: intern(&self.doc),
            inputs,
            outputs,
            params,
            sink: false,
            history: false,
            renders_scene: false,
            shader: Some(shader),
            example: Vec::new(),
            reach: Reach::Image(
                "a kind declared in a graph file: lumagraph cannot tell how far its shader reads",
            ),
        })
    }
}

/// The registry param a declaration makes.
///
/// # Errors
/// A default outside its range, or not one of the options.
fn param_def(p: &ParamDecl) -> Result<ParamDef, String> {
    let ty = match &p.ty {
        ParamTypeDecl::Float { default, min, max } => {
            if !(min <= default && default <= max) {
                return Err(format!("default {default} is not in [{min}, {max}]"));
            }
            ParamType::Float {
                default: *default,
                min: *min,
                max: *max,
            }
        }
        ParamTypeDecl::Int { default, min, max } => {
            if !(min <= default && default <= max) {
                return Err(format!("default {default} is not in [{min}, {max}]"));
            }
            ParamType::Int {
                default: *default,
                min: *min,
                max: *max,
            }
        }
        ParamTypeDecl::Bool { default } => ParamType::Bool { default: *default },
        ParamTypeDecl::Enum { default, options } => {
            if !options.contains(default) {
                return Err(format!("default \"{default}\" is not an option"));
            }
            let options: Vec<(&'static str, &'static str)> =
                options.iter().map(|o| (intern(o), "")).collect();
            ParamType::Enum {
                default: intern(default),
                options: intern_slice(options),
            }
        }
    };
    Ok(ParamDef {
        name: intern(&p.name),
        ty,
        doc: intern(&p.doc),
    })
}
