//! A render pass built from a declared frame: attachments and the subpasses
//! that read and write them.
//!
//! The caller says *what* each subpass does with each attachment; this
//! module derives everything Vulkan wants spelled out: image usage flags,
//! load and store operations, the layout of every reference, the final
//! layouts, and the subpass dependencies. Nothing is listed by hand, so a
//! new pass cannot forget a dependency, and nothing is stored that nobody
//! reads afterwards.

use super::{Context, Image, ImageDesc, VkError};
use ash::vk;
use std::sync::Arc;

/// How an attachment's contents begin in the render pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AttachmentStart {
    /// Cleared to this colour, or for depth formats to `[depth, ..]`.
    Clear([f32; 4]),
    /// Copied in before the render pass (by a transfer the frame records),
    /// left in the layout of its first use.
    Loaded,
    /// Written by an earlier render pass of the frame (and perhaps sampled
    /// by a compute pass since): loaded, in the layout of its first use
    /// here; `CommandBuffer::begin_render_pass` moves it there from its
    /// tracked state. Unlike [`AttachmentStart::Loaded`] it needs no
    /// transfer usage.
    Kept,
    /// Every pixel is written before anything reads it: nothing to load.
    Undefined,
}

/// One attachment of the frame.
#[derive(Clone, Debug)]
pub struct AttachmentSpec {
    pub name: &'static str,
    pub format: vk::Format,
    pub start: AttachmentStart,
    /// Copied out (read back) after the render pass: stored, and left in
    /// TRANSFER_SRC_OPTIMAL.
    pub read_after: bool,
    /// Used by a later render pass or compute pass of the frame: stored,
    /// and left in the layout of its last use here.
    pub kept_after: bool,
    /// Sampled by a compute pass somewhere in the frame: the dependencies
    /// from and to outside the render pass include the compute shader
    /// stage (the previous submission's compute reads must finish before
    /// the attachment is written again).
    pub compute: bool,
}

/// How a subpass uses the depth attachment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthUse {
    /// Tested and written.
    Write,
    /// Tested only (read-only layout; it may also be an input attachment).
    Test,
}

/// One subpass: indices into the attachment list.
#[derive(Clone, Debug, Default)]
pub struct SubpassSpec {
    pub name: &'static str,
    /// Colour targets, in the fragment shader's output location order.
    pub colour: Vec<usize>,
    pub depth: Option<(usize, DepthUse)>,
    /// Input attachments, in `input_attachment_index` order.
    pub inputs: Vec<usize>,
}

/// What a subpass does with one attachment, for deriving layouts and
/// dependencies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Access {
    ColourWrite,
    DepthWrite,
    DepthTest,
    Input,
}

impl Access {
    fn writes(self) -> bool {
        matches!(self, Access::ColourWrite | Access::DepthWrite)
    }

    fn stage_access(self) -> (vk::PipelineStageFlags, vk::AccessFlags) {
        let depth_stages = vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
            | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
        match self {
            Access::ColourWrite => (
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                // Blending reads what it writes.
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE | vk::AccessFlags::COLOR_ATTACHMENT_READ,
            ),
            Access::DepthWrite => (
                depth_stages,
                vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE
                    | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ,
            ),
            Access::DepthTest => (depth_stages, vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ),
            Access::Input => (
                vk::PipelineStageFlags::FRAGMENT_SHADER,
                vk::AccessFlags::INPUT_ATTACHMENT_READ,
            ),
        }
    }
}

fn is_depth(format: vk::Format) -> bool {
    matches!(
        format,
        vk::Format::D16_UNORM
            | vk::Format::D32_SFLOAT
            | vk::Format::X8_D24_UNORM_PACK32
            | vk::Format::D16_UNORM_S8_UINT
            | vk::Format::D24_UNORM_S8_UINT
            | vk::Format::D32_SFLOAT_S8_UINT
    )
}

/// The layout an attachment is in while a subpass uses it.
fn layout_for(depth: bool, uses: &[Access]) -> vk::ImageLayout {
    if depth {
        if uses.contains(&Access::DepthWrite) {
            vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL
        } else {
            vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL
        }
    } else if uses.contains(&Access::ColourWrite) {
        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL
    } else {
        vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL
    }
}

