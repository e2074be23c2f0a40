//! The canvas: an egui-snarl view of the document's graph.
//!
//! The snarl holds only node ids; it is rebuilt from the [`Graph`] whenever the graph's
//! nodes or edges change (an edit, an undo, a paste), and every user action on it (a wire
//! made or cut, a node added, moved or deleted) goes to the [`Document`] first, where it
//! is checked against the registry and recorded for undo. Pins, menus and node labels
//! all come from the registry, so new node kinds appear without editor changes.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use egui::emath::TSTransform;
use egui::{Color32, Pos2, Rect, RichText, Ui, pos2, vec2};
use egui_snarl::ui::{AnyPins, PinInfo, SnarlPin, SnarlStyle, SnarlViewer, SnarlWidget};
use egui_snarl::{InPin, InPinId, NodeId, OutPin, OutPinId, Snarl};
use lumagraph_graph::{Category, Graph, NodeKind, PortType, Registry, split_port_ref};

use crate::document::Document;

/// Horizontal gap used for nodes that have no position in the file.
const AUTO_SPACING: f32 = 220.0;

/// Each node's id, kind and position: when this changes, the snarl is rebuilt.
type Layout = Vec<(String, String, Option<(f32, f32)>)>;

/// Each edge's ports and reroute points: when this changes, the snarl is rebuilt.
type EdgeLayout = Vec<(String, String, Vec<(f32, f32)>)>;

/// What happened on the canvas that the app must act on.
#[derive(Clone, Debug, PartialEq)]
pub enum CanvasEvent {
    /// The user selected these nodes on the canvas.
    Select(Vec<String>),
    /// Preview this output port.
    Preview(String),
    /// An edit was refused; the message says why.
    Refused(String),
    /// Delete these nodes.
    Delete(Vec<String>),
    /// A node was added from the menu.
    Added(String),
    /// The user clicked frame `index`'s title.
    SelectFrame(usize),
}

/// The snarl view and what it was built from.
#[derive(Default)]
pub struct Canvas {
    snarl: Snarl<String>,
    built_from: Option<Layout>,
    built_edges: EdgeLayout,
    auto_pos: HashMap<String, Pos2>,
    last_selection: Vec<NodeId>,
    /// The add-node menu's search text.
    pub search: String,
    /// Graph to screen, as last drawn.
    view: Option<TSTransform>,
    /// Where the canvas was on screen, as last drawn.
    screen: Option<Rect>,
    /// Each node's rectangle in graph space, as last drawn.
    node_rects: HashMap<String, Rect>,
    /// What to frame on the next draw.
    frame: Option<Frame>,
    /// Where `Shift+A` opened Add node (screen), while it is open.
    quick_add: Option<Pos2>,
    /// Each pin's row centre in graph space, as last drawn: `(node, is output, port)`.
    pin_rows: HashMap<(String, bool, String), f32>,
    /// The nodes moved by the drag going on.
    dragged: Vec<String>,
    /// Each reroute point's rectangle in graph space, as last drawn.
    reroute_rects: HashMap<(usize, usize), Rect>,
    /// Snap nodes to a grid of [`GRID`] units when a drag ends.
    pub snap: bool,
}

/// The grid nodes snap to, graph units.
pub const GRID: f32 = 20.0;

/// Moves the nodes `ids` onto the grid (an edit only where one is off it).
fn snap_to_grid(doc: &mut Document, ids: &[String]) {
    let on_grid = |v: f32| (v / GRID).round() * GRID;
    let moves: Vec<(String, (f32, f32))> = ids
        .iter()
        .filter_map(|id| {
            let (x, y) = doc.graph.node(id)?.pos?;
            Some((id.clone(), (on_grid(x), on_grid(y))))
        })
        .collect();
    doc.move_nodes(&moves);
}

/// What [`Canvas::request_frame`] brings into view.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Frame {
    /// Every node.
    All,
    /// These nodes.
    Nodes(Vec<String>),
}

/// The size assumed for a node not drawn yet, in graph units.
const NODE_SIZE: egui::Vec2 = vec2(180.0, 120.0);

impl std::fmt::Debug for Canvas {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Canvas").finish_non_exhaustive()
    }
}

/// The id of the canvas widget (its selection is kept under it).
pub fn canvas_id() -> egui::Id {
    egui::Id::new("lumagraph-canvas")
}

/// A color per port type, for pins and wires.
pub fn port_color(ty: PortType) -> Color32 {
    match ty {
        PortType::HdrColor => Color32::from_rgb(240, 170, 60),
        PortType::LdrColor => Color32::from_rgb(120, 200, 110),
        PortType::Albedo => Color32::from_rgb(200, 120, 200),
        PortType::Normal => Color32::from_rgb(100, 150, 240),
        PortType::Depth | PortType::Scalar => Color32::from_rgb(170, 170, 170),
        PortType::Vector => Color32::from_rgb(90, 200, 200),
        _ => Color32::from_rgb(220, 90, 90),
    }
}

fn kind_of<'r>(registry: &'r Registry, graph: &Graph, id: &str) -> Option<&'r NodeKind> {
    graph
        .node(id)
        .and_then(|n| registry.get(&n.kind))
        .map(|k| &**k)
}

fn structure(graph: &Graph) -> Layout {
    graph
        .nodes
        .iter()
        .map(|n| (n.id.clone(), n.kind.clone(), n.pos))
        .collect()
}

fn edges(graph: &Graph) -> EdgeLayout {
    graph
        .edges
        .iter()
        .map(|e| (e.from.clone(), e.to.clone(), e.via.clone()))
        .collect()
}

/// What starts the snarl id of a reroute point: a control character, so no node id is one.
const REROUTE: &str = "\u{1}reroute ";

/// The snarl id of reroute point `k` of edge `e` (its index in the graph's edges).
fn reroute_id(e: usize, k: usize) -> String {
    format!("{REROUTE}{e}.{k}")
}

/// `(edge index, point index)` of a reroute point's snarl id; `None` for a node's.
pub fn reroute_of(id: &str) -> Option<(usize, usize)> {
    let (e, k) = id.strip_prefix(REROUTE)?.split_once('.')?;
    Some((e.parse().ok()?, k.parse().ok()?))
}

