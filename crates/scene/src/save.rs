//! Writing an edited [`SceneFile`] back over the text it was read from, keeping what the
//! user wrote.
//!
//! [`write()`] compares the edited file with the one parsed from the text, value by value,
//! and changes the text only where a value changed: a changed field of the camera, of the
//! environment map, of the render settings or of a material is replaced in place, a
//! field that became non-default is added (on its own line where the fields are one per
//! line, in the same line otherwise), an optional field that became `None` is removed; a
//! value whose kind changed (`None` → `Map(…)`, `Perspective` → `Gltf`) is written anew
//! on one line, with only the fields that differ from their defaults. Added materials go
//! on their own lines at the end of the map, removed ones leave with the comment lines
//! directly above them. Everything else — comments, layout, the spelling of numbers — is
//! kept byte for byte, so an unchanged file is written exactly as it was read.
//!
//! The editor never changes a file's `version`, `shapes` or `lights`: [`write()`] refuses
//! such an edit ([`ErrorKind::NotEditable`]). The text written always reads back as the
//! edited file; [`write()`] checks that and returns an error instead of a wrong text.
//!
//! [`save()`] writes the result atomically (a temporary file in the same folder, renamed
//! over the old one).

use std::collections::BTreeMap;
use std::fmt::Debug;
use std::ops::Range;
use std::path::Path;

use crate::error::{ErrorKind, SceneError};
use crate::file::{CameraDesc, Environment, MaterialDesc, RenderSettings, SceneFile, V3};

/// `edited` written over `original` (the text it was loaded from): every part of the text
/// whose value did not change is kept byte for byte (comments, layout, number spelling);
/// what changed is replaced in place.
///
/// # Errors
/// When `original` is not a valid scene file (its syntax error, with line and column),
/// when `edited` changes the version, shapes or lights ([`ErrorKind::NotEditable`]), or
/// when the written text would not read back as `edited` ([`ErrorKind::Unwritable`]).
pub fn write(original: &str, edited: &SceneFile) -> Result<String, SceneError> {
    let old = SceneFile::from_ron(original)?;
    let fixed = [
        ("version", same(&old.version, &edited.version)),
        ("shapes", same(&old.shapes, &edited.shapes)),
        ("lights", same(&old.lights, &edited.lights)),
    ];
    if let Some(&(what, _)) = fixed.iter().find(|(_, same)| !same) {
        return Err(SceneError::new(ErrorKind::NotEditable(what)));
    }
    let text = Text::new(original);
    let root = text
        .root()
        .ok_or_else(|| unwritable("cannot find the fields of the scene in its text"))?;
    let (old_value, new_value) = (file_value(&old), file_value(edited));
    let mut edits = Vec::new();
    text.merge_in(&root, &old_value, &new_value, &mut edits);
    let out = apply(original, &edits)?;
    let back = SceneFile::from_ron(&out)
        .map_err(|e| unwritable(format!("the text written does not parse ({e})")))?;
    if !same(&back, edited) {
        return Err(unwritable(
            "the text written reads back as a different scene",
        ));
    }
    Ok(out)
}

/// [`write()`], then the result written to `path` atomically: into a temporary file in the
/// same folder, renamed over `path` (which is untouched when anything fails). Returns the
/// text written.
///
/// # Errors
/// As [`write()`], and when the file cannot be written; errors name `path`.
pub fn save(path: &Path, original: &str, edited: &SceneFile) -> Result<String, SceneError> {
    let text = write(original, edited).map_err(|e| e.in_file(path))?;
    lumagraph_files::write_atomic(path, text.as_bytes())
        .map_err(|source| SceneError::new(ErrorKind::Write { source }).in_file(path))?;
    Ok(text)
}

fn unwritable(message: impl Into<String>) -> SceneError {
    SceneError::new(ErrorKind::Unwritable(message.into()))
}

/// Equal, or written the same (so that a NaN equals itself).
fn same<T: PartialEq + Debug>(a: &T, b: &T) -> bool {
    a == b || format!("{a:?}") == format!("{b:?}")
}

// ---------------------------------------------------------------------------------------
// Values as the writer sees them.

/// A value of the scene file, ready to be compared with another and written.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Val {
    /// Written as is: a number, string, bool, vector, unit or tuple variant.
    Leaf(String),
    /// `Variant(field: value, …)`, or `(…)` for a struct (`variant` empty).
    Struct {
        variant: &'static str,
        /// All fields, in declaration order.
        fields: Vec<Field>,
    },
    /// `{"key": value, …}`.
    Map(BTreeMap<String, Val>),
}

