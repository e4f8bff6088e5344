//! [`EmbreeScene`]: one committed Embree scene holding the mesh as one triangle geometry, behind
//! the `Accel` trait.

use crate::device::Device;
use crate::error::{EmbreeError, InvalidRay};
use crate::params::EmbreeParams;
use crate::rays::{PreparedEmbreeRays, ValidRay, hit_of, occluded_of};
use raybench_accel::{Accel, BuildError, BuildStats, Hit, Memory, PointHit, PreparedRays};
use raybench_embree_sys::{self as sys, intersect_context};
use raybench_geom::{Ray, RayError, TriangleMesh, Vec3};
use std::ffi::c_void;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Sole owner of an `RTCScene`; releases it on drop.
#[derive(Debug)]
struct OwnedScene(sys::RTCScene);

impl Drop for OwnedScene {
    fn drop(&mut self) {
        // SAFETY: the handle came from rtcNewScene and this is its only owner, releasing the
        // one reference it holds. The scene's device is still alive: `EmbreeScene` drops this
        // field before its `Arc<Device>`.
        unsafe { sys::rtcReleaseScene(self.0) };
    }
}

/// Sole owner of an `RTCGeometry` until it is attached; the scene keeps its own reference.
#[derive(Debug)]
struct OwnedGeometry(sys::RTCGeometry);

impl Drop for OwnedGeometry {
    fn drop(&mut self) {
        // SAFETY: the handle came from rtcNewGeometry and this is its only owner; a scene it is
        // attached to holds a separate reference, so releasing ours is the documented pattern.
        unsafe { sys::rtcReleaseGeometry(self.0) };
    }
}

/// An Embree scene over one [`TriangleMesh`], built with [`EmbreeParams`].
///
/// The mesh is copied into Embree-owned buffers (`rtcSetNewGeometryBuffer`), so Embree's
/// padding rules are its own business; the `Arc<TriangleMesh>` is kept for callers. An empty
/// mesh gets no geometry at all, and every ray misses.
///
/// Queries never pass an unchecked ray to Embree: `intersect`/`occluded` answer miss for a ray
/// `Ray::check` rejects, `try_*` return the reason, and prepared batches are checked when
/// prepared.
#[derive(Debug)]
pub struct EmbreeScene {
    /// Declared first so it is released before the device below.
    scene: OwnedScene,
    device: Arc<Device>,
    mesh: Arc<TriangleMesh>,
    params: EmbreeParams,
    name: String,
    commit_time: Duration,
    /// Device memory-monitor change across rtcCommitScene: the BVH Embree keeps.
    commit_bytes: i64,
    /// Device memory-monitor change while the geometry buffers were filled.
    buffer_bytes: i64,
}

// SAFETY: a committed scene is never modified again, and Embree allows rtcIntersect1 and
// rtcOccluded1 on one committed scene from any number of threads at once (rtcIntersect1(3);
// RenderKit/embree#207). Building happens in `build` before the value exists; dropping
// happens with exclusive access. So moving it between threads and sharing `&EmbreeScene` is
// sound. The same holds for rtcPointQuery, which only reads the committed scene (each query
// has its own query, context and callback state; rtcPointQuery(3) even allows nested calls).
// The other fields are Send + Sync on their own.
unsafe impl Send for OwnedScene {}
// SAFETY: see `Send` above: through `&OwnedScene` only ray and point queries on the committed
// scene run.
unsafe impl Sync for OwnedScene {}

impl EmbreeScene {
    /// Builds on a given device instead of `Device::shared(&params.config_string())`.
    /// The device's own config then decides threads and ISA; `params.threads`/`params.isa`
    /// only name the result.
    pub fn build_on(
        device: Arc<Device>,
        mesh: Arc<TriangleMesh>,
        params: &EmbreeParams,
    ) -> Result<EmbreeScene, EmbreeError> {
        device.set_memory_limit(params.memory_limit_bytes);
        let built = Self::commit(&device, &mesh, params);
        let refused = device.refused_at();
        device.set_memory_limit(None);
        let (scene, commit_time, buffer_bytes, commit_bytes) = match (built, refused) {
            (Err(_), Some(reached_bytes)) => {
                return Err(EmbreeError::MemoryLimit {
                    reached_bytes,
                    limit_bytes: params.memory_limit_bytes.unwrap_or(u64::MAX),
                });
            }
            (built, _) => built?,
        };
        Ok(EmbreeScene {
            scene,
            name: params.name(),
            params: params.clone(),
            commit_time,
            commit_bytes,
            buffer_bytes,
            device,
            mesh,
        })
    }