impl Canvas {
    /// Frames `what` on the next draw: the view is panned and zoomed (never beyond 1:1)
    /// so it fills the canvas with a margin.
    pub fn request_frame(&mut self, what: Frame) {
        self.frame = Some(what);
    }

    /// The part of the graph visible on the canvas, in graph space (`None` before the
    /// first draw).
    pub fn visible_rect(&self) -> Option<Rect> {
        Some(self.view?.inverse() * self.screen?)
    }

    /// Where a new node goes so that it shows in the middle of the canvas: its top-left
    /// corner in graph space (`None` before the first draw).
    pub fn new_node_pos(&self) -> Option<(f32, f32)> {
        let c = self.visible_rect()?.center() - NODE_SIZE / 2.0;
        Some((c.x, c.y))
    }

    /// The graph-space rectangle around the nodes `ids` of `graph` (all when `None`).
    fn bounds(&self, graph: &Graph, ids: Option<&[String]>) -> Option<Rect> {
        let rects = graph
            .nodes
            .iter()
            .filter(|n| ids.is_none_or(|ids| ids.contains(&n.id)))
            .map(|n| {
                self.node_rects.get(&n.id).copied().unwrap_or_else(|| {
                    let p = n.pos.map_or_else(
                        || self.auto_pos.get(&n.id).copied().unwrap_or_default(),
                        |(x, y)| pos2(x, y),
                    );
                    Rect::from_min_size(p, NODE_SIZE)
                })
            });
        rects.reduce(Rect::union)
    }

    /// The view that shows `target` (graph space) in the middle of `screen`, filling it
    /// with a margin, zoomed no closer than 1:1 and no further out than the canvas allows
    /// (1:5, egui-snarl's default).
    fn framing(target: Rect, screen: Rect) -> TSTransform {
        let target = target.expand(40.0);
        let scale = (screen.width() / target.width())
            .min(screen.height() / target.height())
            .clamp(0.2, 1.0);
        TSTransform::new(
            screen.center().to_vec2() - target.center().to_vec2() * scale,
            scale,
        )
    }

    /// Rebuilds the snarl when the graph's nodes, positions or edges changed.
    fn sync(&mut self, registry: &Registry, graph: &Graph) {
        let s = structure(graph);
        let e = edges(graph);
        if self.built_from.as_ref() == Some(&s) && self.built_edges == e {
            return;
        }
        let mut snarl = Snarl::new();
        let mut ids = HashMap::new();
        self.auto_pos.clear();
        // Sizes of another graph's nodes (one opened in place) must not frame this one.
        self.node_rects.retain(|id, _| graph.node(id).is_some());
        for (i, n) in graph.nodes.iter().enumerate() {
            #[expect(clippy::cast_precision_loss, reason = "node counts are small")]
            let pos = n
                .pos
                .map_or_else(|| pos2(i as f32 * AUTO_SPACING, 0.0), |(x, y)| pos2(x, y));
            if n.pos.is_none() {
                self.auto_pos.insert(n.id.clone(), pos);
            }
            ids.insert(n.id.clone(), snarl.insert_node(pos, n.id.clone()));
        }
        for (e, edge) in graph.edges.iter().enumerate() {
            let (Some((fnode, fport)), Some((tnode, tport))) =
                (split_port_ref(&edge.from), split_port_ref(&edge.to))
            else {
                continue;
            };
            let (Some(fk), Some(tk)) = (
                kind_of(registry, graph, fnode),
                kind_of(registry, graph, tnode),
            ) else {
                continue;
            };
            let (Some(o), Some(i)) = (
                fk.outputs.iter().position(|p| p.name == fport),
                tk.inputs.iter().position(|p| p.name == tport),
            ) else {
                continue;
            };
            // Through the edge's reroute points, each a small node of one input and one
            // output.
            let mut from = OutPinId {
                node: ids[fnode],
                output: o,
            };
            for (k, &(x, y)) in edge.via.iter().enumerate() {
                let r = snarl.insert_node(pos2(x, y), reroute_id(e, k));
                snarl.connect(from, InPinId { node: r, input: 0 });
                from = OutPinId { node: r, output: 0 };
            }
            snarl.connect(
                from,
                InPinId {
                    node: ids[tnode],
                    input: i,
                },
            );
        }
        self.snarl = snarl;
        self.built_from = Some(s);
        self.built_edges = e;
    }

