//! Property-based fuzzing of every loader: graph files (and their compilation), node group
//! files, scene files (and `GpuScene::build`), glTF/GLB and OBJ/MTL meshes, and PNG, HDR and
//! EXR images. Each property takes a real file of the repository (or one made here from
//! them), mutates it (bit flips, deletions, insertions of format tokens, odd numbers in place
//! of numbers, duplicated chunks, truncation) and asserts that the loader returns
//! `Ok` or `Err`: never a panic, and within [`CASE_LIMIT`] (a hang is a failure).
//!
//! `LUMAGRAPH_FUZZ_CASES=N` runs about `N` cases in all, shared out as the defaults are
//! (`docs/failures.md`, "Fuzzing"); without it the run is fixed (the same cases every time)
//! and takes well under a minute. `LUMAGRAPH_FUZZ_SEED=S` picks the random seed (a long run
//! otherwise takes a new one, printed). A failure writes the smallest input found under
//! `target/fuzz-failures/`.
//!
//! Generated graphs (random kinds, edges and params, declared kinds, groups, escaping
//! output paths) go through compile and render in `tests/graph/fuzz_graphs.rs`.
//!
//! `tests/corpus/` holds broken files (and every input that once made a loader panic); each
//! goes through its loader in [`corpus_files_load_without_panicking`], and the ones the CLI
//! takes through `lumagraph render` in [`render_refuses_the_corpus_with_an_error`].

use crate::common;

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, LazyLock};
use std::time::{Duration, Instant};

use lumagraph::graph::Graph;
use lumagraph::render::image_io;
use lumagraph::scene::{GpuScene, Scene};
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestError, TestRunner};

use common::repo;

/// The longest one case may take before it counts as a hang.
const CASE_LIMIT: Duration = Duration::from_secs(10);

/// Default cases per property; `LUMAGRAPH_FUZZ_CASES` scales them to its total.
const GRAPH_CASES: u32 = 1000;
const GROUP_CASES: u32 = 300;
const SCENE_CASES: u32 = 1000;
const GLTF_CASES: u32 = 1000;
const OBJ_CASES: u32 = 600;
const PLY_CASES: u32 = 400;
const PNG_CASES: u32 = 600;
const HDR_CASES: u32 = 500;
const EXR_CASES: u32 = 600;
const DEFAULT_TOTAL: u32 = GRAPH_CASES
    + GROUP_CASES
    + SCENE_CASES
    + GLTF_CASES
    + OBJ_CASES
    + PLY_CASES
    + PNG_CASES
    + HDR_CASES
    + EXR_CASES;

// ---------------------------------------------------------------------------------------
// Inputs and mutations
// ---------------------------------------------------------------------------------------

/// Files that go to a loader together (a glTF file and its buffer, an OBJ and its MTL);
/// `main` is the one the loader is given.
#[derive(Clone)]
struct FileSet {
    label: String,
    files: Vec<(String, Vec<u8>)>,
    main: usize,
}

impl FileSet {
    fn one(name: &str, bytes: Vec<u8>) -> Self {
        Self {
            label: name.to_owned(),
            files: vec![(name.to_owned(), bytes)],
            main: 0,
        }
    }

    fn main_name(&self) -> &str {
        &self.files[self.main].0
    }

    fn main_bytes(&self) -> &[u8] {
        &self.files[self.main].1
    }

    /// Writes the files into `dir`; returns the main file's path.
    fn write_to(&self, dir: &Path) -> PathBuf {
        for (name, bytes) in &self.files {
            let path = dir.join(name);
            if let Some(parent) = path.parent() {
                std::fs::create_dir_all(parent).unwrap();
            }
            std::fs::write(path, bytes).unwrap();
        }
        dir.join(self.main_name())
    }
}

impl fmt::Debug for FileSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{} (written to target/fuzz-failures/)", self.label)?;
        for (name, bytes) in &self.files {
            let text = String::from_utf8_lossy(&bytes[..bytes.len().min(2000)]);
            writeln!(f, "--- {name} ({} bytes) ---\n{text}", bytes.len())?;
        }
        Ok(())
    }
}

/// One change to a file.
#[derive(Clone, Debug)]
enum Mutation {
    FlipBit(Index, u8),
    SetByte(Index, u8),
    /// An interesting 32-bit value over four bytes (little- or big-endian).
    SetWord(Index, u32, bool),
    Delete(Index, usize),
    /// A token of the format (or an odd number) inserted.
    InsertToken(Index, Index),
    InsertBytes(Index, Vec<u8>),
    /// The `n`th number of the text replaced by an odd one.
    ReplaceNumber(Index, Index),
    /// The `n`th word or quoted string replaced by a token of the format.
    ReplaceWord(Index, Index),
    /// A chunk copied to another place.
    Duplicate(Index, usize, Index),
    Truncate(Index),
}