#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Field {
    pub(crate) name: &'static str,
    pub(crate) value: Val,
    /// Equal to what serde fills in when the field is left out: not written anew.
    pub(crate) default: bool,
    /// An `Option` that is `None`: written by leaving the field out.
    pub(crate) none: bool,
}

/// A field written unless it is `default`.
fn field(name: &'static str, value: Val, default: bool) -> Field {
    Field {
        name,
        value,
        default,
        none: false,
    }
}

/// A field that the file must give.
fn required(name: &'static str, value: String) -> Field {
    field(name, Val::Leaf(value), false)
}

/// A field with a default, `default` written as `value` would be: `-0.0` is not the
/// default `0.0`, so that what is written always reads back bit for bit.
fn given(name: &'static str, value: String, default: &str) -> Field {
    let is_default = value == default;
    field(name, Val::Leaf(value), is_default)
}

/// An optional field, written without `Some(…)` (ron's `implicit_some`).
fn optional<T>(name: &'static str, value: Option<T>, leaf: impl FnOnce(T) -> String) -> Field {
    match value {
        Some(v) => field(name, Val::Leaf(leaf(v)), false),
        None => Field {
            name,
            value: Val::Leaf("None".into()),
            default: true,
            none: true,
        },
    }
}

/// A float that reads back exactly, always with a decimal point or exponent.
pub(crate) fn num(x: f32) -> String {
    format!("{x:?}")
}

pub(crate) fn vec3(v: V3) -> String {
    format!("({:?}, {:?}, {:?})", v[0], v[1], v[2])
}

/// A RON string literal.
pub(crate) fn string(s: &str) -> String {
    ron::to_string(s).unwrap_or_else(|_| {
        let escaped = s.replace('\\', "\\\\").replace('"', "\\\"");
        format!("\"{escaped}\"")
    })
}

fn leaf(s: String) -> Val {
    Val::Leaf(s)
}

fn file_value(f: &SceneFile) -> Val {
    // Shapes and lights are never written: `write` refuses to change them.
    let opaque = || Val::Leaf(String::new());
    Val::Struct {
        variant: "",
        fields: vec![
            required("version", f.version.to_string()),
            field("camera", camera_value(&f.camera), false),
            field(
                "materials",
                Val::Map(
                    f.materials
                        .iter()
                        .map(|(k, m)| (k.clone(), material_value(m)))
                        .collect(),
                ),
                f.materials.is_empty(),
            ),
            field("shapes", opaque(), false),
            field("lights", opaque(), f.lights.is_empty()),
            field(
                "environment",
                environment_value(&f.environment),
                f.environment == Environment::None,
            ),
            field("render", render_value(&f.render), false),
        ],
    }
}

pub(crate) fn camera_value(c: &CameraDesc) -> Val {
    match c {
        CameraDesc::Perspective {
            position,
            target,
            up,
            fov_y,
            aperture_radius,
            focus_distance,
            autofocus,
        } => Val::Struct {
            variant: "Perspective",
            fields: vec![
                required("position", vec3(*position)),
                required("target", vec3(*target)),
                given("up", vec3(*up), "(0.0, 1.0, 0.0)"),
                required("fov_y", num(*fov_y)),
                given("aperture_radius", num(*aperture_radius), "0.0"),
                optional("focus_distance", *focus_distance, num),
                given("autofocus", autofocus.to_string(), "false"),
            ],
        },
        CameraDesc::Gltf {
            shape,
            index,
            aperture_radius,
            focus_distance,
            autofocus,
        } => Val::Struct {
            variant: "Gltf",
            fields: vec![
                required("shape", string(shape)),
                given("index", index.to_string(), "0"),
                given("aperture_radius", num(*aperture_radius), "0.0"),
                optional("focus_distance", *focus_distance, num),
                given("autofocus", autofocus.to_string(), "false"),
            ],
        },
    }
}

