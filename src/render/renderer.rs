//! GPU resources for one scene and the recorded frame.
//!
//! Data flows one way: `Scene` → `SceneGeometry` (meshes, built once) →
//! `FramePlan` (the frame as data) → the attachments and render pass the
//! plan declares, the shared scene resources, and one object per pass →
//! one command buffer recorded once → submitted per frame → images read
//! back.

use super::geometry::SceneGeometry;
use super::passes::{
    atmosphere, bloom, exposure, Attachments, PassResources, PassSetup, RecordPass,
};
use super::plan::{attachment, FramePlan, PassDecl, PassIo};
use super::scene_resources::SceneResources;
use super::shadow_resources::ShadowResources;
use super::sky_resources::SkyResources;
use super::timed_submit::TimedCommands;
use super::RenderError;
use crate::image_io::Pixels;
use crate::scene::{HdrFormat, Scene, ToneMap};
use crate::vk::{
    AttachmentSpec, AttachmentStart, Buffer, BufferUsage, Context, Format, FrameTargets, Image,
    ImageAspectFlags, ImageDesc, ImageUsageFlags, RunSpec, SubpassSpec,
};
use std::sync::Arc;

/// What the passes share, each present when the plan needs it. Fields
/// drop in order: the resources before the attachments.
struct FrameParts {
    scene_resources: Option<SceneResources>,
    sky_resources: Option<SkyResources>,
    /// The exposure the exposure pass measures and the tone map applies,
    /// when the scene asks for automatic exposure.
    exposure: Option<Buffer>,
    /// The shadow pass's and the shadow lookups' shared resources, when a
    /// light casts shadows.
    shadow_resources: Option<ShadowResources>,
    /// The bloom chain the bloom pass writes and the tone map samples,
    /// when the scene asks for bloom.
    bloom: Option<Image>,
    targets: Option<FrameTargets>,
}

impl FrameParts {
    /// What the passes of `plan` record against.
    fn pass_resources(&self, plan: &FramePlan) -> PassResources<'_> {
        PassResources {
            attachments: Attachments {
                names: plan.attachments.iter().map(|a| a.name).collect(),
                images: self.targets.as_ref().map_or(&[], |t| t.images.as_slice()),
            },
            scene: self.scene_resources.as_ref(),
            sky: self.sky_resources.as_ref(),
            exposure: self.exposure.as_ref(),
            shadow: self.shadow_resources.as_ref(),
            bloom: self.bloom.as_ref(),
        }
    }
}

/// Timing of one submitted frame.
#[derive(Clone, Debug)]
pub struct FrameTiming {
    /// GPU time per pass (in `FramePlan::passes` order), in milliseconds;
    /// empty when the device has no timestamps.
    pub pass_ms: Vec<f64>,
    /// CPU time from submit to fence signalled, in milliseconds.
    pub cpu_ms: f64,
    /// Pipeline statistics per pass (in `FramePlan::passes` order); empty
    /// unless the context counts them.
    pub work: Vec<crate::vk::PipelineStats>,
}

/// What [`Renderer::set_view`] had to do for the new view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewChange {
    /// The frame plan stayed the same: only the view-dependent uniforms
    /// (camera, sun) were rewritten; the recorded frame is replayed as is.
    Updated,
    /// The draw order changed with the view (front-to-back opaque draws,
    /// back-to-front transparent ones): the uniforms were rewritten and the
    /// frame recorded again with the same pipelines and resources.
    Recorded,
    /// The plan changed with the view (deferred light tiles, size): the
    /// frame was built and recorded again from the scene's geometry.
    Rebuilt,
}

/// Everything on the GPU for one scene. Fields drop in declaration order:
/// the command buffer first, then the passes, the resources they use, the
/// attachments, and the context (inside each wrapper) last.
pub struct Renderer {
    frame: TimedCommands,
    /// The CPU time recording `frame` took, in seconds.
    record_seconds: f64,
    /// The frame's prefixes, recorded on first use by
    /// `PrefixFrames::render_prefix`: element k records the first k passes.
    prefixes: Vec<TimedCommands>,
    passes: Vec<Box<dyn RecordPass>>,
    parts: FrameParts,
    plan: FramePlan,
    /// The scene's meshes, kept so that a new view can be planned (and,
    /// when the plan changes, built) without tessellating again; `None`
    /// for a renderer that only tone-maps an image.
    geometry: Option<Arc<SceneGeometry>>,
    keep_hdr: bool,
    ctx: Arc<Context>,
}

