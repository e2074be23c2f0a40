//! Uniform param blocks: `#[repr(C)]` [`bytemuck::Pod`] structs that mirror a WGSL struct
//! field by field, declared with [`param_block!`](crate::param_block), which also records
//! where the WGSL twin is. A GPU-free test ([`check_layout`] over [`BLOCKS`]) holds every
//! block to naga's layout of its twin, so a field added on one side only fails before any
//! GPU runs. Enum params reach shaders as the index of their option in the registry
//! ([`enum_index`]), and a test holds the shaders' constants to that order.

use lumagraph_graph::{ParamType, Pass};

use crate::error::{RenderError, Result};

/// Where a param block's WGSL twin is and how the Rust struct is laid out.
#[derive(Clone, Copy, Debug)]
pub struct BlockLayout {
    /// The Rust struct's name.
    pub name: &'static str,
    /// The shader file (under `shaders/`) that declares the twin; for a block of a kind
    /// defined outside this crate, its own file, checked with [`check_layout_in`].
    pub shader: &'static str,
    /// The WGSL struct's name.
    pub wgsl: &'static str,
    /// `size_of` the Rust struct.
    pub size: usize,
    /// Field names and byte offsets, in declaration order.
    pub fields: &'static [(&'static str, usize)],
}

/// A Rust struct uploaded as a WGSL struct.
pub trait ParamBlock: bytemuck::Pod {
    /// Its layout and its WGSL twin.
    const LAYOUT: BlockLayout;
}

/// Declares a param block: the `#[repr(C)]` `Pod` struct and its [`ParamBlock`] impl.
///
/// ```ignore
/// param_block! {
///     /// Exposure's params.
///     pub(crate) struct ExposureParams in "post/exposure.wgsl" as "Params" {
///         scale: f32,
///     }
/// }
/// ```
#[macro_export]
macro_rules! param_block {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident in $shader:literal as $wgsl:literal {
            $($(#[$fmeta:meta])* $field:ident: $ty:ty),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        $vis struct $name {
            $($(#[$fmeta])* pub $field: $ty),*
        }

        impl $crate::params::ParamBlock for $name {
            const LAYOUT: $crate::params::BlockLayout = $crate::params::BlockLayout {
                name: stringify!($name),
                shader: $shader,
                wgsl: $wgsl,
                size: ::std::mem::size_of::<$name>(),
                fields: &[$((stringify!($field), ::std::mem::offset_of!($name, $field))),*],
            };
        }
    };
}

/// Every param block of this crate's nodes and of [`crate::shared`], for the layout test
/// (the path tracer's crate checks its own).
pub const BLOCKS: &[BlockLayout] = &[
    <crate::nodes::tonemap::TonemapParams as ParamBlock>::LAYOUT,
    <crate::nodes::accumulate::AccumulateParams as ParamBlock>::LAYOUT,
    <crate::nodes::temporal::TemporalParams as ParamBlock>::LAYOUT,
    <crate::nodes::denoise::DenoiseParams as ParamBlock>::LAYOUT,
    <crate::nodes::regression::RegressionParams as ParamBlock>::LAYOUT,
    <crate::nodes::blur::BlurParams as ParamBlock>::LAYOUT,
    <crate::nodes::bloom::BloomParams as ParamBlock>::LAYOUT,
    <crate::nodes::lut::LutParams as ParamBlock>::LAYOUT,
    <crate::nodes::difference::DifferenceParams as ParamBlock>::LAYOUT,
    <crate::nodes::auto_exposure::AutoExposureParams as ParamBlock>::LAYOUT,
    <crate::shared::WaveRays as ParamBlock>::LAYOUT,
];

/// Whether `layout` matches naga's layout of its WGSL twin in its shader file under
/// `shaders/`: the same size (the WGSL struct's span) and the same field names at the same
/// offsets.
///
/// # Errors
/// What differs, naming the block and the field.
pub fn check_layout(layout: &BlockLayout) -> std::result::Result<(), String> {
    let source = crate::shader::resolve(layout.shader).map_err(|e| e.to_string())?;
    check_layout_in(layout, &source)
}

/// [`check_layout`] against the WGSL text `source` (the shader of a node kind defined
/// outside this crate, with its imports resolved).
///
/// # Errors
/// What differs, naming the block and the field.
pub fn check_layout_in(layout: &BlockLayout, source: &str) -> std::result::Result<(), String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("{}: {}", layout.shader, e.emit_to_string(source)))?;
    let mut layouter = naga::proc::Layouter::default();
    layouter
        .update(module.to_ctx())
        .map_err(|e| format!("{}: {e}", layout.shader))?;
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(layout.wgsl))
        .ok_or_else(|| format!("{}: no struct {}", layout.shader, layout.wgsl))?;
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        return Err(format!(
            "{}: {} is not a struct",
            layout.shader, layout.wgsl
        ));
    };
    let what = format!("{} ({} in {})", layout.name, layout.wgsl, layout.shader);
    if *span as usize != layout.size {
        return Err(format!(
            "{what}: {} bytes in Rust, {span} in WGSL",
            layout.size
        ));
    }
    let wgsl: Vec<(&str, usize)> = members
        .iter()
        .map(|m| (m.name.as_deref().unwrap_or("?"), m.offset as usize))
        .collect();
    if wgsl.as_slice() != layout.fields {
        return Err(format!(
            "{what}: Rust fields {:?}, WGSL {wgsl:?}",
            layout.fields
        ));
    }
    Ok(())
}

