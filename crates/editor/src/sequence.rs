//! Image sequences in the editor: the frame control.
//!
//! When a param of the graph holds a frame-number pattern (`####`, `%04d`, `$F4`; see
//! [`lumagraph_footage::sequence`]), the preview runs the graph at the current frame: every
//! pattern takes the frame's number, as `lumagraph render --frames` puts it in (both
//! through [`FrameParams`]). Changing frame is then a param edit like any other in the
//! inspector — the preview compiles the graph at the new frame and hands
//! the plan to `Executor::update_params`: the `ImageInput` reloads its file and the passes
//! downstream of it re-run; nothing is rebuilt while the image keeps its size.
//!
//! The frame is view state: it is never written into the graph, so the file keeps its
//! pattern and the undo history never sees a frame change.
//!
//! The range is found on disk: the folder of each patterned input path is listed, and a
//! frame is in the range when every such input has a file for it (the files named as the
//! pattern with the frame's digits in its place). The folders are listed again when a
//! patterned path changes, or with the control's ⟳ button.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use egui::Ui;
use lumagraph_footage::sequence::frames_on_disk;
use lumagraph_graph::{Graph, Registry};
use lumagraph_session::frames::FrameParams;

/// The frame control's state: the current frame, playback, and the frames found on disk.
#[derive(Clone, Debug)]
pub struct Sequence {
    /// The frame the preview shows.
    pub frame: i64,
    /// Whether playback is on: one frame more per repaint, from the last back to the first.
    pub playing: bool,
    /// The frames whose input files exist, sorted (from the last listing of the folders).
    pub frames: Vec<i64>,
    /// The graph's params that hold a frame pattern (none: no control is shown).
    pub params: FrameParams,
    /// Why no frame was found at the last listing, if none was.
    pub problem: Option<String>,
    /// What the last listing was of: the folder and the patterned input paths.
    listed: Option<(PathBuf, Vec<String>)>,
    /// The egui frame in which playback last advanced (one step per frame, not per pass).
    advanced_in: Option<u64>,
}

impl Default for Sequence {
    fn default() -> Self {
        Self {
            frame: 1,
            playing: false,
            frames: Vec::new(),
            params: FrameParams::default(),
            problem: None,
            listed: None,
            advanced_in: None,
        }
    }
}

impl Sequence {
    /// Whether the graph has a param with a frame pattern, so the control is shown.
    pub fn is_active(&self) -> bool {
        !self.params.is_empty()
    }

    /// Finds the patterned params of `graph` (kinds from `registry`, paths relative to
    /// `base`) and, when its patterned input paths changed, lists their folders again.
    /// Returns a message for the status line when that listing finds no frame.
    pub fn refresh(&mut self, graph: &Graph, registry: &Registry, base: &Path) -> Option<String> {
        self.params = FrameParams::of(graph, registry);
        if self.params.is_empty() {
            self.playing = false;
            self.listed = None;
            self.problem = None;
            return None;
        }
        let inputs: Vec<String> = self
            .params
            .params
            .iter()
            .filter(|p| p.input_file)
            .map(|p| p.template.clone())
            .collect();
        let key = (base.to_owned(), inputs);
        if self.listed.as_ref() == Some(&key) {
            return None;
        }
        let said = self.list(base, &key.1);
        self.listed = Some(key);
        said
    }

    /// Lists the folders of the patterned `inputs` again on the next refresh.
    pub fn rescan(&mut self) {
        self.listed = None;
    }

    fn list(&mut self, base: &Path, inputs: &[String]) -> Option<String> {
        let found = frames_present(inputs, base);
        self.problem = match &found {
            Ok(frames) if frames.is_empty() && !inputs.is_empty() => Some(format!(
                "no frames found: no file in the folder matches {} (the pattern with a \
                 frame's digits in its place)",
                inputs
                    .iter()
                    .map(|p| base.join(p).display().to_string())
                    .collect::<Vec<_>>()
                    .join(" and ")
            )),
            Ok(_) => None,
            Err(e) => Some(format!("no frames found: {e}")),
        };
        self.frames = found.unwrap_or_default();
        if !self.frames.is_empty() && !self.frames.contains(&self.frame) {
            self.frame = self.frames[0];
        }
        if self.frames.is_empty() {
            self.playing = false;
        }
        self.problem.clone()
    }