impl Renderer {
    /// The renderer for `scene`; `keep_hdr` reads back the linear HDR
    /// image as well as the tone-mapped output.
    pub fn new(ctx: &Arc<Context>, scene: &Scene, keep_hdr: bool) -> Result<Renderer, RenderError> {
        Renderer::with_geometry(ctx, scene, Arc::new(SceneGeometry::new(scene)?), keep_hdr)
    }

    /// The renderer for `scene` after the device checks (texture and
    /// attachment sizes against the device's limits, see
    /// `preflight::scene_on_device`): the one way `render`, `bench`,
    /// `sweep` and the viewer build one. `geometry`, when given, must be
    /// `SceneGeometry::new(scene)` (the viewer keeps it across rebuilds).
    /// The memory budget is checked before the device exists, with
    /// `preflight::scene_fits`.
    pub fn prepare(
        ctx: &Arc<Context>,
        scene: &Scene,
        geometry: Option<Arc<SceneGeometry>>,
        keep_hdr: bool,
    ) -> Result<Renderer, RenderError> {
        super::preflight::scene_on_device(scene, ctx)?;
        let geometry = match geometry {
            Some(g) => g,
            None => Arc::new(SceneGeometry::new(scene)?),
        };
        Renderer::with_geometry(ctx, scene, geometry, keep_hdr)
    }

    /// [`Renderer::new`] with the scene's meshes already built (they must
    /// be `SceneGeometry::new(scene)`), for callers that use them too.
    pub fn with_geometry(
        ctx: &Arc<Context>,
        scene: &Scene,
        geometry: Arc<SceneGeometry>,
        keep_hdr: bool,
    ) -> Result<Renderer, RenderError> {
        let plan = FramePlan::new(scene, &geometry, keep_hdr);
        Renderer::build(ctx, scene, Some(geometry), plan, None, keep_hdr)
    }

    /// A renderer that tone-maps `image` (linear RGBA, any values,
    /// including Inf, NaN and negatives) with the scene's tone-map subpass.
    pub fn for_hdr_image(
        ctx: &Arc<Context>,
        tone_map: ToneMap,
        image: &Pixels<f32>,
    ) -> Result<Renderer, RenderError> {
        let expected = image.width as usize * image.height as usize * 4;
        if image.width == 0 || image.height == 0 || image.data.len() != expected {
            return Err(RenderError::InvalidImage(format!(
                "{}x{} RGBA needs {expected} values, got {}",
                image.width,
                image.height,
                image.data.len()
            )));
        }
        let plan = FramePlan::for_hdr_image(image.width, image.height, true);
        let scene = Scene::empty(tone_map, image.width, image.height);
        Renderer::build(ctx, &scene, None, plan, Some(image), true)
    }