/// Numbers that break naive parsing and arithmetic.
#[rustfmt::skip]
const NUMBERS: &[&str] = &[
    "1e39", "-1e39", "-0", "-0.0", "NaN", "nan", "inf", "-inf", "0", "-1", "1", "2", "3", "7",
    "255", "256", "65535", "16385", "100000", "4294967295", "4294967296", "2147483648",
    "-2147483649", "9223372036854775808", "18446744073709551615", "18446744073709551616",
    "340282366920938463463374607431768211456", "1e-45", "1e308", "0.5", "1e9",
];

/// 32-bit values written over four bytes of a binary file (sizes, lengths, offsets).
#[rustfmt::skip]
const WORDS: &[u32] = &[
    0, 1, 0x7f, 0x80, 0xff, 0x7fff, 0xffff, 0x1_0000, 0x4000_0000, 0x7fff_ffff, 0x8000_0000,
    0xffff_ffff, 16385,
];

/// RON syntax, and the words and values of graph and scene files.
#[rustfmt::skip]
const RON_TOKENS: &[&str] = &[
    "(", ")", "[", "]", "{", "}", "\"", ":", ",", "Some(", "None", "true", "false", "()", "[]",
    "{}", "\"\"", "r#\"", "\"#", "//", "/*", "*/", "\\", "'", "\n", "\\u{0}", "..",
    "#![enable(implicit_some)]", "version", "version: 1", "version: 2", "version: 3", "nodes",
    "edges", "kinds", "groups", "interface", "params", "inputs", "outputs", "id", "kind",
    "from", "to", "path", "file", "\"Output\"", "\"ImageInput\"", "\"PathTrace\"",
    "\"Accumulate\"", "\"Denoise\"", "\"Tonemap\"", "\"Exposure\"", "\"Bloom\"", "\"Lens\"",
    "\"color\"", "\"in.color\"", "\"x.y.z\"", "\".\"", "\"../\"", "\"/\"",
    "Int(default: 4, min: 9, max: 2)", "Float(default: 0.0)", "Sphere", "Mesh", "Quad", "Box",
    "Rectangle", "Map", "Constant", "Perspective", "Gltf", "Point", "Spot", "Directional",
    "material", "materials", "shapes", "lights", "camera", "environment", "render", "transform",
    "corners", "radius", "center", "emission", "width", "height", "spp", "max_bounces",
    "\"Au\"", "conductor", "roughness", "base_color", "ior", "transmission", "(0.0, 0.0, 0.0)",
    "(1.0, 1.0)", "[(0.0, 0.0, 0.0)]",
];

/// JSON syntax, and glTF's keys and values.
#[rustfmt::skip]
const JSON_TOKENS: &[&str] = &[
    "{", "}", "[", "]", "\"", ":", ",", "null", "true", "false", "[]", "{}", "\"\"", "\\",
    "\\u0000", "\"bufferView\"", "\"byteOffset\"", "\"byteLength\"", "\"byteStride\"",
    "\"count\"", "\"indices\"", "\"material\"", "\"mesh\"", "\"children\"", "\"nodes\"",
    "\"scene\"", "\"sampler\"", "\"source\"", "\"texture\"", "\"index\"", "\"texCoord\"",
    "\"uri\"", "\"componentType\"", "\"type\"", "\"VEC3\"", "\"VEC2\"", "\"SCALAR\"",
    "\"MAT4\"", "\"matrix\"", "\"rotation\"", "\"scale\"", "\"translation\"", "\"mode\"",
    "\"camera\"", "\"extensions\"", "\"KHR_lights_punctual\"", "\"light\"", "\"spot\"",
    "\"range\"", "\"data:application/octet-stream;base64,AAAA\"",
    "\"data:image/png;base64,iVBORw0KGgo=\"", "\"missing.bin\"", "\"%FF%FE.bin\"", "%", "%2e",
    "\"../\"", "5120", "5121", "5122", "5123", "5125", "5126",
];

/// OBJ and MTL keywords and face corners.
#[rustfmt::skip]
const OBJ_TOKENS: &[&str] = &[
    "v ", "vt ", "vn ", "vp ", "f ", "l ", "p ", "o ", "g ", "s ", "usemtl ", "mtllib ",
    "newmtl ", "Ka ", "Kd ", "Ks ", "Ke ", "Ns ", "Ni ", "d ", "Tr ", "illum ", "map_Kd ",
    "map_Ke ", "map_Bump ", "norm ", "Pr ", "Pm ", "/", "//", " ", "\n", "#", "\\\n", "1/1/1",
    "-1/-1/-1", "0/0/0", "1//1", "f 1 2 3\n", "f 1 2 3 4 5\n", "f -1 -2 -3\n", "f 99 1 2\n",
    "v 1 2\n", "v nan nan nan\n", "vt 0.5\n", "usemtl missing\n", "mtllib missing.mtl\n",
    "tex.png", "CornellBox.mtl", "leftWall",
];

