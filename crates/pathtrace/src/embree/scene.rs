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
    /// The scenes of the instanced meshes (one each, committed before `scene`, which places
    /// them), released after it.
    meshes: Vec<NonNull<c_void>>,
    /// Per instance (its Embree geometry ID in `scene`): its mesh's first triangle in the
    /// path tracer's order, and the instance's node slot (a hit's `inst` in the WGSL).
    placed: Vec<[u32; 2]>,
    triangles: usize,
    tuning: Tuning,
    /// The scene whose materials the any-hit filter reads (alpha), kept alive as long as
    /// Embree may call the filter with it.
    any_hit: Option<Arc<lumagraph_scene::GpuScene>>,
    /// What the filter of each triangle geometry reads (its user data), kept at a fixed
    /// address as long as the scenes.
    #[allow(
        clippy::vec_box,
        reason = "Embree holds each record's address: the vector may move, the boxes not"
    )]
    filters: Vec<Box<FilterGeometry>>,
}

// SAFETY: a committed Embree scene is immutable; Embree allows ray queries on it from any
// number of threads at once. It is released once, by `Drop`, which has `&mut self`. The
// filters' records are read only.
unsafe impl Send for HostScene {}
// SAFETY: as above: `&HostScene` only runs ray queries.
unsafe impl Sync for HostScene {}

impl std::fmt::Debug for HostScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HostScene")
            .field("triangles", &self.triangles)
            .field("instances", &self.placed.len())
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
        for mesh in self.meshes.drain(..) {
            // SAFETY: as above; the instances that placed it went with the scene.
            unsafe { (self.embree.api.release_scene)(mesh.as_ptr()) };
        }
    }
}

