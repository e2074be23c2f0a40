//! The compiled plan: passes in execution order, transient textures with their shared
//! allocations, and everything left out.

use std::fmt;
use std::sync::Arc;

use crate::compile::Params;
use crate::registry::NodeKind;
use crate::types::{Extent, PortType, TexFormat};

/// Index of a logical texture in [`Plan::textures`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TextureId(pub usize);

/// One node's work in a frame.
#[derive(Clone)]
pub struct Pass {
    /// Node id.
    pub node: String,
    /// The node's kind: its ports, params, flags (`sink`, `history`, `renders_scene`) and
    /// shader, so that running the pass needs no registry.
    pub kind: Arc<NodeKind>,
    /// Checked params with defaults filled in.
    pub params: Params,
    /// Input port → texture read (optional inputs left unconnected are absent).
    pub inputs: Vec<(&'static str, TextureId)>,
    /// Output port → texture written (only outputs something reads).
    pub outputs: Vec<(&'static str, TextureId)>,
    /// Size of the images the pass works on: its inputs' size, or the size a source
    /// produces. An output port may have another size ([`OutputSize`](crate::registry::OutputSize));
    /// [`Plan::texture`]'s extent is the one a texture really has.
    pub extent: Extent,
}

impl fmt::Debug for Pass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Pass")
            .field("node", &self.node)
            .field("kind", &self.kind.name)
            .field("params", &self.params)
            .field("inputs", &self.inputs)
            .field("outputs", &self.outputs)
            .field("extent", &self.extent)
            .finish()
    }
}

impl Pass {
    /// The texture bound to input `port`.
    pub fn input(&self, port: &str) -> Option<TextureId> {
        self.inputs
            .iter()
            .find(|(p, _)| *p == port)
            .map(|(_, t)| *t)
    }

    /// The texture bound to output `port`, if anything reads it.
    pub fn output(&self, port: &str) -> Option<TextureId> {
        self.outputs
            .iter()
            .find(|(p, _)| *p == port)
            .map(|(_, t)| *t)
    }
}

/// A logical texture: the data on one output port during one frame.
#[derive(Clone, Debug)]
pub struct TextureDesc {
    /// Its index.
    pub id: TextureId,
    /// `"node.port"` of the port that writes it.
    pub name: String,
    /// What it holds.
    pub ty: PortType,
    /// Storage format.
    pub format: TexFormat,
    /// Size.
    pub extent: Extent,
    /// Index of the pass that writes it.
    pub first: usize,
    /// Index of the last pass that reads it (past the last pass for kept textures).
    pub last: usize,
    /// The allocation it lives in.
    pub slot: usize,
}

/// One GPU allocation, shared by textures whose lifetimes do not overlap.
#[derive(Clone, Debug)]
pub struct Slot {
    /// Storage format.
    pub format: TexFormat,
    /// Size.
    pub extent: Extent,
    /// The textures that live in it, in order.
    pub textures: Vec<TextureId>,
}

impl Slot {
    /// Size in bytes.
    pub fn bytes(&self) -> u64 {
        self.extent.pixels() * self.format.bytes_per_pixel()
    }
}

/// Something the compiler did not include, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LeftOut {
    /// What: a node, a texture, a feature.
    pub what: String,
    /// Why.
    pub reason: String,
}

/// A compiled graph, ready to execute.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Passes in execution order.
    pub passes: Vec<Pass>,
    /// Logical textures.
    pub textures: Vec<TextureDesc>,
    /// Allocations.
    pub slots: Vec<Slot>,
    /// Everything left out.
    pub left_out: Vec<LeftOut>,
    /// Outputs of group nodes (`"glow.color"`) with the inner output each shows
    /// (`"glow/tonemap.output"`); see [`crate::group`].
    pub aliases: Vec<(String, String)>,
    /// The colour space of the graph's colour images ([`crate::working_space`]).
    pub working_space: crate::WorkingSpace,
}

