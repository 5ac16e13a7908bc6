//! What a scene needs from the GPU, decided on the CPU before any Vulkan
//! object exists: the frame as data (named attachments and an ordered list
//! of passes saying what each reads and writes), the pipeline variants, the
//! textures, the order of the draws and, for deferred lighting, which
//! lights reach which screen tiles.
//!
//! Everything the scene does not use is left out here, so the GPU side
//! only builds what the plan lists: no G-buffer in forward mode, no
//! transparent pass without transparent objects, no HDR attachment or
//! tone-map subpass when the scene asks for LDR output.

pub use super::draw_list::{
    shininess_exponent, AirLight, Draw, DrawList, Instances, MapSlots, PipelineKey, ShadingKey,
    MAX_SHININESS_EXPONENT,
};
use super::geometry::SceneGeometry;
use super::passes::{aerial_volume, PassType, PASSES};
pub use super::prepass_rule::DepthPrepassRule;
use super::shadow_view;
pub use super::shadow_view::ShadowView;
use super::tiles::{self, TileGroup};
use crate::scene::material_maps::{MapKind, MapSource};
use crate::scene::{
    DepthPrepass, Exposure, HdrFormat, Lighting, Scene, ShadingModel, ToneMapOperator,
};
use crate::vk::{DepthUse, Format};

/// The attachment names passes refer to.
pub mod attachment {
    /// Float HDR colour, before tone mapping.
    pub const HDR: &str = "hdr";
    /// Reversed-Z float depth.
    pub const DEPTH: &str = "depth";
    /// The 8-bit sRGB image the frame produces.
    pub const OUTPUT: &str = "output";
    /// G-buffer: diffuse albedo (kd times texture).
    pub const ALBEDO: &str = "gbuffer albedo";
    /// G-buffer: octahedral-encoded world-space normal.
    pub const NORMAL: &str = "gbuffer normal";
    /// G-buffer: specular colour and shininess.
    pub const MATERIAL: &str = "gbuffer material";
    /// Float HDR colour of the surfaces, before the atmosphere pass (only
    /// with `[atmosphere]`): a second attachment, because a subpass cannot
    /// read its own colour target as an input attachment.
    pub const SURFACE: &str = "surface";
    /// Depth seen from the shadow-casting light, sampled by the passes
    /// that light surfaces (only when a light casts shadows).
    pub const SHADOW_MAP: &str = "shadow map";
}

/// How big an attachment is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AttachmentSize {
    /// The frame's output size.
    Output,
    /// Its own size, whatever the output's (a shadow map).
    Fixed { width: u32, height: u32 },
}

impl AttachmentSize {
    /// Width and height in a frame whose output is `width`×`height`.
    pub fn extent(self, width: u32, height: u32) -> (u32, u32) {
        match self {
            AttachmentSize::Output => (width, height),
            AttachmentSize::Fixed { width, height } => (width, height),
        }
    }
}

/// One attachment of the frame.
#[derive(Clone, Debug, PartialEq)]
pub struct AttachmentDecl {
    pub name: &'static str,
    pub format: Format,
    pub size: AttachmentSize,
    /// Cleared to this value when the frame starts (depth: the first
    /// component); `None` when every pixel is written before it is read.
    pub clear: Option<[f32; 4]>,
}

/// What a pass does with attachments.
#[derive(Clone, Debug, PartialEq)]
pub enum PassIo {
    /// A subpass of the frame's render pass.
    Subpass {
        /// Colour targets, in fragment output location order.
        colour: Vec<&'static str>,
        depth: Option<(&'static str, DepthUse)>,
        /// Input attachments, in `input_attachment_index` order.
        inputs: Vec<&'static str>,
        /// Attachments sampled as textures, written by an earlier render
        /// pass: a subpass sampling what its own render pass writes
        /// begins a new one.
        samples: Vec<&'static str>,
    },
    /// A compute dispatch outside the render passes. Most run before the
    /// first and touch no attachment (what they write, later passes read
    /// from buffers they share with them); one that `samples` attachments
    /// written by earlier subpasses ends the render pass they formed, and
    /// the subpasses after it form the next one.
    Compute {
        /// Attachments the dispatch samples.
        samples: Vec<&'static str>,
    },
    /// Copies outside the render pass.
    Transfer {
        /// Attachments copied out after the render pass.
        reads: Vec<&'static str>,
        /// Attachments copied in before the render pass.
        writes: Vec<&'static str>,
    },
}

impl PassIo {
    /// A subpass writing `colour` (in location order), using `depth` and
    /// reading `inputs` (in `input_attachment_index` order).
    pub fn subpass(
        colour: Vec<&'static str>,
        depth: Option<(&'static str, DepthUse)>,
        inputs: Vec<&'static str>,
    ) -> PassIo {
        PassIo::Subpass {
            colour,
            depth,
            inputs,
            samples: Vec::new(),
        }
    }

    /// This subpass, also sampling `names` (written by earlier render
    /// passes) as textures; other passes unchanged.
    pub fn sampling(mut self, names: &[&'static str]) -> PassIo {
        if let PassIo::Subpass { samples, .. } = &mut self {
            samples.extend_from_slice(names);
        }
        self
    }

    /// The attachments a subpass writes (colour targets, and depth unless
    /// only tested); none for other passes.
    pub fn writes(&self) -> Vec<&'static str> {
        match self {
            PassIo::Subpass { colour, depth, .. } => colour
                .iter()
                .copied()
                .chain(
                    depth
                        .filter(|(_, how)| *how == DepthUse::Write)
                        .map(|(d, _)| d),
                )
                .collect(),
            _ => Vec::new(),
        }
    }

    /// Every attachment a subpass uses as an attachment (not what it
    /// samples).
    fn attached(&self) -> Vec<&'static str> {
        match self {
            PassIo::Subpass {
                colour,
                depth,
                inputs,
                ..
            } => colour
                .iter()
                .chain(inputs)
                .copied()
                .chain(depth.map(|(d, _)| d))
                .collect(),
            _ => Vec::new(),
        }
    }
}

/// One pass of the frame: which pass (an entry of [`PASSES`]), and what it
/// reads and writes.
#[derive(Clone)]
pub struct PassDecl {
    pub pass: &'static dyn PassType,
    pub io: PassIo,
}

impl std::fmt::Debug for PassDecl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PassDecl")
            .field("pass", &self.name())
            .field("io", &self.io)
            .finish()
    }
}

