//! Layers: a part's channels grouped by name, and found by the names users bring.
//!
//! A channel `a.b.C` belongs to layer `a.b` (its name up to the last dot); root channels
//! (`R`, `G`, `B`, `A`, `Z`) to the root layer `""`. Within a layer, `R`, `G`, `B` (and
//! `A`) make a **colour** layer, `Y` (with `RY`, `BY`, `A`) a **luminance** layer; one
//! channel is a **scalar** layer (a depth, a matte), two to four others a **vector** layer
//! (`forward.u`/`forward.v`, `N.X`/`N.Y`/`N.Z`). Channels left over beside colour or
//! luminance (a root `Z`) are scalar layers of their own, named by the channel (`Z`).
//! In a single-part multi-view file (`multiView`), a channel whose first name is another
//! view's (`right.R`) belongs to that view; the rest to the default view.
//!
//! [`Selection`] finds a layer by any of the names it is known by:
//! - its name in the part (`forward`, `ViewLayer.Combined`), or a tail of it after a dot
//!   (`Combined`, as Blender's passes are called);
//! - a single channel's full name (`depth.Z`, `ViewLayer.Depth.Z`, or a tail: `Depth.Z`);
//! - the part's name, with its view's suffix taken off (`depth` for the part
//!   `depth_left` of view `left`), alone for the part's root layer or before the
//!   layer's name;
//!
//! exactly first, then ignoring case. Only layers of the chosen view (the default view
//! when none is chosen) are candidates; two candidates are an error naming both.

use super::{Info, Part};

/// What a layer's channels hold, which decides the port it is read onto.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerKind {
    /// `R`, `G`, `B` and maybe `A`.
    Color {
        /// Whether `A` is there.
        alpha: bool,
    },
    /// `Y`, maybe with `RY` and `BY` (chroma) and `A`.
    Luminance {
        /// Whether `RY` and `BY` are there.
        chroma: bool,
        /// Whether `A` is there.
        alpha: bool,
    },
    /// One channel.
    Scalar,
    /// Two to four channels that are not colour.
    Vector,
}

impl LayerKind {
    /// `color`, `luminance`, `luminance/chroma`, `scalar` or `vector`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Color { .. } => "color",
            Self::Luminance { chroma: false, .. } => "luminance",
            Self::Luminance { chroma: true, .. } => "luminance/chroma",
            Self::Scalar => "scalar",
            Self::Vector => "vector",
        }
    }
}

/// A group of a part's channels read together.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    /// The part it is in.
    pub part: usize,
    /// Its view, when the file has views.
    pub view: Option<String>,
    /// Its name in the part (`""` for the root layer).
    pub name: String,
    /// Its channels' full names, in reading order (`R G B A`, `Y RY BY A`, or as stored).
    pub channels: Vec<String>,
    /// What they hold.
    pub kind: LayerKind,
}

impl Layer {
    /// The names it is found by, most specific first (see the module's doc).
    pub fn names(&self, part: &Part) -> Vec<String> {
        let mut names = Vec::new();
        if !self.name.is_empty() {
            names.push(self.name.clone());
        }
        if let Some(part_name) = &part.name {
            let base = part_base_name(part_name, part.view.as_deref());
            for p in [base, part_name.as_str()] {
                names.push(if self.name.is_empty() {
                    p.to_owned()
                } else {
                    format!("{p}.{}", self.name)
                });
            }
        }
        if let [only] = self.channels.as_slice() {
            names.push(strip_view(only, part, self.view.as_deref()).to_owned());
        }
        names.dedup();
        names
    }

    /// How it is shown in lists: its part's name and its own.
    pub fn label(&self, part: &Part) -> String {
        match (&part.name, self.name.is_empty()) {
            (Some(p), true) => format!("{p:?}"),
            (Some(p), false) => format!("{p:?}: {}", self.name),
            (None, true) => "(root)".to_owned(),
            (None, false) => self.name.clone(),
        }
    }
}

/// The name of a part without its view's suffix (`depth_left` → `depth`).
fn part_base_name<'a>(name: &'a str, view: Option<&str>) -> &'a str {
    let Some(view) = view else {
        return name;
    };
    for sep in ['_', '-', '.'] {
        if let Some(base) = name
            .strip_suffix(view)
            .and_then(|rest| rest.strip_suffix(sep))
            .filter(|b| !b.is_empty())
        {
            return base;
        }
    }
    name
}