    fn build(
        ctx: &Arc<Context>,
        scene: &Scene,
        geometry: Option<Arc<SceneGeometry>>,
        plan: FramePlan,
        hdr_input: Option<&Pixels<f32>>,
        keep_hdr: bool,
    ) -> Result<Renderer, RenderError> {
        // Safe points between the long phases (uploads, the sky's table,
        // pipeline creation), so an interrupt does not wait for all of them.
        crate::interrupt::check()?;
        let targets = build_targets(ctx, &plan)?;
        // One float, written by the exposure pass each frame.
        let exposure = if plan.has(exposure::PASS) {
            let size = std::mem::size_of::<super::gpu_types::ExposureBlock>() as u64;
            Some(Buffer::new(ctx, "exposure", size, BufferUsage::Storage)?)
        } else {
            None
        };
        let bloom = bloom_image(ctx, scene, &plan)?;
        crate::interrupt::check()?;
        // The sky's resources first: objects lit by the atmosphere bind
        // its set.
        let sky_resources = match &scene.sky {
            Some(sky) if plan.has(atmosphere::PASS) => {
                Some(SkyResources::new(ctx, sky, &scene.camera, &plan)?)
            }
            _ => None,
        };
        // The shadow set first too: the object pipelines' layout holds it.
        let shadow_map = plan
            .attachments
            .iter()
            .position(|a| a.name == attachment::SHADOW_MAP);
        let shadow_resources = match (&targets, shadow_map, &plan.shadow) {
            (Some(targets), Some(map), Some(_)) => Some(ShadowResources::new(
                ctx,
                scene,
                &plan,
                &targets.images[map],
            )?),
            _ => None,
        };
        let scene_resources = if plan.draws().next().is_some() {
            let geometry = geometry.as_deref().ok_or_else(|| {
                RenderError::Frame("the plan draws objects but there is no geometry".into())
            })?;
            Some(SceneResources::new(
                ctx,
                scene,
                geometry,
                &plan,
                sky_resources.as_ref(),
                shadow_resources.as_ref().map(|s| &s.layout),
            )?)
        } else {
            None
        };
        crate::interrupt::check()?;
        let parts = FrameParts {
            scene_resources,
            sky_resources,
            exposure,
            shadow_resources,
            bloom,
            targets,
        };
        let frame_resources = parts.pass_resources(&plan);

        // Create every pass, each subpass with its render pass and its
        // index there.
        let mut passes = Vec::with_capacity(plan.passes.len());
        for (decl, slot) in plan.passes.iter().zip(plan.subpass_slots()) {
            crate::interrupt::check()?;
            let setup = PassSetup {
                ctx,
                scene,
                plan: &plan,
                decl,
                render_pass: slot.and_then(|(run, _)| parts.targets.as_ref()?.runs.get(run)),
                subpass: slot.map_or(0, |(_, subpass)| subpass),
                frame: &frame_resources,
                hdr_input,
            };
            passes.push(decl.pass.create(&setup)?);
        }

        drop(frame_resources);
        let recording = std::time::Instant::now();
        let frame = record(ctx, &plan, &passes, &parts, usize::MAX)?;
        let record_seconds = recording.elapsed().as_secs_f64();

        Ok(Renderer {
            frame,
            record_seconds,
            prefixes: Vec::new(),
            passes,
            parts,
            plan,
            geometry,
            keep_hdr,
            ctx: ctx.clone(),
        })
    }

    /// Moves the view to `scene`'s camera and sun, between frames
    /// ([`render_frame`](Self::render_frame) waits for its frame, so nothing
    /// reads the uniforms while they change). `scene` must be the scene
    /// this renderer was built from in everything but the camera, the sun
    /// and the output size: objects, materials, lights and knobs are not
    /// looked at again (build a new renderer for those).
    ///
    /// The frame is planned again for the new view. When the plan is the
    /// same (the usual case: the camera moved a little), only the uniforms
    /// the passes derive from the view are rewritten, by the same code that
    /// wrote them at creation, so the image is the one a new renderer would
    /// give; when only the draw order differs, the frame is also recorded
    /// again. Otherwise it is built again from the kept geometry.
    pub fn set_view(&mut self, scene: &Scene) -> Result<ViewChange, RenderError> {
        let geometry = self.geometry.clone().ok_or_else(|| {
            RenderError::Frame("a renderer of an HDR image has no view to move".into())
        })?;
        let plan = FramePlan::new(scene, &geometry, self.keep_hdr);
        // The atmosphere's pipelines hold its unchanging fields as
        // constants; a sky that changes them needs new pipelines.
        let sky_kept = match (&self.parts.sky_resources, &scene.sky) {
            (Some(resources), Some(sky)) => {
                resources.keeps_static_fields(sky, &scene.camera, &plan)
            }
            (None, None) => true,
            _ => false,
        };
        if sky_kept && same_resources(&self.plan, &plan) {
            if let Some(resources) = &mut self.parts.scene_resources {
                resources.set_view(scene, &plan);
            }
            if let (Some(resources), Some(sky)) = (&mut self.parts.sky_resources, &scene.sky) {
                resources.set_view(sky, &scene.camera, &plan);
            }
            if let Some(resources) = &mut self.parts.shadow_resources {
                resources.set_view(scene, &plan)?;
            }
            for pass in &mut self.passes {
                pass.set_view(scene, &plan)?;
            }
            let change = if same_frame(&self.plan, &plan) {
                ViewChange::Updated
            } else {
                // Only the draw order changed: record the frame again with
                // the same pipelines, buffers and attachments.
                let recording = std::time::Instant::now();
                let frame = record(&self.ctx, &plan, &self.passes, &self.parts, usize::MAX)?;
                self.record_seconds = recording.elapsed().as_secs_f64();
                self.prefixes.clear();
                // The old command buffer is not pending: render_frame
                // waited for it.
                self.frame = frame;
                ViewChange::Recorded
            };
            self.plan = plan;
            return Ok(change);
        }
        let rebuilt = Renderer::build(&self.ctx, scene, Some(geometry), plan, None, self.keep_hdr)?;
        *self = rebuilt;
        Ok(ViewChange::Rebuilt)
    }