/// PLY header words and values.
#[rustfmt::skip]
const PLY_TOKENS: &[&str] = &[
    "ply\n", "format ascii 1.0\n", "format binary_little_endian 1.0\n",
    "format binary_big_endian 1.0\n", "element ", "vertex ", "face ", "property ", "list ",
    "uchar ", "int ", "uint ", "float ", "double ", "char ", "short ", "vertex_indices",
    "vertex_index", "end_header\n", "comment ", "obj_info ", " ", "\n", "4294967295",
    "-1", "nan", "1e39", "255 ", "0 ",
];

/// Tokens worth inserting into a binary file: magic numbers and chunk and attribute names
/// (ASCII: a string's other characters are more than one byte).
#[rustfmt::skip]
const BINARY_TOKENS: &[&str] = &[
    "PNG\r\n", "IHDR", "IDAT", "IEND", "PLTE", "tRNS", "gAMA", "acTL", "fcTL",
    "fdAT", "#?RADIANCE\n", "FORMAT=32-bit_rle_rgbe\n\n", "-Y 4 +X 4\n", "+Y 2 -X 2\n",
    "\u{2}\u{2}", "v/1\u{1}", "channels", "chlist", "compression", "dataWindow",
    "displayWindow", "lineOrder", "tiles", "glTF", "JSON", "BIN\0", "\0\0\0\0",
];

/// One mutation; chunks deleted or duplicated are shorter than `max_chunk` bytes.
fn mutation(max_chunk: usize) -> impl Strategy<Value = Mutation> {
    prop_oneof![
        1 => (any::<Index>(), 0..8u8).prop_map(|(i, b)| Mutation::FlipBit(i, b)),
        1 => (any::<Index>(), any::<u8>()).prop_map(|(i, v)| Mutation::SetByte(i, v)),
        1 => (any::<Index>(), any::<Index>(), any::<bool>())
            .prop_map(|(i, w, le)| Mutation::SetWord(i, *w.get(WORDS), le)),
        1 => (any::<Index>(), 1..max_chunk).prop_map(|(i, n)| Mutation::Delete(i, n)),
        3 => (any::<Index>(), any::<Index>()).prop_map(|(i, t)| Mutation::InsertToken(i, t)),
        1 => (any::<Index>(), prop::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(i, b)| Mutation::InsertBytes(i, b)),
        3 => (any::<Index>(), any::<Index>()).prop_map(|(i, t)| Mutation::ReplaceNumber(i, t)),
        2 => (any::<Index>(), any::<Index>()).prop_map(|(i, t)| Mutation::ReplaceWord(i, t)),
        1 => (any::<Index>(), 1..max_chunk, any::<Index>())
            .prop_map(|(i, n, to)| Mutation::Duplicate(i, n, to)),
        1 => (any::<Index>()).prop_map(Mutation::Truncate),
    ]
}

/// Byte ranges of the numbers in `bytes` (ASCII digits with a sign, point and exponent).
fn numbers(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() {
            let mut start = i;
            if start > 0 && bytes[start - 1] == b'-' {
                start -= 1;
            }
            while i < bytes.len()
                && (bytes[i].is_ascii_digit()
                    || matches!(bytes[i], b'.' | b'e' | b'E' | b'-' | b'+'))
            {
                i += 1;
            }
            out.push((start, i));
        } else {
            i += 1;
        }
    }
    out
}

/// Byte ranges of the words (identifiers) and quoted strings in `bytes`.
fn words(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let start = i;
        if bytes[i] == b'"' {
            i += 1;
            while i < bytes.len() && bytes[i] != b'"' && bytes[i] != b'\n' {
                i += 1;
            }
            i = (i + 1).min(bytes.len());
            out.push((start, i));
        } else if bytes[i].is_ascii_alphabetic() || bytes[i] == b'_' {
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            out.push((start, i));
        } else {
            i += 1;
        }
    }
    out
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation, tokens: &[&str]) {
    let len = bytes.len();
    let at = |i: &Index| if len == 0 { 0 } else { i.index(len) };
    let end = |i: &Index| i.index(len + 1);
    match m {
        Mutation::FlipBit(i, b) if len > 0 => bytes[at(i)] ^= 1 << b,
        Mutation::SetByte(i, v) if len > 0 => bytes[at(i)] = *v,
        Mutation::SetWord(i, w, le) if len >= 4 => {
            let p = i.index(len - 3);
            let b = if *le {
                w.to_le_bytes()
            } else {
                w.to_be_bytes()
            };
            bytes[p..p + 4].copy_from_slice(&b);
        }
        Mutation::Delete(i, n) if len > 0 => {
            let p = at(i);
            bytes.drain(p..(p + n).min(len));
        }
        Mutation::InsertToken(i, t) => {
            let all: Vec<&str> = tokens.iter().chain(NUMBERS).copied().collect();
            let p = end(i);
            bytes.splice(p..p, t.get(&all).bytes());
        }
        Mutation::InsertBytes(i, b) => {
            let p = end(i);
            bytes.splice(p..p, b.iter().copied());
        }
        Mutation::ReplaceNumber(n, t) => {
            let found = numbers(bytes);
            if !found.is_empty() {
                let (s, e) = *n.get(&found);
                bytes.splice(s..e, t.get(NUMBERS).bytes());
            }
        }
        Mutation::ReplaceWord(n, t) => {
            let found = words(bytes);
            if !found.is_empty() {
                let (s, e) = *n.get(&found);
                bytes.splice(s..e, t.get(tokens).bytes());
            }
        }
        Mutation::Duplicate(i, n, to) if len > 0 => {
            let p = at(i);
            let chunk = bytes[p..(p + n).min(len)].to_vec();
            let q = end(to);
            bytes.splice(q..q, chunk);
        }
        Mutation::Truncate(i) => bytes.truncate(at(i)),
        _ => {}
    }
}

