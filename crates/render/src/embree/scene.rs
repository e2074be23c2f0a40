//! A triangle mesh in an Embree scene ([`HostScene`]), built and traced from the host.
#![allow(unsafe_code)]

use std::ffi::c_void;
use std::ptr::NonNull;
use std::sync::Arc;

use rayon::prelude::*;

use super::ffi::*;
use super::{Embree, HostHit, HostRay};

/// How a [`HostScene`] is built and traced. The defaults are what measured fastest on the
/// benchmark mesh (see `examples/embree_rays.rs`); the other settings exist to measure.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tuning {
    /// `RTC_BUILD_QUALITY_*`: 0 low, 1 medium, 2 high.
    pub quality: u32,
    /// `RTC_SCENE_FLAG_ROBUST`.
    pub robust: bool,
    /// `RTC_SCENE_FLAG_COMPACT`.
    pub compact: bool,
    /// `RTC_INTERSECT_CONTEXT_FLAG_COHERENT` rather than `..._INCOHERENT`.
    pub coherent: bool,
    /// Rays per Embree call: 1 (`rtcIntersect1`), 8 or 16 (`rtcIntersect8/16` packets), or
    /// 0 for `rtcIntersect1M` streams of 256.
    pub packet: u32,
    /// Rays per parallel task.
    pub chunk: usize,
}

impl Default for Tuning {
    fn default() -> Self {
        Self {
            quality: RTC_BUILD_QUALITY_MEDIUM,
            robust: false,
            compact: false,
            coherent: false,
            packet: 0,
            chunk: 2048,
        }
    }
}

/// Triangles in an Embree scene, traced from the host: see the module documentation.
pub struct HostScene {
    embree: Arc<Embree>,
    /// `None` without triangles: every ray misses.
    scene: Option<NonNull<c_void>>,
    triangles: usize,
    tuning: Tuning,
    /// The scene whose materials the any-hit filter reads (alpha), kept alive as long as
    /// Embree may call the filter with it.
    any_hit: Option<Arc<lumagraph_scene::GpuScene>>,
}

// SAFETY: a committed Embree scene is immutable; Embree allows ray queries on it from any
// number of threads at once. It is released once, by `Drop`, which has `&mut self`.
unsafe impl Send for HostScene {}
// SAFETY: as above: `&HostScene` only runs ray queries.
unsafe impl Sync for HostScene {}

impl std::fmt::Debug for HostScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HostScene")
            .field("triangles", &self.triangles)
            .field("tuning", &self.tuning)
            .finish_non_exhaustive()
    }
}

impl Drop for HostScene {
    fn drop(&mut self) {
        if let Some(scene) = self.scene.take() {
            // SAFETY: the scene came from `rtcNewScene` on this device and is released once;
            // no query can be running, as `drop` has `&mut self`.
            unsafe { (self.embree.api.release_scene)(scene.as_ptr()) };
        }
    }
}

impl HostScene {
    /// Triangles given by their three corners, in the order the path tracer indexes them
    /// (a hit's `prim` is the index here). Corners that are equal floats make a watertight
    /// mesh. Triangles with a non-finite corner are never hit (Embree leaves them out), nor
    /// are degenerate ones. Errors are Embree's (out of memory, invalid input); no
    /// triangles is fine.
    pub fn new(embree: Arc<Embree>, corners: &[[[f32; 3]; 3]]) -> Result<Self, String> {
        Self::with_tuning(embree, corners, Tuning::default())
    }

    /// [`HostScene::new`] over `scene`'s triangles (`tri_corners`), whose candidate hits
    /// take the any-hit test of every intersector
    /// ([`lumagraph_scene::traverse::triangle_hit_counts`]: alpha masks and blending),
    /// where its materials need it ([`lumagraph_scene::FEATURE_ALPHA`]).
    ///
    /// # Errors
    /// As [`HostScene::new`].
    pub fn of_scene(
        embree: Arc<Embree>,
        scene: &Arc<lumagraph_scene::GpuScene>,
    ) -> Result<Self, String> {
        if !scene.instances.is_empty() {
            return Err(flat_only("host intersection", scene));
        }
        let any_hit = (scene.header.features & lumagraph_scene::FEATURE_ALPHA != 0)
            .then(|| Arc::clone(scene));
        Self::build(embree, &scene.tri_corners, Tuning::default(), any_hit)
    }