/// A built render pass and its framebuffer over some of the frame's
/// attachments (the images live in [`FrameTargets`]).
pub struct RenderTargets {
    pub render_pass: RenderPass,
    pub framebuffer: Framebuffer,
    /// The frame's attachment (index into [`FrameTargets::images`]) behind
    /// each of this pass's attachments, in the pass's order.
    pub attachments: Vec<usize>,
    /// One clear value per attachment (ignored unless cleared).
    pub clears: Vec<vk::ClearValue>,
    /// The layout each attachment is left in.
    pub final_layouts: Vec<vk::ImageLayout>,
    /// The layout each attachment must be in when the pass begins.
    pub initial_layouts: Vec<vk::ImageLayout>,
    /// Frame images (indices into [`FrameTargets::images`]) the pass's
    /// subpasses sample, written by earlier render passes:
    /// `CommandBuffer::begin_render_pass` makes them shader-readable.
    pub sampled: Vec<usize>,
}

/// One render pass of a frame: the frame attachments it uses and its
/// subpasses.
#[derive(Clone, Debug)]
pub struct RunSpec {
    /// The frame's attachment (index into the frame's images) behind each
    /// of this pass's attachments.
    pub attachments: Vec<usize>,
    /// This pass's attachments, in the same order: how each starts and
    /// ends here.
    pub specs: Vec<AttachmentSpec>,
    /// Indices into `specs`.
    pub subpasses: Vec<SubpassSpec>,
    /// Frame images the subpasses sample (not attachments of this pass).
    pub sampled: Vec<usize>,
}

/// A frame's attachment images (created once, sized for the frame) and
/// the render passes ("runs") over them, in frame order.
pub struct FrameTargets {
    /// One image per frame attachment.
    pub images: Vec<Image>,
    pub runs: Vec<RenderTargets>,
}

impl FrameTargets {
    /// One `width`×`height` render pass over every attachment in
    /// `attachments`, in order.
    pub fn single(
        ctx: &Arc<Context>,
        width: u32,
        height: u32,
        attachments: &[AttachmentSpec],
        subpasses: &[SubpassSpec],
    ) -> Result<FrameTargets, VkError> {
        let run = RunSpec {
            attachments: (0..attachments.len()).collect(),
            specs: attachments.to_vec(),
            subpasses: subpasses.to_vec(),
            sampled: Vec::new(),
        };
        let usage = vec![vk::ImageUsageFlags::empty(); attachments.len()];
        let extents = vec![(width, height); attachments.len()];
        FrameTargets::new(ctx, &extents, &usage, &[run])
    }

    /// Derives the render passes of `runs` and creates them, the
    /// attachments (attachment a of size `extents[a]`; usage: the union
    /// over every run, plus `extra_usage[a]`, e.g. SAMPLED for one a later
    /// pass samples) and one framebuffer per run. Every frame attachment
    /// must be used by some run; its name and format come from its first
    /// run's spec. The attachments of one run must share a size.
    pub fn new(
        ctx: &Arc<Context>,
        extents: &[(u32, u32)],
        extra_usage: &[vk::ImageUsageFlags],
        runs: &[RunSpec],
    ) -> Result<FrameTargets, VkError> {
        let mut usages = extra_usage.to_vec();
        let mut specs: Vec<Option<&AttachmentSpec>> = vec![None; extra_usage.len()];
        let mut derived = Vec::with_capacity(runs.len());
        for run in runs {
            let uses = attachment_uses(&run.specs, &run.subpasses)?;
            let described = describe_attachments(&run.specs, &uses)?;
            for (local, &a) in run.attachments.iter().enumerate() {
                let slot = usages.get_mut(a).ok_or_else(|| {
                    VkError::Graph(format!("a render pass uses undeclared attachment {a}"))
                })?;
                *slot |= described.usages[local];
                specs[a].get_or_insert(&run.specs[local]);
            }
            derived.push((uses, described));
        }
        let specs: Vec<AttachmentSpec> = specs
            .into_iter()
            .enumerate()
            .map(|(a, spec)| {
                spec.cloned().ok_or_else(|| {
                    VkError::Graph(format!("attachment {a} is used by no render pass"))
                })
            })
            .collect::<Result<_, _>>()?;
        let images = create_attachment_images(ctx, extents, &specs, &usages)?;
        let mut built = Vec::with_capacity(runs.len());
        for (run, (uses, described)) in runs.iter().zip(derived) {
            let sizes: Vec<(u32, u32)> = run.attachments.iter().map(|&a| extents[a]).collect();
            if sizes.windows(2).any(|w| w[0] != w[1]) {
                return Err(VkError::Graph(format!(
                    "a render pass's attachments differ in size: {:?}",
                    run.specs
                        .iter()
                        .map(|s| s.name)
                        .zip(&sizes)
                        .collect::<Vec<_>>()
                )));
            }
            let render_pass = create_render_pass(
                ctx,
                &run.specs,
                &run.subpasses,
                &uses,
                &described.descriptions,
            )?;
            let refs: Vec<&Image> = run.attachments.iter().map(|&a| &images[a]).collect();
            let framebuffer = Framebuffer::new(ctx, &render_pass, &refs)?;
            built.push(RenderTargets {
                render_pass,
                framebuffer,
                attachments: run.attachments.clone(),
                clears: clear_values(&run.specs),
                final_layouts: described.final_layouts,
                initial_layouts: described.initial_layouts,
                sampled: run.sampled.clone(),
            });
        }
        Ok(FrameTargets {
            images,
            runs: built,
        })
    }
}

