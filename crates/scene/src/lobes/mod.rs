//! The material's parameters, declared once. A material is one record on the GPU
//! ([`GpuMaterial`], WGSL `Material`), read by the lobes of `shaders/pathtrace/bsdf/`; the
//! record and the parameters the lobes take from the scene format are two tables in
//! `lobes/table.rs`, and everything else is derived from them:
//!
//! - **The record's layout**, `material_record!`: the Rust struct [`GpuMaterial`] (`repr(C)`,
//!   `Pod`), its WGSL twin `struct Material`, written from the same rows ([`wgsl`], served by
//!   the shader loader as `pathtrace/material.wgsl`, which `scene_types.wgsl` imports, as
//!   `pathtrace/shapes.wgsl` is served), its field list [`GpuMaterial::FIELDS`] (the
//!   specializer's inline material rows, the layout test against naga) and its values
//!   ([`GpuMaterial::values`]).
//! - **The lobe parameters**, `lobe_params!`: each a lobe's name, its field name, scalar or
//!   RGB, its default, the check the loader applies, its editor label, tooltip and range,
//!   and its doc. From them: the fields of the scene format's
//!   [`MaterialDesc`](crate::file::MaterialDesc) and their defaults, the fields of
//!   [`Material`](crate::Material) and their defaults, and [`PARAMS`], which the loader
//!   (checks), the flattener (the record's field of the same name), save (the format's text),
//!   export (Mitsuba's JSON) and the editor's scene panel (a slider or a colour) go through.
//!
//! Adding a parameter to a lobe: its row in `lobe_params!`, its field in `material_record!`
//! (same name; a padding slot or new space at the end), and the lobe's WGSL reading it.

mod table;

use std::fmt::Write as _;

use glam::Vec3;

pub(crate) use table::lobe_params;
pub use table::{GpuMaterial, PARAMS};

/// The name shaders import the WGSL `Material` struct by.
pub const FILE: &str = "pathtrace/material.wgsl";

/// A field of the GPU record: its name, WGSL type (`f32`, `u32` or `vec3f`), offset and doc.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    /// The name, the same in Rust and WGSL.
    pub name: &'static str,
    /// The WGSL type.
    pub wgsl: &'static str,
    /// Its offset in bytes.
    pub offset: usize,
    /// Its doc comment, one line per source line.
    pub doc: &'static str,
}

/// A value of a field of the GPU record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// `f32`.
    F32(f32),
    /// `u32`.
    U32(u32),
    /// `vec3f`.
    Vec3f([f32; 3]),
}

impl From<f32> for Value {
    fn from(x: f32) -> Self {
        Self::F32(x)
    }
}

impl From<u32> for Value {
    fn from(x: u32) -> Self {
        Self::U32(x)
    }
}

impl From<[f32; 3]> for Value {
    fn from(x: [f32; 3]) -> Self {
        Self::Vec3f(x)
    }
}

/// The WGSL `Material` struct, written from [`GpuMaterial::FIELDS`]: `pathtrace/material.wgsl`.
pub fn wgsl() -> String {
    let size = std::mem::size_of::<GpuMaterial>();
    let mut out = format!(
        "// Generated from crates/scene/src/lobes/table.rs (`material_record!`): the twin of\n\
         // GpuMaterial, field by field. Not a file on disk.\n\n\
         // Material, {size} bytes. Texture indices: 16 bits each, 0xffff = none; each texture\n\
         // multiplies its factor (see textures.wgsl).\n\
         struct Material {{\n"
    );
    for f in GpuMaterial::FIELDS {
        for line in f.doc.lines() {
            let _ = writeln!(out, "    //{}", line.trim_end());
        }
        let _ = writeln!(out, "    {}: {},", f.name, f.wgsl);
    }
    out.push_str("}\n");
    out
}

/// A lobe parameter as the tools see it (a row of `lobe_params!`).
pub struct Param {
    /// The lobe it belongs to (`diffuse`, `specular`, `transmission`, `coat`, `sheen`).
    pub lobe: &'static str,
    /// Its field name: the scene format's, [`crate::Material`]'s and [`GpuMaterial`]'s.
    pub name: &'static str,
    /// Its doc.
    pub doc: &'static str,
    /// The editor's label.
    pub label: &'static str,
    /// The editor's tooltip.
    pub tip: &'static str,
    /// The editor's range: a slider's maximum (from 0), or a colour's largest channel.
    pub max: f32,
    /// The scene format's value, checked, into the material ([`crate::Scene::load`]).
    pub(crate) load:
        fn(&crate::file::MaterialDesc, &mut crate::Material) -> Result<(), crate::SceneError>,
    /// The material's value into the record's field of the same name.
    pub(crate) flatten: fn(&crate::Material, &mut GpuMaterial),
    /// The value in the scene format's text.
    pub(crate) save: fn(&crate::file::MaterialDesc) -> String,
    /// The value as export's JSON writes it.
    pub(crate) export: fn(&crate::Material) -> serde_json::Value,
    /// The value to edit, in the scene format's description.
    pub edit: fn(&mut crate::file::MaterialDesc) -> ParamMut<'_>,
}

/// A parameter's value in a [`crate::file::MaterialDesc`], to edit.
pub enum ParamMut<'a> {
    /// A scalar.
    Scalar(&'a mut f32),
    /// A linear RGB colour.
    Rgb(&'a mut [f32; 3]),
}

/// The types a parameter takes: `f32` everywhere, or an RGB colour (`[f32; 3]` in the
/// scene format and the record, [`Vec3`] in [`crate::Material`]).
pub(crate) trait Kind: Copy {
    /// The type in [`crate::Material`].
    type Scene: Copy;
    /// The scene format's spelling.
    fn text(self) -> String;
    /// The record's field from the material's.
    fn gpu(s: Self::Scene) -> Self;
    /// To edit.
    fn edit(&mut self) -> ParamMut<'_>;
}

impl Kind for f32 {
    type Scene = f32;
    fn text(self) -> String {
        crate::save::num(self)
    }
    fn gpu(s: f32) -> Self {
        s
    }
    fn edit(&mut self) -> ParamMut<'_> {
        ParamMut::Scalar(self)
    }
}

impl Kind for [f32; 3] {
    type Scene = Vec3;
    fn text(self) -> String {
        crate::save::vec3(self)
    }
    fn gpu(s: Vec3) -> Self {
        s.to_array()
    }
    fn edit(&mut self) -> ParamMut<'_> {
        ParamMut::Rgb(self)
    }
}

/// A parameter's type in the scene format (`f32` or `rgb`).
macro_rules! desc_ty {
    (f32) => {
        f32
    };
    (rgb) => {
        [f32; 3]
    };
}

/// A parameter's type in [`crate::Material`].
macro_rules! scene_ty {
    (f32) => {
        f32
    };
    (rgb) => {
        glam::Vec3
    };
}

/// A parameter's value in [`crate::Material`] from its scene-format value.
macro_rules! scene_value {
    (f32, $v:expr) => {
        $v
    };
    (rgb, $v:expr) => {
        glam::Vec3::from_array($v)
    };
}

pub(crate) use {desc_ty, scene_ty, scene_value};
