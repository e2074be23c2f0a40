//! WGSL `#import` resolution, the one implementation the renderer and every test use.
//!
//! A line `#import "common/color.wgsl"` is replaced by that file's text, each file at most
//! once per shader (the first time it is imported), recursively. Where the text of a file
//! comes from is the caller's: the renderer reads embedded copies or the `shaders/` folder
//! ([`from_dir`]), and can replace files with generated code (`overrides`), which is how
//! shaders are specialized to a scene.

use std::path::PathBuf;

/// A resolution failure: the file concerned and what went wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("shader {file}: {message}")]
#[non_exhaustive]
pub struct ImportError {
    /// The shader file the problem is in (or the one that is missing).
    pub file: String,
    /// What went wrong, with the line number for a bad or failing import.
    pub message: String,
}

/// Where file texts come from: the text of the file at a path relative to the shader root,
/// or `None` when there is no such file.
pub type Source<'a> = &'a dyn Fn(&str) -> Option<String>;

/// Reads files from `dir` (the `shaders/` folder).
pub fn from_dir(dir: impl Into<PathBuf>) -> impl Fn(&str) -> Option<String> {
    let dir = dir.into();
    move |name| std::fs::read_to_string(dir.join(name)).ok()
}

/// The text of `name` with its imports resolved; `overrides` replace files by generated
/// text (`(name, text)` pairs).
///
/// # Errors
/// When a file is missing or an import line is malformed; the error names the file and the
/// line of the import.
pub fn resolve(
    name: &str,
    overrides: &[(&str, String)],
    source: Source<'_>,
) -> Result<String, ImportError> {
    let mut seen = Vec::new();
    let mut out = String::new();
    resolve_into(name, overrides, source, &mut seen, &mut out)?;
    Ok(out)
}

/// Every file `name` imports, directly or not, in inclusion order (itself included).
///
/// # Errors
/// As [`resolve`].
pub fn imports(name: &str, source: Source<'_>) -> Result<Vec<String>, ImportError> {
    let mut seen = Vec::new();
    resolve_into(name, &[], source, &mut seen, &mut String::new())?;
    Ok(seen)
}

fn resolve_into(
    name: &str,
    overrides: &[(&str, String)],
    source: Source<'_>,
    seen: &mut Vec<String>,
    out: &mut String,
) -> Result<(), ImportError> {
    if seen.iter().any(|s| s == name) {
        return Ok(());
    }
    seen.push(name.to_owned());
    let text = match overrides.iter().find(|(n, _)| *n == name) {
        Some((_, text)) => text.clone(),
        None => source(name).ok_or_else(|| ImportError {
            file: name.to_owned(),
            message: "no such shader file".to_owned(),
        })?,
    };
    for (i, line) in text.lines().enumerate() {
        if let Some(rest) = line.trim_start().strip_prefix("#import") {
            let target = rest.trim().trim_matches('"');
            if target.is_empty() || !rest.trim().starts_with('"') {
                return Err(ImportError {
                    file: name.to_owned(),
                    message: format!("line {}: expected #import \"path.wgsl\"", i + 1),
                });
            }
            resolve_into(target, overrides, source, seen, out).map_err(|e| {
                if e.file == target {
                    ImportError {
                        file: name.to_owned(),
                        message: format!("line {}: cannot import {target}: {}", i + 1, e.message),
                    }
                } else {
                    e
                }
            })?;
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn files(name: &str) -> Option<String> {
        match name {
            "a.wgsl" => Some("#import \"b.wgsl\"\n#import \"c.wgsl\"\nfn a() {}".into()),
            "b.wgsl" => Some("#import \"c.wgsl\"\nfn b() {}".into()),
            "c.wgsl" => Some("fn c() {}".into()),
            "bad.wgsl" => Some("fn x() {}\n#import c.wgsl".into()),
            "missing.wgsl" => Some("\n\n#import \"nope.wgsl\"".into()),
            _ => None,
        }
    }

    #[test]
    fn each_file_once_in_inclusion_order() {
        assert_eq!(
            resolve("a.wgsl", &[], &files).unwrap(),
            "fn c() {}\nfn b() {}\nfn a() {}\n"
        );
        assert_eq!(
            imports("a.wgsl", &files).unwrap(),
            ["a.wgsl", "b.wgsl", "c.wgsl"]
        );
    }

    #[test]
    fn overrides_replace_files() {
        let o = [("c.wgsl", "fn generated() {}".to_owned())];
        assert!(
            resolve("a.wgsl", &o, &files)
                .unwrap()
                .starts_with("fn generated() {}\n")
        );
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let e = resolve("bad.wgsl", &[], &files).unwrap_err();
        assert_eq!(
            (e.file.as_str(), e.message.as_str()),
            ("bad.wgsl", "line 2: expected #import \"path.wgsl\"")
        );
        let e = resolve("missing.wgsl", &[], &files).unwrap_err();
        assert_eq!(e.file, "missing.wgsl");
        assert!(
            e.message.starts_with("line 3: cannot import nope.wgsl"),
            "{e}"
        );
    }
}