    /// [`HostScene::new`] with other build and trace settings (for measurements).
    #[doc(hidden)]
    pub fn with_tuning(
        embree: Arc<Embree>,
        corners: &[[[f32; 3]; 3]],
        tuning: Tuning,
    ) -> Result<Self, String> {
        Self::build(embree, corners, tuning, None)
    }

    fn build(
        embree: Arc<Embree>,
        corners: &[[[f32; 3]; 3]],
        tuning: Tuning,
        any_hit: Option<Arc<lumagraph_scene::GpuScene>>,
    ) -> Result<Self, String> {
        let mut out = Self {
            embree,
            scene: None,
            triangles: corners.len(),
            tuning: Tuning {
                chunk: tuning.chunk.max(16),
                ..tuning
            },
            any_hit,
        };
        if corners.is_empty() {
            return Ok(out);
        }
        if corners.len() > (u32::MAX / 3) as usize {
            return Err(format!("{} triangles: too many for Embree", corners.len()));
        }
        let e = Arc::clone(&out.embree);
        let api = &e.api;
        let device = e.device.as_ptr();
        // Clears an error left on this thread by an earlier call, so it is not taken for
        // this build's.
        let _ = e.check("earlier call");
        // SAFETY: `device` is live; a null result is handled.
        let scene = unsafe { (api.new_scene)(device) };
        out.scene = NonNull::new(scene);
        let Some(scene) = out.scene else {
            return Err(e
                .check("rtcNewScene")
                .err()
                .unwrap_or_else(|| "rtcNewScene failed".into()));
        };
        let scene = scene.as_ptr();
        // SAFETY: `device` is live; a null result is handled.
        let geometry = unsafe { (api.new_geometry)(device, RTC_GEOMETRY_TYPE_TRIANGLE) };
        if geometry.is_null() {
            return Err(e
                .check("rtcNewGeometry")
                .err()
                .unwrap_or_else(|| "rtcNewGeometry failed".into()));
        }
        let filled = Self::fill(&e, geometry, corners);
        if filled.is_ok() {
            let mut flags = RTC_SCENE_FLAG_NONE;
            if tuning.robust {
                flags |= RTC_SCENE_FLAG_ROBUST;
            }
            if tuning.compact {
                flags |= RTC_SCENE_FLAG_COMPACT;
            }
            let quality = tuning.quality.min(RTC_BUILD_QUALITY_HIGH);
            if let Some(g) = &out.any_hit {
                // SAFETY: `geometry` is live; the user pointer is the `GpuScene` that
                // `out.any_hit` keeps alive as long as the Embree scene, and
                // `any_hit_filter` reads it as one.
                unsafe {
                    (api.set_geometry_user_data)(
                        geometry,
                        Arc::as_ptr(g).cast::<c_void>().cast_mut(),
                    );
                    (api.set_geometry_intersect_filter)(geometry, Some(any_hit_filter));
                    (api.set_geometry_occluded_filter)(geometry, Some(any_hit_filter));
                }
            }
            // SAFETY: `geometry` and `scene` are live and belong to `device`; the geometry
            // has both buffers set. Attaching takes a reference, so releasing ours below
            // leaves the scene owning it.
            unsafe {
                (api.set_geometry_build_quality)(geometry, quality);
                (api.commit_geometry)(geometry);
                (api.attach_geometry)(scene, geometry);
                (api.set_scene_flags)(scene, flags);
                (api.set_scene_build_quality)(scene, quality);
            }
        }
        // SAFETY: our reference to the geometry, made above, is released once.
        unsafe { (api.release_geometry)(geometry) };
        filled?;
        // SAFETY: `scene` is live and complete; nothing traces it yet.
        unsafe { (api.commit_scene)(scene) };
        e.check("rtcCommitScene")?;
        Ok(out)
    }