    /// The scene with `mesh` attached and committed; its commit time, and the bytes its
    /// buffers and its commit took on the device.
    fn commit(
        device: &Device,
        mesh: &TriangleMesh,
        params: &EmbreeParams,
    ) -> Result<(OwnedScene, Duration, i64, i64), EmbreeError> {
        let scene = new_scene(device, params)?;
        let before_buffers = device.allocated_bytes();
        if !mesh.is_empty() {
            attach_triangles(device, &scene, mesh)?;
        }
        let before_commit = device.allocated_bytes();
        let start = Instant::now();
        // SAFETY: the scene is live, configured and fully attached; no other thread knows it.
        unsafe { sys::rtcCommitScene(scene.0) };
        let commit_time = start.elapsed();
        device.check("rtcCommitScene")?;
        let after_commit = device.allocated_bytes();
        Ok((
            scene,
            commit_time,
            before_commit - before_buffers,
            after_commit - before_commit,
        ))
    }

    /// Closest hit, or why the ray may not be traced.
    pub fn try_intersect(&self, ray: &Ray) -> Result<Option<Hit>, RayError> {
        Ok(self.intersect_valid(ValidRay::new(ray)?))
    }

    /// Any hit, or why the ray may not be traced.
    pub fn try_occluded(&self, ray: &Ray) -> Result<bool, RayError> {
        Ok(self.occluded_valid(ValidRay::new(ray)?))
    }

    /// Checks and converts a batch; unlike `Accel::prepare_rays` the error says which ray.
    pub fn prepare_checked(&self, rays: &[Ray]) -> Result<PreparedEmbreeRays, InvalidRay> {
        PreparedEmbreeRays::new(rays)
    }

    pub fn device(&self) -> &Arc<Device> {
        &self.device
    }

    pub fn mesh(&self) -> &Arc<TriangleMesh> {
        &self.mesh
    }

    pub fn params(&self) -> &EmbreeParams {
        &self.params
    }

    /// Wall time of `rtcCommitScene` alone (the BVH build).
    pub fn commit_time(&self) -> Duration {
        self.commit_time
    }

    #[inline(always)]
    fn intersect_valid(&self, ray: ValidRay) -> Option<Hit> {
        let mut rh = ray.ray_hit();
        let mut context = intersect_context();
        // SAFETY: the scene is committed and alive; `rh` is a 16-byte-aligned local built from
        // a ray that passed `Ray::check` (the only way to get a `ValidRay`), so Embree's
        // asserts on invalid rays cannot fire; `context` is initialised as the header's
        // rtcInitIntersectContext does.
        unsafe { sys::rtcIntersect1(self.scene.0, &mut context, &mut rh) };
        hit_of(&rh)
    }

    #[inline(always)]
    fn occluded_valid(&self, ray: ValidRay) -> bool {
        let mut r = ray.ray_hit().ray;
        let mut context = intersect_context();
        // SAFETY: as in `intersect_valid`, with the ray part of the checked `RTCRayHit`.
        unsafe { sys::rtcOccluded1(self.scene.0, &mut context, &mut r) };
        occluded_of(&r)
    }
}

/// Rays per `rtcIntersect1M` call: 64 (four of Embree's AVX-512 packets) keeps
/// the copy on the stack (5 KiB) while the call's fixed cost is shared by many rays.
const STREAM: usize = 64;

impl EmbreeScene {
    /// A coherent batch through Embree's stream API, [`STREAM`] rays a call: the checked rays
    /// are copied to a local array (the call writes its answers into the rays).
    fn intersect_stream(&self, batch: &[ValidRay], out: &mut [Option<Hit>]) {
        let Some(first) = batch.first() else {
            return;
        };
        let mut stream = [first.ray_hit(); STREAM];
        for (rays, out) in batch.chunks(STREAM).zip(out.chunks_mut(STREAM)) {
            for (s, r) in stream.iter_mut().zip(rays) {
                *s = r.ray_hit();
            }
            let mut context = coherent_context();
            // SAFETY: the scene is committed and alive; `stream` holds `rays.len()` (at most
            // STREAM) 16-byte-aligned RTCRayHits, each built from a ray that passed
            // `Ray::check`, laid out `size_of::<RTCRayHit>()` bytes apart; `context` is
            // initialised as rtcInitIntersectContext does, with the coherent flag.
            unsafe {
                sys::rtcIntersect1M(
                    self.scene.0,
                    &mut context,
                    stream.as_mut_ptr(),
                    rays.len() as u32,
                    std::mem::size_of::<sys::RTCRayHit>(),
                )
            };
            for (o, s) in out.iter_mut().zip(&stream) {
                *o = hit_of(s);
            }
        }
    }
}

/// [`intersect_context`] with `RTC_INTERSECT_CONTEXT_FLAG_COHERENT`.
fn coherent_context() -> sys::RTCIntersectContext {
    sys::RTCIntersectContext {
        flags: sys::RTCIntersectContextFlags::RTC_INTERSECT_CONTEXT_FLAG_COHERENT,
        ..intersect_context()
    }
}