pub(crate) fn material_value(m: &MaterialDesc) -> Val {
    let d = MaterialDesc::default();
    // The lobe parameters ([`crate::lobes::PARAMS`]), in the format's order: the
    // roughnesses before `metallic`, the others after `multiscatter`.
    let params = crate::lobes::PARAMS;
    let mut lobes = params
        .iter()
        .map(|p| given(p.name, (p.save)(m), &(p.save)(&d)));
    let before_metallic = params
        .iter()
        .position(|p| p.name == "specular")
        .unwrap_or(0);
    let mut fields = vec![
        given("base_color", vec3(m.base_color), &vec3(d.base_color)),
        given("emission", vec3(m.emission), &vec3(d.emission)),
    ];
    fields.extend(lobes.by_ref().take(before_metallic));
    fields.extend([
        optional("metallic", m.metallic, num),
        optional("conductor", m.conductor.as_deref(), string),
        optional("eta", m.eta, vec3),
        optional("k", m.k, vec3),
        given(
            "multiscatter",
            m.multiscatter.to_string(),
            &d.multiscatter.to_string(),
        ),
    ]);
    fields.extend(lobes);
    fields.extend([
        given("ior", num(m.ior), &num(d.ior)),
        given(
            "two_sided",
            m.two_sided.to_string(),
            &d.two_sided.to_string(),
        ),
        optional("attenuation_color", m.attenuation_color, vec3),
        optional("attenuation_distance", m.attenuation_distance, num),
        optional("medium", m.medium, |x| {
            format!(
                "(sigma_a: {}, sigma_s: {}, g: {})",
                vec3(x.sigma_a),
                vec3(x.sigma_s),
                num(x.g)
            )
        }),
        given(
            "index_matched",
            m.index_matched.to_string(),
            &d.index_matched.to_string(),
        ),
        given(
            "alpha_mode",
            format!("{:?}", m.alpha_mode),
            &format!("{:?}", d.alpha_mode),
        ),
        given("alpha_cutoff", num(m.alpha_cutoff), &num(d.alpha_cutoff)),
        given("opacity", num(m.opacity), &num(d.opacity)),
    ]);
    Val::Struct {
        variant: "",
        fields,
    }
}

pub(crate) fn environment_value(e: &Environment) -> Val {
    match e {
        Environment::None => leaf("None".into()),
        Environment::Constant(c) => leaf(format!("Constant({})", vec3(*c))),
        Environment::Map {
            path,
            intensity,
            azimuth,
            elevation,
            show_background,
        } => Val::Struct {
            variant: "Map",
            fields: vec![
                required("path", string(path)),
                given("intensity", num(*intensity), "1.0"),
                given("azimuth", num(*azimuth), "0.0"),
                given("elevation", num(*elevation), "0.0"),
                given("show_background", show_background.to_string(), "true"),
            ],
        },
    }
}

pub(crate) fn render_value(r: &RenderSettings) -> Val {
    Val::Struct {
        variant: "",
        fields: vec![
            required("width", r.width.to_string()),
            required("height", r.height.to_string()),
            given("max_bounces", r.max_bounces.to_string(), "20"),
            given("spp", r.spp.to_string(), "1"),
            given("seed", r.seed.to_string(), "0"),
            given("texture_mips", r.texture_mips.to_string(), "true"),
        ],
    }
}