impl Plan {
    /// The pass of node `id`.
    pub fn pass(&self, id: &str) -> Option<&Pass> {
        self.passes.iter().find(|p| p.node == id)
    }

    /// The texture on output `"node.port"` (a group node's output is its inner one's).
    pub fn texture_named(&self, port: &str) -> Option<&TextureDesc> {
        let port = self
            .aliases
            .iter()
            .find(|(a, _)| a == port)
            .map_or(port, |(_, b)| b.as_str());
        self.textures.iter().find(|t| t.name == port)
    }

    /// The logical texture `id`.
    pub fn texture(&self, id: TextureId) -> &TextureDesc {
        &self.textures[id.0]
    }

    /// Bytes allocated for transient textures.
    pub fn texture_bytes(&self) -> u64 {
        self.slots.iter().map(Slot::bytes).sum()
    }

    /// Bytes transient textures would take without sharing.
    pub fn unshared_texture_bytes(&self) -> u64 {
        self.textures
            .iter()
            .map(|t| t.extent.pixels() * t.format.bytes_per_pixel())
            .sum()
    }
}

#[expect(clippy::cast_precision_loss, reason = "display only")]
fn mib(bytes: u64) -> String {
    format!("{:.2} MiB", bytes as f64 / (1024.0 * 1024.0))
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.working_space != crate::WorkingSpace::default() {
            writeln!(
                f,
                "working space: {} (the compiler's conversions are the passes named *_to_acescg \
                 and *_to_rec709)",
                self.working_space
            )?;
        }
        writeln!(f, "passes ({}), in order:", self.passes.len())?;
        let w = self.passes.iter().map(|p| p.node.len()).max().unwrap_or(0);
        let k = self
            .passes
            .iter()
            .map(|p| p.kind.name.len())
            .max()
            .unwrap_or(0);
        for (i, p) in self.passes.iter().enumerate() {
            let reads: Vec<_> = p
                .inputs
                .iter()
                .map(|(_, t)| self.textures[t.0].name.as_str())
                .collect();
            let writes: Vec<_> = p
                .outputs
                .iter()
                .map(|(_, t)| self.textures[t.0].name.as_str())
                .collect();
            write!(
                f,
                "  {:>2}. {:<w$}  {:<k$} {:>9}",
                i + 1,
                p.node,
                p.kind.name,
                p.extent.to_string()
            )?;
            if !reads.is_empty() {
                write!(f, "  reads {}", reads.join(", "))?;
            }
            if !writes.is_empty() {
                write!(f, "  writes {}", writes.join(", "))?;
            }
            writeln!(f)?;
        }
        writeln!(
            f,
            "textures ({} in {} allocations, {}; {} without sharing):",
            self.textures.len(),
            self.slots.len(),
            mib(self.texture_bytes()),
            mib(self.unshared_texture_bytes())
        )?;
        for (s, slot) in self.slots.iter().enumerate() {
            let users: Vec<_> = slot
                .textures
                .iter()
                .map(|t| {
                    let t = &self.textures[t.0];
                    let last = if t.last >= self.passes.len() {
                        "end".to_owned()
                    } else {
                        (t.last + 1).to_string()
                    };
                    format!("{} (passes {}-{last})", t.name, t.first + 1)
                })
                .collect();
            let shared = if slot.textures.len() > 1 {
                "  shared by"
            } else {
                ""
            };
            writeln!(
                f,
                "  #{s} {} {} {}{shared}: {}",
                slot.format.name(),
                slot.extent,
                mib(slot.bytes()),
                users.join(", ")
            )?;
        }
        if self.left_out.is_empty() {
            writeln!(f, "left out: nothing")?;
        } else {
            writeln!(f, "left out ({}):", self.left_out.len())?;
            for l in &self.left_out {
                writeln!(f, "  {}: {}", l.what, l.reason)?;
            }
        }
        Ok(())
    }
}