    /// Shows the canvas; edits go to `doc`, other outcomes come back as events.
    pub fn show(
        &mut self,
        ui: &mut Ui,
        doc: &mut Document,
        info: &NodeInfo<'_>,
    ) -> Vec<CanvasEvent> {
        self.sync(doc.registry(), &doc.graph);
        let screen = ui.max_rect();
        self.screen = Some(screen);
        let frame = match self.frame.take() {
            Some(Frame::All) => self.bounds(&doc.graph, None),
            Some(Frame::Nodes(ids)) => self.bounds(&doc.graph, Some(&ids)),
            None => None,
        };
        let mut events = Vec::new();
        let frames = self.frame_boxes(&doc.graph, info.selected_frame);
        let mut viewer = Viewer {
            doc,
            info,
            events: &mut events,
            search: &mut self.search,
            rects: Vec::new(),
            graph_rects: Vec::new(),
            pin_rows: Vec::new(),
            frames: &frames,
            reroute_rects: Vec::new(),
            frame: frame.map(|r| Self::framing(r, screen)),
            view: None,
        };
        let style = SnarlStyle {
            collapsible: Some(false),
            // Pins on the frame's edge: with the default (inside the frame) the pin of
            // every output row after the first is drawn over its label.
            pin_placement: Some(egui_snarl::ui::PinPlacement::Edge),
            ..SnarlStyle::new()
        };
        let canvas_rect = ui.max_rect();
        SnarlWidget::new()
            .id(canvas_id())
            .style(style)
            .show(&mut self.snarl, &mut viewer, ui);
        let rects = std::mem::take(&mut viewer.rects);
        self.view = viewer.view.or(self.view);
        self.node_rects = std::mem::take(&mut viewer.graph_rects)
            .into_iter()
            .collect();
        self.pin_rows = std::mem::take(&mut viewer.pin_rows).into_iter().collect();
        self.reroute_rects = std::mem::take(&mut viewer.reroute_rects)
            .into_iter()
            .collect();

        // A plain click selects a node (shift or ctrl adds or removes it); a click on
        // empty canvas clears the selection. Snarl's own rectangle selection is followed
        // below.
        let (click, modifiers, pointer) = ui.input(|i| {
            (
                i.pointer.primary_clicked(),
                i.modifiers,
                i.pointer.interact_pos(),
            )
        });
        // Only clicks that land on the canvas itself, not on a menu above it.
        let on_canvas = pointer.is_some_and(|p| {
            canvas_rect.contains(p)
                && ui
                    .ctx()
                    .layer_id_at(p)
                    .is_some_and(|l| l.id == canvas_id() || l == ui.layer_id())
        });
        let click = click && on_canvas;
        let clicked = pointer
            .filter(|_| click)
            .and_then(|p| rects.iter().rev().find(|(_, r)| r.contains(p)))
            .map(|(id, _)| id.clone());
        let node_clicked = clicked.is_some();
        if let Some(id) = clicked {
            let mut ids = if modifiers.shift || modifiers.command {
                let mut ids = info.selected.to_vec();
                if let Some(i) = ids.iter().position(|s| *s == id) {
                    ids.remove(i);
                } else {
                    ids.push(id);
                }
                ids
            } else {
                vec![id]
            };
            ids.dedup();
            events.push(CanvasEvent::Select(ids));
        } else if click && (!info.selected.is_empty() || info.selected_frame.is_some()) {
            events.push(CanvasEvent::Select(Vec::new()));
        }

        self.quick_add(ui, doc, canvas_rect, &mut events);

        self.take_moves(doc);
        if ui.input(|i| i.pointer.any_released()) {
            self.drag_ended(doc, &mut events);
        }

        // After the snarl's own moves: a frame's drag moves nodes the snarl has not seen.
        self.frame_titles(ui, doc, &frames, canvas_rect, &mut events);
        // A triple click counts too: its second click may have been on the wire.
        let double = ui.input(|i| {
            let primary = egui::PointerButton::Primary;
            i.pointer.button_double_clicked(primary) || i.pointer.button_triple_clicked(primary)
        });
        let on_reroute = |p: Pos2| {
            self.view
                .is_some_and(|v| self.reroute_rects.values().any(|r| (v * *r).contains(p)))
        };
        if double
            && on_canvas
            && !node_clicked
            && let Some(p) = pointer
            && !on_reroute(p)
        {
            self.add_reroute_at(doc, p);
        }

        let selected = egui_snarl::ui::get_selected_nodes(canvas_id(), ui.ctx());
        if selected != self.last_selection && !node_clicked {
            let ids = selected
                .iter()
                .filter_map(|n| self.snarl.get_node(*n).cloned())
                .filter(|id| reroute_of(id).is_none())
                .collect();
            events.push(CanvasEvent::Select(ids));
            self.last_selection = selected;
        }
        events
    }
}

/// A frame as drawn: its box in graph space around its nodes, with its title bar.
#[derive(Clone, Debug)]
pub struct FrameBox {
    /// Its index in the graph's frames.
    pub index: usize,
    /// The box, graph space.
    pub rect: Rect,
    /// Its title.
    pub label: String,
    /// Its comment.
    pub comment: String,
    /// Its colour.
    pub color: Color32,
    /// Whether it is selected.
    pub selected: bool,
}

/// Space between a frame's nodes and its border, graph units.
const FRAME_PAD: f32 = 14.0;
/// The height of a frame's title bar (and of each comment line), graph units.
const FRAME_TITLE: f32 = 22.0;
/// A frame's colour where it has none.
const FRAME_COLOR: Color32 = Color32::from_rgb(120, 130, 150);

impl FrameBox {
    /// The title bar: where a drag moves the frame and a click selects it.
    pub fn title_rect(&self) -> Rect {
        Rect::from_min_size(self.rect.min, vec2(self.rect.width(), FRAME_TITLE))
    }

    fn paint(&self, painter: &egui::Painter, style: &egui::Style) {
        painter.rect_filled(self.rect, 6.0, self.color.gamma_multiply(0.16));
        let stroke = if self.selected {
            egui::Stroke::new(2.0, Color32::from_rgb(90, 160, 255))
        } else {
            egui::Stroke::new(1.0, self.color.gamma_multiply(0.8))
        };
        painter.rect_stroke(self.rect, 6.0, stroke, egui::StrokeKind::Inside);
        painter.rect_filled(self.title_rect(), 6.0, self.color.gamma_multiply(0.35));
        painter.text(
            self.rect.min + vec2(8.0, FRAME_TITLE * 0.5),
            egui::Align2::LEFT_CENTER,
            &self.label,
            egui::FontId::proportional(14.0),
            style.visuals.strong_text_color(),
        );
        for (i, line) in self.comment.lines().enumerate() {
            #[expect(clippy::cast_precision_loss, reason = "a line's offset")]
            let y = FRAME_TITLE * (1.5 + i as f32);
            painter.text(
                self.rect.min + vec2(8.0, y),
                egui::Align2::LEFT_CENTER,
                line,
                egui::FontId::proportional(12.0),
                style.visuals.text_color(),
            );
        }
    }
}

/// `base` with `color` mixed in, for a node's header colour.
fn tint(base: Color32, color: Color32) -> Color32 {
    let mix = |a: u8, b: u8| {
        let v = (f32::from(a) * 0.55 + f32::from(b) * 0.45).round();
        #[expect(
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss,
            reason = "0 to 255"
        )]
        let v = v as u8;
        v
    };
    Color32::from_rgb(
        mix(base.r(), color.r()),
        mix(base.g(), color.g()),
        mix(base.b(), color.b()),
    )
}

