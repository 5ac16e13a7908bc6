//! The passes a frame is made of, one small type per file. Each file
//! declares its pass with a [`PassType`] (its name, whether a frame holds
//! it and what it reads and writes there, and how it is created) and
//! defines what it creates: a [`RecordPass`] holding its pipelines,
//! descriptor sets and own resources, which records its commands once.
//!
//! [`PASSES`] lists every pass in the order a frame runs them; the plan
//! asks each one for its declaration ([`PassDecl`]) and keeps those a
//! frame holds. Each pass takes its attachments (input attachments in
//! their declared order) from its declaration and everything else from
//! the plan ([`PassSetup`]). The renderer begins a render pass before
//! the first of consecutive subpasses, moves to the next subpass between
//! them and ends it after the last (a compute pass sampling attachments
//! between subpasses splits the frame into several render passes), so no
//! pass knows its subpass index or its neighbours. Adding a pass is a new file here (with its `PassType`), its
//! shaders in `glsl/`, and one line in [`PASSES`].

pub mod aerial_volume;
pub mod atmosphere;
pub mod bloom;
pub mod deferred_lighting;
pub mod depth_prepass;
pub mod exposure;
pub mod shadow_map;
pub mod sky_view;
pub mod surface;
pub mod tonemap;
pub mod transfer;

use super::plan::{FramePlan, FrameShape, PassDecl, PassIo};
use super::scene_resources::SceneResources;
use super::shadow_resources::ShadowResources;
use super::sky_resources::SkyResources;
use super::{Pixels, RenderError};
use crate::scene::Scene;
use crate::shaders;
use crate::vk::{
    Blend, Buffer, CommandBuffer, Context, CullModeFlags, DescriptorBinding, DescriptorPool,
    DescriptorSet, DescriptorSetLayout, DescriptorType, GraphicsPipeline, GraphicsPipelineDesc,
    Image, PipelineLayout, RenderPass, RenderTargets, ShaderModule, ShaderStageFlags,
};
use std::sync::Arc;

/// Every pass, in the order a frame runs them: a frame holds those whose
/// [`PassType::declare`] says so.
pub const PASSES: &[&dyn PassType] = &[
    transfer::HDR_UPLOAD,
    sky_view::PASS,
    aerial_volume::PASS,
    shadow_map::PASS,
    depth_prepass::PASS,
    surface::GBUFFER,
    deferred_lighting::PASS,
    surface::OPAQUE,
    surface::TRANSPARENT,
    atmosphere::PASS,
    exposure::PASS,
    bloom::PASS,
    tonemap::PASS,
    transfer::READBACK,
];

/// A pass as the frame's list holds it: each file under `render/passes`
/// exports one (or a few) as a constant. Plans and queries name a pass by
/// that constant (`plan.has(aerial_volume::PASS)`), never by a string.
pub trait PassType: Sync {
    /// The pass's name in timing tables, reports and the viewer; unique
    /// among [`PASSES`].
    fn name(&self) -> &'static str;

    /// What the pass reads and writes in the frame `shape` describes, or
    /// `None` when that frame does without it.
    fn declare(&self, shape: &FrameShape<'_>) -> Option<PassIo>;

    /// Creates the pass's GPU objects from its declaration (`setup.decl`)
    /// and the plan.
    fn create(&self, setup: &PassSetup<'_>) -> Result<Box<dyn RecordPass>, RenderError>;

    /// Whether the pass is a subpass of one of the frame's render passes
    /// (most are), rather than compute or copies outside them: what `declare`
    /// returns is then always a [`PassIo::Subpass`].
    fn is_subpass(&self) -> bool {
        true
    }
}

/// A created pass.
pub trait RecordPass {
    /// Records the pass's commands (inside its subpass for subpasses).
    fn record(&self, cmd: &CommandBuffer, frame: &PassResources<'_>) -> Result<(), RenderError>;

    /// The buffer an attachment is read back into, for passes that copy
    /// attachments out.
    fn readback(&self, _attachment: &str) -> Option<&Buffer> {
        None
    }

    /// Rewrites what the pass derived from the view (camera, sun) when it
    /// was created, for `scene` whose `plan` records the same commands
    /// (see `Renderer::set_view`). Called between frames. Most passes keep
    /// nothing of the view; the per-frame camera uniforms are shared.
    fn set_view(&mut self, _scene: &Scene, _plan: &FramePlan) -> Result<(), RenderError> {
        Ok(())
    }
}

/// The frame's attachments by name.
pub struct Attachments<'a> {
    pub names: Vec<&'static str>,
    pub images: &'a [Image],
}

impl Attachments<'_> {
    pub fn get(&self, name: &str) -> Result<&Image, RenderError> {
        self.names
            .iter()
            .position(|n| *n == name)
            .map(|i| &self.images[i])
            .ok_or_else(|| {
                RenderError::Frame(format!("no attachment called '{name}' in this frame"))
            })
    }
}

/// What a pass records against: resources shared by several passes.
pub struct PassResources<'a> {
    pub attachments: Attachments<'a>,
    /// Geometry, per-frame and per-object uniforms and textures; present
    /// when the plan draws objects.
    pub scene: Option<&'a SceneResources>,
    /// The atmosphere's uniforms and tables; present when the plan
    /// draws the atmosphere.
    pub sky: Option<&'a SkyResources>,
    /// One float: the exposure the exposure pass measures and the tone
    /// map applies; present when the plan holds the exposure pass.
    pub exposure: Option<&'a Buffer>,
    /// The light's frame set and the shadow set; present when the plan
    /// draws a shadow map.
    pub shadow: Option<&'a ShadowResources>,
    /// The bloom chain (RGBA16F, a mip level per level, level 0 half the
    /// output's size) the bloom pass writes and the tone map samples;
    /// present when the plan holds the bloom pass.
    pub bloom: Option<&'a Image>,
}