/// The index of the option an enum param of `pass` is set to, in the order the registry
/// lists its options: the number its shader is given.
///
/// # Errors
/// When the param is not an enum of the pass's kind or its value is not one of its options
/// (the compiler refuses such graphs; this refuses them again rather than guess).
pub fn enum_index(pass: &Pass, param: &str) -> Result<u32> {
    let options = pass
        .kind
        .param(param)
        .and_then(|p| match &p.ty {
            ParamType::Enum { options, .. } => Some(*options),
            _ => None,
        })
        .ok_or_else(|| {
            RenderError::Gpu(format!("{} has no enum param \"{param}\"", pass.kind.name))
        })?;
    let value = pass.params.str(param);
    options
        .iter()
        .position(|(name, _)| *name == value)
        .and_then(|i| u32::try_from(i).ok())
        .ok_or_else(|| {
            let known: Vec<&str> = options.iter().map(|o| o.0).collect();
            RenderError::Gpu(format!(
                "param \"{param}\" is \"{value}\", not one of {}",
                known.join(", ")
            ))
            .in_node(&pass.node)
        })
}

/// The values of the `u32` constants of `shader` whose names start with `prefix`, by name.
///
/// # Errors
/// When the shader does not resolve or parse.
pub fn shader_constants(
    shader: &str,
    prefix: &str,
) -> std::result::Result<Vec<(String, u32)>, String> {
    let source = crate::shader::resolve(shader).map_err(|e| e.to_string())?;
    let module = naga::front::wgsl::parse_str(&source).map_err(|e| e.emit_to_string(&source))?;
    Ok(module
        .constants
        .iter()
        .filter_map(|(_, c)| {
            let name = c.name.as_deref()?;
            if !name.starts_with(prefix) {
                return None;
            }
            match module.global_expressions[c.init] {
                naga::Expression::Literal(naga::Literal::U32(v)) => Some((name.to_owned(), v)),
                _ => None,
            }
        })
        .collect())
}

/// The enum params whose options a shader numbers with constants `PREFIX_OPTION`: (kind,
/// param, shader, prefix).
pub const ENUM_CONSTANTS: &[(&str, &str, &str, &str)] = &[
    ("Tonemap", "operator", "post/tonemap.wgsl", "TONEMAP_"),
    (
        "PathTrace",
        "sampler",
        "pathtrace/integrator/pathtrace.wgsl",
        "SAMPLER_",
    ),
    (
        "PathTrace",
        "strategy",
        "pathtrace/integrator/pathtrace.wgsl",
        "STRATEGY_",
    ),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_param_block_matches_its_wgsl_struct() {
        let failures: Vec<String> = BLOCKS
            .iter()
            .filter_map(|b| check_layout(b).err())
            .collect();
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }

    #[test]
    fn a_block_that_differs_from_its_twin_is_caught() {
        let mut wrong = <crate::nodes::tonemap::TonemapParams as ParamBlock>::LAYOUT;
        wrong.fields = &[("white", 0), ("op", 4)];
        assert!(check_layout(&wrong).unwrap_err().contains("Rust fields"));
        wrong = <crate::nodes::tonemap::TonemapParams as ParamBlock>::LAYOUT;
        wrong.size = 12;
        assert!(
            check_layout(&wrong)
                .unwrap_err()
                .contains("12 bytes in Rust")
        );
    }

    /// Each enum option's shader constant is its index in the registry's options.
    #[test]
    fn shader_enum_constants_follow_the_registry() {
        let registry = lumagraph_graph::Registry::with_builtins();
        for &(kind, param, shader, prefix) in ENUM_CONSTANTS {
            let ParamType::Enum { options, .. } =
                &registry.get(kind).unwrap().param(param).unwrap().ty
            else {
                panic!("{kind}.{param} is not an enum");
            };
            let constants = shader_constants(shader, prefix).unwrap();
            assert_eq!(
                constants.len(),
                options.len(),
                "{kind}.{param}: {constants:?}"
            );
            for (i, (option, _)) in options.iter().enumerate() {
                let name = format!("{prefix}{}", option.to_ascii_uppercase());
                let value = constants.iter().find(|c| c.0 == name).map(|c| c.1);
                assert_eq!(value, Some(i as u32), "{kind}.{param}: {name}");
            }
        }
    }
}