/// Passes are told apart by name ([`PassType::name`] is unique).
impl PartialEq for PassDecl {
    fn eq(&self, other: &PassDecl) -> bool {
        self.name() == other.name() && self.io == other.io
    }
}

impl PassDecl {
    /// The pass's name in timing tables.
    pub fn name(&self) -> &'static str {
        self.pass.name()
    }

    /// Whether this is `pass` (compared by name).
    pub fn is(&self, pass: &dyn PassType) -> bool {
        self.name() == pass.name()
    }

    pub fn is_subpass(&self) -> bool {
        matches!(self.io, PassIo::Subpass { .. })
    }

    /// The input attachments, in `input_attachment_index` order (none
    /// outside subpasses).
    pub fn inputs(&self) -> &[&'static str] {
        match &self.io {
            PassIo::Subpass { inputs, .. } => inputs,
            _ => &[],
        }
    }

    /// The attachments a subpass samples as textures (none for other
    /// passes).
    pub fn samples(&self) -> &[&'static str] {
        match &self.io {
            PassIo::Subpass { samples, .. } => samples,
            _ => &[],
        }
    }
}

/// Why the split between subpasses is approximate, naming the subpasses:
/// printed under timing tables.
pub fn subpass_timing_note() -> String {
    let names: Vec<&str> = PASSES
        .iter()
        .filter(|p| p.is_subpass())
        .map(|p| p.name())
        .collect();
    let (last, rest) = names.split_last().expect("there are subpasses");
    format!(
        "the {} and {last} passes are subpasses of the frame's render passes (one, or several: one per attachment size, \
         and one on each side of a compute pass that samples what the first wrote): a binning \
         rasterizer \
         (lavapipe, tile-based GPUs) may do a draw's work after a later timestamp, so their time \
         split is approximate; the sum over the render pass is exact, and so is each pass's \
         instruction count (--metric instructions counts frame prefixes)",
        rest.join(", ")
    )
}

/// The frame a scene needs.
#[derive(Clone, Debug)]
pub struct FramePlan {
    pub width: u32,
    pub height: u32,
    pub hdr_format: HdrFormat,
    pub lighting: Lighting,
    /// Opaque draws, grouped by pipeline and texture to save binds, front
    /// to back within a group. In deferred mode these are drawn into the
    /// G-buffer.
    pub opaque: Vec<Draw>,
    /// Transparent draws, back to front from the camera.
    pub transparent: Vec<Draw>,
    /// Draws wholly outside the view (`DrawList::hidden`): not recorded,
    /// but given their pipelines and blocks.
    pub hidden: Vec<Draw>,
    /// Slots of the instance buffer (`DrawList::instance_slots`), 0 for
    /// none.
    pub instance_slots: u32,
    /// Distinct map images (base colour, normal map, ...), each of one
    /// kind, each loaded once.
    pub maps: Vec<(MapKind, MapSource)>,
    /// Deferred lighting: screen tiles grouped by the lights that reach
    /// them (empty in forward mode).
    pub tile_groups: Vec<TileGroup>,
    /// The attachments, each used by at least one pass.
    pub attachments: Vec<AttachmentDecl>,
    /// Passes in the order they run; one timestamp interval each. The
    /// subpasses among them form one render pass, in this order.
    pub passes: Vec<PassDecl>,
    /// The distance from the camera the aerial-perspective volume reaches,
    /// when the frame has one (see [`aerial_volume_reach`]).
    pub aerial_volume_reach: Option<f64>,
    /// The shadow map's view and casters, when the frame draws one.
    pub shadow: Option<ShadowView>,
}

impl FramePlan {
    /// The frame for `scene`, whose meshes and bounds are `geometry`;
    /// `keep_hdr` reads the linear HDR image back too: its draw list and
    /// its frame graph.
    pub fn new(scene: &Scene, geometry: &SceneGeometry, keep_hdr: bool) -> FramePlan {
        let deferred = uses_deferred_lighting(scene);
        let draws = DrawList::new(scene, geometry, deferred);
        let prepass = match scene.output.depth_prepass {
            DepthPrepass::On => true,
            DepthPrepass::Off => false,
            DepthPrepass::Auto => DepthPrepassRule::of(scene, geometry, &draws.opaque).pays(),
        };
        let shadow = shadow_casting(scene, geometry, &draws);
        let cascades = shadow.as_ref().map_or(1, |s| s.count);
        let graph = FrameGraph::with_prepass(scene, keep_hdr, prepass, cascades);
        let shadow = shadow.and_then(|s| {
            ShadowView::fit(
                scene,
                &geometry.bounds,
                &s.in_view,
                s.casters,
                scene.output.shadow_map,
                (s.count, s.depths),
            )
        });
        let tile_groups = if graph.lighting == Lighting::Deferred {
            tiles::group_lights(scene, scene.output.width, scene.output.height)
        } else {
            Vec::new()
        };
        FramePlan {
            width: scene.output.width,
            height: scene.output.height,
            hdr_format: scene.output.hdr_format,
            lighting: graph.lighting,
            opaque: draws.opaque,
            transparent: draws.transparent,
            hidden: draws.hidden,
            instance_slots: draws.instance_slots,
            maps: draws.maps,
            tile_groups,
            aerial_volume_reach: graph
                .has(aerial_volume::PASS)
                .then(|| aerial_volume_reach(scene, &geometry.bounds)),
            shadow,
            attachments: graph.attachments,
            passes: graph.passes,
        }
    }

    /// The frame that only tone-maps a given `width`×`height` HDR image:
    /// no draws, the image copied into a 32-bit float HDR attachment;
    /// `keep_hdr` reads that attachment back too.
    pub fn for_hdr_image(width: u32, height: u32, keep_hdr: bool) -> FramePlan {
        let graph = FrameGraph::for_hdr_image(keep_hdr);
        FramePlan {
            width,
            height,
            hdr_format: HdrFormat::Rgba32F,
            lighting: graph.lighting,
            opaque: Vec::new(),
            transparent: Vec::new(),
            hidden: Vec::new(),
            instance_slots: 0,
            maps: Vec::new(),
            tile_groups: Vec::new(),
            attachments: graph.attachments,
            passes: graph.passes,
            aerial_volume_reach: None,
            shadow: None,
        }
    }