    /// The attachment holding the tone-mapped sRGB output
    /// ([`OUTPUT_FORMAT`](super::plan::OUTPUT_FORMAT)); after each frame it
    /// is left in `TRANSFER_SRC_OPTIMAL` by the readback, ready to be copied
    /// to a window.
    pub fn output_image(&self) -> Option<&Image> {
        let index = self
            .plan
            .attachments
            .iter()
            .position(|a| a.name == attachment::OUTPUT)?;
        self.parts.targets.as_ref()?.images.get(index)
    }

    /// What building this frame cost beyond its passes, as named values
    /// for the reports: the CPU time recording its command buffer took
    /// (`record_ms`; the frame is recorded once and submitted as is), the
    /// sizes of the buffers holding the meshes (`geometry_kib`, each
    /// distinct mesh once) and the instanced draws' transforms
    /// (`instances_kib`) when it draws objects, and the optical-depth table's size (`od_table_kib`) and bake time
    /// (`od_table_bake_ms`) when the scene has an atmosphere.
    pub fn setup_measures(&self) -> Vec<(&'static str, f64)> {
        let mut measures = vec![("record_ms", self.record_seconds * 1e3)];
        if let Some(resources) = &self.parts.scene_resources {
            let kib = |bytes: u64| bytes as f64 / 1024.0;
            measures.push(("geometry_kib", kib(resources.geometry.size())));
            let instances = resources.instances.as_ref().map_or(0, |b| b.size());
            measures.push(("instances_kib", kib(instances)));
        }
        if let Some(sky) = &self.parts.sky_resources {
            measures.push(("od_table_kib", sky.table_bytes as f64 / 1024.0));
            measures.push(("od_table_bake_ms", sky.table_bake_seconds * 1e3));
        }
        measures
    }

    pub fn plan(&self) -> &FramePlan {
        &self.plan
    }

    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }

    /// Submits the recorded frame and waits for it.
    pub fn render_frame(&mut self) -> Result<FrameTiming, RenderError> {
        self.frame.submit()
    }

    /// The buffer `attachment` is read back into, if the plan reads it.
    fn readback(&self, attachment: &str) -> Option<&crate::vk::Buffer> {
        self.passes.iter().find_map(|p| p.readback(attachment))
    }

    /// The tone-mapped sRGB output of the last frame.
    pub fn output(&self) -> Pixels<u8> {
        Pixels {
            width: self.plan.width,
            height: self.plan.height,
            data: self
                .readback(attachment::OUTPUT)
                .map(|b| b.read().to_vec())
                .unwrap_or_default(),
        }
    }

    /// The linear HDR image of the last frame (before tone mapping), when
    /// the renderer was created with `keep_hdr`.
    pub fn hdr(&self) -> Option<Pixels<f32>> {
        let buffer = self.readback(attachment::HDR)?;
        let bytes = buffer.read();
        let data = match self.plan.hdr_format {
            HdrFormat::Rgba16F => bytes
                .chunks_exact(2)
                .map(|c| half::f16::from_le_bytes([c[0], c[1]]).to_f32())
                .collect(),
            HdrFormat::Rgba32F => bytes
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
        };
        Some(Pixels {
            width: self.plan.width,
            height: self.plan.height,
            data,
        })
    }
}

impl super::PrefixFrames for Renderer {
    fn pass_count(&self) -> usize {
        self.plan.passes.len()
    }

