//! The scene file being edited: its text as loaded, the values the scene panel edits, the
//! furnace view, and building what the preview renders.
//!
//! The panel edits a [`SceneFile`] (the file's values as written); every change is a new
//! [`GpuScene`] for the preview, so the preview's accumulation restarts. Saving writes
//! only the values that changed into the text the file was loaded from
//! ([`lumagraph_scene::save`]): comments and layout stay as the user wrote them.

use std::path::{Path, PathBuf};

use lumagraph_scene::file::SceneFile;
use lumagraph_scene::{GpuScene, Scene};

/// A scene file open in the editor.
#[derive(Clone, Debug)]
pub struct SceneDoc {
    /// The file.
    pub path: PathBuf,
    /// Its text when it was loaded or last saved.
    pub text: String,
    /// The values of that text.
    pub saved: SceneFile,
    /// The values as edited.
    pub file: SceneFile,
    /// Show the scene as a white furnace (see [`Scene::make_furnace`]); a view only, never
    /// saved.
    pub furnace: bool,
}

impl SceneDoc {
    /// Reads and parses `path`.
    ///
    /// # Errors
    /// A message naming the file, with line and column for syntax errors.
    pub fn load(path: &Path) -> Result<Self, String> {
        let read = lumagraph_scene::edit::SceneText::load(path).map_err(|e| e.to_string())?;
        Ok(Self {
            path: read.path,
            text: read.text,
            saved: read.file.clone(),
            file: read.file,
            furnace: false,
        })
    }

    /// Whether the values differ from the file's.
    pub fn is_dirty(&self) -> bool {
        self.file != self.saved
    }

    /// The folder paths in the file are relative to.
    pub fn base_dir(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new("."))
    }

    /// The scene as edited (a furnace when [`Self::furnace`] is set), at the file's
    /// resolution.
    ///
    /// # Errors
    /// What loading the scene's meshes, textures and environment map reports, naming the
    /// file.
    pub fn build(&self) -> Result<GpuScene, String> {
        let mut scene = Scene::from_file(&self.file, self.base_dir())
            .map_err(|e| e.in_file(&self.path).to_string())?;
        if self.furnace {
            scene.make_furnace();
        }
        GpuScene::build(&scene).map_err(|e| e.in_file(&self.path).to_string())
    }

    /// Writes the edited values into the file, keeping everything else of its text.
    ///
    /// # Errors
    /// When the file cannot be written (it is then unchanged).
    pub fn save(&mut self) -> Result<(), String> {
        let text = lumagraph_scene::save::save(&self.path, &self.text, &self.file)
            .map_err(|e| e.to_string())?;
        self.text = text;
        self.saved = self.file.clone();
        Ok(())
    }

    /// Back to the values of the file as last loaded or saved.
    pub fn revert(&mut self) {
        self.file = self.saved.clone();
    }
}

/// `gpu` with its image size scaled so the longer side is at most `max` (the aspect kept).
pub fn cap_resolution(gpu: &mut GpuScene, max: u32) {
    let full = (gpu.settings.width, gpu.settings.height);
    let longest = full.0.max(full.1).max(1);
    if longest > max {
        let scale = |x: u32| {
            u32::try_from(u64::from(x) * u64::from(max) / u64::from(longest))
                .unwrap_or(1)
                .max(1)
        };
        gpu.settings.width = scale(full.0);
        gpu.settings.height = scale(full.1);
    }
}