    /// Where each pass records, in `passes` order: for a subpass, its
    /// render pass (counted from 0 in frame order) and its subpass index
    /// there; `None` for other passes. Consecutive subpasses form one
    /// render pass, except that a new one begins at a subpass whose
    /// attachments are of another size, or that samples an attachment the
    /// current render pass writes; any other pass between subpasses (a
    /// compute pass sampling what they wrote) ends it too.
    pub fn subpass_slots(&self) -> Vec<Option<(usize, u32)>> {
        let mut slots = Vec::with_capacity(self.passes.len());
        let (mut run, mut subpass) = (0, 0);
        // The open render pass's size and what it writes.
        let mut open: Option<((u32, u32), Vec<&str>)> = None;
        for decl in &self.passes {
            if !decl.is_subpass() {
                if open.take().is_some() {
                    run += 1;
                    subpass = 0;
                }
                slots.push(None);
                continue;
            }
            let size = self.subpass_size(decl);
            let joins = open.as_ref().is_some_and(|(open_size, written)| {
                *open_size == size && !decl.samples().iter().any(|s| written.contains(s))
            });
            if !joins {
                if open.is_some() {
                    run += 1;
                    subpass = 0;
                }
                open = Some((size, Vec::new()));
            }
            let (_, written) = open.as_mut().expect("opened above");
            written.extend(decl.io.writes());
            slots.push(Some((run, subpass)));
            subpass += 1;
        }
        slots
    }

    /// The size of a subpass's attachments (that of its first; the
    /// renderer checks that they agree): the output's for one with none.
    pub fn subpass_size(&self, decl: &PassDecl) -> (u32, u32) {
        decl.io
            .attached()
            .first()
            .and_then(|name| self.attachment(name))
            .map_or((self.width, self.height), |a| {
                a.size.extent(self.width, self.height)
            })
    }

    /// The size of attachment `a`'s images in this frame.
    pub fn attachment_extent(&self, a: &AttachmentDecl) -> (u32, u32) {
        a.size.extent(self.width, self.height)
    }

    /// How many render passes the frame records.
    pub fn render_pass_count(&self) -> usize {
        self.subpass_slots()
            .iter()
            .flatten()
            .map(|&(run, _)| run + 1)
            .max()
            .unwrap_or(0)
    }

    /// The pass names, in order.
    pub fn pass_names(&self) -> Vec<&'static str> {
        self.passes.iter().map(PassDecl::name).collect()
    }

    /// Whether `pass` (an entry of [`PASSES`]) is in the frame.
    pub fn has(&self, pass: &dyn PassType) -> bool {
        self.passes.iter().any(|p| p.is(pass))
    }

    /// Whether an attachment of this name exists.
    pub fn has_attachment(&self, name: &str) -> bool {
        self.attachments.iter().any(|a| a.name == name)
    }

    /// The attachment called `name`.
    pub fn attachment(&self, name: &str) -> Option<&AttachmentDecl> {
        self.attachments.iter().find(|a| a.name == name)
    }

    /// Every draw, in view or not: what the frame's pipelines, blocks and
    /// buffers are made for.
    pub fn draws(&self) -> impl Iterator<Item = &Draw> {
        self.opaque
            .iter()
            .chain(&self.transparent)
            .chain(&self.hidden)
    }
}

/// The frame's attachments and passes: what a scene needs, from the scene
/// alone (no meshes), so `preflight` sizes memory from the same graph the
/// renderer builds.
#[derive(Clone, Debug)]
pub struct FrameGraph {
    pub lighting: Lighting,
    pub attachments: Vec<AttachmentDecl>,
    pub passes: Vec<PassDecl>,
}

/// What decides a frame's attachments and passes: the scene and the
/// decisions several passes share, made once per frame. Each pass's
/// [`PassType::declare`] reads it and decides the rest.
pub struct FrameShape<'a> {
    /// The scene drawn; `None` for a frame that only tone-maps an HDR
    /// image copied in (`aerial tonemap`).
    pub scene: Option<&'a Scene>,
    /// The linear HDR image is read back too.
    pub keep_hdr: bool,
    /// Lit in a G-buffer and a lighting pass rather than while drawing.
    pub deferred: bool,
    /// Some object is drawn in the transparent pass.
    pub any_transparent: bool,
    /// An atmosphere pass draws the sky over the surfaces.
    pub sky: bool,
    /// Drawn straight into the sRGB output, without an HDR target.
    pub direct: bool,
    /// The attachment the objects are drawn into.
    pub target: &'static str,
    /// Opaque surfaces are drawn depth-only first ([`DepthPrepassRule`]).
    pub prepass: bool,
    /// The shadow map's width and height (of one cascade's tile), when a
    /// light casts shadows and some opaque object casts them.
    pub shadow_map: Option<u32>,
    /// Cascades in the shadow map, each a tile (`shadow_view::tiles`).
    pub shadow_cascades: u32,
}

impl FrameShape<'_> {
    /// How the opaque surfaces use depth: after a depth pre-pass they only
    /// test it (EQUAL), as it already holds the nearest.
    pub fn surface_depth(&self) -> DepthUse {
        if self.prepass {
            DepthUse::Test
        } else {
            DepthUse::Write
        }
    }

    /// The passes of [`PASSES`] this frame holds, in order, each with its
    /// declaration.
    fn passes(&self) -> Vec<PassDecl> {
        PASSES
            .iter()
            .filter_map(|&pass| {
                let io = pass.declare(self)?;
                Some(PassDecl { pass, io })
            })
            .collect()
    }
}

impl FrameGraph {
    /// The graph for `scene`; `keep_hdr` reads the linear HDR image back too.
    /// `depth_prepass = "auto"` counts as off here, for want of the meshes
    /// its rule weighs ([`FramePlan::new`] decides it): the pre-pass adds
    /// no attachment, so what `preflight` sizes from this graph is the same.
    pub fn new(scene: &Scene, keep_hdr: bool) -> FrameGraph {
        let prepass = scene.output.depth_prepass == DepthPrepass::On;
        // Automatic cascades count as the most, for the same reason.
        let views = shadow_view::view_count(scene, None);
        FrameGraph::with_prepass(scene, keep_hdr, prepass, views)
    }