/// A channel's name without the leading view name of a multi-view part.
fn strip_view<'a>(channel: &'a str, part: &Part, view: Option<&str>) -> &'a str {
    match view {
        Some(v) if part.multi_view.first().map(String::as_str) != Some(v) => channel
            .strip_prefix(v)
            .and_then(|rest| rest.strip_prefix('.'))
            .unwrap_or(channel),
        _ => channel,
    }
}

/// Every layer of every part of `info`, in file order.
pub(super) fn of(info: &Info) -> Vec<Layer> {
    info.parts.iter().flat_map(layers_of_part).collect()
}

/// A group of channels: its view and its layer name.
type GroupKey = (Option<String>, String);

fn layers_of_part(part: &Part) -> Vec<Layer> {
    // (view, layer name) → (suffix, full name), in channel order.
    let mut groups: Vec<(GroupKey, Vec<(String, String)>)> = Vec::new();
    let default_view = part.multi_view.first();
    for channel in &part.channels {
        let full = channel.name.as_str();
        let (view, rest) = match full.split_once('.') {
            Some((first, rest))
                if part.multi_view.iter().any(|v| v == first)
                    && Some(&first.to_owned()) != default_view =>
            {
                (Some(first.to_owned()), rest)
            }
            _ => (part.view.clone().or_else(|| default_view.cloned()), full),
        };
        let (layer, suffix) = rest.rsplit_once('.').unwrap_or(("", rest));
        let key = (view, layer.to_owned());
        let entry = (suffix.to_owned(), full.to_owned());
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, members)) => members.push(entry),
            None => groups.push((key, vec![entry])),
        }
    }
    let mut out = Vec::new();
    for ((view, name), members) in groups {
        let layer = |name: String, channels: Vec<String>, kind| Layer {
            part: part.index,
            view: view.clone(),
            name,
            channels,
            kind,
        };
        let find = |s: &str| {
            members
                .iter()
                .find(|(suffix, _)| suffix == s)
                .map(|(_, f)| f.clone())
        };
        let (main, used): (Option<(Vec<String>, LayerKind)>, Vec<&str>) =
            match (find("R"), find("G"), find("B"), find("Y")) {
                (Some(r), Some(g), Some(b), _) => {
                    let a = find("A");
                    let alpha = a.is_some();
                    let channels = [Some(r), Some(g), Some(b), a]
                        .into_iter()
                        .flatten()
                        .collect();
                    (
                        Some((channels, LayerKind::Color { alpha })),
                        vec!["R", "G", "B", "A"],
                    )
                }
                (_, _, _, Some(y))
                    if (members.len() > 1 || name.is_empty())
                        && members.iter().all(|(suffix, _)| {
                            ["Y", "RY", "BY", "A"].contains(&suffix.as_str())
                        }) =>
                {
                    let (ry, by, a) = (find("RY"), find("BY"), find("A"));
                    let chroma = ry.is_some() && by.is_some();
                    let alpha = a.is_some();
                    let mut channels = vec![y];
                    let mut used = vec!["Y", "A"];
                    if chroma {
                        channels.extend([ry, by].into_iter().flatten());
                        used.extend(["RY", "BY"]);
                    }
                    channels.extend(a);
                    (
                        Some((channels, LayerKind::Luminance { chroma, alpha })),
                        used,
                    )
                }
                _ => (None, Vec::new()),
            };
        if let Some((channels, kind)) = main {
            out.push(layer(name.clone(), channels, kind));
            for (suffix, full) in members.iter().filter(|(s, _)| !used.contains(&s.as_str())) {
                let scalar_name = if name.is_empty() {
                    suffix.clone()
                } else {
                    format!("{name}.{suffix}")
                };
                out.push(layer(scalar_name, vec![full.clone()], LayerKind::Scalar));
            }
        } else if members.len() == 1 {
            out.push(layer(name, vec![members[0].1.clone()], LayerKind::Scalar));
        } else if members.len() <= 4 {
            let channels = vector_order(&members);
            out.push(layer(name, channels, LayerKind::Vector));
        } else {
            for (suffix, full) in &members {
                let scalar_name = if name.is_empty() {
                    suffix.clone()
                } else {
                    format!("{name}.{suffix}")
                };
                out.push(layer(scalar_name, vec![full.clone()], LayerKind::Scalar));
            }
        }
    }
    out
}