impl Canvas {
    /// Where the snarl moved nodes and reroute points this frame, into the graph (one undo
    /// step per drag); the moved nodes join the drag going on.
    fn take_moves(&mut self, doc: &mut Document) {
        // Positions back into the graph (one undo step per drag); reroute points into
        // their edges.
        let mut reroutes = Vec::new();
        let moves: Vec<(String, (f32, f32))> = self
            .snarl
            .nodes_pos_ids()
            .filter(|(_, pos, id)| {
                if let Some((e, k)) = reroute_of(id) {
                    let at = doc.graph.edges.get(e).and_then(|ed| ed.via.get(k));
                    if at.is_some_and(|&(x, y)| pos2(x, y) != *pos) {
                        reroutes.push((e, k, (pos.x, pos.y)));
                    }
                    return false;
                }
                let graph_pos = doc.graph.node(id).and_then(|n| n.pos);
                match graph_pos {
                    Some((x, y)) => pos2(x, y) != *pos,
                    None => self.auto_pos.get(*id) != Some(pos),
                }
            })
            .map(|(_, pos, id)| (id.clone(), (pos.x, pos.y)))
            .collect();
        for (e, k, pos) in reroutes {
            let (from, to) = (
                doc.graph.edges[e].from.clone(),
                doc.graph.edges[e].to.clone(),
            );
            doc.move_reroute(&from, &to, k, pos);
            self.built_edges = edges(&doc.graph);
        }
        if !moves.is_empty() {
            doc.move_nodes(&moves);
            self.built_from = Some(structure(&doc.graph));
            for (id, _) in &moves {
                if !self.dragged.contains(id) {
                    self.dragged.push(id.clone());
                }
            }
        }
    }

    /// A drag let go: with grid snap, the dragged nodes land on the grid; a single unwired
    /// node dropped on a wire goes into it.
    fn drag_ended(&mut self, doc: &mut Document, events: &mut Vec<CanvasEvent>) {
        if self.snap {
            snap_to_grid(doc, &self.dragged);
        }
        if let [id] = std::mem::take(&mut self.dragged).as_slice()
            && let Some(edge) = self.wire_under(&doc.graph, id)
        {
            match doc.insert_on_edge(&edge.0, &edge.1, id) {
                Ok(()) => self.built_from = None,
                Err(why) => events.push(CanvasEvent::Refused(why)),
            }
        }
        self.dragged.clear();
    }

    /// A double-click on a wire (`at`, on screen): a reroute point there, splitting the
    /// stretch of the wire it was on.
    fn add_reroute_at(&mut self, doc: &mut Document, at: Pos2) {
        let Some(view) = self.view else { return };
        let p = view.inverse() * at;
        let half = self
            .reroute_rects
            .values()
            .next()
            .map_or(vec2(10.0, 10.0), |r| r.size() * 0.5);
        let mut best: Option<(f32, usize, usize)> = None;
        for (e, edge) in doc.graph.edges.iter().enumerate() {
            let Some((start, end)) = self.wire_ends(edge) else {
                continue;
            };
            let mut points = vec![start];
            for (k, &(x, y)) in edge.via.iter().enumerate() {
                let center = self
                    .reroute_rects
                    .get(&(e, k))
                    .map_or(pos2(x, y) + half, Rect::center);
                points.push(center);
            }
            points.push(end);
            for (i, w) in points.windows(2).enumerate() {
                let d = distance_to_wire(p, w[0], w[1]);
                if d < WIRE_HIT && best.is_none_or(|(bd, ..)| d < bd) {
                    best = Some((d, e, i));
                }
            }
        }
        if let Some((_, e, index)) = best {
            let (from, to) = (
                doc.graph.edges[e].from.clone(),
                doc.graph.edges[e].to.clone(),
            );
            let at = p - half;
            doc.add_reroute(&from, &to, index, (at.x, at.y));
        }
    }

    /// Where the pin of `node`'s port `port` (an output when `output`) was last drawn,
    /// graph space.
    pub fn pin_pos(&self, node: &str, output: bool, port: &str) -> Option<Pos2> {
        let r = self.node_rects.get(node)?;
        let y = self
            .pin_rows
            .get(&(node.to_owned(), output, port.to_owned()))?;
        Some(pos2(if output { r.right() } else { r.left() }, *y))
    }

    /// Where `edge`'s wire leaves its output pin and enters its input pin, as last drawn,
    /// graph space.
    fn wire_ends(&self, edge: &lumagraph_graph::Edge) -> Option<(Pos2, Pos2)> {
        let (a, ap) = split_port_ref(&edge.from)?;
        let (b, bp) = split_port_ref(&edge.to)?;
        Some((self.pin_pos(a, true, ap)?, self.pin_pos(b, false, bp)?))
    }

    /// Reroute point `k` of edge `e` as last drawn, graph space.
    pub fn reroute_rect(&self, e: usize, k: usize) -> Option<Rect> {
        self.reroute_rects.get(&(e, k)).copied()
    }

    /// Where the output (`output`) or input pin of reroute point `k` of edge `e` was last
    /// drawn, graph space.
    pub fn reroute_pin_pos(&self, e: usize, k: usize, output: bool) -> Option<Pos2> {
        let r = self.reroute_rects.get(&(e, k))?;
        let y = self
            .pin_rows
            .get(&(reroute_id(e, k), output, String::new()))?;
        Some(pos2(if output { r.right() } else { r.left() }, *y))
    }

    /// Where graph point `p` was on screen when the canvas was last drawn.
    pub fn to_screen(&self, p: Pos2) -> Option<Pos2> {
        self.view.map(|v| v * p)
    }