    /// [`FrameGraph::new`] with the depth pre-pass decided by the caller
    /// (`prepass`; it has no effect on a frame without opaque draws), and
    /// the shadow map's cascades (`cascades`, its tiles).
    pub fn with_prepass(scene: &Scene, keep_hdr: bool, prepass: bool, cascades: u32) -> FrameGraph {
        let mut shape = FrameShape::of(scene, keep_hdr);
        shape.prepass = prepass && has_opaque_draws(scene);
        shape.shadow_cascades = cascades;
        let lighting = if shape.deferred {
            Lighting::Deferred
        } else {
            Lighting::Forward
        };
        let mut attachments = frame_attachments(scene, &shape);
        let passes = shape.passes();
        // Cleared attachments first, so the render pass needs no clear
        // value for an attachment it does not clear.
        attachments.sort_by_key(|a| a.clear.is_none());
        FrameGraph {
            lighting,
            attachments,
            passes,
        }
    }
}

impl FrameShape<'_> {
    fn of(scene: &Scene, keep_hdr: bool) -> FrameShape<'_> {
        use attachment::*;
        let debug = scene.output.debug_view.map_or(0, |v| v as u32);
        let deferred = uses_deferred_lighting(scene);
        // Drawn in the transparent pass: every object whose material is
        // not opaque, outside the debug views (see `DrawList`).
        let any_transparent = debug == 0
            && scene
                .objects
                .iter()
                .any(|o| scene.materials[o.material].opacity < 1.0);
        // LDR output without --hdr: draw straight into the sRGB output when
        // that gives exactly clamp(exposure * HDR): exposure 1, each pixel
        // written once (no transparent object blended over a clamped
        // colour), no deferred lighting, which adds lights onto the ambient
        // term (accumulating in the 8-bit target rounds each partial sum:
        // measured 1/255 off on 9 % of the pixels), and no atmosphere, whose
        // pass reads HDR surfaces and writes the HDR target. Otherwise the
        // HDR target stays, with a clamping tone map. And only with an
        // rgba32f target: the shader's f32 colour is then what the target
        // would hold, so the PNG is the same with or without --hdr (which
        // needs the target); an rgba16f target rounds it (relative 2^-11),
        // which moved 4.8 % of default.toml's pixels by 1/255.
        // Bloom blurs the HDR image before the tone map, so it needs both.
        // A debug view shows surface attributes: no atmosphere over them.
        let sky = scene.sky.is_some() && debug == 0;
        let direct = debug == 0
            && scene.tone_map.operator == ToneMapOperator::None
            && scene.tone_map.exposure == Exposure::Fixed(1.0)
            && scene.tone_map.bloom.is_none()
            && scene.output.hdr_format == HdrFormat::Rgba32F
            && !any_transparent
            && !keep_hdr
            && !deferred
            && !sky;
        let target = if sky {
            SURFACE
        } else if direct {
            OUTPUT
        } else {
            HDR
        };
        FrameShape {
            scene: Some(scene),
            keep_hdr,
            deferred,
            any_transparent,
            sky,
            direct,
            target,
            prepass: false,
            shadow_map: shadow_map_size(scene, debug),
            shadow_cascades: 1,
        }
    }
}

/// The frame's attachments, in the order they are declared (not yet
/// sorted by clearing).
fn frame_attachments(scene: &Scene, shape: &FrameShape) -> Vec<AttachmentDecl> {
    use attachment::*;
    let black = Some([0.0; 4]);
    let mut attachments = vec![AttachmentDecl {
        name: OUTPUT,
        format: OUTPUT_FORMAT,
        size: AttachmentSize::Output,
        // The tone map writes every pixel (alpha 1); drawn directly, the
        // background is opaque black like the tone-mapped one.
        clear: if shape.direct {
            Some([0.0, 0.0, 0.0, 1.0])
        } else {
            None
        },
    }];
    if !shape.direct {
        attachments.push(AttachmentDecl {
            name: HDR,
            format: hdr_format(scene.output.hdr_format),
            size: AttachmentSize::Output,
            clear: black,
        });
    }
    if shape.sky {
        attachments.push(AttachmentDecl {
            name: SURFACE,
            format: hdr_format(scene.output.hdr_format),
            size: AttachmentSize::Output,
            clear: black,
        });
    }
    attachments.push(AttachmentDecl {
        name: DEPTH,
        format: DEPTH_FORMAT,
        size: AttachmentSize::Output,
        // Reversed-Z: the far plane is 0.
        clear: Some([0.0; 4]),
    });
    if let Some(side) = shape.shadow_map {
        attachments.push(AttachmentDecl {
            name: SHADOW_MAP,
            format: DEPTH_FORMAT,
            size: {
                let (across, down) = shadow_view::tiles(shape.shadow_cascades);
                AttachmentSize::Fixed {
                    width: side * across,
                    height: side * down,
                }
            },
            // Forward depth (not reversed): 1 is nothing in the way.
            clear: Some([1.0; 4]),
        });
    }
    if shape.deferred {
        let wide = gbuffer_format(scene);
        for (name, format) in [(ALBEDO, wide), (NORMAL, NORMAL_FORMAT), (MATERIAL, wide)] {
            // Written wherever depth is; the lighting pass only reads
            // pixels that have a surface.
            attachments.push(AttachmentDecl {
                name,
                format,
                size: AttachmentSize::Output,
                clear: None,
            });
        }
    }
    attachments
}

impl FrameGraph {
    /// The graph that only tone-maps an HDR image: the image copied into a
    /// 32-bit float HDR attachment, tone-mapped, read back (`keep_hdr`: the
    /// HDR attachment too).
    pub fn for_hdr_image(keep_hdr: bool) -> FrameGraph {
        use attachment::*;
        let shape = FrameShape {
            scene: None,
            keep_hdr,
            deferred: false,
            any_transparent: false,
            sky: false,
            direct: false,
            target: HDR,
            prepass: false,
            shadow_map: None,
            shadow_cascades: 1,
        };
        FrameGraph {
            lighting: Lighting::Forward,
            attachments: vec![
                AttachmentDecl {
                    name: OUTPUT,
                    format: OUTPUT_FORMAT,
                    size: AttachmentSize::Output,
                    clear: None,
                },
                AttachmentDecl {
                    name: HDR,
                    format: hdr_format(HdrFormat::Rgba32F),
                    size: AttachmentSize::Output,
                    clear: None,
                },
            ],
            passes: shape.passes(),
        }
    }