    /// Gives `geometry` its vertex and index buffers: a triangle soup, corner `3i + k` of
    /// triangle `i` at vertex `3i + k`.
    fn fill(e: &Embree, geometry: RtcGeometry, corners: &[[[f32; 3]; 3]]) -> Result<(), String> {
        let n = corners.len();
        // SAFETY: `geometry` is live; 12-byte FLOAT3 items, 3 per triangle. Embree pads
        // vertex buffers for its 16-byte loads itself.
        let vertices = unsafe {
            (e.api.set_new_geometry_buffer)(
                geometry,
                RTC_BUFFER_TYPE_VERTEX,
                0,
                RTC_FORMAT_FLOAT3,
                12,
                3 * n,
            )
        };
        e.check("vertex buffer")?;
        // SAFETY: as above, 12-byte UINT3 items, one per triangle.
        let indices = unsafe {
            (e.api.set_new_geometry_buffer)(
                geometry,
                RTC_BUFFER_TYPE_INDEX,
                0,
                RTC_FORMAT_UINT3,
                12,
                n,
            )
        };
        e.check("index buffer")?;
        if vertices.is_null() || indices.is_null() {
            return Err("Embree: rtcSetNewGeometryBuffer returned no buffer".to_owned());
        }
        // SAFETY: Embree allocated `3n` FLOAT3 vertices and `n` UINT3 triangles at these
        // (16-byte aligned) addresses, owned by `geometry` and written by nobody else now.
        let (vertices, indices) = unsafe {
            (
                std::slice::from_raw_parts_mut(vertices.cast::<[[f32; 3]; 3]>(), n),
                std::slice::from_raw_parts_mut(indices.cast::<[u32; 3]>(), n),
            )
        };
        vertices.copy_from_slice(corners);
        for (i, tri) in indices.iter_mut().enumerate() {
            let first = 3 * i as u32;
            *tri = [first, first + 1, first + 2];
        }
        Ok(())
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles == 0
    }

    /// The closest hit of each ray, into `hits` (same length; [`HostHit::MISS`] where a ray
    /// misses or is "no ray"), traced on rayon's threads.
    ///
    /// # Panics
    /// If `hits` and `rays` differ in length.
    pub fn intersect(&self, rays: &[HostRay], hits: &mut [HostHit]) {
        assert_eq!(rays.len(), hits.len(), "one hit per ray");
        let Some(scene) = self.scene else {
            hits.fill(HostHit::MISS);
            return;
        };
        let scene = Scene(scene.as_ptr());
        let chunk = self.tuning.chunk;
        rays.par_chunks(chunk)
            .zip(hits.par_chunks_mut(chunk))
            .for_each(|(rays, hits)| match self.tuning.packet {
                0 => self.intersect_stream(scene, rays, hits),
                8 => self.intersect_packets::<8>(scene, rays, hits, self.embree.api.intersect8),
                16 => self.intersect_packets::<16>(scene, rays, hits, self.embree.api.intersect16),
                _ => self.intersect_single(scene, rays, hits),
            });
    }

    /// Whether each ray hits anything between `tnear` and `tfar`, into `out` (same
    /// length): 1 or 0 (0 for "no ray"), traced on rayon's threads.
    ///
    /// # Panics
    /// If `out` and `rays` differ in length.
    pub fn occluded(&self, rays: &[HostRay], out: &mut [u32]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        let Some(scene) = self.scene else {
            out.fill(0);
            return;
        };
        let scene = Scene(scene.as_ptr());
        let chunk = self.tuning.chunk;
        rays.par_chunks(chunk)
            .zip(out.par_chunks_mut(chunk))
            .for_each(|(rays, out)| match self.tuning.packet {
                0 => self.occluded_stream(scene, rays, out),
                8 => self.occluded_packets::<8>(scene, rays, out, self.embree.api.occluded8),
                16 => self.occluded_packets::<16>(scene, rays, out, self.embree.api.occluded16),
                _ => self.occluded_single(scene, rays, out),
            });
    }

    fn context(&self) -> RtcIntersectContext {
        RtcIntersectContext::new(self.tuning.coherent)
    }

    fn intersect_single(&self, scene: Scene, rays: &[HostRay], hits: &mut [HostHit]) {
        let mut ctx = self.context();
        for (ray, hit) in rays.iter().zip(hits) {
            if !ray.is_active() {
                *hit = HostHit::MISS;
                continue;
            }
            let mut rh = RtcRayHit {
                ray: rtc_ray(ray),
                hit: NO_HIT,
            };
            // SAFETY: `scene` is committed and outlives the call; `ctx` and `rh` are
            // initialized as the headers require (16-byte aligned, valid segment, geomID
            // invalid, flags 0).
            unsafe { (self.embree.api.intersect1)(scene.0, &raw mut ctx, &raw mut rh) };
            *hit = host_hit(
                rh.ray.tfar,
                rh.hit.u,
                rh.hit.v,
                rh.hit.prim_id,
                rh.hit.geom_id,
            );
        }
    }

