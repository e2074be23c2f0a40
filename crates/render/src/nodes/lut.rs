//! `LUT`: a 3D LUT from a `.cube` file (Adobe/Resolve format), uploaded as a 3D texture and
//! applied by `shaders/post/lut.wgsl`. The parser and [`Lut::apply`], the CPU reference of
//! the shader, are here.

use std::path::{Path, PathBuf};

use lumagraph_graph::Pass;

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{NodeExec, NodeImpl, Recording, Resources, boxed};

/// The `LUT` kind.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("LUT", |ctx, pass, resources| {
    boxed(LutNode::new(ctx, pass, resources))
});

/// Largest `LUT_3D_SIZE` accepted (256³ texels are 256 MiB as rgba32f).
pub const MAX_SIZE: usize = 256;

/// A 3D LUT: `size`³ rgb entries, red the fastest index, then green, then blue.
#[derive(Clone, Debug, PartialEq)]
pub struct Lut {
    /// Entries per axis.
    pub size: usize,
    /// Input value mapped to the first entry, per channel.
    pub domain_min: [f32; 3],
    /// Input value mapped to the last entry, per channel.
    pub domain_max: [f32; 3],
    /// The entries.
    pub table: Vec<[f32; 3]>,
}

impl Lut {
    /// Parses the text of a `.cube` file; `path` names it in errors, each with its line.
    ///
    /// # Errors
    /// A 1D LUT, a missing or bad `LUT_3D_SIZE`, a line that is not three numbers, a
    /// domain with max ≤ min, or a count of entries other than size³.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let err = |line: usize, m: String| RenderError::image(path, format!("line {line}: {m}"));
        let mut size = None;
        let mut domain_min = [0.0_f32; 3];
        let mut domain_max = [1.0_f32; 3];
        let mut table = Vec::new();
        let numbers = |line: usize, words: &[&str]| -> Result<[f32; 3]> {
            let v: Vec<f32> = words
                .iter()
                .map(|w| w.parse::<f32>().ok().filter(|v| v.is_finite()))
                .collect::<Option<_>>()
                .ok_or_else(|| {
                    err(
                        line,
                        format!("\"{}\" is not three finite numbers", words.join(" ")),
                    )
                })?;
            <[f32; 3]>::try_from(v)
                .map_err(|v| err(line, format!("{} numbers where 3 belong", v.len())))
        };
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let content = raw.split('#').next().unwrap_or("").trim();
            let words: Vec<&str> = content.split_whitespace().collect();
            let Some(&first) = words.first() else {
                continue;
            };
            match first {
                "TITLE" => {}
                "LUT_1D_SIZE" | "LUT_1D_INPUT_RANGE" => {
                    return Err(err(
                        line,
                        "1D LUTs are not supported (only LUT_3D_SIZE)".into(),
                    ));
                }
                "LUT_3D_SIZE" => {
                    let n = words
                        .get(1)
                        .and_then(|w| w.parse::<usize>().ok())
                        .filter(|n| (2..=MAX_SIZE).contains(n))
                        .ok_or_else(|| err(line, format!("LUT_3D_SIZE must be 2 to {MAX_SIZE}")))?;
                    size = Some(n);
                }
                "DOMAIN_MIN" => domain_min = numbers(line, &words[1..])?,
                "DOMAIN_MAX" => domain_max = numbers(line, &words[1..])?,
                "LUT_3D_INPUT_RANGE" => {
                    let [lo, hi, _] = numbers(line, &[&words[1..], &["0"]].concat())?;
                    domain_min = [lo; 3];
                    domain_max = [hi; 3];
                }
                w if w.starts_with(|c: char| c.is_ascii_alphabetic()) => {
                    return Err(err(line, format!("unknown keyword \"{w}\"")));
                }
                _ => {
                    if size.is_none() {
                        return Err(err(line, "entries before LUT_3D_SIZE".into()));
                    }
                    table.push(numbers(line, &words)?);
                }
            }
        }
        let size = size.ok_or_else(|| err(text.lines().count(), "no LUT_3D_SIZE".into()))?;
        if table.len() != size * size * size {
            return Err(err(
                text.lines().count(),
                format!(
                    "{} entries; LUT_3D_SIZE {size} needs {}",
                    table.len(),
                    size * size * size
                ),
            ));
        }
        if (0..3).any(|c| domain_max[c] <= domain_min[c]) {
            return Err(err(
                0,
                "DOMAIN_MAX must be above DOMAIN_MIN in every channel".into(),
            ));
        }
        Ok(Self {
            size,
            domain_min,
            domain_max,
            table,
        })
    }

    /// Reads and parses a `.cube` file.
    ///
    /// # Errors
    /// When it cannot be read, or as [`Lut::parse`].
    pub fn load(path: &Path) -> Result<Self> {
        let text = lumagraph_graph::read_text(path).map_err(|e| RenderError::image(path, e))?;
        Self::parse(&text, path)
    }

    fn entry(&self, [r, g, b]: [usize; 3]) -> [f64; 3] {
        self.table[(b * self.size + g) * self.size + r].map(f64::from)
    }

    /// The CPU reference of the shader: `rgb` looked up, trilinear or tetrahedral.
    pub fn apply(&self, rgb: [f64; 3], tetrahedral: bool) -> [f64; 3] {
        let n = (self.size - 1) as f64;
        let mut i = [0_usize; 3];
        let mut f = [0.0; 3];
        for c in 0..3 {
            let (lo, hi) = (f64::from(self.domain_min[c]), f64::from(self.domain_max[c]));
            let t = ((rgb[c] - lo) / (hi - lo)).clamp(0.0, 1.0) * n;
            #[expect(
                clippy::cast_possible_truncation,
                clippy::cast_sign_loss,
                reason = "in [0, n]"
            )]
            let k = (t.floor() as usize).min(self.size - 2);
            i[c] = k;
            f[c] = t - k as f64;
        }
        let at = |d: [usize; 3]| self.entry([i[0] + d[0], i[1] + d[1], i[2] + d[2]]);
        let lerp = |a: [f64; 3], b: [f64; 3], t: f64| [0, 1, 2].map(|c| a[c] + (b[c] - a[c]) * t);
        if !tetrahedral {
            let x0 = lerp(
                lerp(at([0, 0, 0]), at([1, 0, 0]), f[0]),
                lerp(at([0, 1, 0]), at([1, 1, 0]), f[0]),
                f[1],
            );
            let x1 = lerp(
                lerp(at([0, 0, 1]), at([1, 0, 1]), f[0]),
                lerp(at([0, 1, 1]), at([1, 1, 1]), f[0]),
                f[1],
            );
            return lerp(x0, x1, f[2]);
        }
        // The tetrahedron holding f: corners along the path from 000 to 111 that steps the
        // largest fraction's axis first.
        let mut order = [0, 1, 2];
        order.sort_by(|&a, &b| f[b].total_cmp(&f[a]));
        let mut corner = [0_usize; 3];
        let mut out = at(corner).map(|v| v * (1.0 - f[order[0]]));
        for k in 0..3 {
            corner[order[k]] = 1;
            let w = f[order[k]] - if k < 2 { f[order[k + 1]] } else { 0.0 };
            let c = at(corner);
            for ch in 0..3 {
                out[ch] += w * c[ch];
            }
        }
        out
    }
}