/// `uses[s][a]`: what subpass s does with attachment a. A subpass may not
/// both write and read (as an input) the same attachment.
fn attachment_uses(
    attachments: &[AttachmentSpec],
    subpasses: &[SubpassSpec],
) -> Result<Vec<Vec<Vec<Access>>>, VkError> {
    let n = attachments.len();
    let uses: Vec<Vec<Vec<Access>>> = subpasses
        .iter()
        .map(|s| {
            let mut u = vec![Vec::new(); n];
            for &c in &s.colour {
                u[c].push(Access::ColourWrite);
            }
            if let Some((d, how)) = s.depth {
                u[d].push(match how {
                    DepthUse::Write => Access::DepthWrite,
                    DepthUse::Test => Access::DepthTest,
                });
            }
            for &i in &s.inputs {
                u[i].push(Access::Input);
            }
            u
        })
        .collect();
    for (s, spec) in subpasses.iter().enumerate() {
        for (a, u) in uses[s].iter().enumerate() {
            if u.contains(&Access::Input) && u.iter().any(|x| x.writes()) {
                return Err(VkError::Graph(format!(
                    "subpass '{}' both writes and reads attachment '{}'",
                    spec.name, attachments[a].name
                )));
            }
        }
    }
    Ok(uses)
}

/// What the render pass and the images need to know of each attachment,
/// one entry per [`AttachmentSpec`] in the same order.
struct DescribedAttachments {
    descriptions: Vec<vk::AttachmentDescription>,
    initial_layouts: Vec<vk::ImageLayout>,
    final_layouts: Vec<vk::ImageLayout>,
    usages: Vec<vk::ImageUsageFlags>,
}

/// The description, layouts and image usage of every attachment, from
/// how it starts, whether it is read after the pass, and its uses.
fn describe_attachments(
    attachments: &[AttachmentSpec],
    uses: &[Vec<Vec<Access>>],
) -> Result<DescribedAttachments, VkError> {
    let n = attachments.len();
    let mut described = DescribedAttachments {
        descriptions: Vec::with_capacity(n),
        initial_layouts: Vec::with_capacity(n),
        final_layouts: Vec::with_capacity(n),
        usages: Vec::with_capacity(n),
    };
    for (a, spec) in attachments.iter().enumerate() {
        let depth = is_depth(spec.format);
        let users: Vec<usize> = (0..uses.len())
            .filter(|&s| !uses[s][a].is_empty())
            .collect();
        let (Some(&first), Some(&last)) = (users.first(), users.last()) else {
            return Err(VkError::Graph(format!(
                "attachment '{}' is used by no subpass",
                spec.name
            )));
        };
        let mut usage = attachment_usage(users.iter().flat_map(|&s| &uses[s][a]));
        let (load, initial) = match spec.start {
            AttachmentStart::Clear(_) => (vk::AttachmentLoadOp::CLEAR, vk::ImageLayout::UNDEFINED),
            AttachmentStart::Undefined => {
                (vk::AttachmentLoadOp::DONT_CARE, vk::ImageLayout::UNDEFINED)
            }
            AttachmentStart::Loaded | AttachmentStart::Kept if depth => {
                return Err(VkError::Graph(format!(
                    "attachment '{}': loading a depth attachment is not supported",
                    spec.name
                )));
            }
            AttachmentStart::Kept => (
                vk::AttachmentLoadOp::LOAD,
                layout_for(depth, &uses[first][a]),
            ),
            AttachmentStart::Loaded => {
                usage |= vk::ImageUsageFlags::TRANSFER_DST;
                (
                    vk::AttachmentLoadOp::LOAD,
                    layout_for(depth, &uses[first][a]),
                )
            }
        };
        // Stored only when something reads it after the pass.
        let (store, final_layout) = if spec.read_after {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
            (
                vk::AttachmentStoreOp::STORE,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            )
        } else if spec.kept_after {
            (
                vk::AttachmentStoreOp::STORE,
                layout_for(depth, &uses[last][a]),
            )
        } else {
            (
                vk::AttachmentStoreOp::DONT_CARE,
                layout_for(depth, &uses[last][a]),
            )
        };
        described.descriptions.push(
            vk::AttachmentDescription::default()
                .format(spec.format)
                .samples(vk::SampleCountFlags::TYPE_1)
                .load_op(load)
                .store_op(store)
                .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                .initial_layout(initial)
                .final_layout(final_layout),
        );
        described.initial_layouts.push(initial);
        described.final_layouts.push(final_layout);
        described.usages.push(usage);
    }
    Ok(described)
}