/// `v` written anew: structs on one line with their non-default fields; maps on one line,
/// or one entry a line when `indent` (that of the line the map starts on) is given.
pub(crate) fn render(v: &Val, indent: Option<&str>, nl: &str) -> String {
    match v {
        Val::Leaf(s) => s.clone(),
        Val::Struct { variant, fields } => {
            let written: Vec<String> = fields
                .iter()
                .filter(|f| !f.default)
                .map(|f| format!("{}: {}", f.name, render(&f.value, None, nl)))
                .collect();
            format!("{variant}({})", written.join(", "))
        }
        Val::Map(map) => {
            let entries = map
                .iter()
                .map(|(k, v)| format!("{}: {}", string(k), render(v, None, nl)));
            match indent {
                Some(indent) if !map.is_empty() => {
                    let mut out = format!("{{{nl}");
                    for e in entries {
                        out.push_str(&format!("{indent}    {e},{nl}"));
                    }
                    out.push_str(&format!("{indent}}}"));
                    out
                }
                _ => format!("{{{}}}", entries.collect::<Vec<_>>().join(", ")),
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Edits of the text.

/// Replace `range` of the text with `text` (an insertion when the range is empty).
#[derive(Debug)]
struct Edit {
    range: Range<usize>,
    text: String,
}

impl Edit {
    fn insert(at: usize, text: impl Into<String>) -> Self {
        Self {
            range: at..at,
            text: text.into(),
        }
    }

    fn delete(range: Range<usize>) -> Self {
        Self {
            range,
            text: String::new(),
        }
    }
}

/// `text` with `edits` made; they must not overlap.
fn apply(text: &str, edits: &[Edit]) -> Result<String, SceneError> {
    let mut order: Vec<&Edit> = edits.iter().collect();
    // Stable: insertions at one place stay in the order they were made.
    order.sort_by_key(|e| (e.range.start, e.range.end));
    let mut out = String::with_capacity(text.len());
    let mut at = 0;
    for e in order {
        let kept = (e.range.start >= at)
            .then(|| text.get(at..e.range.start))
            .flatten()
            .ok_or_else(|| unwritable("overlapping edits of the text"))?;
        out.push_str(kept);
        out.push_str(&e.text);
        at = e.range.end;
    }
    out.push_str(
        text.get(at..)
            .ok_or_else(|| unwritable("an edit past the end of the text"))?,
    );
    Ok(out)
}

// ---------------------------------------------------------------------------------------
// The text: a scanner for RON that skips strings and comments, finds the entries of a
// struct or map, and knows lines.

/// One `key: value` of a struct or map, as byte ranges of the text.
#[derive(Clone, Debug)]
struct Entry {
    /// The field name or the map key as written.
    key: Range<usize>,
    /// The value as written, without the whitespace and comments around it.
    value: Range<usize>,
    /// The comma after the value.
    comma: Option<usize>,
}

/// A struct `Name(…)`/`(…)` or a map `{…}` in the text.
#[derive(Clone, Debug)]
struct Container {
    /// The opening bracket.
    open: usize,
    /// The closing bracket.
    close: usize,
    entries: Vec<Entry>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Tok {
    Open,
    Close,
    Comma,
    Colon,
    Other,
}

/// What happens to one entry of a container.
#[derive(Clone, Copy)]
enum Action<'v> {
    Keep,
    Remove,
    /// Its value changed from the first to the second.
    Merge(&'v Val, &'v Val),
}

/// The changes to one container.
struct Plan<'v> {
    /// One per entry of the text.
    actions: Vec<Action<'v>>,
    /// New entries (key as written, value) to insert before entry `i`.
    before: Vec<Vec<(String, &'v Val)>>,
    /// New entries after the last one.
    append: Vec<(String, &'v Val)>,
}

impl<'v> Plan<'v> {
    fn new(entries: usize) -> Self {
        Self {
            actions: vec![Action::Keep; entries],
            before: vec![Vec::new(); entries],
            append: Vec::new(),
        }
    }
}

struct Text<'a> {
    s: &'a str,
    b: &'a [u8],
    /// The file's line ending.
    nl: &'static str,
}

fn is_ident_byte(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_' || c == b'#' || c >= 0x80
}

impl<'a> Text<'a> {
    fn new(s: &'a str) -> Self {
        Self {
            s,
            b: s.as_bytes(),
            nl: if s.contains("\r\n") { "\r\n" } else { "\n" },
        }
    }

    // --- Tokens.

    /// The first position from `i` that is not whitespace or a comment.
    fn trivia(&self, mut i: usize) -> usize {
        let b = self.b;
        loop {
            while i < b.len() && b[i].is_ascii_whitespace() {
                i += 1;
            }
            if b[i..].starts_with(b"//") {
                i = self.line_end(i);
            } else if b[i..].starts_with(b"/*") {
                // Block comments nest in RON.
                let mut depth = 0usize;
                while i < b.len() {
                    if b[i..].starts_with(b"/*") {
                        depth += 1;
                        i += 2;
                    } else if b[i..].starts_with(b"*/") {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        i += 1;
                    }
                }
            } else {
                return i.min(b.len());
            }
        }
    }

    /// The token that starts at `i` (not trivia, before the end): its kind and end.
    fn token(&self, i: usize) -> (Tok, usize) {
        let b = self.b;
        let quoted = |close: u8| {
            let mut j = i + 1;
            while j < b.len() {
                match b[j] {
                    b'\\' => j += 2,
                    c if c == close => return j + 1,
                    _ => j += 1,
                }
            }
            b.len()
        };
        match b[i] {
            b'(' | b'[' | b'{' => (Tok::Open, i + 1),
            b')' | b']' | b'}' => (Tok::Close, i + 1),
            b',' => (Tok::Comma, i + 1),
            b':' => (Tok::Colon, i + 1),
            b'"' => (Tok::Other, quoted(b'"')),
            b'\'' => (Tok::Other, quoted(b'\'')),
            b'r' => {
                // A raw string r"…" or r#"…"#; else an identifier's letter.
                let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
                if b.get(i + 1 + hashes) == Some(&b'"') {
                    let from = i + 2 + hashes;
                    let close = format!("\"{}", "#".repeat(hashes));
                    let end = self.s[from..]
                        .find(&close)
                        .map_or(b.len(), |n| from + n + close.len());
                    (Tok::Other, end)
                } else {
                    (Tok::Other, i + 1)
                }
            }
            _ => (
                Tok::Other,
                i + self.s[i..].chars().next().map_or(1, char::len_utf8),
            ),
        }
    }

    /// The end of the value, map key or field name that starts at `i`: the end of its
    /// last token before a `,`, `:` or closing bracket outside brackets.
    fn value_end(&self, i: usize) -> Option<usize> {
        let mut depth = 0usize;
        let (mut j, mut end) = (i, i);
        loop {
            j = self.trivia(j);
            if j >= self.b.len() {
                return (depth == 0).then_some(end);
            }
            let (tok, after) = self.token(j);
            match tok {
                Tok::Close | Tok::Comma | Tok::Colon if depth == 0 => return Some(end),
                Tok::Open => depth += 1,
                Tok::Close => depth -= 1,
                _ => {}
            }
            (j, end) = (after, after);
        }
    }

    /// The end of the bracketed group that opens at `open`.
    fn group_end(&self, open: usize) -> Option<usize> {
        let mut depth = 0usize;
        let mut j = open;
        loop {
            j = self.trivia(j);
            if j >= self.b.len() {
                return None;
            }
            let (tok, after) = self.token(j);
            match tok {
                Tok::Open => depth += 1,
                Tok::Close => {
                    depth = depth.checked_sub(1)?;
                    if depth == 0 {
                        return Some(after);
                    }
                }
                _ => {}
            }
            j = after;
        }
    }

    /// The struct or map whose text starts at `i` (after an optional name).
    fn container(&self, i: usize) -> Option<Container> {
        let b = self.b;
        let mut j = self.trivia(i);
        while j < b.len() && is_ident_byte(b[j]) {
            j += 1;
        }
        let open = self.trivia(j);
        let close_byte = match b.get(open)? {
            b'(' => b')',
            b'{' => b'}',
            _ => return None,
        };
        let mut entries = Vec::new();
        let mut j = open + 1;
        loop {
            j = self.trivia(j);
            if *b.get(j)? == close_byte {
                return Some(Container {
                    open,
                    close: j,
                    entries,
                });
            }
            let key = j..self.value_end(j)?;
            j = self.trivia(key.end);
            if key.is_empty() || b.get(j) != Some(&b':') {
                return None;
            }
            let start = self.trivia(j + 1);
            let value = start..self.value_end(start)?;
            if value.is_empty() {
                return None;
            }
            j = self.trivia(value.end);
            let comma = (b.get(j) == Some(&b',')).then_some(j);
            if comma.is_some() {
                j += 1;
            } else if b.get(j) != Some(&close_byte) {
                return None;
            }
            entries.push(Entry { key, value, comma });
        }
    }

    /// The file's top-level struct, after any `#![enable(…)]` attributes.
    fn root(&self) -> Option<Container> {
        let mut j = self.trivia(0);
        while self.b.get(j) == Some(&b'#') {
            j = self.trivia(j + 1);
            if self.b.get(j) == Some(&b'!') {
                j = self.trivia(j + 1);
            }
            if self.b.get(j) != Some(&b'[') {
                return None;
            }
            j = self.trivia(self.group_end(j)?);
        }
        let root = self.container(j)?;
        (self.trivia(root.close + 1) == self.b.len()).then_some(root)
    }

    // --- Lines.

    fn line_start(&self, p: usize) -> usize {
        self.s[..p].rfind('\n').map_or(0, |n| n + 1)
    }

    /// The position of the `\n` that ends the line of `p`, or the end of the text.
    fn line_end(&self, p: usize) -> usize {
        self.s[p..].find('\n').map_or(self.s.len(), |n| p + n)
    }

    /// The whitespace that starts the line of `p`.
    fn indent(&self, p: usize) -> &'a str {
        let line = &self.s[self.line_start(p)..];
        let rest = line.trim_start_matches([' ', '\t']);
        &line[..line.len() - rest.len()]
    }

    /// Nothing but whitespace before `p` on its line.
    fn first_on_line(&self, p: usize) -> bool {
        self.s[self.line_start(p)..p].trim().is_empty()
    }

    /// The entry has its lines to itself: only whitespace before it, and only whitespace
    /// or a `//` comment after its comma.
    fn own_line(&self, e: &Entry) -> bool {
        let after = e.comma.map_or(e.value.end, |c| c + 1);
        let rest = self.s[after..self.line_end(after)].trim();
        self.first_on_line(e.key.start) && (rest.is_empty() || rest.starts_with("//"))
    }

    /// The start of the `//` comment lines directly above the line starting at `ls`, or
    /// `ls` when there are none.
    fn comment_block_start(&self, mut ls: usize) -> usize {
        while ls > 0 {
            let above = self.line_start(ls - 1);
            if self.s[above..ls - 1].trim_start().starts_with("//") {
                ls = above;
            } else {
                break;
            }
        }
        ls
    }

    // --- Merging.

    /// The edits that turn the value at `span` (which reads as `old`) into `new`.
    fn merge(&self, span: Range<usize>, old: &Val, new: &Val, edits: &mut Vec<Edit>) {
        if old == new {
            return;
        }
        let planned = match (old, new) {
            (
                Val::Struct {
                    variant: a,
                    fields: old_fields,
                },
                Val::Struct {
                    variant: b,
                    fields: new_fields,
                },
            ) if a == b => self
                .whole_container(&span)
                .and_then(|c| Some((self.plan_struct(&c, old_fields, new_fields)?, c))),
            (Val::Map(old_map), Val::Map(new_map)) => self
                .whole_container(&span)
                .and_then(|c| Some((self.plan_map(&c, old_map, new_map)?, c))),
            _ => None,
        };
        match planned {
            Some((plan, c)) => self.carry_out(&c, &plan, edits),
            None => edits.push(Edit {
                text: render(new, Some(self.indent(span.start)), self.nl),
                range: span,
            }),
        }
    }

    /// [`Text::merge`] of a container already found.
    fn merge_in(&self, c: &Container, old: &Val, new: &Val, edits: &mut Vec<Edit>) {
        let plan = match (old, new) {
            (Val::Struct { fields: a, .. }, Val::Struct { fields: b, .. }) => {
                self.plan_struct(c, a, b)
            }
            _ => None,
        };
        match plan {
            Some(plan) => self.carry_out(c, &plan, edits),
            None => self.merge(c.open..c.close + 1, old, new, edits),
        }
    }

    /// The container that is exactly the value at `span`.
    fn whole_container(&self, span: &Range<usize>) -> Option<Container> {
        self.container(span.start)
            .filter(|c| c.close + 1 == span.end)
    }

    /// Field by field: changed fields merged, fields that became `None` removed, fields
    /// missing from the text that changed inserted before the next field (in declaration
    /// order) the text has, else at the end.
    fn plan_struct<'v>(
        &self,
        c: &Container,
        old: &'v [Field],
        new: &'v [Field],
    ) -> Option<Plan<'v>> {
        if old.len() != new.len() {
            return None;
        }
        let names: Vec<&str> = c
            .entries
            .iter()
            .map(|e| {
                let k = &self.s[e.key.clone()];
                k.strip_prefix("r#").unwrap_or(k)
            })
            .collect();
        let mut plan = Plan::new(c.entries.len());
        let mut pending = Vec::new();
        for (o, n) in old.iter().zip(new) {
            if o.name != n.name {
                return None;
            }
            let Some(i) = names.iter().position(|&k| k == n.name) else {
                if o.value != n.value && !n.none {
                    pending.push((n.name.to_owned(), &n.value));
                }
                continue;
            };
            plan.actions[i] = if o.value == n.value {
                Action::Keep
            } else if n.none {
                Action::Remove
            } else {
                Action::Merge(&o.value, &n.value)
            };
            if !matches!(plan.actions[i], Action::Remove) {
                plan.before[i].append(&mut pending);
            }
        }
        plan.append = pending;
        Some(plan)
    }

    /// Entry by key: changed materials merged, removed ones removed, new ones appended.
    fn plan_map<'v>(
        &self,
        c: &Container,
        old: &'v BTreeMap<String, Val>,
        new: &'v BTreeMap<String, Val>,
    ) -> Option<Plan<'v>> {
        let mut keys = Vec::with_capacity(c.entries.len());
        for e in &c.entries {
            let key: String = ron::from_str(&self.s[e.key.clone()]).ok()?;
            if keys.contains(&key) || !old.contains_key(&key) {
                return None;
            }
            keys.push(key);
        }
        if keys.len() != old.len() {
            return None;
        }
        let mut plan = Plan::new(c.entries.len());
        for (i, key) in keys.iter().enumerate() {
            plan.actions[i] = match (&old[key], new.get(key)) {
                (_, None) => Action::Remove,
                (o, Some(n)) if o == n => Action::Keep,
                (o, Some(n)) => Action::Merge(o, n),
            };
        }
        plan.append = new
            .iter()
            .filter(|(k, _)| !old.contains_key(*k))
            .map(|(k, v)| (string(k), v))
            .collect();
        Some(plan)
    }

    fn carry_out(&self, c: &Container, plan: &Plan, edits: &mut Vec<Edit>) {
        let kept = plan
            .actions
            .iter()
            .rposition(|a| !matches!(a, Action::Remove));
        // Removed entries after the last kept one that share lines with others go in one
        // cut, with the kept entry's comma when nothing follows them, so that what is left
        // reads `{"a": 1}` rather than `{"a": 1, }`.
        let tail = &c.entries[kept.map_or(0, |k| k + 1)..];
        let cut_tail = !tail.is_empty()
            && !tail.iter().any(|e| self.own_line(e))
            && kept.is_none_or(|k| {
                c.entries[k].comma.is_some() && tail.last().is_some_and(|e| e.comma.is_none())
            });
        for (i, e) in c.entries.iter().enumerate() {
            if !plan.before[i].is_empty() {
                self.insert_before(e, &plan.before[i], edits);
            }
            match plan.actions[i] {
                Action::Keep => {}
                Action::Merge(old, new) => self.merge(e.value.clone(), old, new, edits),
                Action::Remove if cut_tail && kept.is_none_or(|k| i > k) => {}
                Action::Remove => edits.push(self.removal(e)),
            }
        }
        let last = kept.map(|k| &c.entries[k]);
        match (cut_tail, last, c.entries.last()) {
            (true, Some(k), Some(end)) => {
                edits.push(Edit::delete(k.comma.unwrap_or(k.value.end)..end.value.end));
                if !plan.append.is_empty() {
                    self.append(c, Some((k, None)), &plan.append, edits);
                }
            }
            (true, _, _) => {
                // Nothing kept: the inside is the new entries.
                let items = self.inline_items(&plan.append);
                let pad = if items.is_empty() || self.b[c.open] != b'{' {
                    ""
                } else {
                    " "
                };
                edits.push(Edit {
                    range: c.open + 1..c.close,
                    text: format!("{pad}{items}{pad}"),
                });
            }
            _ if plan.append.is_empty() => {}
            _ => self.append(c, last.map(|k| (k, k.comma)), &plan.append, edits),
        }
    }

    /// `key: value, …` on one line.
    fn inline_items(&self, new: &[(String, &Val)]) -> String {
        new.iter()
            .map(|(k, v)| format!("{k}: {}", render(v, None, self.nl)))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// New entries before `e`: on their own lines (above its comments) when `e` starts
    /// its line, else in front of it.
    fn insert_before(&self, e: &Entry, new: &[(String, &Val)], edits: &mut Vec<Edit>) {
        let nl = self.nl;
        if self.first_on_line(e.key.start) {
            let indent = self.indent(e.key.start);
            let text: String = new
                .iter()
                .map(|(k, v)| format!("{indent}{k}: {},{nl}", render(v, Some(indent), nl)))
                .collect();
            let at = self.comment_block_start(self.line_start(e.key.start));
            edits.push(Edit::insert(at, text));
        } else {
            let text: String = new
                .iter()
                .map(|(k, v)| format!("{k}: {}, ", render(v, None, nl)))
                .collect();
            edits.push(Edit::insert(e.key.start, text));
        }
    }

    /// The removal of entry `e`: its lines and the comment lines above when it has its
    /// lines to itself, else the entry, its comma and the spaces after.
    fn removal(&self, e: &Entry) -> Edit {
        if self.own_line(e) {
            let after = e.comma.map_or(e.value.end, |c| c + 1);
            let end = (self.line_end(after) + 1).min(self.s.len());
            let start = self.comment_block_start(self.line_start(e.key.start));
            return Edit::delete(start..end);
        }
        match e.comma {
            Some(comma) => {
                let spaces = self.b[comma + 1..]
                    .iter()
                    .take_while(|&&c| c == b' ' || c == b'\t')
                    .count();
                Edit::delete(e.key.start..comma + 1 + spaces)
            }
            None => Edit::delete(e.key.start..e.value.end),
        }
    }

    /// New entries at the end: one a line before the closing bracket when it starts its
    /// line, else after `last`, the last entry kept (with its comma, if it keeps one).
    fn append(
        &self,
        c: &Container,
        last: Option<(&Entry, Option<usize>)>,
        new: &[(String, &Val)],
        edits: &mut Vec<Edit>,
    ) {
        let nl = self.nl;
        if self.first_on_line(c.close) {
            if let Some((k, None)) = last {
                edits.push(Edit::insert(k.value.end, ","));
            }
            let indent = c
                .entries
                .iter()
                .rev()
                .find(|e| self.first_on_line(e.key.start))
                .map_or_else(
                    || {
                        let outer = self.indent(c.close);
                        let unit = if outer.contains('\t') { "\t" } else { "    " };
                        format!("{outer}{unit}")
                    },
                    |e| self.indent(e.key.start).to_owned(),
                );
            let text: String = new
                .iter()
                .map(|(k, v)| format!("{indent}{k}: {},{nl}", render(v, Some(&indent), nl)))
                .collect();
            edits.push(Edit::insert(self.line_start(c.close), text));
            return;
        }
        let items = self.inline_items(new);
        let inside = &self.s[c.open + 1..c.close];
        edits.push(match last {
            Some((_, Some(comma))) => Edit::insert(comma + 1, format!(" {items},")),
            Some((k, None)) => Edit::insert(k.value.end, format!(", {items}")),
            None if c.entries.is_empty() && inside.trim().is_empty() => {
                let pad = if self.b[c.open] == b'{' { " " } else { "" };
                Edit {
                    range: c.open + 1..c.close,
                    text: format!("{pad}{items}{pad}"),
                }
            }
            None => Edit::insert(c.open + 1, format!("{items}, ")),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(text: &str) -> Vec<(String, String)> {
        let t = Text::new(text);
        let c = t.container(0).unwrap();
        c.entries
            .iter()
            .map(|e| {
                (
                    text[e.key.clone()].to_owned(),
                    text[e.value.clone()].to_owned(),
                )
            })
            .collect()
    }

    #[test]
    fn scanner_skips_strings_comments_and_nesting() {
        let text = r#"Name( // a comment, with: colons
            a: "x, ) y", /* block /* nested */ , */ b: (1, [2, 3], {"k": 4}),
            r#c: r"raw ) string", d: 'q', e: Some((1.0e3, -2))
        )"#;
        assert_eq!(
            entries(text),
            [
                ("a", r#""x, ) y""#),
                ("b", r#"(1, [2, 3], {"k": 4})"#),
                ("r#c", r#"r"raw ) string""#),
                ("d", "'q'"),
                ("e", "Some((1.0e3, -2))"),
            ]
            .map(|(k, v)| (k.to_owned(), v.to_owned()))
        );
        assert_eq!(
            entries(r#"{ "a:b": 1, "c\"": (x: 2) }"#),
            [(r#""a:b""#, "1"), (r#""c\"""#, "(x: 2)")].map(|(k, v)| (k.to_owned(), v.to_owned()))
        );
    }

    #[test]
    fn scanner_rejects_broken_text() {
        for text in [
            "(a: 1",
            "(a 1)",
            "(a: )",
            "(a: 1 b: 2)",
            "[1, 2]",
            "(a: \"open)",
        ] {
            assert!(Text::new(text).container(0).is_none(), "{text}");
        }
        assert!(
            Text::new("#![enable(implicit_some)]\n(a: 1)")
                .root()
                .is_some()
        );
        assert!(Text::new("(a: 1) trailing").root().is_none());
    }

    #[test]
    fn floats_and_strings_read_back() {
        for x in [
            0.0f32,
            -0.0,
            1.0,
            0.885_809,
            1e-7,
            3e20,
            f32::MAX,
            f32::MIN_POSITIVE,
        ] {
            let back: f32 = ron::from_str(&num(x)).unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{x}");
        }
        for s in ["plain", "q\"uote", "back\\slash", "new\nline", "é ✓", ""] {
            let back: String = ron::from_str(&string(s)).unwrap();
            assert_eq!(back, s);
        }
    }

    #[test]
    fn overlapping_edits_are_an_error() {
        let edits = [Edit::delete(0..3), Edit::insert(1, "x")];
        assert!(apply("abcdef", &edits).is_err());
        let edits = [
            Edit::insert(2, "x"),
            Edit::delete(2..4),
            Edit::insert(2, "y"),
        ];
        assert_eq!(apply("abcdef", &edits).unwrap(), "abxyef");
    }
}