/// The PNG chunks' CRCs recomputed, so that a mutation reaches the decoder and is not only
/// a checksum error.
fn fix_png_crcs(bytes: &mut [u8]) {
    let mut p = 8;
    while p + 12 <= bytes.len() {
        let n = u32::from_be_bytes(bytes[p..p + 4].try_into().unwrap()) as usize;
        let Some(end) = (p + 8).checked_add(n).filter(|&e| e + 4 <= bytes.len()) else {
            break;
        };
        let crc = crc32(&bytes[p + 4..end]);
        bytes[end..end + 4].copy_from_slice(&crc.to_be_bytes());
        p = end + 4;
    }
}

fn crc32(data: &[u8]) -> u32 {
    let mut crc = 0xffff_ffff_u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Mutated versions of `seeds`: one file of a set picked, 1 to 4 mutations applied to it,
/// PNG checksums fixed on half the PNG cases.
fn mutated(seeds: Vec<FileSet>, tokens: &'static [&'static str]) -> impl Strategy<Value = FileSet> {
    let seeds = Arc::new(seeds);
    (
        any::<Index>(),
        any::<Index>(),
        prop::collection::vec(mutation(256), 1..5),
        any::<bool>(),
    )
        .prop_map(move |(s, f, ms, fix_crc)| {
            let mut set = s.get(&seeds).clone();
            let k = f.index(set.files.len());
            let (name, bytes) = &mut set.files[k];
            for m in &ms {
                apply(bytes, m, tokens);
            }
            if fix_crc && name.ends_with(".png") {
                fix_png_crcs(bytes);
            }
            set.label = format!("{} with {name} mutated", set.label);
            set
        })
}

// ---------------------------------------------------------------------------------------
// Running cases
// ---------------------------------------------------------------------------------------

/// `default` scaled so that all properties run about `LUMAGRAPH_FUZZ_CASES` cases.
fn cases(default: u32) -> u32 {
    match std::env::var("LUMAGRAPH_FUZZ_CASES") {
        Ok(n) => {
            let total: u64 = n
                .trim()
                .parse()
                .expect("LUMAGRAPH_FUZZ_CASES: a number of cases");
            let scaled = total * u64::from(default) / u64::from(DEFAULT_TOTAL);
            u32::try_from(scaled.max(1)).unwrap_or(u32::MAX)
        }
        Err(_) => default,
    }
}

/// The seed: `LUMAGRAPH_FUZZ_SEED`, else a new one for a long run, else fixed per property.
fn seed(name: &str) -> u64 {
    if let Ok(s) = std::env::var("LUMAGRAPH_FUZZ_SEED") {
        return s.trim().parse().expect("LUMAGRAPH_FUZZ_SEED: a number");
    }
    let fixed = name.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    });
    if std::env::var_os("LUMAGRAPH_FUZZ_CASES").is_some() {
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        fixed ^ u64::try_from(now.as_nanos() & u128::from(u64::MAX)).unwrap_or_default()
    } else {
        fixed
    }
}

/// A loader run on one input: its `Ok` or its error message.
type Check<T> = Arc<dyn Fn(T) -> Result<(), String> + Send + Sync>;

/// Runs `check` on its own thread and returns what it returned (the loader's `Ok` or
/// `Err`, both fine); `Err` for a panic or a run longer than [`CASE_LIMIT`] (a hung thread
/// is left behind: the test fails anyway).
fn guarded<T: Send + 'static>(check: &Check<T>, input: T) -> Result<Result<(), String>, String> {
    let check = Arc::clone(check);
    common::guarded(CASE_LIMIT, move || check(input))
}

/// Where a failing input is written.
fn failure_dir(name: &str) -> PathBuf {
    repo("target/fuzz-failures").join(name)
}

