//! Files as the graph and the scene crates both handle them: [`write_atomic`], the one
//! writer every lumagraph crate saves through (graphs, scenes, images, checkpoints, lists),
//! so that readers never see half of a file; and errors located in a file ([`Located`]:
//! the file, the line and column, what it concerns), the one type graph and scene errors
//! both are, said the same way.
//!
//! A leaf crate with no lumagraph dependency, so that crates which do not depend on each
//! other (the graph and the scene) can share it.

use std::fmt;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// A line and column in a text file, both starting at 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pos {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1.
    pub col: usize,
}

/// An error of kind `K` with where it is: the file, the line and column, and what it
/// concerns (`S`: a graph's node, a scene's shape or material), each where known. Displayed
/// as compilers do: `FILE:LINE:COL: WHAT: KIND`.
#[derive(Debug)]
pub struct Located<K, S = String> {
    /// The file, when the error came from one.
    pub file: Option<PathBuf>,
    /// Line and column in the file, when known.
    pub pos: Option<Pos>,
    /// What the error concerns, when there is one.
    pub about: Option<S>,
    /// What went wrong.
    pub kind: Box<K>,
}

impl<K, S> Located<K, S> {
    /// An error with no location yet.
    pub fn new(kind: K) -> Self {
        Self {
            file: None,
            pos: None,
            about: None,
            kind: Box::new(kind),
        }
    }

    /// The same error, in `file`, unless it already names one.
    #[must_use]
    pub fn in_file(mut self, file: impl Into<PathBuf>) -> Self {
        if self.file.is_none() {
            self.file = Some(file.into());
        }
        self
    }

    /// The same error, at `pos`, unless it already has a position.
    #[must_use]
    pub fn at(mut self, pos: Option<Pos>) -> Self {
        if self.pos.is_none() {
            self.pos = pos;
        }
        self
    }

    /// The same error, about `about`, unless it already names what it concerns.
    #[must_use]
    pub fn about(mut self, about: impl Into<S>) -> Self {
        if self.about.is_none() {
            self.about = Some(about.into());
        }
        self
    }

    /// The same error, about `about` in place of what it named (an error inside a group
    /// of nodes is about the group's node in the graph using it).
    #[must_use]
    pub fn now_about(mut self, about: impl Into<S>) -> Self {
        self.about = Some(about.into());
        self
    }
}

impl<K: fmt::Display, S: fmt::Display> fmt::Display for Located<K, S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let about = self.about.as_ref().map(ToString::to_string);
        write_location(f, self.file.as_deref(), self.pos, about.as_deref())?;
        write!(f, "{}", self.kind)
    }
}

impl<K: std::error::Error + 'static, S: fmt::Debug + fmt::Display> std::error::Error
    for Located<K, S>
{
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.kind.source()
    }
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
