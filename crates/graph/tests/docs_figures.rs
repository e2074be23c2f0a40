//! The figures README.md and ARCHITECTURE.md give, held to the code's own lists: the
//! Mitsuba suite's scene count, the built-in kinds and generic post filters, and the crate
//! table's crates and the lumagraph crates each depends on. Text only, no GPU: when one of
//! these fails, the document is what to correct (or the code, if it changed by mistake).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use lumagraph_graph::Registry;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
}

fn read(path: &str) -> String {
    std::fs::read_to_string(repo(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// An English number word up to ninety-nine ("thirteen", "Twenty-two"), or digits.
fn number(word: &str) -> Option<usize> {
    const ONES: [&str; 20] = [
        "zero",
        "one",
        "two",
        "three",
        "four",
        "five",
        "six",
        "seven",
        "eight",
        "nine",
        "ten",
        "eleven",
        "twelve",
        "thirteen",
        "fourteen",
        "fifteen",
        "sixteen",
        "seventeen",
        "eighteen",
        "nineteen",
    ];
    const TENS: [&str; 8] = [
        "twenty", "thirty", "forty", "fifty", "sixty", "seventy", "eighty", "ninety",
    ];
    if let Ok(n) = word.parse() {
        return Some(n);
    }
    let word = word.to_lowercase();
    let (tens, ones) = word.split_once('-').unwrap_or((&word, ""));
    if let Some(n) = ONES.iter().position(|w| *w == tens) {
        return ones.is_empty().then_some(n);
    }
    let t = TENS.iter().position(|w| *w == tens)?;
    let o = match ones {
        "" => 0,
        o => ONES[1..10].iter().position(|w| *w == o)? + 1,
    };
    Some(20 + 10 * t + o)
}

/// The text between `before` and `after` in `doc` (the first place `before` occurs).
fn between<'d>(doc: &'d str, before: &str, after: &str) -> &'d str {
    let start = doc
        .find(before)
        .unwrap_or_else(|| panic!("no {before:?} in the document"))
        + before.len();
    let len = doc[start..]
        .find(after)
        .unwrap_or_else(|| panic!("no {after:?} after {before:?}"));
    &doc[start..start + len]
}

/// The README's suite is every scene of `tests/scenes/` (the suite's own test,
/// `every_scene_is_tested` in `tests/mitsuba_suite.rs`, holds the folder to its list).
#[test]
fn the_readme_counts_the_suites_scenes() {
    let scenes = std::fs::read_dir(repo("tests/scenes"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "ron")
        })
        .count();
    let readme = read("README.md");
    let said = between(&readme, "against a suite of ", " scenes");
    assert_eq!(
        number(said),
        Some(scenes),
        "README.md: a suite of {said} scenes"
    );
}

/// ARCHITECTURE.md's "Fifteen of the thirty-three built-in kinds are generic post filters:
/// `WhiteBalance`, … `Crop` (Transform);": both counts and the names, against the registry.
#[test]
fn the_architecture_counts_the_kinds_and_names_the_post_filters() {
    let doc = read("ARCHITECTURE.md").replace('\n', " ");
    let sentence = between(
        &doc,
        "params). ",
        " built-in kinds are generic post filters",
    );
    let (filters, kinds) = sentence
        .split_once(" of the ")
        .unwrap_or_else(|| panic!("{sentence:?}"));
    let registry = Registry::with_builtins();
    let generic: BTreeSet<&str> = registry
        .kinds()
        .iter()
        .filter(|k| k.shader.is_some())
        .map(|k| k.name)
        .collect();
    assert_eq!(
        number(kinds),
        Some(registry.kinds().len()),
        "ARCHITECTURE.md: {kinds} built-in kinds"
    );
    assert_eq!(
        number(filters),
        Some(generic.len()),
        "ARCHITECTURE.md: {filters} generic post filters"
    );
    // The names, each group of a category followed by it in parentheses.
    let list = between(&doc, "are generic post filters: ", ";");
    let named: BTreeSet<&str> = list
        .split(", ")
        .map(|n| n.split(" (").next().unwrap().trim())
        .collect();
    assert_eq!(named, generic, "ARCHITECTURE.md's list of post filters");
}

/// A package's `lumagraph` dependencies (its `[dependencies]` table only).
fn lumagraph_dependencies(manifest: &str) -> BTreeSet<String> {
    let mut in_table = false;
    let mut out = BTreeSet::new();
    for line in manifest.lines() {
        if line.starts_with('[') {
            in_table = line.trim() == "[dependencies]";
        } else if in_table && line.starts_with("lumagraph") {
            let name = line.split(['.', '=', ' ']).next().unwrap();
            out.insert(name.to_owned());
        }
    }
    out
}

/// The crate table has a row for every crate in `crates/`, and names the lumagraph crates
/// each depends on (as `lumagraph-graph` or `graph`), no more and no fewer.
#[test]
fn the_architecture_lists_every_crate_and_its_lumagraph_dependencies() {
    let doc = read("ARCHITECTURE.md");
    let rows: Vec<Vec<&str>> = doc
        .lines()
        .filter(|l| l.starts_with("| `lumagraph"))
        .map(|l| l.split(" | ").collect())
        .collect();
    let folders = std::fs::read_dir(repo("crates")).unwrap();
    let mut missing = Vec::new();
    for folder in folders {
        let folder = folder.unwrap().path();
        let manifest = std::fs::read_to_string(folder.join("Cargo.toml")).unwrap();
        let name = between(&manifest, "name = \"", "\"").to_owned();
        let Some(row) = rows
            .iter()
            .find(|r| r[0].starts_with(&format!("| `{name}` ")))
        else {
            missing.push(name);
            continue;
        };
        // The column without its parenthesised remarks, split at commas.
        let mut depends = String::new();
        let mut depth = 0_u32;
        for c in row[1].chars() {
            match c {
                '(' => depth += 1,
                ')' => depth = depth.saturating_sub(1),
                _ if depth == 0 => depends.push(c),
                _ => {}
            }
        }
        let said: BTreeSet<String> = depends
            .split(',')
            .map(str::trim)
            .filter(|d| *d == "lumagraph" || d.starts_with("lumagraph-") || !d.contains(' '))
            .map(|d| match d {
                "lumagraph" => d.to_owned(),
                d if d.starts_with("lumagraph-") => d.to_owned(),
                d => format!("lumagraph-{d}"),
            })
            .filter(|d| d == "lumagraph" || repo(&format!("crates/{}", &d[10..])).is_dir())
            .collect();
        assert_eq!(
            said,
            lumagraph_dependencies(&manifest),
            "ARCHITECTURE.md's row of {name}"
        );
    }
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md has no row for {missing:?}"
    );
}

#[test]
fn number_words_read() {
    for (w, n) in [
        ("thirteen", 13),
        ("Twenty", 20),
        ("twenty-two", 22),
        ("18", 18),
    ] {
        assert_eq!(number(w), Some(n), "{w}");
    }
    assert_eq!(number("twenty-twelve"), None);
}