/// The image usage an attachment needs for `accesses`, its uses in every
/// subpass.
fn attachment_usage<'a>(accesses: impl Iterator<Item = &'a Access>) -> vk::ImageUsageFlags {
    let mut usage = vk::ImageUsageFlags::empty();
    for u in accesses {
        usage |= match u {
            Access::ColourWrite => vk::ImageUsageFlags::COLOR_ATTACHMENT,
            Access::DepthWrite | Access::DepthTest => vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            Access::Input => vk::ImageUsageFlags::INPUT_ATTACHMENT,
        };
    }
    usage
}

/// The render pass: the subpasses' attachment references and the
/// dependencies their uses imply.
fn create_render_pass(
    ctx: &Arc<Context>,
    attachments: &[AttachmentSpec],
    subpasses: &[SubpassSpec],
    uses: &[Vec<Vec<Access>>],
    descriptions: &[vk::AttachmentDescription],
) -> Result<RenderPass, VkError> {
    // Attachment references, kept alive until the pass is created.
    let reference = |s: usize, a: usize| vk::AttachmentReference {
        attachment: a as u32,
        layout: layout_for(is_depth(attachments[a].format), &uses[s][a]),
    };
    let colour_refs: Vec<Vec<vk::AttachmentReference>> = subpasses
        .iter()
        .enumerate()
        .map(|(s, spec)| spec.colour.iter().map(|&a| reference(s, a)).collect())
        .collect();
    let input_refs: Vec<Vec<vk::AttachmentReference>> = subpasses
        .iter()
        .enumerate()
        .map(|(s, spec)| spec.inputs.iter().map(|&a| reference(s, a)).collect())
        .collect();
    let depth_refs: Vec<Option<vk::AttachmentReference>> = subpasses
        .iter()
        .enumerate()
        .map(|(s, spec)| spec.depth.map(|(a, _)| reference(s, a)))
        .collect();
    let descs: Vec<vk::SubpassDescription> = (0..subpasses.len())
        .map(|s| {
            let mut d = vk::SubpassDescription::default()
                .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
                .color_attachments(&colour_refs[s])
                .input_attachments(&input_refs[s]);
            if let Some(r) = &depth_refs[s] {
                d = d.depth_stencil_attachment(r);
            }
            d
        })
        .collect();

    let dependencies = dependencies(attachments, uses);
    let info = vk::RenderPassCreateInfo::default()
        .attachments(descriptions)
        .subpasses(&descs)
        .dependencies(&dependencies);
    // SAFETY: valid device; every referenced array is a local alive for
    // the call, and attachment indices are within `descriptions`.
    let handle = unsafe { ctx.device.create_render_pass(&info, None) }?;
    Ok(RenderPass {
        ctx: ctx.clone(),
        handle,
    })
}

/// One image per attachment, of its size in `extents`, with the usage its
/// uses need.
fn create_attachment_images(
    ctx: &Arc<Context>,
    extents: &[(u32, u32)],
    attachments: &[AttachmentSpec],
    usages: &[vk::ImageUsageFlags],
) -> Result<Vec<Image>, VkError> {
    attachments
        .iter()
        .zip(usages)
        .zip(extents)
        .map(|((spec, &usage), &(width, height))| {
            Image::new(
                ctx,
                spec.name,
                ImageDesc {
                    width,
                    height,
                    format: spec.format,
                    usage,
                    mip_levels: 1,
                    aspect: if is_depth(spec.format) {
                        vk::ImageAspectFlags::DEPTH
                    } else {
                        vk::ImageAspectFlags::COLOR
                    },
                },
            )
        })
        .collect()
}