/// A vector layer's channels in component order: `X Y Z W`, `U V W`, `R G B A` (either
/// case) where the names are letters of one of these, else as stored. EXR stores channels
/// sorted by name, which puts `W` before `X`.
fn vector_order(members: &[(String, String)]) -> Vec<String> {
    for order in ["XYZW", "UVW", "RGBA"] {
        let rank = |suffix: &str| {
            let mut chars = suffix.chars();
            match (chars.next(), chars.next()) {
                (Some(c), None) => order.find(c.to_ascii_uppercase()),
                _ => None,
            }
        };
        if members.iter().all(|(suffix, _)| rank(suffix).is_some()) {
            let mut sorted: Vec<&(String, String)> = members.iter().collect();
            sorted.sort_by_key(|(suffix, _)| rank(suffix));
            return sorted.into_iter().map(|(_, full)| full.clone()).collect();
        }
    }
    members.iter().map(|(_, full)| full.clone()).collect()
}

/// Which layer to read: by name (empty: the default colour layer) and view (empty: the
/// default view).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Selection {
    /// A layer's name as the module's doc lists them; empty for the file's colour image.
    pub layer: String,
    /// A view's name; empty for the default view.
    pub view: String,
}

impl Selection {
    /// A selection of `layer` in the default view.
    pub fn layer(layer: &str) -> Self {
        Self {
            layer: layer.to_owned(),
            view: String::new(),
        }
    }

    /// The layer of `info` this selection names.
    ///
    /// # Errors
    /// No such view or layer (the message lists what there is), two layers by that name,
    /// or, for the default, no colour layer.
    pub fn find(&self, info: &Info) -> Result<Layer, String> {
        let views = info.views();
        let view = if self.view.is_empty() {
            info.default_view().map(str::to_owned)
        } else if views.contains(&self.view) {
            Some(self.view.clone())
        } else if views.is_empty() {
            return Err(format!(
                "the file has no views; `view: {:?}` names none",
                self.view
            ));
        } else {
            return Err(format!(
                "the file has no view {:?}; its views: {}",
                self.view,
                views.join(", ")
            ));
        };
        let all = info.layers();
        let in_view: Vec<&Layer> = all
            .iter()
            .filter(|l| l.view.is_none() || view.is_none() || l.view == view)
            .collect();
        let listing = || {
            let names: Vec<String> = in_view
                .iter()
                .map(|l| format!("{} ({})", l.label(&info.parts[l.part]), l.kind.name()))
                .collect();
            names.join(", ")
        };
        if self.layer.is_empty() {
            return in_view
                .iter()
                .find(|l| {
                    l.name.is_empty()
                        && matches!(
                            l.kind,
                            LayerKind::Color { .. } | LayerKind::Luminance { .. }
                        )
                })
                .map(|l| (*l).clone())
                .ok_or_else(|| {
                    format!(
                        "the file has no colour image at its root{}: choose a layer: {}",
                        view.as_ref()
                            .map(|v| format!(" in view {v:?}"))
                            .unwrap_or_default(),
                        listing()
                    )
                });
        }
        let q = self.layer.as_str();
        let tests: [&dyn Fn(&str) -> bool; 4] = [
            &|n: &str| n == q,
            &|n: &str| n.ends_with(q) && n[..n.len() - q.len()].ends_with('.'),
            &|n: &str| n.eq_ignore_ascii_case(q),
            &|n: &str| {
                n.len() > q.len()
                    && n.is_char_boundary(n.len() - q.len())
                    && n[n.len() - q.len()..].eq_ignore_ascii_case(q)
                    && n[..n.len() - q.len()].ends_with('.')
            },
        ];
        for test in tests {
            let found: Vec<&&Layer> = in_view
                .iter()
                .filter(|l| l.names(&info.parts[l.part]).iter().any(|n| test(n)))
                .collect();
            match found.as_slice() {
                [] => {}
                [one] => return Ok((**one).clone()),
                many => {
                    let names: Vec<String> =
                        many.iter().map(|l| l.label(&info.parts[l.part])).collect();
                    return Err(format!(
                        "layer {q:?} is ambiguous: it names {}; give more of the name",
                        names.join(" and ")
                    ));
                }
            }
        }
        Err(format!(
            "the file has no layer {q:?}; its layers: {}",
            listing()
        ))
    }
}