/// Runs the property `name`: `check` on `cases(default)` inputs from `strategy`.
fn fuzz<S>(
    name: &str,
    default: u32,
    strategy: &S,
    check: impl Fn(FileSet) -> Result<(), String> + Send + Sync + 'static,
) where
    S: Strategy<Value = FileSet>,
{
    let cases = cases(default);
    let seed = seed(name);
    let config = Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        max_shrink_iters: 2000,
        max_shrink_time: 120_000,
        ..Config::default()
    };
    let check: Check<FileSet> = Arc::new(check);
    let start = Instant::now();
    let loaded = AtomicU32::new(0);
    let mut runner = TestRunner::new(config);
    let result = runner.run(strategy, |input| {
        let outcome = guarded(&check, input).map_err(TestCaseError::fail)?;
        if outcome.is_ok() {
            loaded.fetch_add(1, Ordering::Relaxed);
        }
        Ok(())
    });
    eprintln!(
        "fuzz {name}: {cases} cases ({} loaded, the others refused), seed {seed}, {:.1} s",
        loaded.into_inner(),
        start.elapsed().as_secs_f64()
    );
    match result {
        Ok(()) => {}
        Err(TestError::Fail(reason, input)) => {
            let dir = failure_dir(name);
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            input.write_to(&dir);
            panic!(
                "fuzz {name} (seed {seed}): {reason}\nsmallest input, in {}:\n{input:?}",
                dir.display()
            );
        }
        Err(e) => panic!("fuzz {name} (seed {seed}): {e}"),
    }
}

// ---------------------------------------------------------------------------------------
// Seeds
// ---------------------------------------------------------------------------------------

fn read(rel: &str) -> Vec<u8> {
    std::fs::read(repo(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The files in `dir` (under the repository root) whose names end in `ext`, sorted.
fn files_in(dir: &str, ext: &str) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(repo(dir))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    out.sort();
    out
}

fn file_seeds(dir: &str, ext: &str) -> Vec<FileSet> {
    files_in(dir, ext)
        .into_iter()
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            FileSet::one(&name, std::fs::read(&p).unwrap())
        })
        .collect()
}

fn base64_decode(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' => Some(62),
        b'/' => Some(63),
        _ => None,
    };
    let mut out = Vec::new();
    let (mut acc, mut bits) = (0u32, 0);
    for v in text.bytes().filter_map(value) {
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    out
}

/// The bytes of a `data:` URI.
fn data_uri(uri: &str) -> Vec<u8> {
    base64_decode(uri.split_once(",").expect("a data URI").1)
}

/// `BoxTextured.gltf` with its buffer and its image in files of their own.
fn box_split() -> FileSet {
    let mut json: serde_json::Value =
        serde_json::from_slice(&read("assets/BoxTextured/BoxTextured.gltf")).unwrap();
    let bin = data_uri(json["buffers"][0]["uri"].as_str().unwrap());
    let png = data_uri(json["images"][0]["uri"].as_str().unwrap());
    json["buffers"][0]["uri"] = "box.bin".into();
    json["images"][0]["uri"] = "box.png".into();
    FileSet {
        label: "BoxTextured as .gltf + .bin + .png".into(),
        files: vec![
            ("box.gltf".into(), serde_json::to_vec_pretty(&json).unwrap()),
            ("box.bin".into(), bin),
            ("box.png".into(), png),
        ],
        main: 0,
    }
}

/// `BoxTextured.gltf` as a binary `.glb`: its buffer in the BIN chunk.
fn box_glb() -> FileSet {
    let mut json: serde_json::Value =
        serde_json::from_slice(&read("assets/BoxTextured/BoxTextured.gltf")).unwrap();
    let mut bin = data_uri(json["buffers"][0]["uri"].as_str().unwrap());
    json["buffers"][0].as_object_mut().unwrap().remove("uri");
    let mut text = serde_json::to_vec(&json).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let mut glb = Vec::with_capacity(total);
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&u32::try_from(total).unwrap().to_le_bytes());
    glb.extend_from_slice(&u32::try_from(text.len()).unwrap().to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&text);
    glb.extend_from_slice(&u32::try_from(bin.len()).unwrap().to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    FileSet::one("box.glb", glb)
}

fn gltf_seeds() -> Vec<FileSet> {
    vec![
        FileSet::one("box.gltf", read("assets/BoxTextured/BoxTextured.gltf")),
        FileSet::one("cornell.gltf", read("assets/CornellBox/CornellBox.gltf")),
        FileSet::one("lights.gltf", read("tests/scenes/gltf_lights.gltf")),
        box_split(),
        box_glb(),
    ]
}

/// An OBJ with texture coordinates, normals, negative indices, a quad, a polygon and a
/// textured material.
const TEXTURED_OBJ: &str = "mtllib tex.mtl\no quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\n\
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl tex\nf 1/1/1 2/2/1 3/3/1 4/4/1\n\
f -5/-4/-1 -4/-3/-1 -1/-2/-1\ng poly\ns 1\nf 1 2 3 5 4\nusemtl plain\nf 1//1 3//1 4//1\n";
const TEXTURED_MTL: &str = "newmtl tex\nKd 1 1 1\nmap_Kd tex.png\nNs 10\nNi 1.5\nd 1\nillum 2\n\
newmtl plain\nKd 0.5 0.2 0.1\nKe 1 1 1\n";