    fn occluded_single(&self, scene: Scene, rays: &[HostRay], out: &mut [u32]) {
        let mut ctx = self.context();
        for (ray, out) in rays.iter().zip(out) {
            if !ray.is_active() {
                *out = 0;
                continue;
            }
            let mut r = rtc_ray(ray);
            // SAFETY: as in `intersect_single`; Embree sets `tfar` to -inf on a hit.
            unsafe { (self.embree.api.occluded1)(scene.0, &raw mut ctx, &raw mut r) };
            *out = u32::from(r.tfar == f32::NEG_INFINITY);
        }
    }

    fn intersect_stream(&self, scene: Scene, rays: &[HostRay], hits: &mut [HostHit]) {
        let mut ctx = self.context();
        let mut stream = [EMPTY_RAY_HIT; STREAM];
        for (rays, hits) in rays.chunks(STREAM).zip(hits.chunks_mut(STREAM)) {
            let stream = &mut stream[..rays.len()];
            for (s, r) in stream.iter_mut().zip(rays) {
                *s = stream_ray(r);
            }
            // SAFETY: `stream` holds `rays.len()` (at most `STREAM`) 16-byte aligned
            // ray/hits set up as for `rtcIntersect1`, inactive ones with tnear > tfar as
            // the API defines; `scene` is committed.
            unsafe {
                (self.embree.api.intersect1m)(
                    scene.0,
                    &raw mut ctx,
                    stream.as_mut_ptr(),
                    stream.len() as u32,
                    std::mem::size_of::<RtcRayHit>(),
                );
            }
            for (rh, hit) in stream.iter().zip(hits) {
                *hit = host_hit(
                    rh.ray.tfar,
                    rh.hit.u,
                    rh.hit.v,
                    rh.hit.prim_id,
                    rh.hit.geom_id,
                );
            }
        }
    }

    fn occluded_stream(&self, scene: Scene, rays: &[HostRay], out: &mut [u32]) {
        let mut ctx = self.context();
        let mut stream = [EMPTY_RAY_HIT; STREAM];
        for (rays, out) in rays.chunks(STREAM).zip(out.chunks_mut(STREAM)) {
            let stream = &mut stream[..rays.len()];
            for (s, r) in stream.iter_mut().zip(rays) {
                *s = stream_ray(r);
            }
            // SAFETY: as in `intersect_stream`; the stride steps over the hit halves, which
            // `rtcOccluded1M` does not touch.
            unsafe {
                (self.embree.api.occluded1m)(
                    scene.0,
                    &raw mut ctx,
                    stream.as_mut_ptr(),
                    stream.len() as u32,
                    std::mem::size_of::<RtcRayHit>(),
                );
            }
            for (rh, out) in stream.iter().zip(out) {
                *out = u32::from(rh.ray.tfar == f32::NEG_INFINITY);
            }
        }
    }

    fn intersect_packets<const N: usize>(
        &self,
        scene: Scene,
        rays: &[HostRay],
        hits: &mut [HostHit],
        f: PacketFn<N>,
    ) {
        let mut ctx = self.context();
        for (rays, hits) in rays.chunks(N).zip(hits.chunks_mut(N)) {
            let (valid, mut packet) = packet::<N>(rays);
            if valid.0.iter().all(|&v| v == 0) {
                hits.fill(HostHit::MISS);
                continue;
            }
            // SAFETY: `packet` and `valid` are 64-byte aligned, active lanes initialized as
            // for `rtcIntersect1`; `scene` is committed.
            unsafe { f(&raw const valid, scene.0, &raw mut ctx, &raw mut packet) };
            for (i, hit) in hits.iter_mut().enumerate() {
                *hit = if valid.0[i] == 0 {
                    HostHit::MISS
                } else {
                    host_hit(
                        packet.tfar[i],
                        packet.u[i],
                        packet.v[i],
                        packet.prim_id[i],
                        packet.geom_id[i],
                    )
                };
            }
        }
    }

    fn occluded_packets<const N: usize>(
        &self,
        scene: Scene,
        rays: &[HostRay],
        out: &mut [u32],
        f: PacketFn<N>,
    ) {
        let mut ctx = self.context();
        for (rays, out) in rays.chunks(N).zip(out.chunks_mut(N)) {
            let (valid, mut packet) = packet::<N>(rays);
            if valid.0.iter().all(|&v| v == 0) {
                out.fill(0);
                continue;
            }
            // SAFETY: as in `intersect_packets`; `rtcOccludedN` reads the ray half.
            unsafe { f(&raw const valid, scene.0, &raw mut ctx, &raw mut packet) };
            for (i, out) in out.iter_mut().enumerate() {
                *out = u32::from(valid.0[i] != 0 && packet.tfar[i] == f32::NEG_INFINITY);
            }
        }
    }
}