crate::param_block! {
    /// The shader's params.
    pub(crate) struct LutParams in "post/lut.wgsl" as "Params" {
        size: u32,
        tetrahedral: u32,
        pad0: u32,
        pad1: u32,
        domain_min: [f32; 4],
        domain_max: [f32; 4],
    }
}

struct LutNode {
    kernel: Kernel,
    params: wgpu::Buffer,
    resources: Resources,
    loaded: Option<Loaded>,
}

/// The file a LUT node has loaded: its table on the GPU, its size and domain.
struct Loaded {
    path: PathBuf,
    block: LutParams,
    view: wgpu::TextureView,
}

impl LutNode {
    fn new(ctx: &GpuContext, pass: &Pass, resources: &Resources) -> Result<Self> {
        let mut node = Self {
            kernel: Kernel::new(ctx, "post/lut.wgsl")?,
            params: uniform_buffer(ctx, "lut params", bytemuck::bytes_of(&LutParams::default())),
            resources: resources.clone(),
            loaded: None,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

/// Uploads `lut` as an `rgba32float` 3D texture (x red, y green, z blue).
fn upload(ctx: &GpuContext, lut: &Lut) -> wgpu::TextureView {
    let n = u32::try_from(lut.size).unwrap_or(2);
    let size = wgpu::Extent3d {
        width: n,
        height: n,
        depth_or_array_layers: n,
    };
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("lut"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let texels: Vec<[f32; 4]> = lut
        .table
        .iter()
        .map(|[r, g, b]| [*r, *g, *b, 1.0])
        .collect();
    ctx.queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(&texels),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(n * 16),
            rows_per_image: Some(n),
        },
        size,
    );
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

impl NodeExec for LutNode {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let path = self.resources.input(pass.params.str("path"));
        if self.loaded.as_ref().is_none_or(|l| l.path != path) {
            // Parsed and uploaded only when the file changes, not on every param edit.
            let lut = Lut::load(&path)?;
            let d = |v: [f32; 3], w| [v[0], v[1], v[2], w];
            self.loaded = Some(Loaded {
                block: LutParams {
                    size: u32::try_from(lut.size).unwrap_or(2),
                    domain_min: d(lut.domain_min, 0.0),
                    domain_max: d(lut.domain_max, 1.0),
                    ..LutParams::default()
                },
                view: upload(ctx, &lut),
                path,
            });
        }
        let Some(loaded) = &self.loaded else {
            return Ok(());
        };
        let block = LutParams {
            tetrahedral: crate::params::enum_index(pass, "interpolation")?,
            ..loaded.block
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&block));
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, timer) = rec.parts();
        let (Some(out), Some(Loaded { view: lut, .. })) = (pass.output("color"), &self.loaded)
        else {
            return Ok(());
        };
        self.kernel
            .pass(&pass.node)
            .read(&io.input(pass, "color")?.view)
            .read(lut)
            .write(&io.texture(out).view)
            .uniform(&self.params)
            .dispatch_2d(ctx, encoder, pass.extent, timer)
    }
}
