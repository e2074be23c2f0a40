//! Tiled rendering's geometry: how far a plan reads around a pixel (its apron), and the
//! tiles an image splits into.
//!
//! A tile's **core** is the part of the image it delivers; its **window** is what it
//! renders: the core and, on every side that is not the image's edge, the apron. Every node
//! that renders the scene renders its pixels of the whole image, so a window's pixels are
//! those of the whole image, and a node that reads at most `r` pixels away
//! ([`Reach::Within`]) gives, `r` pixels inside the window's inner edges, the pixels it
//! gives in the whole image. Summed along every path from the scene to an output, the
//! reaches make the apron, and the cores come out as the whole image would.
//!
//! Windows all have one size (the tile and two aprons, at most the image): a window that
//! would stick out of the image is moved back inside it, which keeps the apron on its inner
//! sides, so one compiled plan serves every tile.

use std::fmt;

use crate::Plan;
use crate::registry::Reach;

/// A rectangle of pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl fmt::Display for Rect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}×{} at ({}, {})",
            self.width, self.height, self.x, self.y
        )
    }
}

/// One tile of a tiled render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// The pixels it delivers.
    pub core: Rect,
    /// The pixels it renders: the core and the apron around it, inside the image.
    pub window: Rect,
}

impl Tile {
    /// Where the core lies in the window.
    pub fn core_in_window(&self) -> (u32, u32) {
        (self.core.x - self.window.x, self.core.y - self.window.y)
    }
}

/// Why a plan cannot run tile by tile: the node, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Untileable {
    /// The node's id.
    pub node: String,
    /// Its kind.
    pub kind: String,
    /// Why it needs the whole image.
    pub reason: String,
}

impl fmt::Display for Untileable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "node \"{}\" ({}) cannot run tile by tile: {}",
            self.node, self.kind, self.reason
        )
    }
}

/// The apron a tiled run of `plan` needs: the most pixels any output pixel depends on away
/// from it, summed along the paths from the sources.
///
/// # Errors
/// The first node that needs the whole image ([`Reach::Image`]) or changes the image size.
pub fn apron(plan: &Plan) -> Result<u32, Untileable> {
    let mut margin = vec![0_u32; plan.passes.len()];
    for (p, pass) in plan.passes.iter().enumerate() {
        let reach = match pass.kind.reach {
            Reach::Pixel => 0,
            Reach::Within(f) => f(&pass.params),
            Reach::Image(why) => {
                return Err(Untileable {
                    node: pass.node.clone(),
                    kind: pass.kind.name.to_owned(),
                    reason: why.to_owned(),
                });
            }
        };
        let sized = pass
            .inputs
            .iter()
            .chain(&pass.outputs)
            .all(|(_, t)| plan.textures[t.0].extent == pass.extent);
        if !sized {
            return Err(Untileable {
                node: pass.node.clone(),
                kind: pass.kind.name.to_owned(),
                reason: "it changes the image size".to_owned(),
            });
        }
        let upstream = pass
            .inputs
            .iter()
            .map(|(_, t)| margin[plan.textures[t.0].first])
            .max()
            .unwrap_or(0);
        margin[p] = upstream.saturating_add(reach);
    }
    Ok(margin.into_iter().max().unwrap_or(0))
}

/// The tiles of a `width` × `height` image with cores of at most `tile` × `tile` pixels,
/// as many as that takes and of nearly equal sizes, row by row; every window is the
/// largest core and two aprons wide and high, or the image's width or height where that is
/// less ([`window`]).
pub fn tiles(width: u32, height: u32, tile: u32, apron: u32) -> Vec<Tile> {
    let tile = tile.max(1);
    let axis = |len: u32| -> Vec<(u32, u32, u32, u32)> {
        // As many tiles as `tile` needs, all of nearly one size (none a thin sliver).
        let count = len.div_ceil(tile).max(1);
        let size = len.div_ceil(count);
        let window = size.saturating_add(apron.saturating_mul(2)).min(len);
        (0..count)
            .map(|i| {
                let start = (u64::from(len) * u64::from(i) / u64::from(count)) as u32;
                let end = (u64::from(len) * u64::from(i + 1) / u64::from(count)) as u32;
                let w_start = start.saturating_sub(apron).min(len - window);
                (start, end - start, w_start, window)
            })
            .collect()
    };
    let (xs, ys) = (axis(width), axis(height));
    let mut out = Vec::with_capacity(xs.len() * ys.len());
    for &(y, h, wy, wh) in &ys {
        for &(x, w, wx, ww) in &xs {
            out.push(Tile {
                core: Rect {
                    x,
                    y,
                    width: w,
                    height: h,
                },
                window: Rect {
                    x: wx,
                    y: wy,
                    width: ww,
                    height: wh,
                },
            });
        }
    }
    out
}

/// The window side [`tiles`] gives along an axis of `len` pixels.
pub fn window(len: u32, tile: u32, apron: u32) -> u32 {
    let count = len.div_ceil(tile.max(1)).max(1);
    len.div_ceil(count)
        .saturating_add(apron.saturating_mul(2))
        .min(len)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_hold_their_core_and_its_apron_inside_the_image() {
        for (w, h, tile, apron) in [
            (100, 70, 32, 5),
            (64, 64, 64, 0),
            (50, 9, 16, 20),
            (7, 7, 3, 1),
        ] {
            let tiles = tiles(w, h, tile, apron);
            let mut covered = vec![0_u32; (w * h) as usize];
            let first = tiles[0].window;
            for t in &tiles {
                let (c, win) = (t.core, t.window);
                assert_eq!((win.width, win.height), (first.width, first.height));
                assert_eq!(win.width, window(w, tile, apron));
                assert_eq!(win.height, window(h, tile, apron));
                assert!(c.width <= tile && c.height <= tile);
                assert!(win.x + win.width <= w && win.y + win.height <= h);
                assert!(win.x <= c.x && c.x + c.width <= win.x + win.width);
                assert!(win.y <= c.y && c.y + c.height <= win.y + win.height);
                // Every inner edge of the window is at least `apron` away from the core.
                assert!(win.x == 0 || c.x - win.x >= apron);
                assert!(win.y == 0 || c.y - win.y >= apron);
                assert!(win.x + win.width == w || win.x + win.width - (c.x + c.width) >= apron);
                assert!(win.y + win.height == h || win.y + win.height - (c.y + c.height) >= apron);
                for y in c.y..c.y + c.height {
                    for x in c.x..c.x + c.width {
                        covered[(y * w + x) as usize] += 1;
                    }
                }
            }
            assert!(covered.iter().all(|&n| n == 1), "{w}×{h} tile {tile}");
        }
    }
}