    /// The graph's frames as drawn: each box around its nodes (as last drawn; a node not
    /// drawn yet by its position), padded, with room for the title and the comment.
    pub fn frame_boxes(&self, graph: &Graph, selected: Option<usize>) -> Vec<FrameBox> {
        graph
            .frames
            .iter()
            .enumerate()
            .filter_map(|(index, f)| {
                let rect = f
                    .nodes
                    .iter()
                    .filter_map(|id| {
                        self.node_rects.get(id).copied().or_else(|| {
                            let (x, y) = graph.node(id)?.pos?;
                            Some(Rect::from_min_size(pos2(x, y), NODE_SIZE))
                        })
                    })
                    .reduce(Rect::union)?;
                #[expect(clippy::cast_precision_loss, reason = "a count of lines")]
                let lines = f.comment.lines().count() as f32;
                let rect = Rect::from_min_max(
                    rect.min - vec2(FRAME_PAD, FRAME_PAD + FRAME_TITLE * (1.0 + lines)),
                    rect.max + vec2(FRAME_PAD, FRAME_PAD),
                );
                Some(FrameBox {
                    index,
                    rect,
                    label: f.label.clone(),
                    comment: f.comment.clone(),
                    color: f
                        .color
                        .map_or(FRAME_COLOR, |(r, g, b)| Color32::from_rgb(r, g, b)),
                    selected: selected == Some(index),
                })
            })
            .collect()
    }

    /// Each frame's title bar on screen: a drag moves the frame (its nodes), a click
    /// selects it.
    fn frame_titles(
        &mut self,
        ui: &mut Ui,
        doc: &mut Document,
        frames: &[FrameBox],
        canvas_rect: Rect,
        events: &mut Vec<CanvasEvent>,
    ) {
        let Some(view) = self.view else { return };
        for f in frames {
            let screen = view * f.title_rect();
            if !canvas_rect.intersects(screen) {
                continue;
            }
            let area = egui::Area::new(canvas_id().with(("frame title", f.index)))
                .fixed_pos(screen.min)
                .order(egui::Order::Middle)
                .movable(false)
                .constrain(false)
                .show(ui.ctx(), |ui| {
                    ui.allocate_response(screen.size(), egui::Sense::click_and_drag())
                        .on_hover_cursor(egui::CursorIcon::Grab)
                });
            let r = area.inner;
            if r.clicked() || r.drag_started() {
                events.push(CanvasEvent::SelectFrame(f.index));
            }
            if r.dragged() {
                let d = r.drag_delta() / view.scaling;
                if d != egui::Vec2::ZERO {
                    doc.move_frame(f.index, (d.x, d.y));
                    self.built_from = None;
                }
            }
            if r.drag_stopped()
                && self.snap
                && let Some(frame) = doc.graph.frames.get(f.index)
            {
                let ids = frame.nodes.clone();
                snap_to_grid(doc, &ids);
                self.built_from = None;
            }
        }
    }
}

impl Canvas {
    /// The wire (`(from, to)` ports) under node `id`'s centre, as last drawn, when `id` has
    /// no wire of its own; the nearest within a few points.
    fn wire_under(&self, graph: &Graph, id: &str) -> Option<(String, String)> {
        let split = |p: &str| split_port_ref(p).map(|(n, port)| (n.to_owned(), port.to_owned()));
        let wired = graph
            .edges
            .iter()
            .filter_map(|e| Some((split(&e.from)?.0, split(&e.to)?.0)))
            .any(|(a, b)| a == id || b == id);
        if wired {
            return None;
        }
        let center = self.node_rects.get(id)?.center();
        let mut best: Option<(f32, (String, String))> = None;
        for e in graph.edges.iter().filter(|e| e.via.is_empty()) {
            let Some((start, end)) = self.wire_ends(e) else {
                continue;
            };
            let d = distance_to_wire(center, start, end);
            if d < WIRE_HIT && best.as_ref().is_none_or(|(bd, _)| d < *bd) {
                best = Some((d, (e.from.clone(), e.to.clone())));
            }
        }
        best.map(|(_, edge)| edge)
    }
}

/// How near a node's centre must be to a wire to go into it, in graph units.
const WIRE_HIT: f32 = 14.0;

/// The distance from `p` to the wire from `p0` to `p3`: a cubic Bézier leaving and
/// entering horizontally, as the canvas draws wires, sampled.
fn distance_to_wire(p: Pos2, p0: Pos2, p3: Pos2) -> f32 {
    let k = ((p3.x - p0.x).abs() * 0.5).max(24.0);
    let (p1, p2) = (p0 + vec2(k, 0.0), p3 - vec2(k, 0.0));
    (0..=64)
        .map(|i| {
            #[expect(clippy::cast_precision_loss, reason = "a sample's parameter")]
            let t = i as f32 / 64.0;
            let u = 1.0 - t;
            let q = p0.to_vec2() * (u * u * u)
                + p1.to_vec2() * (3.0 * u * u * t)
                + p2.to_vec2() * (3.0 * u * t * t)
                + p3.to_vec2() * (t * t * t);
            (q.to_pos2() - p).length()
        })
        .fold(f32::MAX, f32::min)
}

impl Canvas {
    /// `Shift+A` over the canvas (Blender's key): Add node at the pointer, the node placed
    /// there. `Escape` or a click elsewhere closes it.
    fn quick_add(
        &mut self,
        ui: &mut Ui,
        doc: &mut Document,
        canvas_rect: Rect,
        events: &mut Vec<CanvasEvent>,
    ) {
        let (pressed, escape, clicked, hover) = ui.input(|i| {
            (
                i.modifiers.shift && !i.modifiers.command && i.key_pressed(egui::Key::A),
                i.key_pressed(egui::Key::Escape),
                i.pointer.any_click(),
                i.pointer.hover_pos(),
            )
        });
        if pressed
            && self.quick_add.is_none()
            && !ui.ctx().egui_wants_keyboard_input()
            && let Some(at) = hover.filter(|p| canvas_rect.contains(*p))
        {
            self.quick_add = Some(at);
            self.search.clear();
            return;
        }
        let Some(at) = self.quick_add else { return };
        let mut picked = None;
        let area = egui::Area::new(egui::Id::new("quick add node"))
            .fixed_pos(at)
            .order(egui::Order::Foreground)
            .show(ui.ctx(), |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| {
                    ui.label("Add node");
                    picked = add_node_menu(ui, doc.registry(), &mut self.search);
                });
            });
        let outside = clicked && hover.is_some_and(|p| !area.response.rect.contains(p));
        if let Some(kind) = picked {
            let pos = self.view.map_or(at, |v| v.inverse() * at);
            match doc.add_node(kind, Some((pos.x, pos.y))) {
                Ok(id) => events.push(CanvasEvent::Added(id)),
                Err(e) => events.push(CanvasEvent::Refused(e)),
            }
            self.quick_add = None;
        } else if escape || outside {
            self.quick_add = None;
        }
    }
}