/// The instanced meshes of a scene and their instances, as Embree places them.
struct Placements<'a> {
    /// Each mesh's triangles and the index of its first one in the path tracer's order.
    meshes: Vec<(&'a [[[f32; 3]; 3]], u32)>,
    /// Each instance in top-level order: its mesh, its object-to-world rows and its node
    /// slot.
    instances: Vec<(usize, [[f32; 4]; 3], u32)>,
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
    /// With instanced meshes, each mesh is an Embree scene of its own (its triangles in its
    /// own space, built once) and each instance an instance geometry placing it; a hit on
    /// one names its instance ([`HostScene::intersect_instances`]).
    ///
    /// # Errors
    /// As [`HostScene::new`]; and when the scene's instance records do not fit its meshes.
    pub fn of_scene(
        embree: Arc<Embree>,
        scene: &Arc<lumagraph_scene::GpuScene>,
    ) -> Result<Self, String> {
        let any_hit = (scene.header.features & lumagraph_scene::FEATURE_ALPHA != 0)
            .then(|| Arc::clone(scene));
        if scene.instances.is_empty() {
            return Self::build(embree, &scene.tri_corners, None, Tuning::default(), any_hit);
        }
        let own = scene.tri_source.len();
        let corners = &scene.tri_corners;
        let meshes = scene
            .mesh_triangles
            .iter()
            .map(|&[first, count]| {
                let (first, count) = (first as usize, count as usize);
                corners
                    .get(first..first + count)
                    .map(|c| (c, first as u32))
                    .ok_or_else(|| {
                        format!(
                            "an instanced mesh's triangles {first}..{} are past the scene's {}",
                            first + count,
                            corners.len()
                        )
                    })
            })
            .collect::<Result<Vec<_>, String>>()?;
        if scene.instance_mesh.len() != scene.instances.len() {
            return Err(format!(
                "{} instances but {} instance meshes",
                scene.instances.len(),
                scene.instance_mesh.len()
            ));
        }
        let nodes = scene.bvh_nodes.len();
        let instances = scene
            .instances
            .iter()
            .zip(&scene.instance_mesh)
            .enumerate()
            .map(|(k, (inst, &mesh))| {
                if mesh as usize >= meshes.len() {
                    return Err(format!("instance {k}: no mesh {mesh}"));
                }
                let slot = u32::try_from(nodes + 2 * k)
                    .map_err(|_| format!("instance {k}: its node slot is past 2^32"))?;
                Ok((mesh as usize, inst.to_world, slot))
            })
            .collect::<Result<Vec<_>, String>>()?;
        Self::build(
            embree,
            corners.get(..own).unwrap_or(corners),
            Some(Placements { meshes, instances }),
            Tuning::default(),
            any_hit,
        )
    }

    /// [`HostScene::new`] with other build and trace settings (for measurements).
    #[doc(hidden)]
    pub fn with_tuning(
        embree: Arc<Embree>,
        corners: &[[[f32; 3]; 3]],
        tuning: Tuning,
    ) -> Result<Self, String> {
        Self::build(embree, corners, None, tuning, None)
    }

    fn build(
        embree: Arc<Embree>,
        corners: &[[[f32; 3]; 3]],
        placements: Option<Placements<'_>>,
        tuning: Tuning,
        any_hit: Option<Arc<lumagraph_scene::GpuScene>>,
    ) -> Result<Self, String> {
        let placements = placements.unwrap_or(Placements {
            meshes: Vec::new(),
            instances: Vec::new(),
        });
        let mut out = Self {
            embree,
            scene: None,
            meshes: Vec::new(),
            placed: Vec::new(),
            triangles: corners.len() + placements.meshes.iter().map(|m| m.0.len()).sum::<usize>(),
            tuning: Tuning {
                chunk: tuning.chunk.max(16),
                ..tuning
            },
            any_hit,
            filters: Vec::new(),
        };
        if corners.is_empty() && placements.instances.is_empty() {
            return Ok(out);
        }
        let e = Arc::clone(&out.embree);
        let api = &e.api;
        let mut flags = RTC_SCENE_FLAG_NONE;
        if tuning.robust {
            flags |= RTC_SCENE_FLAG_ROBUST;
        }
        if tuning.compact {
            flags |= RTC_SCENE_FLAG_COMPACT;
        }
        let quality = tuning.quality.min(RTC_BUILD_QUALITY_HIGH);
        // Clears an error left on this thread by an earlier call, so it is not taken for
        // this build's.
        let _ = e.check("earlier call");
        // Each mesh in a scene of its own, committed before any instance places it.
        for &(mesh, base) in &placements.meshes {
            let scene = out.new_scene(flags, quality)?;
            out.meshes.push(scene);
            out.attach_triangles(scene.as_ptr(), mesh, base, quality)?;
            // SAFETY: `scene` is live and complete; nothing traces it yet.
            unsafe { (api.commit_scene)(scene.as_ptr()) };
            e.check("rtcCommitScene (an instanced mesh)")?;
        }
        let scene = out.new_scene(flags, quality)?.as_ptr();
        out.scene = NonNull::new(scene);
        // The instances first: instance `k` is geometry `k`.
        for (k, &(mesh, to_world, slot)) in placements.instances.iter().enumerate() {
            let (_, base) = placements.meshes[mesh];
            out.attach_instance(scene, out.meshes[mesh].as_ptr(), &to_world, k)?;
            out.placed.push([base, slot]);
        }
        if !corners.is_empty() {
            out.attach_triangles(scene, corners, 0, quality)?;
        }
        // SAFETY: `scene` is live and complete; nothing traces it yet.
        unsafe { (api.commit_scene)(scene) };
        e.check("rtcCommitScene")?;
        Ok(out)
    }

    /// A new scene with these flags and build quality.
    fn new_scene(&self, flags: u32, quality: u32) -> Result<NonNull<c_void>, String> {
        let e = &self.embree;
        // SAFETY: the device is live; a null result is handled.
        let scene = unsafe { (e.api.new_scene)(e.device.as_ptr()) };
        let Some(scene) = NonNull::new(scene) else {
            return Err(e
                .check("rtcNewScene")
                .err()
                .unwrap_or_else(|| "rtcNewScene failed".into()));
        };
        // SAFETY: `scene` is live.
        unsafe {
            (e.api.set_scene_flags)(scene.as_ptr(), flags);
            (e.api.set_scene_build_quality)(scene.as_ptr(), quality);
        }
        Ok(scene)
    }

    /// A new geometry of `kind`.
    fn new_geometry(&self, kind: u32) -> Result<RtcGeometry, String> {
        let e = &self.embree;
        // SAFETY: the device is live; a null result is handled.
        let geometry = unsafe { (e.api.new_geometry)(e.device.as_ptr(), kind) };
        if geometry.is_null() {
            return Err(e
                .check("rtcNewGeometry")
                .err()
                .unwrap_or_else(|| "rtcNewGeometry failed".into()));
        }
        Ok(geometry)
    }

    /// Attaches `corners` to `scene` as a committed triangle geometry whose triangle `i` is
    /// the path tracer's `base + i` (for the any-hit filter).
    fn attach_triangles(
        &mut self,
        scene: RtcScene,
        corners: &[[[f32; 3]; 3]],
        base: u32,
        quality: u32,
    ) -> Result<(), String> {
        if corners.len() > (u32::MAX / 3) as usize {
            return Err(format!("{} triangles: too many for Embree", corners.len()));
        }
        let e = Arc::clone(&self.embree);
        let api = &e.api;
        let geometry = self.new_geometry(RTC_GEOMETRY_TYPE_TRIANGLE)?;
        let filled = Self::fill(&e, geometry, corners);
        if filled.is_ok() {
            if let Some(g) = &self.any_hit {
                let filter = Box::new(FilterGeometry {
                    scene: Arc::as_ptr(g),
                    base,
                });
                // SAFETY: `geometry` is live; the user pointer is the boxed record, which
                // `self.filters` keeps at its address as long as the scenes (and the
                // `GpuScene` it points to with `self.any_hit`); `any_hit_filter` reads it
                // as one.
                unsafe {
                    (api.set_geometry_user_data)(
                        geometry,
                        std::ptr::from_ref::<FilterGeometry>(&*filter)
                            .cast_mut()
                            .cast::<c_void>(),
                    );
                    (api.set_geometry_intersect_filter)(geometry, Some(any_hit_filter));
                    (api.set_geometry_occluded_filter)(geometry, Some(any_hit_filter));
                }
                self.filters.push(filter);
            }
            // SAFETY: `geometry` and `scene` are live and belong to the device; the
            // geometry has both buffers set. Attaching takes a reference, so releasing ours
            // below leaves the scene owning it.
            unsafe {
                (api.set_geometry_build_quality)(geometry, quality);
                (api.commit_geometry)(geometry);
                (api.attach_geometry)(scene, geometry);
            }
        }
        // SAFETY: our reference to the geometry, made above, is released once.
        unsafe { (api.release_geometry)(geometry) };
        filled?;
        e.check("triangle geometry")
    }

    /// Attaches an instance of `mesh` (a committed scene) placed by the object-to-world
    /// `rows` to `scene`, as its geometry `k`.
    fn attach_instance(
        &self,
        scene: RtcScene,
        mesh: RtcScene,
        rows: &[[f32; 4]; 3],
        k: usize,
    ) -> Result<(), String> {
        let e = &self.embree;
        let api = &e.api;
        let id = u32::try_from(k)
            .ok()
            .filter(|&id| id != RTC_INVALID_GEOMETRY_ID)
            .ok_or_else(|| format!("{k} instances: too many for Embree"))?;
        if rows.iter().flatten().any(|x| !x.is_finite()) {
            return Err(format!("instance {k}: its transform is not finite"));
        }
        let geometry = self.new_geometry(RTC_GEOMETRY_TYPE_INSTANCE)?;
        // SAFETY: `geometry`, `mesh` and `scene` are live and belong to the device; the
        // transform is 12 floats, row major, read during the call. Attaching takes a
        // reference, so releasing ours leaves the scene owning the geometry.
        unsafe {
            (api.set_geometry_instanced_scene)(geometry, mesh);
            (api.set_geometry_transform)(
                geometry,
                0,
                RTC_FORMAT_FLOAT3X4_ROW_MAJOR,
                rows.as_ptr().cast::<c_void>(),
            );
            (api.commit_geometry)(geometry);
            (api.attach_geometry_by_id)(scene, geometry, id);
            (api.release_geometry)(geometry);
        }
        e.check("instance geometry")
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
    /// misses or is "no ray"), traced on rayon's threads. A hit on an instanced mesh's
    /// triangle has that triangle's index in the path tracer's order as its `prim`; which
    /// instance it is of, [`HostScene::intersect_instances`] says.
    ///
    /// # Panics
    /// If `hits` and `rays` differ in length.
    pub fn intersect(&self, rays: &[HostRay], hits: &mut [HostHit]) {
        assert_eq!(rays.len(), hits.len(), "one hit per ray");
        self.trace_hits(rays, hits, None);
    }

    /// [`HostScene::intersect`], and into `insts` (same length) the instance of each hit:
    /// its node slot (the WGSL's `inst`, `GpuScene::bvh_nodes.len() + 2 k` for instance
    /// `k`), or [`lumagraph_scene::NO_INSTANCE`] for the scene's own triangles and misses.
    ///
    /// # Panics
    /// If `hits` or `insts` and `rays` differ in length.
    pub fn intersect_instances(&self, rays: &[HostRay], hits: &mut [HostHit], insts: &mut [u32]) {
        assert_eq!(rays.len(), hits.len(), "one hit per ray");
        assert_eq!(rays.len(), insts.len(), "one instance per ray");
        self.trace_hits(rays, hits, Some(insts));
    }

    /// Whether the scene has instances (their hits name them: `intersect_instances`).
    pub fn has_instances(&self) -> bool {
        !self.placed.is_empty()
    }

    fn trace_hits(&self, rays: &[HostRay], hits: &mut [HostHit], insts: Option<&mut [u32]>) {
        let Some(scene) = self.scene else {
            hits.fill(HostHit::MISS);
            if let Some(insts) = insts {
                insts.fill(lumagraph_scene::NO_INSTANCE);
            }
            return;
        };
        let scene = Scene(scene.as_ptr());
        let chunk = self.tuning.chunk;
        let mut insts = insts;
        let tasks: Vec<_> = rays
            .chunks(chunk)
            .zip(hits.chunks_mut(chunk))
            .map(|(r, h)| {
                let i = insts.as_mut().map(|all| {
                    let (this, rest) = std::mem::take(all).split_at_mut(r.len());
                    *all = rest;
                    this
                });
                (r, h, i)
            })
            .collect();
        tasks.into_par_iter().for_each(|(rays, hits, mut insts)| {
            let mut out = Hits {
                hits,
                insts: insts.as_deref_mut(),
            };
            match self.tuning.packet {
                0 => self.intersect_stream(scene, rays, &mut out),
                8 => self.intersect_packets::<8>(scene, rays, &mut out, self.embree.api.intersect8),
                16 => {
                    self.intersect_packets::<16>(
                        scene,
                        rays,
                        &mut out,
                        self.embree.api.intersect16,
                    );
                }
                _ => self.intersect_single(scene, rays, &mut out),
            }
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

    /// The context of a query over `rays` (a ray's `id` is its index there: the any-hit
    /// filter reads the ray as given, in world space, whichever instance it is in).
    fn context(&self, rays: &[HostRay]) -> QueryContext {
        QueryContext {
            base: RtcIntersectContext::new(self.tuning.coherent),
            rays: rays.as_ptr(),
            len: rays.len(),
        }
    }

    /// The hit Embree reported, as the path tracer's: its triangle in the path tracer's
    /// order and its instance's node slot (or `NO_INSTANCE`).
    fn hit(&self, tfar: f32, u: f32, v: f32, ids: [u32; 3]) -> (HostHit, u32) {
        let [prim_id, geom_id, inst_id] = ids;
        if geom_id == RTC_INVALID_GEOMETRY_ID {
            return (HostHit::MISS, lumagraph_scene::NO_INSTANCE);
        }
        let (base, inst) = match self.placed.get(inst_id as usize) {
            Some(&[base, slot]) => (base, slot),
            None => (0, lumagraph_scene::NO_INSTANCE),
        };
        (
            HostHit {
                t: tfar,
                u,
                v,
                prim: base + prim_id,
            },
            inst,
        )
    }

    fn intersect_single(&self, scene: Scene, rays: &[HostRay], out: &mut Hits<'_>) {
        let mut ctx = self.context(rays);
        for (j, ray) in rays.iter().enumerate() {
            if !ray.is_active() {
                out.set(j, (HostHit::MISS, lumagraph_scene::NO_INSTANCE));
                continue;
            }
            let mut rh = RtcRayHit {
                ray: rtc_ray(ray, j),
                hit: NO_HIT,
            };
            // SAFETY: `scene` is committed and outlives the call; `ctx` and `rh` are
            // initialized as the headers require (16-byte aligned, valid segment, geomID
            // and instID invalid, flags 0); `ctx`'s rays are `rays`.
            unsafe { (self.embree.api.intersect1)(scene.0, &raw mut ctx.base, &raw mut rh) };
            let h = &rh.hit;
            out.set(
                j,
                self.hit(rh.ray.tfar, h.u, h.v, [h.prim_id, h.geom_id, h.inst_id[0]]),
            );
        }
    }

    fn occluded_single(&self, scene: Scene, rays: &[HostRay], out: &mut [u32]) {
        let mut ctx = self.context(rays);
        for (j, (ray, out)) in rays.iter().zip(out).enumerate() {
            if !ray.is_active() {
                *out = 0;
                continue;
            }
            let mut r = rtc_ray(ray, j);
            // SAFETY: as in `intersect_single`; Embree sets `tfar` to -inf on a hit.
            unsafe { (self.embree.api.occluded1)(scene.0, &raw mut ctx.base, &raw mut r) };
            *out = u32::from(r.tfar == f32::NEG_INFINITY);
        }
    }

    fn intersect_stream(&self, scene: Scene, rays: &[HostRay], out: &mut Hits<'_>) {
        let mut ctx = self.context(rays);
        let mut stream = [EMPTY_RAY_HIT; STREAM];
        for (s0, rays) in (0..).step_by(STREAM).zip(rays.chunks(STREAM)) {
            let stream = &mut stream[..rays.len()];
            for (k, (s, r)) in stream.iter_mut().zip(rays).enumerate() {
                *s = stream_ray(r, s0 + k);
            }
            // SAFETY: `stream` holds `rays.len()` (at most `STREAM`) 16-byte aligned
            // ray/hits set up as for `rtcIntersect1`, inactive ones with tnear > tfar as
            // the API defines; `scene` is committed; the rays' ids index `ctx`'s rays.
            unsafe {
                (self.embree.api.intersect1m)(
                    scene.0,
                    &raw mut ctx.base,
                    stream.as_mut_ptr(),
                    stream.len() as u32,
                    std::mem::size_of::<RtcRayHit>(),
                );
            }
            for (k, rh) in stream.iter().enumerate() {
                let h = &rh.hit;
                out.set(
                    s0 + k,
                    self.hit(rh.ray.tfar, h.u, h.v, [h.prim_id, h.geom_id, h.inst_id[0]]),
                );
            }
        }
    }

    fn occluded_stream(&self, scene: Scene, rays: &[HostRay], out: &mut [u32]) {
        let mut ctx = self.context(rays);
        let mut stream = [EMPTY_RAY_HIT; STREAM];
        for (s0, (rays, out)) in (0..)
            .step_by(STREAM)
            .zip(rays.chunks(STREAM).zip(out.chunks_mut(STREAM)))
        {
            let stream = &mut stream[..rays.len()];
            for (k, (s, r)) in stream.iter_mut().zip(rays).enumerate() {
                *s = stream_ray(r, s0 + k);
            }
            // SAFETY: as in `intersect_stream`; the stride steps over the hit halves, which
            // `rtcOccluded1M` does not touch.
            unsafe {
                (self.embree.api.occluded1m)(
                    scene.0,
                    &raw mut ctx.base,
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
        out: &mut Hits<'_>,
        f: PacketFn<N>,
    ) {
        let mut ctx = self.context(rays);
        for (p0, chunk) in (0..).step_by(N).zip(rays.chunks(N)) {
            let (valid, mut packet) = packet::<N>(chunk, p0);
            if valid.0.iter().any(|&v| v != 0) {
                // SAFETY: `packet` and `valid` are 64-byte aligned, active lanes initialized
                // as for `rtcIntersect1`; `scene` is committed; the lanes' ids index `ctx`'s
                // rays.
                unsafe {
                    f(
                        &raw const valid,
                        scene.0,
                        &raw mut ctx.base,
                        &raw mut packet,
                    );
                };
            }
            for i in 0..chunk.len() {
                let hit = if valid.0[i] == 0 {
                    (HostHit::MISS, lumagraph_scene::NO_INSTANCE)
                } else {
                    self.hit(
                        packet.tfar[i],
                        packet.u[i],
                        packet.v[i],
                        [packet.prim_id[i], packet.geom_id[i], packet.inst_id[i]],
                    )
                };
                out.set(p0 + i, hit);
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
        let mut ctx = self.context(rays);
        for (p0, (chunk, out)) in (0..).step_by(N).zip(rays.chunks(N).zip(out.chunks_mut(N))) {
            let (valid, mut packet) = packet::<N>(chunk, p0);
            if valid.0.iter().all(|&v| v == 0) {
                out.fill(0);
                continue;
            }
            // SAFETY: as in `intersect_packets`; `rtcOccludedN` reads the ray half.
            unsafe {
                f(
                    &raw const valid,
                    scene.0,
                    &raw mut ctx.base,
                    &raw mut packet,
                );
            };
            for (i, out) in out.iter_mut().enumerate() {
                *out = u32::from(valid.0[i] != 0 && packet.tfar[i] == f32::NEG_INFINITY);
            }
        }
    }
}

/// Where a chunk's hits go: each ray's hit, and its instance where asked.
struct Hits<'a> {
    hits: &'a mut [HostHit],
    insts: Option<&'a mut [u32]>,
}

impl Hits<'_> {
    fn set(&mut self, j: usize, (hit, inst): (HostHit, u32)) {
        self.hits[j] = hit;
        if let Some(insts) = self.insts.as_deref_mut() {
            insts[j] = inst;
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

/// An active ray as Embree's (`tnear` clamped to 0, mask all ones, flags 0), its `id` its
/// index `j` in the query's rays.
fn rtc_ray(r: &HostRay, j: usize) -> RtcRay {
    RtcRay {
        org: r.origin,
        tnear: r.tnear.max(0.0),
        dir: r.dir,
        time: 0.0,
        tfar: r.tfar,
        mask: u32::MAX,
        id: j as u32,
        flags: 0,
    }
}

/// A ray for `rtcIntersect1M`/`rtcOccluded1M`: inactive ones get `tnear` > `tfar`.
fn stream_ray(r: &HostRay, j: usize) -> RtcRayHit {
    if r.is_active() {
        RtcRayHit {
            ray: rtc_ray(r, j),
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

/// Up to `N` rays as a packet and its valid mask (missing and inactive lanes off), their ids
/// their indices from `first` on.
fn packet<const N: usize>(rays: &[HostRay], first: usize) -> (ValidN<N>, RtcRayHitN<N>) {
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
        p.id[i] = (first + i) as u32;
    }
    (valid, p)
}

/// Why an intersector that takes flat scenes only refuses `scene` (it has instances).
pub(crate) fn flat_only(what: &str, scene: &lumagraph_scene::GpuScene) -> String {
    format!(
        "{what} takes flat scenes only, and this one has {} instances (the binary BVH and \
         host intersection trace them; `instancing: Off` in the scene file copies them)",
        scene.instances.len()
    )
}