    /// Whether `pass` (an entry of [`PASSES`]) is in the frame.
    pub fn has(&self, pass: &dyn PassType) -> bool {
        self.passes.iter().any(|p| p.is(pass))
    }
}

/// How far from the camera the aerial-perspective volume reaches: the far
/// side of the farthest object whose bounding sphere (`bounds`, one per
/// object) may be in view, no farther than the far plane reaches, and at
/// least a millimetre. Slices spread over this distance alone, so a scene
/// of metre-sized objects gets centimetre slices and one with objects
/// across a continent gets kilometre ones; a surface beyond it (none, by
/// construction) would march its own ray.
pub fn aerial_volume_reach(scene: &Scene, bounds: &[(glam::DVec3, f32)]) -> f64 {
    let camera = &scene.camera;
    let aspect = f64::from(scene.output.width) / f64::from(scene.output.height);
    let (forward, right, up) = super::sky_resources::ray_basis(camera, aspect);
    // The view cone around `forward` through the frustum's corners.
    let corner = forward + right + up;
    let cos_corner = corner.normalize().dot(forward);
    let half_angle = cos_corner.clamp(-1.0, 1.0).acos();
    let in_view = |centre: glam::DVec3, radius: f64| {
        let to = centre - camera.eye;
        let distance = to.length();
        if distance <= radius {
            return true;
        }
        let angle = (to.dot(forward) / distance).clamp(-1.0, 1.0).acos();
        angle - (radius / distance).asin() <= half_angle
    };
    let farthest = bounds
        .iter()
        .filter(|(c, r)| in_view(*c, f64::from(*r)))
        .map(|(c, r)| c.distance(camera.eye) + f64::from(*r))
        .fold(0.0_f64, f64::max);
    // The far plane cuts view depth; along the corner ray it is farthest.
    let far_plane = camera
        .far
        .map_or(f64::INFINITY, |far| f64::from(far) * corner.length());
    farthest.min(far_plane).max(1e-3)
}

/// What the shadow map is fitted to, before the frame graph sizes it.
struct ShadowCasting {
    in_view: Vec<usize>,
    casters: Vec<Draw>,
    depths: (f64, f64),
    count: u32,
}

/// The objects in view, the casters drawn into the shadow map, the depths
/// the cascades split and their count, when the frame draws a shadow map.
fn shadow_casting(
    scene: &Scene,
    geometry: &SceneGeometry,
    draws: &DrawList,
) -> Option<ShadowCasting> {
    let debug = scene.output.debug_view.map_or(0, |v| v as u32);
    shadow_map_size(scene, debug)?;
    let in_view: Vec<usize> = draws
        .opaque
        .iter()
        .chain(&draws.transparent)
        .flat_map(|d| d.visible().iter().copied())
        .collect();
    let casters: Vec<Draw> = draws
        .opaque
        .iter()
        .chain(draws.hidden.iter().filter(|d| !d.pipeline.blended))
        .filter(|d| scene.objects[d.object].casts_shadows)
        .filter(|d| shadow_view::may_shadow(scene, geometry, &in_view, d.objects()))
        .cloned()
        .collect();
    let depths = shadow_view::caster_depths(scene, geometry, &in_view, &casters);
    Some(ShadowCasting {
        count: shadow_view::view_count(scene, Some(depths)),
        in_view,
        casters,
        depths,
    })
}

/// The shadow map's side for `scene` (`debug`: its debug view, 0 for
/// none): when a light casts shadows, outside the debug views, and some
/// opaque object casts them.
pub(crate) fn shadow_map_size(scene: &Scene, debug: u32) -> Option<u32> {
    let casters = scene
        .objects
        .iter()
        .any(|o| o.casts_shadows && scene.materials[o.material].opacity >= 1.0);
    (scene.shadow_light.is_some() && debug == 0 && casters).then_some(scene.output.shadow_map)
}

/// Whether `scene` draws opaque surfaces: a debug view draws every object
/// opaque, otherwise those whose material is (see `DrawList`).
fn has_opaque_draws(scene: &Scene) -> bool {
    let debug = scene.output.debug_view.is_some();
    scene
        .objects
        .iter()
        .any(|o| debug || scene.materials[o.material].opacity >= 1.0)
}

/// Whether `scene` is lit in a deferred lighting pass: asked for, outside
/// the debug views (which draw attributes, not light), and with an opaque
/// Phong surface to light (Gouraud and toon keep their forward form, drawn
/// in the same subpass).
pub fn uses_deferred_lighting(scene: &Scene) -> bool {
    scene.output.debug_view.is_none()
        && scene.output.lighting == Lighting::Deferred
        && scene.objects.iter().any(|o| {
            let m = &scene.materials[o.material];
            m.opacity >= 1.0 && m.shading == ShadingModel::Phong
        })
}

/// The 8-bit output: UNORM holding sRGB-encoded values, which the shaders
/// writing it encode themselves (`glsl/include/srgb.glsl`), so its bytes do
/// not depend on the driver's own encode.
pub const OUTPUT_FORMAT: Format = Format::R8G8B8A8_UNORM;
pub const DEPTH_FORMAT: Format = Format::D32_SFLOAT;
/// kd can exceed 1 (it is only required to be >= 0), so not UNORM: the
/// G-buffer's albedo (kd × texture) and material (ks, shininess) are 16-bit
/// floats, or 32-bit ones for a scene whose values 16 bits cannot hold
/// ([`gbuffer_format`]).
pub const ALBEDO_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
/// Octahedral normal, two signed 16-bit components.
pub const NORMAL_FORMAT: Format = Format::R16G16_SNORM;
/// The G-buffer's material (ks rgb, shininess a) has the albedo's format.
/// The wide G-buffer format for albedo and material.
pub const WIDE_GBUFFER_FORMAT: Format = Format::R32G32B32A32_SFLOAT;