/// What the canvas shows on nodes besides the graph itself.
#[derive(Debug)]
pub struct NodeInfo<'a> {
    /// Compile errors per node id.
    pub errors: &'a BTreeMap<String, Vec<String>>,
    /// Milliseconds per node id, from the last preview frame.
    pub pass_ms: &'a BTreeMap<String, f64>,
    /// The previewed port.
    pub preview: Option<&'a str>,
    /// Nodes selected in the app (highlighted header).
    pub selected: &'a [String],
    /// The frame selected in the app (highlighted border).
    pub selected_frame: Option<usize>,
    /// Pictures of the nodes' outputs (texture, size in points), when they are on.
    pub thumbnails: &'a BTreeMap<String, (egui::TextureId, egui::Vec2)>,
}

struct Viewer<'a, 'i> {
    doc: &'a mut Document,
    info: &'a NodeInfo<'i>,
    events: &'a mut Vec<CanvasEvent>,
    search: &'a mut String,
    /// Each node's rectangle on screen, in drawing order (topmost last).
    rects: Vec<(String, egui::Rect)>,
    /// Each node's rectangle in graph space.
    graph_rects: Vec<(String, egui::Rect)>,
    /// Each pin's row centre in graph space.
    pin_rows: Vec<((String, bool, String), f32)>,
    /// The frames to draw behind the nodes.
    frames: &'a [FrameBox],
    /// Each reroute point's rectangle in graph space: `((edge, point), rect)`.
    reroute_rects: Vec<((usize, usize), egui::Rect)>,
    /// A view to take (framing), applied when the snarl asks.
    frame: Option<TSTransform>,
    /// The view the snarl is drawn with.
    view: Option<TSTransform>,
}

impl Viewer<'_, '_> {
    fn kind(&self, id: &str) -> Option<Arc<NodeKind>> {
        let kind = self.doc.graph.node(id)?.kind.as_str();
        self.doc.registry().get(kind).cloned()
    }

    fn out_ref(&self, snarl: &Snarl<String>, pin: OutPinId) -> Option<String> {
        let id = snarl.get_node(pin.node)?;
        let port = self.kind(id)?.outputs.get(pin.output)?.name;
        Some(format!("{id}.{port}"))
    }

    /// The pin of a reroute point (none for a node's): no label, the colour of the type
    /// its wire carries.
    fn reroute_pin(&mut self, id: &str, output: bool, ui: &mut Ui) -> Option<PinInfo> {
        let (e, _) = reroute_of(id)?;
        let row = ui
            .allocate_exact_size(vec2(4.0, 12.0), egui::Sense::hover())
            .0;
        self.pin_rows
            .push(((id.to_owned(), output, String::new()), row.center().y));
        let from = &self.doc.graph.edges.get(e)?.from;
        let color = self
            .doc
            .port_types(from, true)
            .and_then(|t| t.first().copied())
            .map_or(Color32::GRAY, port_color);
        Some(PinInfo::circle().with_fill(color).with_wire_color(color))
    }

    /// The edge `(from, to)` a wire between snarl nodes `a` and `b` belongs to when either
    /// is a reroute point.
    fn rerouted_edge(
        &self,
        snarl: &Snarl<String>,
        a: NodeId,
        b: NodeId,
    ) -> Option<(String, String)> {
        let e = reroute_of(&snarl[a]).or_else(|| reroute_of(&snarl[b]))?.0;
        let edge = self.doc.graph.edges.get(e)?;
        Some((edge.from.clone(), edge.to.clone()))
    }

    fn in_ref(&self, snarl: &Snarl<String>, pin: InPinId) -> Option<String> {
        let id = snarl.get_node(pin.node)?;
        let port = self.kind(id)?.inputs.get(pin.input)?.name;
        Some(format!("{id}.{port}"))
    }
}

/// The add-node menu: a search field and the registry's kinds grouped by category.
/// Returns the kind picked.
pub fn add_node_menu(ui: &mut Ui, reg: &Registry, search: &mut String) -> Option<&'static str> {
    add_node_menu_of(ui, reg, search, &|_| true)
}

/// The port of `kind` a wire from (`output`) or to a port of `types` would take: its first
/// input accepting the output's type, or its first output of a type the input accepts.
pub fn fitting_port(kind: &NodeKind, types: &[PortType], output: bool) -> Option<&'static str> {
    if output {
        kind.inputs
            .iter()
            .find(|i| types.iter().any(|t| i.accepts.contains(t)))
            .map(|i| i.name)
    } else {
        kind.outputs
            .iter()
            .find(|o| types.contains(&o.ty))
            .map(|o| o.name)
    }
}

/// [`add_node_menu`] listing only the kinds `show` keeps.
pub fn add_node_menu_of(
    ui: &mut Ui,
    reg: &Registry,
    search: &mut String,
    show: &dyn Fn(&NodeKind) -> bool,
) -> Option<&'static str> {
    ui.add(egui::TextEdit::singleline(search).hint_text("search nodes"))
        .request_focus();
    let needle = search.to_lowercase();
    let mut by_cat: BTreeMap<Category, Vec<&NodeKind>> = BTreeMap::new();
    for k in reg.kinds().iter().filter(|k| show(k)) {
        if needle.is_empty()
            || k.name.to_lowercase().contains(&needle)
            || k.doc.to_lowercase().contains(&needle)
        {
            by_cat.entry(k.category).or_default().push(k);
        }
    }
    let mut picked = None;
    if by_cat.is_empty() {
        ui.weak("no node matches");
    }
    for (cat, kinds) in by_cat {
        ui.label(RichText::new(cat.name()).strong());
        for k in kinds {
            if ui.button(k.name).on_hover_text(k.doc).clicked() {
                picked = Some(k.name);
            }
        }
    }
    if picked.is_some() {
        search.clear();
        ui.close();
    }
    picked
}

impl SnarlViewer<String> for Viewer<'_, '_> {
    fn title(&mut self, node: &String) -> String {
        if reroute_of(node).is_some() {
            return String::new();
        }
        node.clone()
    }