fn obj_seeds() -> Vec<FileSet> {
    vec![
        FileSet {
            label: "CornellBox.obj".into(),
            files: vec![
                (
                    "CornellBox.obj".into(),
                    read("assets/CornellBox/CornellBox.obj"),
                ),
                (
                    "CornellBox.mtl".into(),
                    read("assets/CornellBox/CornellBox.mtl"),
                ),
            ],
            main: 0,
        },
        FileSet {
            label: "textured OBJ".into(),
            files: vec![
                ("tex.obj".into(), TEXTURED_OBJ.into()),
                ("tex.mtl".into(), TEXTURED_MTL.into()),
                ("tex.png".into(), small_png(image::ColorType::Rgb8, 4, 4)),
            ],
            main: 0,
        },
    ]
}

fn small_png(color: image::ColorType, w: u32, h: u32) -> Vec<u8> {
    let n = (w * h) as usize * usize::from(color.bytes_per_pixel());
    let data: Vec<u8> = (0..n).map(|i| (i * 37 % 251) as u8).collect();
    let mut out = Vec::new();
    image::write_buffer_with_format(
        &mut std::io::Cursor::new(&mut out),
        &data,
        w,
        h,
        color,
        image::ImageFormat::Png,
    )
    .unwrap();
    out
}

fn png_seeds() -> Vec<FileSet> {
    use image::ColorType::{L8, L16, La8, Rgb8, Rgba8, Rgba16};
    let mut seeds: Vec<FileSet> = [
        (L8, 5, 3),
        (La8, 4, 4),
        (L16, 3, 2),
        (Rgb8, 9, 2),
        (Rgba8, 6, 6),
        (Rgba16, 2, 3),
    ]
    .into_iter()
    .map(|(c, w, h)| FileSet::one("image.png", small_png(c, w, h)))
    .collect();
    seeds.push(FileSet::one(
        "image.png",
        box_split().files.swap_remove(2).1,
    ));
    seeds
}

fn hdr_seeds() -> Vec<FileSet> {
    let encode = |w: usize, h: usize| {
        let pixels: Vec<image::Rgb<f32>> = (0..w * h)
            .map(|i| image::Rgb([i as f32 * 0.1, 1.0, 1e-3]))
            .collect();
        let mut out = Vec::new();
        image::codecs::hdr::HdrEncoder::new(&mut out)
            .encode(&pixels, w, h)
            .unwrap();
        FileSet::one("image.hdr", out)
    };
    // The real map's header and first scanlines (the rest cut off).
    let venice = read("assets/hdri/venice_sunset_1k.hdr");
    vec![
        encode(4, 3),
        encode(16, 4),
        encode(40, 2),
        FileSet::one("image.hdr", venice[..venice.len().min(3000)].to_vec()),
    ]
}

fn exr_seeds() -> Vec<FileSet> {
    use exr::prelude::*;
    let chart = FileSet::one("image.exr", self::read("assets/test_chart.exr"));
    let mut seeds = vec![chart];
    let compressions = [
        Compression::Uncompressed,
        Compression::RLE,
        Compression::ZIP1,
        Compression::ZIP16,
        Compression::PIZ,
        Compression::PXR24,
        Compression::B44,
    ];
    for (i, compression) in compressions.into_iter().enumerate() {
        let blocks = if i % 2 == 0 {
            Blocks::ScanLines
        } else {
            Blocks::Tiles(Vec2(4, 4))
        };
        let encoding = Encoding {
            compression,
            blocks,
            line_order: LineOrder::Increasing,
        };
        let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
            (x as f32 * 0.25, y as f32, f16::from_f32(0.5), 1.0_f32)
        });
        let mut out = Vec::new();
        Image::from_encoded_channels((9, 6), encoding, channels)
            .write()
            .to_buffered(std::io::Cursor::new(&mut out))
            .unwrap();
        seeds.push(FileSet::one("image.exr", out));
    }
    seeds
}

// ---------------------------------------------------------------------------------------
// Loaders under test
// ---------------------------------------------------------------------------------------

/// A small scene for compiling graphs that render one.
static SCENE: LazyLock<GpuScene> = LazyLock::new(|| {
    GpuScene::build(&Scene::load(&repo("tests/scenes/diffuse_sphere_quad_light.ron")).unwrap())
        .unwrap()
});

/// What `lumagraph validate` does with a graph file: load, then check it as a group or
/// compile it (with and without a scene).
fn validate_graph(path: &Path) -> Result<(), String> {
    let graph = Graph::load(path).map_err(|e| e.to_string())?;
    let library = lumagraph::pathtrace::library::builtins();
    let registry = library.registry_for(&graph).map_err(|e| e.to_string())?;
    let has_sink = graph
        .nodes
        .iter()
        .any(|n| registry.get(&n.kind).is_some_and(|k| k.sink));
    if !graph.interface.is_empty() && !has_sink {
        lumagraph::render::custom::check_group(&graph, registry).map_err(|e| e.to_string())?;
        return Ok(());
    }
    let _ = library.compile(&graph, &[], None);
    library
        .compile(&graph, &[], Some(&SCENE))
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// A folder laid out as the repository for graph files: `graphs/` (with `groups/` and the
/// WGSL file) copied, `assets/` linked.
fn graph_workspace() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let graphs = dir.path().join("graphs");
    std::fs::create_dir_all(graphs.join("groups")).unwrap();
    for sub in ["graphs", "graphs/groups"] {
        for entry in std::fs::read_dir(repo(sub)).unwrap() {
            let p = entry.unwrap().path();
            if p.is_file() {
                std::fs::copy(&p, dir.path().join(sub).join(p.file_name().unwrap())).unwrap();
            }
        }
    }
    std::os::unix::fs::symlink(repo("assets"), dir.path().join("assets")).unwrap();
    dir
}