fn new_scene(device: &Device, params: &EmbreeParams) -> Result<OwnedScene, EmbreeError> {
    // SAFETY: the device is live; a null result is checked below.
    let raw = unsafe { sys::rtcNewScene(device.raw()) };
    if raw.is_null() {
        device.check("rtcNewScene")?;
        return Err(api_error("rtcNewScene", "returned no scene"));
    }
    let scene = OwnedScene(raw);
    let flags = if params.robust {
        sys::RTCSceneFlags::RTC_SCENE_FLAG_ROBUST
    } else {
        sys::RTCSceneFlags::RTC_SCENE_FLAG_NONE
    };
    // SAFETY: the scene is live and not yet shared; flags and quality are valid enum values.
    unsafe {
        sys::rtcSetSceneFlags(scene.0, flags);
        sys::rtcSetSceneBuildQuality(scene.0, params.quality.to_rtc());
    }
    device.check("rtcSetSceneFlags/rtcSetSceneBuildQuality")?;
    Ok(scene)
}

/// Copies the mesh into one triangle geometry and attaches it to `scene`.
fn attach_triangles(
    device: &Device,
    scene: &OwnedScene,
    mesh: &TriangleMesh,
) -> Result<(), EmbreeError> {
    let triangle = sys::RTCGeometryType::RTC_GEOMETRY_TYPE_TRIANGLE;
    // SAFETY: the device is live; a null result is checked below.
    let raw = unsafe { sys::rtcNewGeometry(device.raw(), triangle) };
    if raw.is_null() {
        device.check("rtcNewGeometry")?;
        return Err(api_error("rtcNewGeometry", "returned no geometry"));
    }
    let geometry = OwnedGeometry(raw);
    let vertices = mesh.positions().iter().map(|p| p.to_array());
    let vertex = (
        sys::RTCBufferType::RTC_BUFFER_TYPE_VERTEX,
        sys::RTCFormat::RTC_FORMAT_FLOAT3,
    );
    fill_new_buffer(device, &geometry, vertex, vertices)?;
    let index = (
        sys::RTCBufferType::RTC_BUFFER_TYPE_INDEX,
        sys::RTCFormat::RTC_FORMAT_UINT3,
    );
    fill_new_buffer(device, &geometry, index, mesh.indices().iter().copied())?;
    // SAFETY: the geometry is live and has both buffers; the scene is live and not yet shared.
    unsafe {
        sys::rtcCommitGeometry(geometry.0);
        sys::rtcAttachGeometry(scene.0, geometry.0);
    }
    device.check("rtcCommitGeometry/rtcAttachGeometry")
    // `geometry` is released here; the scene holds its own reference.
}

/// Allocates an Embree-owned buffer of `items.len()` elements of `T` (whose size must be the
/// format's: 12 bytes for FLOAT3 and UINT3) and writes `items` into it.
fn fill_new_buffer<T: Copy>(
    device: &Device,
    geometry: &OwnedGeometry,
    (kind, format): (sys::RTCBufferType, sys::RTCFormat),
    items: impl ExactSizeIterator<Item = T>,
) -> Result<(), EmbreeError> {
    let count = items.len();
    let stride = size_of::<T>();
    // SAFETY: the geometry is live; Embree allocates `count * stride` bytes (plus its own
    // padding) and returns null on failure, checked below.
    let buffer: *mut c_void =
        unsafe { sys::rtcSetNewGeometryBuffer(geometry.0, kind, 0, format, stride, count) };
    if buffer.is_null() {
        device.check("rtcSetNewGeometryBuffer")?;
        return Err(api_error("rtcSetNewGeometryBuffer", "returned no buffer"));
    }
    let buffer = buffer.cast::<T>();
    for (i, item) in items.enumerate().take(count) {
        // SAFETY: `i < count`, so the write is inside the buffer Embree just allocated for
        // `count` items of `stride = size_of::<T>()` bytes; unaligned writes need no alignment
        // promise from Embree's allocator.
        unsafe { buffer.add(i).write_unaligned(item) };
    }
    Ok(())
}

fn api_error(operation: &'static str, message: &str) -> EmbreeError {
    EmbreeError::Api {
        operation,
        code: "no error code",
        message: message.to_string(),
    }
}

/// The prepared batch inside `prepared`; anything else is a caller bug (rays prepared by
/// another structure), reported loudly rather than traced unchecked.
fn prepared_batch(prepared: &PreparedRays) -> &PreparedEmbreeRays {
    match prepared {
        PreparedRays::Foreign(any) => any
            .downcast_ref::<PreparedEmbreeRays>()
            .expect("rays were prepared by a structure other than EmbreeScene"),
        PreparedRays::Native => panic!("EmbreeScene needs rays from its own prepare_rays"),
    }
}

impl Accel for EmbreeScene {
    type Params = EmbreeParams;