    fn node_frame(
        &mut self,
        default: egui::Frame,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        snarl: &Snarl<String>,
    ) -> egui::Frame {
        let id = &snarl[node];
        if reroute_of(id).is_some() {
            return default
                .inner_margin(egui::Margin::same(1))
                .corner_radius(egui::CornerRadius::same(8));
        }
        let default = match self.doc.graph.node(id).and_then(|n| n.color) {
            Some((r, g, b)) => default.fill(tint(default.fill, Color32::from_rgb(r, g, b))),
            None => default,
        };
        if self.info.errors.contains_key(id) {
            default.stroke(egui::Stroke::new(2.0, Color32::from_rgb(230, 60, 60)))
        } else if self.info.selected.contains(id) {
            default.stroke(egui::Stroke::new(2.0, Color32::from_rgb(90, 160, 255)))
        } else {
            default
        }
    }

    fn header_frame(
        &mut self,
        default: egui::Frame,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        snarl: &Snarl<String>,
    ) -> egui::Frame {
        if reroute_of(&snarl[node]).is_some() {
            // A reroute point has no title: no header box.
            return egui::Frame::NONE;
        }
        default
    }

    fn show_header(
        &mut self,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) {
        let id = snarl[node].clone();
        if reroute_of(&id).is_some() {
            return;
        }
        let kind = self
            .doc
            .graph
            .node(&id)
            .map(|n| n.kind.clone())
            .unwrap_or_default();
        // The title moves the node when dragged, rather than selecting its text.
        ui.style_mut().interaction.selectable_labels = false;
        ui.horizontal(|ui| {
            ui.label(RichText::new(&id).strong());
            let weak = ui.weak(&kind);
            if let Some(k) = self.kind(&id) {
                weak.on_hover_text(k.doc);
            }
            if let Some(errs) = self.info.errors.get(&id) {
                ui.colored_label(Color32::from_rgb(230, 60, 60), "⚠")
                    .on_hover_text(errs.join("\n"));
            }
        });
    }

    fn inputs(&mut self, node: &String) -> usize {
        if reroute_of(node).is_some() {
            return 1;
        }
        self.kind(node).map_or(0, |k| k.inputs.len())
    }

    fn outputs(&mut self, node: &String) -> usize {
        if reroute_of(node).is_some() {
            return 1;
        }
        self.kind(node).map_or(0, |k| k.outputs.len())
    }