fn load_scene(text: &str, base: &Path) -> Result<(), String> {
    let scene = Scene::from_ron(text, base).map_err(|e| e.to_string())?;
    GpuScene::build(&scene)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn load_mesh(path: &Path) -> Result<(), String> {
    lumagraph::scene::import::import_mesh(path, glam::Mat4::IDENTITY)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn load_image(path: &Path) -> Result<(), String> {
    let _ = image_io::dimensions(path);
    image_io::load(path).map(|_| ()).map_err(|e| e.to_string())
}

// ---------------------------------------------------------------------------------------
// Properties
// ---------------------------------------------------------------------------------------

#[test]
fn graph_files() {
    let work = graph_workspace();
    let dir = work.path().join("graphs");
    let seeds = file_seeds("graphs", "ron");
    fuzz(
        "graph",
        GRAPH_CASES,
        &mutated(seeds, RON_TOKENS),
        move |input| validate_graph(&input.write_to(&dir)),
    );
}

#[test]
fn node_group_files() {
    let work = graph_workspace();
    let dir = work.path().join("graphs/groups");
    let user = work.path().join("graphs/node_group.ron");
    let seeds = file_seeds("graphs/groups", "ron");
    fuzz(
        "group",
        GROUP_CASES,
        &mutated(seeds, RON_TOKENS),
        move |input| {
            let _ = validate_graph(&input.write_to(&dir));
            validate_graph(&user)
        },
    );
}

#[test]
fn scene_files() {
    // Named by their path in the repository: meshes and maps load from beside them.
    let seeds: Vec<FileSet> = ["assets", "tests/scenes"]
        .into_iter()
        .flat_map(|dir| {
            files_in(dir, "ron").into_iter().map(move |p| {
                let name = format!("{dir}/{}", p.file_name().unwrap().to_string_lossy());
                FileSet::one(&name, std::fs::read(&p).unwrap())
            })
        })
        .collect();
    fuzz("scene", SCENE_CASES, &mutated(seeds, RON_TOKENS), |input| {
        let text = String::from_utf8_lossy(input.main_bytes());
        let base = repo(input.main_name()).parent().unwrap().to_owned();
        load_scene(&text, &base)
    });
}

#[test]
fn gltf_files() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().to_owned();
    fuzz(
        "gltf",
        GLTF_CASES,
        &mutated(gltf_seeds(), JSON_TOKENS),
        move |input| load_mesh(&input.write_to(&dir)),
    );
}

#[test]
fn obj_files() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().to_owned();
    fuzz(
        "obj",
        OBJ_CASES,
        &mutated(obj_seeds(), OBJ_TOKENS),
        move |input| load_mesh(&input.write_to(&dir)),
    );
}

fn ply_seeds() -> Vec<FileSet> {
    ["ascii", "binary_little_endian", "binary_big_endian"]
        .into_iter()
        .map(|format| FileSet {
            label: format!("{format} PLY"),
            files: vec![("mesh.ply".into(), common::ply_bytes(format))],
            main: 0,
        })
        .collect()
}

#[test]
fn ply_files() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().to_owned();
    fuzz(
        "ply",
        PLY_CASES,
        &mutated(ply_seeds(), PLY_TOKENS),
        move |input| load_mesh(&input.write_to(&dir)),
    );
}

#[test]
fn png_files() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().to_owned();
    fuzz(
        "png",
        PNG_CASES,
        &mutated(png_seeds(), BINARY_TOKENS),
        move |input| load_image(&input.write_to(&dir)),
    );
}

#[test]
fn hdr_files() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().to_owned();
    fuzz(
        "hdr",
        HDR_CASES,
        &mutated(hdr_seeds(), BINARY_TOKENS),
        move |input| load_image(&input.write_to(&dir)),
    );
}

#[test]
fn exr_files() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().to_owned();
    fuzz(
        "exr",
        EXR_CASES,
        &mutated(exr_seeds(), BINARY_TOKENS),
        move |input| load_image(&input.write_to(&dir)),
    );
}