/// Clear values up to the last cleared attachment only: best-practices
/// validation warns about values given for attachments that are not
/// cleared (callers list cleared attachments first to avoid any).
fn clear_values(attachments: &[AttachmentSpec]) -> Vec<vk::ClearValue> {
    let cleared = attachments
        .iter()
        .rposition(|a| matches!(a.start, AttachmentStart::Clear(_)))
        .map_or(0, |i| i + 1);
    attachments[..cleared]
        .iter()
        .map(|spec| {
            let v = match spec.start {
                AttachmentStart::Clear(v) => v,
                _ => [0.0; 4],
            };
            if is_depth(spec.format) {
                super::clear_depth(v[0])
            } else {
                super::clear_color(v)
            }
        })
        .collect()
}

/// The stages and accesses of all of `list`'s uses together.
fn combined(list: &[Access]) -> (vk::PipelineStageFlags, vk::AccessFlags) {
    list.iter().fold(
        (vk::PipelineStageFlags::empty(), vk::AccessFlags::empty()),
        |(s, a), u| {
            let (us, ua) = u.stage_access();
            (s | us, a | ua)
        },
    )
}

/// What the previous submission may still be doing with any attachment:
/// writing it in a subpass, reading it in a shader, copying out of it or
/// into it.
const PREVIOUS_STAGES: vk::PipelineStageFlags = vk::PipelineStageFlags::from_raw(
    vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT.as_raw()
        | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS.as_raw()
        | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS.as_raw()
        | vk::PipelineStageFlags::FRAGMENT_SHADER.as_raw()
        | vk::PipelineStageFlags::TRANSFER.as_raw(),
);
const PREVIOUS_WRITES: vk::AccessFlags = vk::AccessFlags::from_raw(
    vk::AccessFlags::COLOR_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw()
        | vk::AccessFlags::TRANSFER_WRITE.as_raw(),
);