/// A committed scene handle, copied into rayon's tasks.
#[derive(Clone, Copy)]
struct Scene(RtcScene);
// SAFETY: see `HostScene`: queries on a committed scene may run on any thread.
unsafe impl Send for Scene {}
// SAFETY: as above.
unsafe impl Sync for Scene {}

/// An active ray as Embree's (`tnear` clamped to 0, mask all ones, flags 0).
fn rtc_ray(r: &HostRay) -> RtcRay {
    RtcRay {
        org: r.origin,
        tnear: r.tnear.max(0.0),
        dir: r.dir,
        time: 0.0,
        tfar: r.tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

/// A ray for `rtcIntersect1M`/`rtcOccluded1M`: inactive ones get `tnear` > `tfar`.
fn stream_ray(r: &HostRay) -> RtcRayHit {
    if r.is_active() {
        RtcRayHit {
            ray: rtc_ray(r),
            hit: NO_HIT,
        }
    } else {
        EMPTY_RAY_HIT
    }
}

/// Rays per `rtcIntersect1M`/`rtcOccluded1M` call, on the stack (20 KiB).
const STREAM: usize = 256;

/// `RTCHit` before a query: no geometry.
const NO_HIT: RtcHit = RtcHit {
    ng: [0.0; 3],
    u: 0.0,
    v: 0.0,
    prim_id: RTC_INVALID_GEOMETRY_ID,
    geom_id: RTC_INVALID_GEOMETRY_ID,
    inst_id: [RTC_INVALID_GEOMETRY_ID],
};

/// An inactive stream entry (tnear > tfar).
const EMPTY_RAY_HIT: RtcRayHit = RtcRayHit {
    ray: RtcRay {
        org: [0.0; 3],
        tnear: 1.0,
        dir: [1.0, 0.0, 0.0],
        time: 0.0,
        tfar: 0.0,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    },
    hit: NO_HIT,
};

/// Up to `N` rays as a packet and its valid mask (missing and inactive lanes off).
fn packet<const N: usize>(rays: &[HostRay]) -> (ValidN<N>, RtcRayHitN<N>) {
    let mut valid = ValidN([0; N]);
    let mut p = RtcRayHitN::<N> {
        org_x: [0.0; N],
        org_y: [0.0; N],
        org_z: [0.0; N],
        tnear: [0.0; N],
        dir_x: [1.0; N],
        dir_y: [0.0; N],
        dir_z: [0.0; N],
        time: [0.0; N],
        tfar: [-1.0; N],
        mask: [u32::MAX; N],
        id: [0; N],
        flags: [0; N],
        ng_x: [0.0; N],
        ng_y: [0.0; N],
        ng_z: [0.0; N],
        u: [0.0; N],
        v: [0.0; N],
        prim_id: [RTC_INVALID_GEOMETRY_ID; N],
        geom_id: [RTC_INVALID_GEOMETRY_ID; N],
        inst_id: [RTC_INVALID_GEOMETRY_ID; N],
    };
    for (i, r) in rays.iter().enumerate().take(N) {
        if !r.is_active() {
            continue;
        }
        valid.0[i] = -1;
        [p.org_x[i], p.org_y[i], p.org_z[i]] = r.origin;
        [p.dir_x[i], p.dir_y[i], p.dir_z[i]] = r.dir;
        p.tnear[i] = r.tnear.max(0.0);
        p.tfar[i] = r.tfar;
    }
    (valid, p)
}

/// A [`HostHit`] from Embree's output: a miss where `geom_id` is invalid.
fn host_hit(tfar: f32, u: f32, v: f32, prim_id: u32, geom_id: u32) -> HostHit {
    if geom_id == RTC_INVALID_GEOMETRY_ID {
        HostHit::MISS
    } else {
        HostHit {
            t: tfar,
            u,
            v,
            prim: prim_id,
        }
    }
}

/// Why an intersector that takes flat scenes only refuses `scene` (it has instances).
pub(crate) fn flat_only(what: &str, scene: &lumagraph_scene::GpuScene) -> String {
    format!(
        "{what} takes flat scenes only, and this one has {} instances (the binary BVH walks \
         them; `instancing: Off` in the scene file copies them)",
        scene.instances.len()
    )
}