/// Every image seed cut short at each of its first 200 lengths (and then every 61 bytes).
#[test]
fn truncated_image_headers() {
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().to_owned();
    let check: Check<FileSet> = Arc::new(move |input: FileSet| {
        let _ = load_image(&input.write_to(&dir));
        Ok(())
    });
    for seed in png_seeds()
        .into_iter()
        .chain(hdr_seeds())
        .chain(exr_seeds())
    {
        let bytes = seed.main_bytes();
        for len in (0..bytes.len().min(200)).chain((200..bytes.len()).step_by(61)) {
            let cut = FileSet::one(seed.main_name(), bytes[..len].to_vec());
            if let Err(e) = guarded(&check, cut) {
                panic!("{} cut to {len} bytes: {e}", seed.label);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// The corpus
// ---------------------------------------------------------------------------------------

/// Corpus files that load: an MTL file tobj panicked on (now a warning), a B44 block
/// whose decoding overflowed (now wrapping, as in `OpenEXR`). Every other one is refused.
const CORPUS_LOADS: &[&str] = &["image/b44_block_underflow.exr", "obj/short_color.obj"];

/// The corpus files with their loader's kind, sorted (MTL files go with their OBJ).
fn corpus() -> Vec<(String, PathBuf)> {
    let mut out = Vec::new();
    for kind in ["graph", "scene", "gltf", "obj", "image"] {
        for entry in std::fs::read_dir(repo("tests/corpus").join(kind)).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e != "mtl") {
                out.push((kind.to_owned(), path));
            }
        }
    }
    out.sort();
    out
}

fn load_corpus_file(kind: &str, path: &Path) -> Result<(), String> {
    match kind {
        "graph" => validate_graph(path),
        "scene" => {
            let scene = Scene::load(path).map_err(|e| e.to_string())?;
            GpuScene::build(&scene)
                .map(|_| ())
                .map_err(|e| e.to_string())
        }
        "gltf" | "obj" => load_mesh(path),
        _ => load_image(path),
    }
}

#[test]
fn corpus_files_load_without_panicking() {
    let check: Check<(String, PathBuf)> =
        Arc::new(|(kind, path): (String, PathBuf)| load_corpus_file(&kind, &path));
    let root = repo("tests/corpus");
    let mut problems = Vec::new();
    for (kind, path) in corpus() {
        let rel = path
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        match guarded(&check, (kind, path)) {
            Err(e) => problems.push(format!("{rel}: {e}")),
            Ok(Ok(())) if !CORPUS_LOADS.contains(&rel.as_str()) => {
                problems.push(format!("{rel}: loads, but the corpus holds broken files"));
            }
            Ok(Err(e)) if CORPUS_LOADS.contains(&rel.as_str()) => {
                problems.push(format!("{rel}: expected to load, got: {e}"));
            }
            Ok(result) => eprintln!("{rel}: {result:?}"),
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The command line on the refused corpus files, each where `lumagraph render` takes it
/// (meshes through a scene, images through an `ImageInput`): a non-zero exit, an
/// `error:` line and no panic.
#[test]
fn render_refuses_the_corpus_with_an_error() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let out_arg = out.to_string_lossy().into_owned();
    let root = repo("tests/corpus");
    let mut problems = Vec::new();
    for (i, (kind, path)) in corpus().into_iter().enumerate() {
        let rel = path
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        if CORPUS_LOADS.contains(&rel.as_str()) {
            continue;
        }
        let file = path.to_string_lossy().into_owned();
        let (graph, scene) = match kind.as_str() {
            "graph" => (file, None),
            "scene" => ("graphs/pathtrace.ron".to_owned(), Some(file)),
            "gltf" | "obj" => {
                let scene = tmp.path().join(format!("mesh{i}.ron"));
                std::fs::write(&scene, MESH_SCENE.replace("MESH", &file)).unwrap();
                let scene = scene.to_string_lossy().into_owned();
                ("graphs/pathtrace.ron".to_owned(), Some(scene))
            }
            _ => {
                let graph = tmp.path().join(format!("image{i}.ron"));
                std::fs::write(&graph, IMAGE_GRAPH.replace("IMAGE", &file)).unwrap();
                (graph.to_string_lossy().into_owned(), None)
            }
        };
        let mut args = vec!["render", graph.as_str(), "--out", out_arg.as_str()];
        if let Some(scene) = &scene {
            args.extend(["--scene", scene.as_str()]);
        }
        let (ok, _, stderr) = common::cli(&args);
        if ok || !stderr.contains("error:") || stderr.contains("panicked") {
            problems.push(format!("{rel}: exit ok = {ok}, stderr:\n{stderr}"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// A scene around one mesh file (`MESH`: its absolute path).
const MESH_SCENE: &str = r#"(
    version: 2,
    camera: Perspective(position: (0.0, 0.0, 3.0), target: (0.0, 0.0, 0.0), fov_y: 40.0),
    materials: {"grey": (base_color: (0.8, 0.8, 0.8))},
    shapes: [Mesh(name: "mesh", path: "MESH")],
    environment: Constant((1.0, 1.0, 1.0)),
    render: (width: 32, height: 32, max_bounces: 2, spp: 1, seed: 0),
)"#;

/// A graph that reads one image (`IMAGE`: its absolute path) and writes it.
const IMAGE_GRAPH: &str = r#"(
    version: 1,
    nodes: [
        (id: "input", kind: "ImageInput", params: {"path": "IMAGE"}),
        (id: "out", kind: "Output", params: {"path": "image.png"}),
    ],
    edges: [(from: "input.color", to: "out.color")],
)"#;