impl PassResources<'_> {
    pub fn sky(&self) -> Result<&SkyResources, RenderError> {
        self.sky
            .ok_or_else(|| RenderError::Frame("the frame has no atmosphere resources".into()))
    }

    pub fn shadow(&self) -> Result<&ShadowResources, RenderError> {
        self.shadow
            .ok_or_else(|| RenderError::Frame("the frame has no shadow map".into()))
    }

    pub fn exposure(&self) -> Result<&Buffer, RenderError> {
        self.exposure
            .ok_or_else(|| RenderError::Frame("the frame has no exposure buffer".into()))
    }

    pub fn bloom(&self) -> Result<&Image, RenderError> {
        self.bloom
            .ok_or_else(|| RenderError::Frame("the frame has no bloom image".into()))
    }
}

/// What a pass is created from.
pub struct PassSetup<'a> {
    pub ctx: &'a Arc<Context>,
    pub scene: &'a Scene,
    pub plan: &'a FramePlan,
    /// This pass's declaration.
    pub decl: &'a PassDecl,
    /// The render pass this subpass belongs to (a frame may have several,
    /// see `FramePlan::subpass_slots`), and its subpass index there.
    pub render_pass: Option<&'a RenderTargets>,
    pub subpass: u32,
    pub frame: &'a PassResources<'a>,
    /// The image an upload pass copies into the HDR attachment.
    pub hdr_input: Option<&'a Pixels<f32>>,
}

impl PassSetup<'_> {
    /// The render pass, for subpasses.
    pub fn render_pass(&self) -> Result<&RenderTargets, RenderError> {
        self.render_pass.ok_or_else(|| {
            RenderError::Frame(format!("pass '{}' is not a subpass", self.decl.name()))
        })
    }

    /// The atmosphere's resources, for passes that march it.
    pub fn sky_resources(&self) -> Result<&SkyResources, RenderError> {
        self.frame.sky()
    }

    /// The shared scene resources, for passes that draw objects.
    pub fn scene_resources(&self) -> Result<&SceneResources, RenderError> {
        self.frame.scene.ok_or_else(|| {
            RenderError::Frame(format!(
                "pass '{}' draws objects but the frame has no scene resources",
                self.decl.name()
            ))
        })
    }
}

/// A descriptor set whose binding i is the pass's declared input
/// attachment i (`input_attachment_index` i in its shader), with its own
/// layout and pool. Fields drop in order: the set before its pool, the
/// layout last.
pub struct InputAttachments {
    pub set: DescriptorSet,
    _pool: DescriptorPool,
    pub layout: DescriptorSetLayout,
}

impl InputAttachments {
    pub fn declared(setup: &PassSetup<'_>) -> Result<InputAttachments, RenderError> {
        let names = setup.decl.inputs();
        let bindings: Vec<DescriptorBinding> = (0..names.len() as u32)
            .map(|binding| DescriptorBinding {
                binding,
                kind: DescriptorType::INPUT_ATTACHMENT,
                stages: ShaderStageFlags::FRAGMENT,
            })
            .collect();
        let layout = DescriptorSetLayout::new(setup.ctx, &bindings)?;
        let pool = DescriptorPool::for_layouts(setup.ctx, &[&layout])?;
        let set = pool.allocate(&layout)?;
        for (binding, name) in names.iter().enumerate() {
            set.write_input_attachment(binding as u32, setup.frame.attachments.get(name)?);
        }
        Ok(InputAttachments {
            set,
            _pool: pool,
            layout,
        })
    }
}

/// A pipeline that draws one triangle over the whole framebuffer
/// (`fullscreen.vert`, at depth 0: the far plane of reversed Z) with the
/// `fragment` shader into one colour target: no vertex input, no depth
/// writes, no blending. `depth_test` compares against the subpass's
/// read-only depth, so a pass can shade only the pixels where nothing was
/// drawn (EQUAL) or only the others (LESS). The tone map, the atmosphere
/// and the empty pass are all this shape.
pub(crate) fn fullscreen_pipeline(
    ctx: &Arc<Context>,
    layout: &PipelineLayout,
    render_pass: &RenderPass,
    subpass: u32,
    fragment: &[u8],
    specialization: &[(u32, u32)],
    depth_test: Option<crate::vk::CompareOp>,
) -> Result<GraphicsPipeline, RenderError> {
    let vertex = ShaderModule::new(ctx, shaders::FULLSCREEN_VERT.base())?;
    let fragment = ShaderModule::new(ctx, fragment)?;
    Ok(GraphicsPipeline::new(
        ctx,
        layout,
        render_pass,
        &GraphicsPipelineDesc {
            vertex_shader: &vertex,
            fragment_shader: Some(&fragment),
            specialization,
            vertex_stride: 0,
            vertex_attributes: &[],
            instance_stride: 0,
            instance_attributes: &[],
            cull_mode: CullModeFlags::NONE,
            depth_test,
            depth_write: false,
            depth_bias: None,
            blend: &[Blend::Replace],
            subpass,
        },
    )?)
}