/// The dependencies the uses imply:
/// - from outside into the first subpass using each attachment: the
///   previous submission of the same frame (or a copy into a loaded
///   attachment) must be done with it;
/// - between subpasses: each use waits for the latest earlier use of the
///   same attachment when either of them writes (read after write, write
///   after read, write after write), by region since attachments are
///   pixel-local;
/// - out of the last subpass using a stored attachment, to the copy that
///   reads it back.
///
/// Dependencies between the same pair of subpasses are merged.
fn dependencies(
    attachments: &[AttachmentSpec],
    uses: &[Vec<Vec<Access>>],
) -> Vec<vk::SubpassDependency> {
    let mut deps: Vec<vk::SubpassDependency> = Vec::new();
    let mut add = |src: u32,
                   dst: u32,
                   src_stage: vk::PipelineStageFlags,
                   src_access: vk::AccessFlags,
                   dst_stage: vk::PipelineStageFlags,
                   dst_access: vk::AccessFlags| {
        let flags = if src != vk::SUBPASS_EXTERNAL && dst != vk::SUBPASS_EXTERNAL {
            vk::DependencyFlags::BY_REGION
        } else {
            vk::DependencyFlags::empty()
        };
        if let Some(d) = deps
            .iter_mut()
            .find(|d| d.src_subpass == src && d.dst_subpass == dst)
        {
            d.src_stage_mask |= src_stage;
            d.src_access_mask |= src_access;
            d.dst_stage_mask |= dst_stage;
            d.dst_access_mask |= dst_access;
        } else {
            deps.push(
                vk::SubpassDependency::default()
                    .src_subpass(src)
                    .dst_subpass(dst)
                    .src_stage_mask(src_stage)
                    .src_access_mask(src_access)
                    .dst_stage_mask(dst_stage)
                    .dst_access_mask(dst_access)
                    .dependency_flags(flags),
            );
        }
    };
    let previous_stages = PREVIOUS_STAGES;
    let previous_writes = PREVIOUS_WRITES;
    for (a, spec) in attachments.iter().enumerate() {
        let users: Vec<usize> = (0..uses.len())
            .filter(|&s| !uses[s][a].is_empty())
            .collect();
        let Some(&first) = users.first() else {
            continue;
        };
        let (mut dst_stage, mut dst_access) = combined(&uses[first][a]);
        if spec.start == AttachmentStart::Kept && !is_depth(spec.format) {
            // Loading a colour attachment reads it in the attachment
            // output stage, whatever the subpass then does with it.
            dst_stage |= vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT;
            dst_access |= vk::AccessFlags::COLOR_ATTACHMENT_READ;
        }
        // A compute pass sampling the attachment (earlier in this
        // submission, or in the previous one) reads it in the compute stage.
        let compute_stage = if spec.compute {
            vk::PipelineStageFlags::COMPUTE_SHADER
        } else {
            vk::PipelineStageFlags::empty()
        };
        add(
            vk::SUBPASS_EXTERNAL,
            first as u32,
            previous_stages | compute_stage,
            previous_writes,
            dst_stage,
            dst_access,
        );
        for pair in users.windows(2) {
            let (src, dst) = (pair[0], pair[1]);
            let writes = uses[src][a].iter().chain(&uses[dst][a]).any(|u| u.writes());
            if writes {
                let (ss, sa) = combined(&uses[src][a]);
                let (ds, da) = combined(&uses[dst][a]);
                add(src as u32, dst as u32, ss, sa, ds, da);
            }
        }
        // Out of the last subpass using it, to what reads it after the
        // render pass: the compute pass sampling it or the later render
        // pass loading it (as an input or colour attachment), and the copy
        // that reads it back.
        let mut after = (vk::PipelineStageFlags::empty(), vk::AccessFlags::empty());
        if spec.kept_after {
            after.0 |= vk::PipelineStageFlags::FRAGMENT_SHADER
                | vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
                | compute_stage;
            after.1 |= vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::INPUT_ATTACHMENT_READ
                | vk::AccessFlags::COLOR_ATTACHMENT_READ
                | vk::AccessFlags::COLOR_ATTACHMENT_WRITE;
        }
        if spec.read_after {
            after.0 |= vk::PipelineStageFlags::TRANSFER;
            after.1 |= vk::AccessFlags::TRANSFER_READ;
        }
        if !after.0.is_empty() {
            let last = *users.last().expect("non-empty");
            let (ss, sa) = combined(&uses[last][a]);
            add(last as u32, vk::SUBPASS_EXTERNAL, ss, sa, after.0, after.1);
        }
    }
    deps
}

/// A Vulkan render pass.
pub struct RenderPass {
    ctx: Arc<Context>,
    pub(crate) handle: vk::RenderPass,
}

impl Drop for RenderPass {
    fn drop(&mut self) {
        // SAFETY: pipelines/framebuffers using it are gone or idle.
        unsafe { self.ctx.device.destroy_render_pass(self.handle, None) };
    }
}

/// The attachments of one [`RenderPass`], bound together.
pub struct Framebuffer {
    ctx: Arc<Context>,
    pub(crate) handle: vk::Framebuffer,
    pub(crate) extent: vk::Extent2D,
}

impl Framebuffer {
    /// `attachments` in the render pass's attachment order, all the size of
    /// the first.
    pub fn new(
        ctx: &Arc<Context>,
        pass: &RenderPass,
        attachments: &[&Image],
    ) -> Result<Framebuffer, VkError> {
        let first = attachments
            .first()
            .ok_or_else(|| VkError::Graph("a framebuffer needs an attachment".into()))?;
        let extent = vk::Extent2D {
            width: first.desc.width,
            height: first.desc.height,
        };
        let views: Vec<vk::ImageView> = attachments.iter().map(|i| i.view).collect();
        let info = vk::FramebufferCreateInfo::default()
            .render_pass(pass.handle)
            .attachments(&views)
            .width(extent.width)
            .height(extent.height)
            .layers(1);
        // SAFETY: views match the pass's attachment formats and sizes (the
        // callers create them from the same description).
        let handle = unsafe { ctx.device.create_framebuffer(&info, None) }?;
        Ok(Framebuffer {
            ctx: ctx.clone(),
            handle,
            extent,
        })
    }
}

impl Drop for Framebuffer {
    fn drop(&mut self) {
        // SAFETY: no pending command buffer uses it.
        unsafe { self.ctx.device.destroy_framebuffer(self.handle, None) };
    }
}