    /// `graph` (the one [`Self::refresh`] was given) at the current frame: the patterns of
    /// [`Self::params`] replaced by its number; `graph` itself when there are none.
    pub fn at<'g>(&self, graph: &'g Graph) -> Cow<'g, Graph> {
        if self.params.is_empty() {
            return Cow::Borrowed(graph);
        }
        Cow::Owned(self.params.at(graph, self.frame))
    }

    /// Moves `by` frames through the frames found (wrapping at either end); with none
    /// found, `by` frame numbers.
    pub fn step(&mut self, by: i64) {
        let n = self.frames.len();
        if n == 0 {
            self.frame += by;
            return;
        }
        // A frame between those found (the slider can stop there) counts as just after
        // the one before it.
        let at = match self.frames.binary_search(&self.frame) {
            Ok(i) => i as i64,
            Err(i) if by > 0 => i as i64 - 1,
            Err(i) => i as i64,
        };
        let to = (at + by).rem_euclid(n as i64) as usize;
        self.frame = self.frames[to];
    }

    /// While playing, the next frame, once per egui frame (`frame_nr`, the context's
    /// cumulative frame number). Returns whether playback is on (the caller asks for
    /// another repaint).
    pub fn play(&mut self, frame_nr: u64) -> bool {
        if !self.playing {
            return false;
        }
        if self.advanced_in != Some(frame_nr) {
            self.advanced_in = Some(frame_nr);
            self.step(1);
        }
        true
    }

    /// Draws the control: a slider over the range, ◀ ▶ steps, ▶ play / ⏸ pause, how many
    /// frames were found, and ⟳ to list the folders again.
    pub fn ui(&mut self, ui: &mut Ui) {
        let range = self
            .frames
            .first()
            .copied()
            .zip(self.frames.last().copied());
        ui.horizontal_wrapped(|ui| {
            match range {
                Some((first, last)) => {
                    ui.add(
                        egui::Slider::new(&mut self.frame, first..=last)
                            .text("frame")
                            .clamping(egui::SliderClamping::Always),
                    )
                    .on_hover_text(
                        "the frame the preview shows: every frame pattern (####, %04d, $F4) \
                         in the graph takes its number; the file keeps the pattern",
                    );
                }
                None => {
                    ui.label("frame");
                    ui.add(egui::DragValue::new(&mut self.frame))
                        .on_hover_text("the frame number the patterns take");
                }
            }
            if ui.button("◀").on_hover_text("the frame before").clicked() {
                self.playing = false;
                self.step(-1);
            }
            if ui.button("▶").on_hover_text("the next frame").clicked() {
                self.playing = false;
                self.step(1);
            }
            let label = if self.playing {
                "⏸ pause"
            } else {
                "▶ play"
            };
            if ui
                .add_enabled(!self.frames.is_empty(), egui::Button::new(label))
                .on_hover_text("play the frames found, one a repaint, from the last to the first")
                .clicked()
            {
                self.playing = !self.playing;
            }
            match range {
                Some((first, last)) => {
                    ui.weak(format!("{} frames, {first}–{last}", self.frames.len()))
                        .on_hover_text(
                            "the frames whose input files exist, from the folders of the \
                             patterned input paths",
                        );
                }
                None => {
                    ui.weak("no frames found");
                }
            }
            if ui
                .small_button("⟳")
                .on_hover_text("list the folders of the sequence again")
                .clicked()
            {
                self.rescan();
            }
        });
        if let Some(p) = &self.problem {
            ui.colored_label(egui::Color32::from_rgb(240, 90, 90), p);
        }
    }
}

/// The frames for which every one of `inputs` (paths with a frame pattern, relative to
/// `base`) has a file: for each, the files of its folder that match it
/// ([`frames_on_disk`]); the frames all of them have, sorted. Empty without inputs.
///
/// # Errors
/// When a folder cannot be read, or the pattern is in a folder's name: the path and why.
pub fn frames_present(inputs: &[String], base: &Path) -> Result<Vec<i64>, String> {
    let mut present: Option<Vec<i64>> = None;
    for input in inputs {
        let path = base.join(input);
        let frames = frames_on_disk(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        present = Some(match present {
            Some(before) => before.into_iter().filter(|f| frames.contains(f)).collect(),
            None => frames,
        });
    }
    Ok(present.unwrap_or_default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frames_present_are_those_every_input_has() {
        let dir = std::env::temp_dir().join(format!("lumagraph-editor-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in [
            "a.0001.exr",
            "a.0002.exr",
            "a.0003.exr",
            "b.002.exr",
            "b.003.exr",
        ] {
            std::fs::write(dir.join(name), b"").unwrap();
        }
        let (a, b) = ("a.####.exr".to_owned(), "b.%03d.exr".to_owned());
        assert_eq!(
            frames_present(&[a.clone(), b.clone()], &dir),
            Ok(vec![2, 3])
        );
        assert_eq!(
            frames_present(std::slice::from_ref(&a), &dir),
            Ok(vec![1, 2, 3])
        );
        assert_eq!(frames_present(&[], &dir), Ok(vec![]));
        let missing = frames_present(&[a], &dir.join("nowhere")).unwrap_err();
        assert!(missing.contains("nowhere"), "{missing}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn steps_go_through_the_frames_found_and_wrap() {
        let mut s = Sequence {
            frames: vec![1, 2, 5],
            frame: 1,
            ..Sequence::default()
        };
        s.step(1);
        assert_eq!(s.frame, 2);
        s.step(1);
        assert_eq!(s.frame, 5);
        s.step(1);
        assert_eq!(s.frame, 1);
        s.step(-1);
        assert_eq!(s.frame, 5);
        // From a frame between those found (the slider can stop there).
        s.frame = 3;
        s.step(1);
        assert_eq!(s.frame, 5);
        s.frame = 3;
        s.step(-1);
        assert_eq!(s.frame, 2);
        s.frame = 0;
        s.step(1);
        assert_eq!(s.frame, 1);
        s.frame = 9;
        s.step(1);
        assert_eq!(s.frame, 1);
        s.frame = 9;
        s.step(-1);
        assert_eq!(s.frame, 5);
        // Playback steps once per egui frame.
        s.frame = 1;
        s.playing = true;
        assert!(s.play(10));
        assert!(s.play(10));
        assert_eq!(s.frame, 2);
        assert!(s.play(11));
        assert_eq!(s.frame, 5);
        s.playing = false;
        assert!(!s.play(12));
        assert_eq!(s.frame, 5);
    }
}
