//! Where the files a graph writes go. A graph file may come from someone else, so the
//! paths it names for its outputs (the path params of its sinks, such as `Output`'s
//! `path`) stay inside the output folder the user chose: an absolute path, one whose `..`
//! climb out of the folder, or one that leaves it through a symbolic link inside it is
//! refused, unless the user allows it (`lumagraph render --allow-outputs-outside`).
//! `docs/security.md` states what a graph may read and write.

use std::path::{Component, Path, PathBuf};

use crate::error::{ErrorKind, GraphError, GraphErrors};
use crate::graph::Graph;
use crate::plan::Plan;
use crate::types::ParamType;

/// An output path that would write outside the output folder.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "output path \"{path}\" is outside the output folder {}: {why} (a graph writes only \
     inside the output folder; `--allow-outputs-outside` lets it write elsewhere)",
    folder.display()
)]
pub struct OutsideOutput {
    /// The path as the graph gives it.
    pub path: String,
    /// The output folder.
    pub folder: PathBuf,
    /// How it leaves the folder.
    pub why: String,
}

/// The file `path` (as a graph names an output) names in `folder`: `folder` joined with
/// `path`, its `.` and `..` resolved in the text. With `anywhere`, `path` is joined as it
/// is (an absolute path replaces the folder), as the user asked.
///
/// # Errors
/// Without `anywhere`: when `path` is absolute, when its `..` climb out of `folder`, when
/// it names no file inside it (`.`, `a/..`), or when a folder on the way is a symbolic link
/// (or inside one) that leads out of `folder` (the deepest folder that exists is resolved).
pub fn resolve_output(folder: &Path, path: &str, anywhere: bool) -> Result<PathBuf, OutsideOutput> {
    if anywhere {
        return Ok(folder.join(path));
    }
    let outside = |why: &str| OutsideOutput {
        path: path.to_owned(),
        folder: folder.to_owned(),
        why: why.to_owned(),
    };
    let mut parts: Vec<&std::ffi::OsStr> = Vec::new();
    for c in Path::new(path).components() {
        match c {
            Component::Prefix(_) | Component::RootDir => return Err(outside("it is absolute")),
            Component::CurDir => {}
            Component::ParentDir => {
                if parts.pop().is_none() {
                    return Err(outside("its `..` climb out of the folder"));
                }
            }
            Component::Normal(p) => parts.push(p),
        }
    }
    if parts.is_empty() {
        return Err(outside("it names the folder itself, not a file in it"));
    }
    let resolved: PathBuf = parts.iter().fold(folder.to_owned(), |p, c| p.join(c));
    // Folders on the way that exist: the deepest one, resolved, must still be in `folder`
    // (a symbolic link inside it can lead anywhere). The file itself is replaced by a
    // rename when written, so a link in its place is replaced, not followed.
    if let Ok(root) = std::fs::canonicalize(folder) {
        let mut deepest = folder.to_owned();
        for c in &parts[..parts.len() - 1] {
            let next = deepest.join(c);
            if std::fs::symlink_metadata(&next).is_err() {
                break;
            }
            deepest = next;
        }
        match std::fs::canonicalize(&deepest) {
            Ok(real) if real.starts_with(&root) => {}
            Ok(real) => {
                return Err(outside(&format!(
                    "{} leads to {} through a symbolic link",
                    deepest.display(),
                    real.display()
                )));
            }
            Err(e) => {
                return Err(outside(&format!(
                    "{} cannot be resolved ({e})",
                    deepest.display()
                )));
            }
        }
    }
    Ok(resolved)
}

/// A file a plan writes: the sink node, its path param and the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputFile {
    /// The node (`group/inner` for a node inside a group).
    pub node: String,
    /// The param that names it.
    pub param: &'static str,
    /// The file, in the output folder.
    pub path: PathBuf,
}