/// The largest finite 16-bit float.
const F16_MAX: f32 = 65504.0;
/// The smallest normal 16-bit float: below it 16-bit floats lose relative
/// precision (subnormals), down to 0 below 2^-25.
const F16_MIN_NORMAL: f32 = 6.103_515_6e-5;

/// Whether a 16-bit float holds `x` (>= 0) to its full relative precision
/// (2^-11): 0, or a normal 16-bit number.
fn fits_f16(x: f32) -> bool {
    x == 0.0 || (F16_MIN_NORMAL..=F16_MAX).contains(&x)
}

/// The format of the G-buffer's albedo and material attachments for a
/// scene: [`ALBEDO_FORMAT`] (16-bit floats, half the memory and bandwidth)
/// when every deferred-lit material's kd, ks and shininess fit 16-bit
/// floats at full precision, [`WIDE_GBUFFER_FORMAT`] otherwise, so that
/// deferred lighting reads the material forward lighting uses (kd up to
/// the scene's 1e6 overflowed 16 bits at 65504 before). A texture only
/// scales kd down; texels that take it below 2^-14 lose relative precision
/// but not more than 2^-25 absolute, far below 1/255 of any lit pixel.
pub fn gbuffer_format(scene: &Scene) -> Format {
    let narrow = scene.objects.iter().all(|o| {
        let m = &scene.materials[o.material];
        let lit_later = m.opacity >= 1.0 && m.shading == ShadingModel::Phong;
        !lit_later
            || (m.kd.to_array().into_iter().all(fits_f16)
                && m.ks.to_array().into_iter().all(fits_f16)
                && m.shininess <= F16_MAX)
    });
    if narrow {
        ALBEDO_FORMAT
    } else {
        WIDE_GBUFFER_FORMAT
    }
}

pub fn hdr_format(format: HdrFormat) -> Format {
    match format {
        HdrFormat::Rgba16F => Format::R16G16B16A16_SFLOAT,
        HdrFormat::Rgba32F => Format::R32G32B32A32_SFLOAT,
    }
}

#[cfg(test)]
mod tests {

    use super::*;
    use crate::scene::AerialPerspective;
    use std::path::Path;

    fn load(file: &str) -> (Scene, FramePlan) {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/scenes")
            .join(file);
        let scene = Scene::load(&path).unwrap();
        let plan = FramePlan::new(&scene, &SceneGeometry::new(&scene).unwrap(), false);
        (scene, plan)
    }

    /// A pass's subpass-ness matches how every plan declares it, every
    /// pass of `PASSES` is declared by some plan under its own name, and
    /// the timing note names exactly the subpasses.
    #[test]
    fn passes_agree_with_their_declarations_and_the_note() {
        let mut plans: Vec<FramePlan> = ["default.toml", "earth_noon.toml", "transparency.toml"]
            .iter()
            .map(|f| load(f).1)
            .collect();
        let (mut scene, _) = load("many_lights.toml");
        scene.output.lighting = Lighting::Deferred;
        plans.push(FramePlan::new(
            &scene,
            &SceneGeometry::new(&scene).unwrap(),
            true,
        ));
        plans.push(FramePlan::for_hdr_image(8, 8, true));
        let (mut scene, _) = load("default.toml");
        scene.output.depth_prepass = DepthPrepass::On;
        plans.push(FramePlan::new(
            &scene,
            &SceneGeometry::new(&scene).unwrap(),
            false,
        ));
        let (mut scene, _) = load("earth_objects.toml");
        scene.sky.as_mut().unwrap().aerial_perspective = AerialPerspective::Volume;
        scene.tone_map.exposure = Exposure::Auto;
        scene.shadow_light = Some(crate::scene::ShadowLight::Sun);
        scene.tone_map.bloom = Some(crate::scene::Bloom::default());
        plans.push(FramePlan::new(
            &scene,
            &SceneGeometry::new(&scene).unwrap(),
            false,
        ));
        let mut seen = std::collections::HashSet::new();
        for decl in plans.iter().flat_map(|p| &p.passes) {
            assert_eq!(decl.pass.is_subpass(), decl.is_subpass(), "{decl:?}");
            seen.insert(decl.name());
        }
        let names: std::collections::HashSet<_> = PASSES.iter().map(|p| p.name()).collect();
        assert_eq!(names.len(), PASSES.len(), "two passes share a name");
        assert_eq!(seen, names, "a pass no plan declares");
        let note = subpass_timing_note();
        for pass in PASSES {
            assert_eq!(note.contains(pass.name()), pass.is_subpass(), "{note}");
        }
    }

    #[test]
    fn only_whole_shininess_up_to_the_maximum_is_an_exponent() {
        for (shininess, exponent) in [
            (1.0, 1),
            (30.0, 30),
            (1023.0, MAX_SHININESS_EXPONENT),
            (30.5, 0),
            (0.0, 0),
            (0.25, 0),
            (1024.0, 0),
            (f32::NAN, 0),
        ] {
            assert_eq!(shininess_exponent(shininess), exponent, "{shininess}");
        }
    }

    /// Forward draws carry their material's exponent; G-buffer draws of
    /// Phong surfaces leave lighting to the lighting pass and carry none.
    #[test]
    fn forward_draws_carry_the_shininess_exponent() {
        let (mut scene, plan) = load("default.toml");
        // default.toml: the ground's material has shininess 8, the ball's
        // ("red") 48 and the ring's ("gold") 64, whole numbers in the
        // exponent's range, so each is its own exponent.
        let expected = |name: &str| match name {
            "ground" => 8,
            "ball" => 48,
            "ring" => 64,
            other => panic!("default.toml has no object {other}"),
        };
        assert_eq!(plan.opaque.len(), 3);
        for d in plan.opaque.iter().chain(&plan.transparent) {
            let name = &scene.objects[d.object].name;
            assert_eq!(d.pipeline.shininess_exponent, expected(name), "{name}");
        }
        scene.output.lighting = Lighting::Deferred;
        let plan = FramePlan::new(&scene, &SceneGeometry::new(&scene).unwrap(), false);
        for d in &plan.opaque {
            let material = &scene.materials[scene.objects[d.object].material];
            if material.shading == ShadingModel::Phong {
                assert_eq!(d.pipeline.shininess_exponent, 0);
            }
        }
    }

