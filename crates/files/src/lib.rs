//! Files as the graph and the scene crates both handle them: [`write_atomic`], the one
//! writer every lumagraph crate saves through (graphs, scenes, images, checkpoints, lists),
//! so that readers never see half of a file; and where in a file an error is ([`Pos`],
//! [`write_location`]), said the same way for graphs and scenes.
//!
//! A leaf crate with no lumagraph dependency, so that crates which do not depend on each
//! other (the graph and the scene) can share it.

use std::fmt;
use std::io::Write as _;
use std::path::Path;

/// A line and column in a text file, both starting at 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pos {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1.
    pub col: usize,
}

/// Writes where an error is, as compilers do: `FILE:LINE:COL: ` (the position only with a
/// file), then `WHAT: ` (the node, the shape or the material it concerns), each where known.
///
/// # Errors
/// What the formatter returns.
pub fn write_location(
    f: &mut fmt::Formatter<'_>,
    file: Option<&Path>,
    pos: Option<Pos>,
    what: Option<&str>,
) -> fmt::Result {
    if let Some(file) = file {
        write!(f, "{}", file.display())?;
        if let Some(pos) = pos {
            write!(f, ":{}:{}", pos.line, pos.col)?;
        }
        f.write_str(": ")?;
    }
    if let Some(what) = what {
        write!(f, "{what}: ")?;
    }
    Ok(())
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename,
/// so readers see either the old file or the whole new one.
///
/// # Errors
/// When the temporary file cannot be created, written or renamed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".lumagraph-").suffix(".tmp");
    // Keep the permissions of the file being replaced; a new file gets the usual rw-r--r--
    // rather than the temporary file's private rw-------.
    let permissions = match std::fs::metadata(path) {
        Ok(m) => Some(m.permissions()),
        #[cfg(unix)]
        Err(_) => Some(std::os::unix::fs::PermissionsExt::from_mode(0o644)),
        #[cfg(not(unix))]
        Err(_) => None,
    };
    if let Some(p) = permissions {
        builder.permissions(p);
    }
    let mut tmp = builder.tempfile_in(dir)?;
    tmp.write_all(bytes)?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_write_replaces_the_file_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        write_atomic(&path, b"one").unwrap();
        write_atomic(&path, b"two").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["a.txt"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_replaced_file_keeps_its_permissions_and_a_new_one_is_readable() {
        use std::os::unix::fs::PermissionsExt as _;
        let dir = tempfile::tempdir().unwrap();
        let (new, kept) = (dir.path().join("new"), dir.path().join("kept"));
        write_atomic(&new, b"x").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&new), 0o644);
        std::fs::write(&kept, b"x").unwrap();
        std::fs::set_permissions(&kept, std::fs::Permissions::from_mode(0o600)).unwrap();
        write_atomic(&kept, b"y").unwrap();
        assert_eq!(mode(&kept), 0o600);
    }
}