/// Every file `plan` (compiled from `graph`) writes into `folder`: each path param of each
/// sink, resolved by [`resolve_output`].
///
/// # Errors
/// One error per path that leaves `folder` (without `anywhere`), naming the node, the
/// path and the folder, located at the param in the graph file when it is there.
pub fn output_files(
    plan: &Plan,
    graph: &Graph,
    folder: &Path,
    anywhere: bool,
) -> Result<Vec<OutputFile>, GraphErrors> {
    let mut files = Vec::new();
    let mut errors = Vec::new();
    for pass in plan.passes.iter().filter(|p| p.kind.sink) {
        for def in &pass.kind.params {
            if !matches!(def.ty, ParamType::Path { .. }) || !pass.params.has(def.name) {
                continue;
            }
            match resolve_output(folder, pass.params.str(def.name), anywhere) {
                Ok(path) => files.push(OutputFile {
                    node: pass.node.clone(),
                    param: def.name,
                    path,
                }),
                Err(e) => {
                    let e = GraphError::new(ErrorKind::OutsideOutput(e)).now_about(&pass.node);
                    errors.push(graph.locate(e, None, Some(def.name)));
                }
            }
        }
    }
    if errors.is_empty() {
        Ok(files)
    } else {
        // In file order, as the compiler's (the plan's order is the passes').
        errors.sort_by_key(|e| e.pos.map(|p| (p.line, p.col)));
        Err(GraphErrors(errors))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn why(folder: &Path, path: &str) -> String {
        resolve_output(folder, path, false).unwrap_err().why
    }

    #[test]
    fn paths_inside_the_folder_resolve_in_it() {
        let out = Path::new("no/such/out");
        for (path, want) in [
            ("a.png", "no/such/out/a.png"),
            ("./sub/b.exr", "no/such/out/sub/b.exr"),
            ("sub/../c.png", "no/such/out/c.png"),
            ("sub/deeper/../../d.png", "no/such/out/d.png"),
        ] {
            assert_eq!(resolve_output(out, path, false).unwrap(), Path::new(want));
        }
    }

    #[test]
    fn absolute_and_climbing_paths_are_refused() {
        let out = Path::new("no/such/out");
        assert_eq!(why(out, "/tmp/elsewhere.exr"), "it is absolute");
        assert_eq!(
            why(out, "../../tmp/x/evil.png"),
            "its `..` climb out of the folder"
        );
        assert_eq!(
            why(out, "a/../../b.png"),
            "its `..` climb out of the folder"
        );
        assert_eq!(
            why(out, "a/.."),
            "it names the folder itself, not a file in it"
        );
        let e = resolve_output(out, "/tmp/elsewhere.exr", false).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("\"/tmp/elsewhere.exr\"") && text.contains("no/such/out"),
            "{text}"
        );
        // Allowed, the path is taken as it is.
        assert_eq!(
            resolve_output(out, "/tmp/elsewhere.exr", true).unwrap(),
            Path::new("/tmp/elsewhere.exr")
        );
        assert_eq!(
            resolve_output(out, "../x.png", true).unwrap(),
            Path::new("no/such/out/../x.png")
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_link_out_of_the_folder_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let elsewhere = tmp.path().join("elsewhere");
        std::fs::create_dir_all(out.join("real")).unwrap();
        std::fs::create_dir_all(&elsewhere).unwrap();
        std::os::unix::fs::symlink(&elsewhere, out.join("link")).unwrap();
        std::os::unix::fs::symlink(out.join("real"), out.join("inner_link")).unwrap();
        let e = resolve_output(&out, "link/x.png", false).unwrap_err();
        assert!(e.why.contains("through a symbolic link"), "{e}");
        // Through folders that do not exist yet below the link, too.
        assert!(resolve_output(&out, "link/new/deeper/x.png", false).is_err());
        // A link that stays inside the folder is fine, as are folders not made yet.
        assert!(resolve_output(&out, "inner_link/x.png", false).is_ok());
        assert!(resolve_output(&out, "real/new/x.png", false).is_ok());
        // A file that is a link is replaced when written (a rename), not followed.
        std::os::unix::fs::symlink(elsewhere.join("f.png"), out.join("f.png")).unwrap();
        assert!(resolve_output(&out, "f.png", false).is_ok());
    }
}