    #[test]
    fn a_scene_without_transparency_or_textures_gets_neither() {
        let (_, plan) = load("default.toml");
        assert_eq!(plan.pass_names(), vec!["opaque", "tonemap", "readback"]);
        assert!(plan.maps.is_empty());
        assert!(plan
            .draws()
            .all(|d| d.pipeline.maps.is_empty() && !d.pipeline.blended));
        assert!(!plan.has_attachment(attachment::ALBEDO));
    }

    #[test]
    fn transparent_draws_are_sorted_back_to_front() {
        let (scene, plan) = load("transparency.toml");
        assert!(plan.pass_names().contains(&"transparent"));
        // transparency.toml: the eye at (0, 2.4, 8.5); the glass spheres'
        // centres are 7.457 (blue, at (-0.6, 1, 1.2)), 7.414 (pink, at
        // (0, 1.95, 1.1)) and 7.359 (green, at (0.6, 1, 1.3)) away.
        let order: Vec<&str> = plan
            .transparent
            .iter()
            .map(|d| scene.objects[d.object].name.as_str())
            .collect();
        assert_eq!(order, ["blue glass", "pink glass", "green glass"]);
        assert!(plan.opaque.iter().all(|d| !d.pipeline.blended));
    }

    #[test]
    fn textures_are_loaded_once_and_only_when_used() {
        let (_, plan) = load("flag.toml");
        assert_eq!(plan.maps.len(), 1);
        let textured = plan
            .draws()
            .filter(|d| d.maps[MapKind::BaseColor as usize].is_some())
            .count();
        assert!(textured >= 1);
    }

    /// A unit sphere at the origin and a cutoff of 1e-3: the directional
    /// light (0) always reaches it; the point light 1 unit above its
    /// surface (2) keeps 1 / (1 + 1²) = 0.5 of its strength; the one 99
    /// units away (1) keeps 1 / (1 + 99²) = 1.0e-4, below the cutoff.
    #[test]
    fn each_draw_carries_only_the_lights_that_reach_it() {
        let toml = "light_cutoff = 0.001\n\
            [camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\
            [[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\ncolor = [1.0, 1.0, 1.0]\n\
            [[lights]]\ntype = \"point\"\nposition = [100.0, 0.0, 0.0]\ncolor = [1.0, 1.0, 1.0]\n\
            attenuation = [1.0, 0.0, 1.0]\n\
            [[lights]]\ntype = \"point\"\nposition = [0.0, 2.0, 0.0]\ncolor = [1.0, 1.0, 1.0]\n\
            attenuation = [1.0, 0.0, 1.0]\n\
            [[materials]]\nname = \"grey\"\nkd = [0.5, 0.5, 0.5]\n\
            [[objects]]\nname = \"ball\"\nmaterial = \"grey\"\nshape = { type = \"sphere\", radius = 1.0 }\n";
        let scene = Scene::from_toml(toml, "lights.toml", Path::new(".")).unwrap();
        let plan = FramePlan::new(&scene, &SceneGeometry::new(&scene).unwrap(), false);
        let lights: Vec<&Vec<usize>> = plan.draws().map(|d| &d.lights).collect();
        assert_eq!(lights, [&vec![0, 2]]);
    }

    #[test]
    fn with_an_atmosphere_every_draw_is_lit_by_its_sun_and_sky_forward_and_deferred() {
        let (mut scene, plan) = load("earth_objects.toml");
        for d in plan.draws() {
            // Per point in the shaders, not a light of the object's block.
            assert_eq!(d.pipeline.air, AirLight::SunAndSky);
            assert_eq!(d.pipeline.lights as usize, d.lights.len());
        }
        // Single scattering: the sun alone, as on the ground.
        scene.sky.as_mut().unwrap().multiple_scattering = false;
        let geometry = SceneGeometry::new(&scene).unwrap();
        let plan = FramePlan::new(&scene, &geometry, false);
        assert!(plan.draws().all(|d| d.pipeline.air == AirLight::Sun));
        // Deferred: the scene's lights move to the lighting pass, the sun
        // stays with the surface pass.
        scene.output.lighting = Lighting::Deferred;
        let plan = FramePlan::new(&scene, &geometry, false);
        assert_eq!(plan.lighting, Lighting::Deferred);
        assert!(plan.opaque.iter().all(|d| d.lights.is_empty()
            && d.pipeline.air == AirLight::Sun
            && d.pipeline.lights == 0));
        // A debug view draws attributes: no light at all.
        scene.output.debug_view = Some(crate::scene::DebugView::Normals);
        let plan = FramePlan::new(&scene, &geometry, false);
        assert!(plan.draws().all(|d| d.pipeline.air == AirLight::None));
        // No atmosphere, no air light.
        let (_, plan) = load("default.toml");
        assert!(plan.draws().all(|d| d.pipeline.air == AirLight::None));
    }

    #[test]
    fn ldr_output_has_no_hdr_attachment_and_no_tone_map() {
        let (mut scene, _) = load("default.toml");
        scene.tone_map.operator = ToneMapOperator::None;
        let geometry = SceneGeometry::new(&scene).unwrap();
        // An rgba16f target rounds the colour: it stays, so the PNG does
        // not depend on --hdr.
        let plan = FramePlan::new(&scene, &geometry, false);
        assert_eq!(plan.pass_names(), vec!["opaque", "tonemap", "readback"]);
        scene.output.hdr_format = HdrFormat::Rgba32F;
        let plan = FramePlan::new(&scene, &geometry, false);
        assert_eq!(plan.pass_names(), vec!["opaque", "readback"]);
        assert!(!plan.has_attachment(attachment::HDR));
        // Reading the HDR image back needs it, and the tone map (a clamp).
        let plan = FramePlan::new(&scene, &geometry, true);
        assert_eq!(plan.pass_names(), vec!["opaque", "tonemap", "readback"]);
        assert!(plan.has_attachment(attachment::HDR));
        // So does an exposure, which the tone map applies.
        scene.tone_map.exposure = crate::scene::Exposure::Fixed(2.0);
        let plan = FramePlan::new(&scene, &geometry, false);
        assert_eq!(plan.pass_names(), vec!["opaque", "tonemap", "readback"]);
    }