    /// Submits the frame with only its first `recorded` passes and waits
    /// for it; `recorded` = [`Self::pass_count`] is the whole frame. The
    /// difference between the work of prefixes k+1 and k is the work of
    /// pass k, wherever the driver did it (a CPU driver bins draws and may
    /// rasterise them only at the end of the render pass). The prefixes
    /// are recorded on the first call.
    fn render_prefix(&mut self, recorded: usize) -> Result<FrameTiming, RenderError> {
        if recorded >= self.pass_count() {
            return self.frame.submit();
        }
        if self.prefixes.is_empty() {
            let prefixes = (0..self.pass_count())
                .map(|k| record(&self.ctx, &self.plan, &self.passes, &self.parts, k))
                .collect::<Result<Vec<_>, _>>()?;
            self.prefixes = prefixes;
        }
        self.prefixes[recorded].submit()
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // Nothing may be pending when the resources go; render_frame always
        // waits, but a frame interrupted by an error might not have.
        let _ = self.ctx.wait_idle();
    }
}

/// Records the frame once; every submission replays it. Each render pass
/// begins before its first subpass and ends right after its last, before
/// that pass's closing timestamp.
///
/// Only the first `recorded` passes record their commands; the later ones
/// keep their place (their subpass is still begun, their timestamps still
/// written) but do nothing. A frame of all passes is the frame; the shorter
/// ones are the prefixes whose differences give each pass's instruction
/// count (see `PrefixFrames::render_prefix`).
fn record(
    ctx: &Arc<Context>,
    plan: &FramePlan,
    passes: &[Box<dyn RecordPass>],
    parts: &FrameParts,
    recorded: usize,
) -> Result<TimedCommands, RenderError> {
    let frame_resources = &parts.pass_resources(plan);
    let targets = parts.targets.as_ref();
    let frame = TimedCommands::begin(ctx, plan.passes.len() as u32)?;
    let cmd = frame.cmd();
    let slots = plan.subpass_slots();
    // The render pass begun and not yet ended.
    let mut open: Option<usize> = None;
    for (i, (pass, slot)) in passes.iter().zip(&slots).enumerate() {
        if let (Some((run, _)), Some(t)) = (*slot, targets) {
            if open == Some(run) {
                cmd.next_subpass();
            } else {
                cmd.begin_render_pass(&t.runs[run], &t.images);
                open = Some(run);
            }
        }
        frame.begin_pass();
        if i < recorded {
            pass.record(cmd, frame_resources)?;
        }
        frame.end_pass();
        let next_run = slots.get(i + 1).copied().flatten().map(|(run, _)| run);
        if let (Some(run), Some(t)) = (open, targets) {
            if next_run != Some(run) {
                cmd.end_render_pass(&t.runs[run], &t.images);
                open = None;
            }
        }
        frame.stamp();
    }
    frame.finish()
}

/// The bloom chain, when the plan holds the bloom pass: RGBA16F, sampled
/// and written as a storage image, with one mip level per level of the
/// chain, level 0 a quarter of the output's size.
fn bloom_image(
    ctx: &Arc<Context>,
    scene: &Scene,
    plan: &FramePlan,
) -> Result<Option<Image>, RenderError> {
    if !plan.has(bloom::PASS) {
        return Ok(None);
    }
    let Some(settings) = scene.tone_map.bloom else {
        return Ok(None);
    };
    let (width, height) = bloom::level_size(plan.width, plan.height, 0);
    let desc = ImageDesc {
        width,
        height,
        format: Format::R16G16B16A16_SFLOAT,
        usage: ImageUsageFlags::STORAGE | ImageUsageFlags::SAMPLED,
        mip_levels: settings.chain_levels(plan.width, plan.height),
        aspect: ImageAspectFlags::COLOR,
    };
    Ok(Some(Image::new(ctx, "bloom", desc)?))
}

/// Whether a new view's plan `b` can reuse everything created for `a`:
/// the same attachments and passes at the same size, the same draws (in
/// any order: the order of opaque and transparent draws follows the
/// camera) and the same deferred light tiles. The uniforms may differ.
fn same_resources(a: &FramePlan, b: &FramePlan) -> bool {
    // Every draw, in view or not, without what the view decides.
    let by_object = |plan: &FramePlan| {
        let mut d: Vec<_> = plan.draws().map(super::plan::Draw::without_view).collect();
        d.sort_by_key(|d| d.object);
        d
    };
    a.width == b.width
        && a.height == b.height
        && a.attachments == b.attachments
        && a.pass_names() == b.pass_names()
        && a.instance_slots == b.instance_slots
        && by_object(a) == by_object(b)
        && a.tile_groups == b.tile_groups
        && shadow_casters(a) == shadow_casters(b)
}