    fn show_input(
        &mut self,
        pin: &InPin,
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) -> impl SnarlPin + 'static {
        if let Some(pin) = self.reroute_pin(&snarl[pin.id.node], false, ui) {
            return pin;
        }
        let Some(def) = self
            .kind(&snarl[pin.id.node])
            .and_then(|k| k.inputs.get(pin.id.input).cloned())
        else {
            return PinInfo::circle();
        };
        let types: Vec<_> = def.accepts.iter().map(|t| t.name()).collect();
        let row = ui
            .label(def.name)
            .on_hover_text(format!("{}\naccepts {}", def.doc, types.join(" or ")))
            .rect;
        self.pin_rows.push((
            (snarl[pin.id.node].clone(), false, def.name.to_owned()),
            row.center().y,
        ));
        let fill = if def.accepts.len() == 1 {
            port_color(def.accepts[0])
        } else {
            Color32::GRAY
        };
        PinInfo::circle().with_fill(fill)
    }

    fn show_output(
        &mut self,
        pin: &OutPin,
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) -> impl SnarlPin + 'static {
        let id = snarl[pin.id.node].clone();
        if let Some(pin) = self.reroute_pin(&id, true, ui) {
            return pin;
        }
        let Some(def) = self
            .kind(&id)
            .and_then(|k| k.outputs.get(pin.id.output).cloned())
        else {
            return PinInfo::circle();
        };
        let port = format!("{id}.{}", def.name);
        let shown = self.info.preview == Some(port.as_str());
        let label = if shown {
            format!("👁 {}", def.name)
        } else {
            def.name.to_owned()
        };
        let response = ui.selectable_label(shown, label).on_hover_text(format!(
            "{}\nproduces {}\nclick to preview",
            def.doc, def.ty
        ));
        self.pin_rows
            .push(((id, true, def.name.to_owned()), response.rect.center().y));
        if response.clicked() {
            self.events.push(CanvasEvent::Preview(port));
        }
        PinInfo::circle()
            .with_fill(port_color(def.ty))
            .with_wire_color(port_color(def.ty))
    }

    fn has_body(&mut self, node: &String) -> bool {
        self.info.errors.contains_key(node) || self.info.thumbnails.contains_key(node)
    }

    fn show_body(
        &mut self,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) {
        if let Some(errs) = self.info.errors.get(&snarl[node]) {
            ui.set_max_width(240.0);
            for e in errs {
                ui.colored_label(Color32::from_rgb(230, 80, 80), e);
            }
        }
        if let Some(&(texture, size)) = self.info.thumbnails.get(&snarl[node]) {
            ui.add(egui::Image::new((texture, size)));
        }
    }

    fn has_footer(&mut self, node: &String) -> bool {
        self.info.pass_ms.contains_key(node)
    }

    fn show_footer(
        &mut self,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) {
        if let Some(ms) = self.info.pass_ms.get(&snarl[node]) {
            ui.weak(format!("{ms:.2} ms")).on_hover_text(
                "time of this node's passes in the last preview frame: GPU timestamps, or on \
                 a CPU adapter the wall time of each pass submitted alone",
            );
        }
    }

    fn final_node_rect(
        &mut self,
        node: NodeId,
        rect: egui::Rect,
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) {
        if let Some(at) = reroute_of(&snarl[node]) {
            self.reroute_rects.push((at, rect));
            return;
        }
        let global = ui
            .ctx()
            .layer_transform_to_global(ui.layer_id())
            .map_or(rect, |t| t * rect);
        self.rects.push((snarl[node].clone(), global));
        self.graph_rects.push((snarl[node].clone(), rect));
    }

    fn draw_background(
        &mut self,
        background: Option<&egui_snarl::ui::BackgroundPattern>,
        viewport: &Rect,
        snarl_style: &SnarlStyle,
        style: &egui::Style,
        painter: &egui::Painter,
        _snarl: &Snarl<String>,
    ) {
        if let Some(background) = background {
            background.draw(viewport, snarl_style, style, painter);
        }
        for f in self.frames {
            f.paint(painter, style);
        }
    }

    fn current_transform(&mut self, to_global: &mut TSTransform, _snarl: &mut Snarl<String>) {
        if let Some(frame) = self.frame.take() {
            *to_global = frame;
        }
        self.view = Some(*to_global);
    }

    fn has_graph_menu(&mut self, _pos: Pos2, _snarl: &mut Snarl<String>) -> bool {
        true
    }

    fn show_graph_menu(&mut self, pos: Pos2, ui: &mut Ui, _snarl: &mut Snarl<String>) {
        ui.label("Add node");
        if let Some(kind) = add_node_menu(ui, self.doc.registry(), self.search) {
            match self.doc.add_node(kind, Some((pos.x, pos.y))) {
                Ok(id) => self.events.push(CanvasEvent::Added(id)),
                Err(e) => self.events.push(CanvasEvent::Refused(e)),
            }
        }
    }

    fn has_dropped_wire_menu(&mut self, _src_pins: AnyPins, _snarl: &mut Snarl<String>) -> bool {
        true
    }

    /// A wire dropped on empty canvas: Add node, listing the kinds with a port that fits
    /// it; the node picked goes where the wire was dropped, wired to it.
    fn show_dropped_wire_menu(
        &mut self,
        pos: Pos2,
        ui: &mut Ui,
        src_pins: AnyPins,
        snarl: &mut Snarl<String>,
    ) {
        let (port, output) = match src_pins {
            AnyPins::Out(pins) => (pins.first().and_then(|p| self.out_ref(snarl, *p)), true),
            AnyPins::In(pins) => (pins.first().and_then(|p| self.in_ref(snarl, *p)), false),
        };
        let Some(port) = port else { return };
        let Some(types) = self.doc.port_types(&port, output) else {
            return;
        };
        ui.label(format!("Add node wired to {port}"));
        let fits = |k: &NodeKind| fitting_port(k, &types, output).is_some();
        if let Some(kind) = add_node_menu_of(ui, self.doc.registry(), self.search, &fits) {
            match self.doc.add_wired(kind, (pos.x, pos.y), &port, output) {
                Ok(id) => self.events.push(CanvasEvent::Added(id)),
                Err(e) => self.events.push(CanvasEvent::Refused(e)),
            }
        }
    }

    fn has_node_menu(&mut self, _node: &String) -> bool {
        true
    }

    fn show_node_menu(
        &mut self,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        ui: &mut Ui,
        snarl: &mut Snarl<String>,
    ) {
        let id = snarl[node].clone();
        if let Some((e, k)) = reroute_of(&id) {
            if ui.button("Remove reroute").clicked()
                && let Some(edge) = self.doc.graph.edges.get(e).cloned()
            {
                self.doc.remove_reroute(&edge.from, &edge.to, k);
                ui.close();
            }
            return;
        }
        if let Some(k) = self.kind(&id) {
            for o in &k.outputs {
                if ui.button(format!("Preview {}", o.name)).clicked() {
                    self.events
                        .push(CanvasEvent::Preview(format!("{id}.{}", o.name)));
                    ui.close();
                }
            }
        }
        if ui.button("Delete").clicked() {
            self.events.push(CanvasEvent::Delete(vec![id]));
            ui.close();
        }
    }

    fn connect(&mut self, from: &OutPin, to: &InPin, snarl: &mut Snarl<String>) {
        if reroute_of(&snarl[to.id.node]).is_some() {
            self.events.push(CanvasEvent::Refused(
                "a reroute point carries its own wire only".into(),
            ));
            return;
        }
        if let Some((e, _)) = reroute_of(&snarl[from.id.node]) {
            // From a reroute point: another wire from the same output.
            let source = self.doc.graph.edges.get(e).map(|ed| ed.from.clone());
            if let (Some(f), Some(t)) = (source, self.in_ref(snarl, to.id))
                && let Err(why) = self.doc.connect(&f, &t)
            {
                self.events.push(CanvasEvent::Refused(why));
            }
            return;
        }
        let (Some(f), Some(t)) = (self.out_ref(snarl, from.id), self.in_ref(snarl, to.id)) else {
            return;
        };
        match self.doc.connect(&f, &t) {
            Ok(()) => {
                snarl.drop_inputs(to.id);
                snarl.connect(from.id, to.id);
            }
            Err(why) => self.events.push(CanvasEvent::Refused(why)),
        }
    }

    fn disconnect(&mut self, from: &OutPin, to: &InPin, snarl: &mut Snarl<String>) {
        if let Some(edge) = self.rerouted_edge(snarl, from.id.node, to.id.node) {
            self.doc.disconnect(&edge.0, &edge.1);
            return;
        }
        if let (Some(f), Some(t)) = (self.out_ref(snarl, from.id), self.in_ref(snarl, to.id)) {
            self.doc.disconnect(&f, &t);
        }
        snarl.disconnect(from.id, to.id);
    }

    fn drop_outputs(&mut self, pin: &OutPin, snarl: &mut Snarl<String>) {
        if let Some(edge) = self.rerouted_edge(snarl, pin.id.node, pin.id.node) {
            self.doc.disconnect(&edge.0, &edge.1);
            return;
        }
        if let Some(p) = self.out_ref(snarl, pin.id) {
            self.doc.disconnect_port(&p);
        }
        snarl.drop_outputs(pin.id);
    }

    fn drop_inputs(&mut self, pin: &InPin, snarl: &mut Snarl<String>) {
        if let Some(edge) = self.rerouted_edge(snarl, pin.id.node, pin.id.node) {
            self.doc.disconnect(&edge.0, &edge.1);
            return;
        }
        if let Some(p) = self.in_ref(snarl, pin.id) {
            self.doc.disconnect_port(&p);
        }
        snarl.drop_inputs(pin.id);
    }
}
