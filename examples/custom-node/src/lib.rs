//! A node kind written in Rust outside lumagraph's crates: `ZonePlate`, a procedural
//! source with its own compute shader (`src/zone_plate.wgsl`).
//!
//! A kind is two values: its registry entry ([`kind`]: ports, params, docs) and its
//! implementation ([`IMPL`]: how a pass of it is created on the GPU, and for a source, the
//! size of its image). [`library`] adds both to the built-in node library; the binary
//! (`src/main.rs`) runs the whole `lumagraph` command line, editor included, with it.
//! [`reference`] computes the same image on the CPU, for the tests.
//!
//! A zone plate's rings get finer with the distance from the centre, so one image holds
//! every frequency up to `frequency` cycles per pixel: what a resampling filter does with
//! each shows at a glance (`graphs/zone_plate.ron` shrinks it with `Resize`'s two kernels).

use std::path::Path;

use lumagraph::graph::registry::{OutputDef, ParamDef, Reach};
use lumagraph::graph::{Category, Extent, NodeKind, Params, Pass, PortType};
use lumagraph::render::cpu::Image;
use lumagraph::render::nodes::{NodeExec, NodeImpl, Recording, boxed};
use lumagraph::render::{GpuContext, Kernel, NodeLibrary, Result, uniform_buffer, wgpu};

/// The kind's name, as graph files write it.
pub const NAME: &str = "ZonePlate";

/// The compute shader: one invocation per pixel writes the pattern.
pub const SHADER: &str = include_str!("zone_plate.wgsl");

/// The largest `width` and `height`.
const MAX_SIDE: i64 = 16384;

lumagraph::render::param_block! {
    /// The shader's `Params` (a test holds the two to the same layout).
    pub struct ZonePlateParams in "zone_plate.wgsl" as "Params" {
        frequency: f32,
    }
}

/// The registry entry: no inputs (a source), one output, the image size and the
/// frequency reached at half the width as params.
pub fn kind() -> NodeKind {
    NodeKind {
        name: NAME,
        category: Category::Input,
        doc: "A circular zone plate, 0.5 + 0.5 cos(π f r² / R) around the image centre with \
              R half the width: rings whose frequency grows from 0 at the centre to \
              `frequency` cycles per pixel at R, to show what a resampling filter does with \
              each frequency.",
        inputs: Vec::new(),
        outputs: vec![OutputDef::new(
            "color",
            PortType::HdrColor,
            "the pattern, grey in [0, 1], alpha 1",
        )],
        params: vec![
            ParamDef::int("width", 512, [1, MAX_SIDE], "image width in pixels"),
            ParamDef::int("height", 512, [1, MAX_SIDE], "image height in pixels"),
            ParamDef::float(
                "frequency",
                0.5,
                [0.0, 2.0],
                "cycles per pixel at half the width from the centre (0.5: the finest a \
                 pixel grid holds)",
            ),
        ],
        sink: false,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: Reach::Image("it draws its rings around the whole image's centre"),
    }
}

/// How `ZonePlate` runs: a [`ZonePlate`] per pass, its image sized by its params.
pub const IMPL: NodeImpl =
    NodeImpl::new(NAME, |ctx, pass, _| boxed(ZonePlate::new(ctx, pass))).sized_by(extent);

/// The image size `width` × `height` (the compiler has checked both are in range).
fn extent(_base_dir: &Path, params: &Params) -> std::result::Result<Extent, String> {
    let side = |name: &str| {
        u32::try_from(params.int(name))
            .map_err(|_| format!("{name} {} is out of range", params.int(name)))
    };
    Ok(Extent::new(side("width")?, side("height")?))
}

/// The built-in node library with `ZonePlate` added.
///
/// # Errors
/// When the library refuses the kind (it would, were a kind of that name built in).
pub fn library() -> Result<NodeLibrary> {
    lumagraph::pathtrace::library::with_builtins().with_kind(kind(), IMPL)
}

/// `ZonePlate`'s GPU side: the shader's pipeline and its param block.
#[derive(Debug)]
pub struct ZonePlate {
    kernel: Kernel,
    params: wgpu::Buffer,
}

impl ZonePlate {
    /// Compiles the shader and writes the params of `pass`.
    ///
    /// # Errors
    /// When the shader does not compile.
    pub fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let mut node = Self {
            kernel: Kernel::from_source(ctx, "zone_plate.wgsl", SHADER)?,
            params: uniform_buffer(
                ctx,
                "zone plate params",
                bytemuck::bytes_of(&ZonePlateParams::default()),
            ),
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for ZonePlate {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        #[expect(clippy::cast_possible_truncation, reason = "GPU math is f32")]
        let block = ZonePlateParams {
            frequency: pass.params.float("frequency") as f32,
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&block));
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, timer) = rec.parts();
        // An output nothing reads is not planned: nothing to do.
        let Some(out) = pass.output("color") else {
            return Ok(());
        };
        self.kernel
            .pass(&pass.node)
            .write(&io.texture(out).view)
            .uniform(&self.params)
            .dispatch_2d(ctx, encoder, pass.extent, timer)
    }
}

/// What `ZonePlate` computes, on the CPU in `f64`: the tests' reference.
pub fn reference(width: u32, height: u32, frequency: f64) -> Image {
    let (cx, cy) = (f64::from(width) / 2.0, f64::from(height) / 2.0);
    let mut image = Image::filled(width, height, [0.0, 0.0, 0.0, 1.0]);
    for y in 0..height {
        for x in 0..width {
            let (dx, dy) = (f64::from(x) + 0.5 - cx, f64::from(y) + 0.5 - cy);
            let phase = std::f64::consts::PI * frequency * (dx * dx + dy * dy) / cx;
            #[expect(clippy::cast_possible_truncation, reason = "a value in [0, 1]")]
            let v = (0.5 + 0.5 * phase.cos()) as f32;
            image.pixels[(y * width + x) as usize] = [v, v, v, 1.0];
        }
    }
    image
}
