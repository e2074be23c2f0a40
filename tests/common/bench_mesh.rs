//! The mesh benchmark's blob (`assets/bench/blob.obj`, not in git), made once with
//! `scripts/bench/mesh_env.py` when missing. Shared by the root tests (`common`) and the
//! render crate's Embree tests, which include this file.

use std::path::{Path, PathBuf};

/// `repo/assets/bench/blob.obj`, made first when missing. One thread of a process makes it
/// while the others wait (they would write the same file beside it at once); it is written
/// beside and renamed, so other processes making it at once never read half a file.
///
/// # Panics
/// When `python3 scripts/bench/mesh_env.py make` fails.
pub fn bench_blob(repo: &Path) -> PathBuf {
    static MAKING: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let blob = repo.join("assets/bench/blob.obj");
    let _one = MAKING
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if !blob.exists() {
        let tmp = blob.with_extension(format!("obj.{}", std::process::id()));
        let ok = std::process::Command::new("python3")
            .arg(repo.join("scripts/bench/mesh_env.py"))
            .arg("make")
            .arg(&tmp)
            .status()
            .is_ok_and(|s| s.success());
        assert!(ok, "python3 scripts/bench/mesh_env.py make failed");
        std::fs::rename(&tmp, &blob).unwrap();
    }
    blob
}