    #[test]
    fn deferred_lighting_adds_the_gbuffer_and_lighting_subpass() {
        let (mut scene, _) = load("many_lights.toml");
        scene.output.lighting = Lighting::Deferred;
        let plan = FramePlan::new(&scene, &SceneGeometry::new(&scene).unwrap(), false);
        assert_eq!(
            plan.pass_names(),
            vec!["gbuffer", "lighting", "tonemap", "readback"]
        );
        for name in [attachment::ALBEDO, attachment::NORMAL, attachment::MATERIAL] {
            assert!(plan.has_attachment(name));
        }
        // Phong surfaces are lit by the lighting pass, not while drawn.
        assert!(plan.opaque.iter().all(|d| d.lights.is_empty()));
        assert!(!plan.tile_groups.is_empty());
    }

    #[test]
    fn deferred_without_phong_surfaces_stays_forward() {
        let (mut scene, _) = load("shading_models.toml");
        scene.output.lighting = Lighting::Deferred;
        for m in &mut scene.materials {
            m.shading = ShadingModel::Toon;
        }
        let plan = FramePlan::new(&scene, &SceneGeometry::new(&scene).unwrap(), false);
        assert_eq!(plan.lighting, Lighting::Forward);
        assert!(!plan.has_attachment(attachment::ALBEDO));
    }

    #[test]
    fn only_a_scene_with_an_atmosphere_gets_the_atmosphere_pass_and_surface_attachment() {
        let (_, plan) = load("default.toml");
        assert!(!plan.pass_names().contains(&"atmosphere"));
        assert!(!plan.has_attachment(attachment::SURFACE));
        let (mut scene, _) = load("earth_sunset.toml");
        let plan = FramePlan::new(&scene, &SceneGeometry::new(&scene).unwrap(), false);
        assert_eq!(
            plan.pass_names(),
            vec!["sky view", "opaque", "atmosphere", "tonemap", "readback"]
        );
        assert!(plan.has_attachment(attachment::SURFACE));
        // Without the sky-view table, no compute pass before the render pass.
        let mut marched = scene.clone();
        marched.sky.as_mut().unwrap().sky_view = None;
        let plan = FramePlan::new(&marched, &SceneGeometry::new(&marched).unwrap(), false);
        assert_eq!(
            plan.pass_names(),
            vec!["opaque", "atmosphere", "tonemap", "readback"]
        );
        // LDR output still goes through HDR: the atmosphere writes it.
        scene.tone_map.operator = ToneMapOperator::None;
        let plan = FramePlan::new(&scene, &SceneGeometry::new(&scene).unwrap(), false);
        assert!(plan.pass_names().contains(&"atmosphere"));
        assert!(plan.has_attachment(attachment::HDR));
    }

    /// The aerial-perspective volume's pass (and with it its image,
    /// bindings and shader variant, which the renderer builds for the pass)
    /// is in a frame only with aerial_perspective = "volume" and objects
    /// under the atmosphere; it reaches the far side of the farthest object
    /// in view.
    #[test]
    fn only_volume_mode_with_objects_under_an_atmosphere_gets_the_aerial_volume() {
        let plan_of =
            |scene: &Scene| FramePlan::new(scene, &SceneGeometry::new(scene).unwrap(), false);
        let (mut scene, plan) = load("earth_objects.toml");
        assert!(!plan.has(aerial_volume::PASS));
        assert_eq!(plan.aerial_volume_reach, None);
        scene.sky.as_mut().unwrap().aerial_perspective = AerialPerspective::Volume;
        let plan = plan_of(&scene);
        assert_eq!(
            plan.pass_names(),
            vec![
                "sky view",
                "aerial volume",
                "opaque",
                "atmosphere",
                "tonemap",
                "readback"
            ]
        );
        // The farthest sphere: radius 600 m, its centre 13 013.7 m away.
        let reach = plan.aerial_volume_reach.unwrap();
        assert!((13_613.0..13_700.0).contains(&reach), "{reach}");
        // Deferred lighting and no sky view: still there.
        scene.output.lighting = Lighting::Deferred;
        scene.sky.as_mut().unwrap().sky_view = None;
        let plan = plan_of(&scene);
        assert_eq!(
            plan.pass_names(),
            vec![
                "aerial volume",
                "gbuffer",
                "lighting",
                "atmosphere",
                "tonemap",
                "readback"
            ]
        );
        // A debug view draws no atmosphere, so no volume.
        let mut debug = scene.clone();
        debug.output.debug_view = Some(crate::scene::DebugView::Normals);
        assert!(!plan_of(&debug).has(aerial_volume::PASS));
        // No objects: nothing reads the volume.
        let (mut sky_only, _) = load("earth_noon.toml");
        sky_only.sky.as_mut().unwrap().aerial_perspective = AerialPerspective::Volume;
        let plan = plan_of(&sky_only);
        assert!(!plan.has(aerial_volume::PASS), "{:?}", plan.pass_names());
        assert_eq!(plan.aerial_volume_reach, None);
    }

    /// The reach counts only objects that may be in view, and stops at the
    /// far plane.
    #[test]
    fn the_aerial_volume_reaches_the_farthest_object_in_view() {
        let (mut scene, _) = load("earth_objects.toml");
        let eye = scene.camera.eye;
        let forward = (scene.camera.look_at - eye).normalize();
        let ahead = (eye + 100.0 * forward, 1.0_f32);
        let behind = (eye - 1e5 * forward, 10.0_f32);
        let reach = aerial_volume_reach(&scene, &[ahead, behind]);
        assert!((reach - 101.0).abs() < 1e-9, "{reach}");
        // Just outside the view cone to the side, however far: left out.
        let side = glam::DVec3::Y.cross(forward).normalize();
        let aside = (eye + 1e4 * (forward + 2.0 * side), 1.0_f32);
        assert!((aerial_volume_reach(&scene, &[ahead, aside]) - 101.0).abs() < 1e-9);
        // An object around the camera counts.
        let around = (eye, 5.0_f32);
        assert!((aerial_volume_reach(&scene, &[around]) - 5.0).abs() < 1e-9);
        // The far plane cuts it, at the frustum's corner.
        scene.camera.far = Some(50.0);
        let reach = aerial_volume_reach(&scene, &[ahead]);
        assert!(reach > 50.0 && reach < 70.0, "{reach}");
    }
}