/// What the shadow pass draws, without what the view decides: its casters
/// and views.
fn shadow_casters(plan: &FramePlan) -> Option<(Vec<super::plan::Draw>, usize)> {
    plan.shadow.as_ref().map(|s| {
        let casters = s
            .casters
            .iter()
            .map(super::plan::Draw::without_view)
            .collect();
        (casters, s.cascades.len())
    })
}

/// Whether two plans record the same commands: the same resources, and the
/// draws in the same order. The uniforms may still differ.
fn same_frame(a: &FramePlan, b: &FramePlan) -> bool {
    same_resources(a, b) && a.opaque == b.opaque && a.transparent == b.transparent
}

/// The attachments and render passes the plan's subpasses form (see
/// [`FramePlan::subpass_slots`]): what each attachment starts with and
/// whether it is kept are derived from the passes around each render pass
/// (an upload before the first loads the attachment; an earlier render
/// pass using it makes a later one load it; a later render pass or a
/// compute pass sampling it stores it; a readback after the last stores
/// it). `None` when the plan has no subpass. A frame of one render pass is
/// built exactly as it always was.
fn build_targets(
    ctx: &Arc<Context>,
    plan: &FramePlan,
) -> Result<Option<FrameTargets>, RenderError> {
    let slots = plan.subpass_slots();
    let runs = plan.render_pass_count();
    if runs == 0 {
        return Ok(None);
    }
    let io = FrameIo::of(plan, &slots)?;
    let mut subpasses: Vec<Vec<SubpassSpec>> = vec![Vec::new(); runs];
    for (decl, slot) in plan.passes.iter().zip(&slots) {
        if let (PassIo::Subpass { .. }, Some((run, _))) = (&decl.io, slot) {
            subpasses[*run].push(io.subpass(decl)?);
        }
    }
    let used = |run: usize, a: usize| {
        subpasses[run].iter().any(|s| {
            s.colour.contains(&a) || s.inputs.contains(&a) || s.depth.is_some_and(|(d, _)| d == a)
        })
    };
    let run_specs: Vec<RunSpec> = (0..runs)
        .map(|run| {
            let attachments: Vec<usize> = (0..plan.attachments.len())
                .filter(|&a| used(run, a))
                .collect();
            let specs = attachments
                .iter()
                .map(|&a| {
                    let decl = &plan.attachments[a];
                    let earlier = (0..run).any(|r| used(r, a));
                    let later = (run + 1..runs).any(|r| used(r, a));
                    let sampled_after = io.sampled.iter().any(|&(s, r)| s == a && r >= run)
                        || io.sampled_by_runs.iter().any(|&(s, r)| s == a && r > run);
                    AttachmentSpec {
                        name: decl.name,
                        format: decl.format,
                        start: if earlier {
                            AttachmentStart::Kept
                        } else if io.loaded.contains(&decl.name) {
                            AttachmentStart::Loaded
                        } else if let Some(v) = decl.clear {
                            AttachmentStart::Clear(v)
                        } else {
                            AttachmentStart::Undefined
                        },
                        read_after: io.read_after.contains(&decl.name) && !later,
                        kept_after: later || sampled_after,
                        compute: io.sampled.iter().any(|&(s, _)| s == a),
                    }
                })
                .collect();
            let local = |a: usize| attachments.iter().position(|&x| x == a).unwrap_or(a);
            let subpasses = subpasses[run]
                .iter()
                .map(|s| SubpassSpec {
                    name: s.name,
                    colour: s.colour.iter().map(|&a| local(a)).collect(),
                    depth: s.depth.map(|(a, how)| (local(a), how)),
                    inputs: s.inputs.iter().map(|&a| local(a)).collect(),
                })
                .collect();
            RunSpec {
                attachments,
                specs,
                subpasses,
                sampled: io
                    .sampled_by_runs
                    .iter()
                    .filter(|&&(_, r)| r == run)
                    .map(|&(a, _)| a)
                    .collect(),
            }
        })
        .collect();
    let extra_usage: Vec<ImageUsageFlags> = (0..plan.attachments.len())
        .map(|a| {
            let by_subpass = io.sampled_by_runs.iter().any(|&(s, _)| s == a);
            if by_subpass || io.sampled.iter().any(|&(s, _)| s == a) {
                ImageUsageFlags::SAMPLED
            } else {
                ImageUsageFlags::empty()
            }
        })
        .collect();
    let extents: Vec<(u32, u32)> = plan
        .attachments
        .iter()
        .map(|a| plan.attachment_extent(a))
        .collect();
    Ok(Some(FrameTargets::new(
        ctx,
        &extents,
        &extra_usage,
        &run_specs,
    )?))
}

