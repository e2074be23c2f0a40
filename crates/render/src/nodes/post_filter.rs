//! The generic post filter: every registry kind that names a `shader` runs here. The pass
//! reads the kind's inputs (in declaration order, one texture binding each), writes its
//! outputs (in declaration order, one storage texture each) and gets the node's params in
//! declaration order in the shader's `Params` struct (float → `f32`, int → `i32`, bool and
//! enum option index → `u32`), then one `has_<input>: u32` per optional input (1 when it
//! is connected; an unconnected one reads as zeros). A new filter of this shape is its
//! registry entry, its WGSL and its CPU reference test, with no Rust of its own. [`check`]
//! holds every such kind's shader to that contract without a GPU.

use lumagraph_graph::{NodeKind, ParamType, Pass};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::kernel::Binding;
use crate::nodes::{FilterPass, NodeExec, NodeImpl, Recording, boxed};

/// The implementation of every kind with a `shader` (its `kind` is a placeholder:
/// [`crate::nodes::implementation`] hands it out for those kinds).
pub(crate) const IMPL: NodeImpl = NodeImpl::new("(post filter)", |ctx, pass, _| {
    boxed(PostFilter::new(ctx, pass))
});

/// The WGSL type each kind of param is given as.
fn wgsl_scalar(ty: &ParamType) -> Option<&'static str> {
    match ty {
        ParamType::Float { .. } => Some("f32"),
        ParamType::Int { .. } => Some("i32"),
        ParamType::Bool { .. } | ParamType::Enum { .. } => Some("u32"),
        _ => None,
    }
}

/// The node's params packed for its `Params` struct, 4 bytes each in declaration order,
/// then whether each optional input is connected.
fn pack(kind: &NodeKind, pass: &Pass) -> Result<Vec<u8>> {
    let mut words: Vec<u32> = Vec::with_capacity(kind.params.len());
    for p in &kind.params {
        #[expect(clippy::cast_possible_truncation, reason = "GPU math is f32 and i32")]
        let word = match p.ty {
            ParamType::Float { .. } => (pass.params.float(p.name) as f32).to_bits(),
            ParamType::Int { .. } => (pass.params.int(p.name) as i32).cast_unsigned(),
            ParamType::Bool { .. } => u32::from(pass.params.bool(p.name)),
            ParamType::Enum { .. } => crate::params::enum_index(pass, p.name)?,
            _ => {
                return Err(RenderError::Gpu(format!(
                    "{}: param \"{}\" cannot be given to a shader",
                    kind.name, p.name
                )));
            }
        };
        words.push(word);
    }
    for i in kind.inputs.iter().filter(|i| i.optional) {
        words.push(u32::from(pass.input(i.name).is_some()));
    }
    words.resize(words.len().next_multiple_of(4).max(4), 0);
    Ok(bytemuck::cast_slice(&words).to_vec())
}

struct PostFilter {
    filter: FilterPass,
}

impl PostFilter {
    fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let shader = pass
            .kind
            .shader
            .as_ref()
            .ok_or_else(|| RenderError::Unimplemented(pass.kind.name.to_owned()))?;
        Ok(Self {
            filter: FilterPass::new(ctx, shader, &pack(&pass.kind, pass)?)?,
        })
    }
}

impl NodeExec for PostFilter {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        self.filter.set_params(ctx, &pack(&pass.kind, pass)?);
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        self.filter.record(pass, rec)
    }
}

/// Whether `kind`'s shader keeps the generic filter's contract: bindings one texture per
/// input, (a sampler,) one storage texture per output in the format of the port's type,
/// uniform `Params`; and `Params` declares the kind's params, by name, in order, as the
/// scalars they are packed as, then `has_<input>: u32` per optional input.
///
/// # Errors
/// What differs.
pub fn check(kind: &NodeKind) -> std::result::Result<(), String> {
    let shader = kind.shader.as_ref().ok_or("no shader")?;
    let source = crate::shader::source_of(shader).map_err(|e| e.to_string())?;
    let (bindings, _) =
        crate::kernel::reflect(shader.label(), &source).map_err(|e| e.to_string())?;
    if kind.outputs.is_empty() {
        return Err(format!(
            "{}: a generic post filter has an output",
            kind.name
        ));
    }
    let outputs = kind.outputs.iter().map(|o| Binding::StorageTexture {
        format: crate::pool::wgpu_format(o.ty.format()),
        access: wgpu::StorageTextureAccess::WriteOnly,
    });
    let want: Vec<(String, String)> = kind
        .params
        .iter()
        .map(|p| {
            (
                p.name.to_owned(),
                wgsl_scalar(&p.ty)
                    .unwrap_or("(not a shader param)")
                    .to_owned(),
            )
        })
        .chain(
            kind.inputs
                .iter()
                .filter(|i| i.optional)
                .map(|i| (format!("has_{}", i.name), "u32".to_owned())),
        )
        .collect();
    // A kind with nothing to pass has no param block (WGSL has no empty structs).
    let uniform = (!want.is_empty()).then_some(Binding::Uniform);
    let n = kind.inputs.len();
    let filtered = Binding::FilteredTexture {
        dim: wgpu::TextureViewDimension::D2,
    };
    let plain: Vec<Binding> = std::iter::repeat_n(Binding::Texture, n)
        .chain(outputs.clone())
        .chain(uniform)
        .collect();
    let sampling: Vec<Binding> = std::iter::repeat_n(filtered, n)
        .chain([Binding::Sampler])
        .chain(outputs)
        .chain(uniform)
        .collect();
    if bindings != plain && bindings != sampling {
        return Err(format!(
            "{shader}: bindings {bindings:?}, want {plain:?} (one texture per input, one \
             storage texture per output, as post/filter.wgsl) or {sampling:?} (with a \
             sampler, as post/resample.wgsl)"
        ));
    }
    if want.is_empty() {
        return Ok(());
    }
    let module = naga::front::wgsl::parse_str(&source).map_err(|e| e.emit_to_string(&source))?;
    let (_, params) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some("Params"))
        .ok_or_else(|| format!("{shader}: no struct Params"))?;
    let naga::TypeInner::Struct { members, .. } = &params.inner else {
        return Err(format!("{shader}: Params is not a struct"));
    };
    let got: Vec<(String, String)> = members
        .iter()
        .map(|m| {
            let ty = match module.types[m.ty].inner {
                naga::TypeInner::Scalar(s) => match (s.kind, s.width) {
                    (naga::ScalarKind::Float, 4) => "f32",
                    (naga::ScalarKind::Sint, 4) => "i32",
                    (naga::ScalarKind::Uint, 4) => "u32",
                    _ => "?",
                },
                _ => "?",
            };
            (m.name.clone().unwrap_or_default(), ty.to_owned())
        })
        .collect();
    if got != want {
        return Err(format!(
            "{shader}: struct Params has {got:?}; the {} node's params are {want:?}",
            kind.name
        ));
    }
    Ok(())
}