    fn build(mesh: Arc<TriangleMesh>, params: &EmbreeParams) -> Result<Self, BuildError> {
        params.check_isa().map_err(BuildError::Unsupported)?;
        let device = Device::shared(&params.config_string())?;
        Ok(EmbreeScene::build_on(device, mesh, params)?)
    }

    fn name(&self) -> &str {
        &self.name
    }

    // Embree's work cannot be counted: same answers, counters untouched.
    raybench_accel::uncounted_queries!();

    /// A ray `Ray::check` rejects is reported as a miss (see [`EmbreeScene::try_intersect`]).
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.try_intersect(ray).unwrap_or(None)
    }

    /// A ray `Ray::check` rejects is reported as unoccluded (see [`EmbreeScene::try_occluded`]).
    fn occluded(&self, ray: &Ray) -> bool {
        self.try_occluded(ray).unwrap_or(false)
    }

    /// `rtcPointQuery` with a callback computing the same point–triangle distance as every
    /// other structure (see `point.rs`). A query with no answer by definition (non-finite or
    /// huge point, negative or NaN radius) returns `None` without reaching Embree.
    fn closest_point(&self, p: Vec3, max_radius: f32) -> Option<PointHit> {
        // SAFETY: `self.scene` is committed and alive for as long as `self`, and `build_on`
        // attached exactly `self.mesh`'s triangles in order as its only geometry (none when
        // the mesh is empty).
        unsafe { crate::point::closest_point(self.scene.0, &self.mesh, p, max_radius) }
    }

    /// Embree does not expose its tree's shape: only timing and settings are reported.
    fn build_stats(&self) -> BuildStats {
        let mut stats = BuildStats::default();
        let extra = [
            ("commit_ms", self.commit_time.as_secs_f64() * 1e3),
            ("quality", self.params.quality.to_rtc().0 as f64),
            ("robust", f64::from(u8::from(self.params.robust))),
            ("buffer_bytes", self.buffer_bytes as f64),
        ];
        stats
            .extra
            .extend(extra.map(|(key, value)| (key.to_string(), value)));
        stats
    }

    /// `nodes`: what the device's memory monitor counted across `rtcCommitScene` (the whole
    /// BVH, leaves with their triangle copies included). Exact only when no other build ran on
    /// the same device meanwhile (see [`Device`]).
    fn memory(&self) -> Memory {
        Memory {
            nodes: self.commit_bytes.max(0) as u64,
            ..Memory::default()
        }
    }

    fn prepare_rays(&self, rays: &[Ray]) -> Result<PreparedRays, RayError> {
        let batch = self.prepare_checked(rays).map_err(|bad| bad.error)?;
        Ok(PreparedRays::Foreign(Box::new(batch)))
    }

    fn prepare_coherent_rays(&self, rays: &[Ray]) -> Result<PreparedRays, RayError> {
        let batch = self.prepare_checked(rays).map_err(|bad| bad.error)?;
        let batch = if self.params.coherent_packet16 {
            batch.with_packets16()
        } else {
            batch.coherent(self.params.coherent_stream)
        };
        Ok(PreparedRays::Foreign(Box::new(batch)))
    }

    fn intersect_prepared(
        &self,
        _rays: &[Ray],
        prepared: &PreparedRays,
        first: usize,
        out: &mut [Option<Hit>],
    ) {
        let prepared = prepared_batch(prepared);
        if let Some(packets) = prepared.packets16().and_then(|p| p.range(first, out.len())) {
            // SAFETY: `self.scene` is committed and alive for as long as `self`.
            return unsafe { crate::packet16::intersect16(self.scene.0, packets, out) };
        }
        let batch = prepared.slice(first, out.len());
        if prepared.is_coherent() {
            return self.intersect_stream(batch, out);
        }
        for (o, &ray) in out.iter_mut().zip(batch) {
            *o = self.intersect_valid(ray);
        }
    }

    fn occluded_prepared(
        &self,
        _rays: &[Ray],
        prepared: &PreparedRays,
        first: usize,
        out: &mut [bool],
    ) {
        let prepared = prepared_batch(prepared);
        if self.params.coherent_occluded16
            && let Some(packets) = prepared.packets16().and_then(|p| p.range(first, out.len()))
        {
            // SAFETY: `self.scene` is committed and alive for as long as `self`.
            return unsafe { crate::packet16::occluded16(self.scene.0, packets, out) };
        }
        // Coherent any-hit batches otherwise go ray by ray: through rtcOccluded1M and
        // rtcOccluded16, rays lying in a triangle's plane were reported occluded, which
        // rtcOccluded1 and brute force do not report (docs/validation.md, E11).
        let batch = prepared.slice(first, out.len());
        for (o, &ray) in out.iter_mut().zip(batch) {
            *o = self.occluded_valid(ray);
        }
    }
}