/// What the passes outside the render passes do with attachments.
struct FrameIo<'a> {
    plan: &'a FramePlan,
    /// Copied in before the first render pass.
    loaded: Vec<&'static str>,
    /// Copied out after the first render pass began (the readback).
    read_after: Vec<&'static str>,
    /// (attachment, the render pass before the compute pass sampling it).
    sampled: Vec<(usize, usize)>,
    /// (attachment, the render pass whose subpasses sample it).
    sampled_by_runs: Vec<(usize, usize)>,
}

impl<'a> FrameIo<'a> {
    fn of(plan: &'a FramePlan, slots: &[Option<(usize, u32)>]) -> Result<FrameIo<'a>, RenderError> {
        let first_subpass = slots.iter().position(Option::is_some).unwrap_or(0);
        let mut io = FrameIo {
            plan,
            loaded: Vec::new(),
            read_after: Vec::new(),
            sampled: Vec::new(),
            sampled_by_runs: Vec::new(),
        };
        for (i, decl) in plan.passes.iter().enumerate() {
            match &decl.io {
                PassIo::Transfer { reads, writes } => {
                    if i < first_subpass {
                        io.loaded.extend(writes);
                    } else {
                        io.read_after.extend(reads);
                    }
                }
                PassIo::Compute { samples } => {
                    let before = slots[..i].iter().flatten().last();
                    for name in samples {
                        let Some(&(run, _)) = before else {
                            return Err(RenderError::Frame(format!(
                                "pass '{}' samples attachment '{name}' before any subpass wrote it",
                                decl.name()
                            )));
                        };
                        io.sampled.push((io.index(name)?, run));
                    }
                }
                PassIo::Subpass { samples, .. } => {
                    let Some((run, _)) = slots[i] else {
                        continue;
                    };
                    for name in samples {
                        let a = io.index(name)?;
                        // Written by an earlier render pass (the slots put
                        // a subpass sampling what its own render pass
                        // writes into the next one).
                        let written = plan.passes[..i].iter().zip(slots).any(|(d, s)| {
                            d.io.writes().contains(name) && s.is_some_and(|(r, _)| r < run)
                        });
                        if !written {
                            return Err(RenderError::Frame(format!(
                                "pass '{}' samples attachment '{name}', which no earlier render \
                                 pass writes",
                                decl.name()
                            )));
                        }
                        io.sampled_by_runs.push((a, run));
                    }
                }
            }
        }
        Ok(io)
    }

    fn index(&self, name: &str) -> Result<usize, RenderError> {
        self.plan
            .attachments
            .iter()
            .position(|a| a.name == name)
            .ok_or_else(|| {
                RenderError::Frame(format!(
                    "a pass uses attachment '{name}', which the plan does not declare"
                ))
            })
    }

    /// A subpass's declaration with the frame's attachment indices.
    fn subpass(&self, decl: &PassDecl) -> Result<SubpassSpec, RenderError> {
        let PassIo::Subpass {
            colour,
            depth,
            inputs,
            ..
        } = &decl.io
        else {
            return Err(RenderError::Frame(format!(
                "pass '{}' is not a subpass",
                decl.name()
            )));
        };
        Ok(SubpassSpec {
            name: decl.name(),
            colour: colour
                .iter()
                .map(|n| self.index(n))
                .collect::<Result<_, _>>()?,
            depth: depth
                .map(|(n, how)| self.index(n).map(|i| (i, how)))
                .transpose()?,
            inputs: inputs
                .iter()
                .map(|n| self.index(n))
                .collect::<Result<_, _>>()?,
        })
    }
}
