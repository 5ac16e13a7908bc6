//! When `depth_prepass = "auto"` turns the depth pre-pass on: an estimate,
//! from what the plan knows before any GPU work (the opaque draws, their
//! lights and their bounding spheres seen from the camera), of what the
//! pre-pass saves against what it costs.
//!
//! The pre-pass draws the opaque geometry a second time, depth only: its
//! cost is a second vertex stage and rasterization of every triangle, and
//! a depth test and write for every covered fragment. It saves the shading
//! of fragments that are later hidden: today the opaque draws are sorted
//! front to back within pipeline groups, so early depth testing already
//! rejects part of them, and the rest are shaded and then overwritten.
//! What one hidden fragment costs grows with the lights its surface
//! loops over. The constants below are calibrated on lavapipe's
//! instruction counts (`docs/performance.md`, "Depth pre-pass").

use super::draw_list::Draw;
use super::geometry::SceneGeometry;
use crate::scene::Scene;

/// The cost of shading one fragment of a forward-lit surface, in units of
/// a depth-only fragment (about 60 instructions on lavapipe, vertex work
/// included): a base (the material, the ambient term, the output) plus
/// one term per light in the draw's loop, which costs more when the light
/// is read from the object's block than when it is a constant
/// (`render::static_lights`). Measured: 6 constant lights with two maps,
/// 6 units; 8 constant lights, 10; 16 lights from the block, 40.
const FRAGMENT_BASE: f64 = 2.0;
const CONSTANT_LIGHT: f64 = 0.8;
const BLOCK_LIGHT: f64 = 2.4;
/// A fragment lit by the atmosphere's sun and sky (its tables read per
/// fragment) costs as much as this many constant lights.
const AIR_LIGHTS: f64 = 8.0;
/// What a triangle adds to the pre-pass beyond its covered pixels: its
/// second vertex stage and setup, and the partly covered 4×4 blocks along
/// its edges that lavapipe rasterizes whole (measured: about 20 units a
/// triangle, the culled back faces averaged in).
const TRIANGLE: f64 = 20.0;
/// How much more the estimated saving must be than the estimated cost:
/// the estimate of the overdrawn area from bounding spheres is coarse, and
/// near the break-even point the pass is not worth a second drawing.
const MARGIN: f64 = 1.5;

/// One opaque draw seen from the camera: the pixel rectangle its bounding
/// sphere covers (clipped to the screen), the area of its disc in it, its
/// distance, and what shading one of its fragments costs.
#[derive(Clone, Copy, Debug)]
struct Footprint {
    x: (f64, f64),
    y: (f64, f64),
    area: f64,
    distance: f64,
    radius: f64,
    fragment_cost: f64,
}

/// The estimate for one frame, in units of one depth-only fragment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthPrepassRule {
    /// Whether the opaque surfaces are lit while drawn (not deferred, not
    /// a debug view): only then is a hidden fragment expensive.
    pub forward: bool,
    /// The opaque draws' screen areas, summed, over the frame's pixels.
    pub coverage: f64,
    /// Fragments shaded and then covered, over the frame's pixels: where a
    /// draw whose bounding sphere lies wholly in front of another's centre
    /// comes after it in the draw order (another pipeline group), the
    /// overlap of their footprints. Self-occlusion within a mesh and
    /// surfaces nearer than their spheres suggest are not counted.
    pub overdrawn: f64,
    /// What shading those fragments costs without the pre-pass.
    pub saved: f64,
    /// What the pre-pass costs: a depth-only fragment per covered pixel of
    /// every draw, and its triangles again.
    pub cost: f64,
}

impl DepthPrepassRule {
    /// The estimate for `scene`'s `opaque` draws (in drawing order), whose
    /// bounds and meshes are `geometry`'s.
    pub fn of(scene: &Scene, geometry: &SceneGeometry, opaque: &[Draw]) -> DepthPrepassRule {
        let pixels = f64::from(scene.output.width) * f64::from(scene.output.height);
        let forward =
            scene.output.debug_view.is_none() && !super::plan::uses_deferred_lighting(scene);
        let air = if scene.sky.is_some() && scene.output.debug_view.is_none() {
            AIR_LIGHTS
        } else {
            0.0
        };
        // An instance batch puts each of its members in view on screen.
        let footprints: Vec<Footprint> = opaque
            .iter()
            .flat_map(|d| {
                let cost = fragment_cost(scene, d, air);
                d.visible().iter().map(move |&object| {
                    let (centre, radius) = geometry.bounds[object];
                    footprint(scene, centre, f64::from(radius), cost)
                })
            })
            .collect();
        let triangles: f64 = opaque
            .iter()
            .flat_map(|d| d.visible())
            .map(|&object| geometry.meshes[object].indices.len() as f64 / 3.0)
            .sum();
        let covered = covered_areas(&footprints);
        let overdrawn: f64 = covered.iter().sum();
        let saved: f64 = covered
            .iter()
            .zip(&footprints)
            .map(|(c, f)| c * f.fragment_cost)
            .sum();
        let area: f64 = footprints.iter().map(|f| f.area).sum();
        DepthPrepassRule {
            forward,
            coverage: area / pixels,
            overdrawn: overdrawn / pixels,
            saved,
            cost: area + triangles * TRIANGLE,
        }
    }

    /// The rule: on for forward-lit surfaces when shading the fragments
    /// that are overdrawn is estimated to cost more than the pre-pass. A
    /// G-buffer fragment is cheap (it writes attributes and lights
    /// nothing), so deferred frames keep it off.
    pub fn pays(&self) -> bool {
        self.forward && self.saved > MARGIN * self.cost
    }
}

/// For each footprint (in drawing order), the area of it that later ones
/// wholly in front of its centre cover: its fragments there were shaded
/// for nothing (at most its whole area). Spheres merely overlapping in
/// depth (a flag beside its pole, a ball on the ground) hide little of
/// each other, so they are not counted. Only footprints whose horizontal
/// spans meet can overlap, so the pairs are found by a sweep along x:
/// about the neighbours of each, not every pair (10⁵ objects in view).
fn covered_areas(footprints: &[Footprint]) -> Vec<f64> {
    let mut covered = vec![0.0; footprints.len()];
    let mut by_left: Vec<usize> = (0..footprints.len())
        .filter(|&i| footprints[i].area > 0.0)
        .collect();
    by_left.sort_by(|&a, &b| footprints[a].x.0.total_cmp(&footprints[b].x.0));
    for (k, &a) in by_left.iter().enumerate() {
        for &b in &by_left[k + 1..] {
            if footprints[b].x.0 >= footprints[a].x.1 {
                break;
            }
            let (far, near) = (a.min(b), a.max(b));
            let (f, n) = (&footprints[far], &footprints[near]);
            if n.distance + n.radius <= f.distance {
                covered[far] += overlap(f, n);
            }
        }
    }
    for (c, f) in covered.iter_mut().zip(footprints) {
        *c = c.min(f.area);
    }
    covered
}

/// What shading one fragment of `draw` costs, `air` the atmosphere's
/// light in constant lights (0 without one).
fn fragment_cost(scene: &Scene, draw: &Draw, air: f64) -> f64 {
    let lights = draw.lights.len() as f64;
    let constant = scene.output.static_lights && super::static_lights::fits(&draw.lights);
    let per_light = if constant {
        CONSTANT_LIGHT
    } else {
        BLOCK_LIGHT
    };
    FRAGMENT_BASE + per_light * lights + CONSTANT_LIGHT * air
}

/// The overlap of two footprints' rectangles, no more than either's area.
fn overlap(a: &Footprint, b: &Footprint) -> f64 {
    let span = |p: (f64, f64), q: (f64, f64)| (p.1.min(q.1) - p.0.max(q.0)).max(0.0);
    (span(a.x, b.x) * span(a.y, b.y)).min(a.area).min(b.area)
}

/// Where the sphere (`centre`, `radius`) lands on `scene`'s screen, in
/// pixels: its bounding rectangle clipped to the screen, and its projected
/// disc's area within it; `fragment_cost` is carried along.
fn footprint(scene: &Scene, centre: glam::DVec3, radius: f64, fragment_cost: f64) -> Footprint {
    let camera = &scene.camera;
    let (w, h) = (
        f64::from(scene.output.width),
        f64::from(scene.output.height),
    );
    let (forward, right, up) = super::sky_resources::ray_basis(camera, w / h);
    let to = centre - camera.eye;
    let distance = to.length();
    let depth = to.dot(forward);
    let screen = Footprint {
        x: (0.0, w),
        y: (0.0, h),
        area: w * h,
        distance,
        radius,
        fragment_cost,
    };
    if distance <= radius {
        // Around the camera: it may cover everything.
        return screen;
    }
    if depth <= -radius {
        return Footprint {
            area: 0.0,
            x: (0.0, 0.0),
            ..screen
        };
    }
    // The disc in NDC units, sized at the sphere's nearest view depth so
    // one close to the camera plane is not undersized.
    let near = (depth - radius).max(radius * 1e-3);
    let centre_ndc = (
        to.dot(right) / right.length_squared() / depth.max(near),
        to.dot(up) / up.length_squared() / depth.max(near),
    );
    let r = (radius / near / right.length(), radius / near / up.length());
    let clip = |c: f64, r: f64, size: f64| {
        let to_px = |v: f64| (v.clamp(-1.0, 1.0) + 1.0) * 0.5 * size;
        (to_px(c - r), to_px(c + r))
    };
    let x = clip(centre_ndc.0, r.0, w);
    let y = clip(centre_ndc.1, r.1, h);
    let disc = std::f64::consts::PI * r.0 * r.1 / 4.0 * w * h;
    Footprint {
        x,
        y,
        area: disc.min((x.1 - x.0) * (y.1 - y.0)),
        distance,
        radius,
        fragment_cost,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::passes::depth_prepass;
    use crate::render::plan::FramePlan;
    use crate::scene::DepthPrepass;
    use std::path::Path;

    /// The sweep along x finds what comparing every pair finds: random
    /// footprints, some off screen (zero area), some overlapping in depth.
    #[test]
    fn the_sweep_covers_what_every_pair_covers() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let footprints: Vec<Footprint> = (0..400)
            .map(|_| {
                let (x, y, size) = (next() * 300.0, next() * 200.0, next() * 40.0);
                let on_screen = next() > 0.1;
                Footprint {
                    x: (x, x + size),
                    y: (y, y + size),
                    area: if on_screen { 0.7 * size * size } else { 0.0 },
                    distance: 2.0 + next() * 20.0,
                    radius: next() * 2.0,
                    fragment_cost: 1.0,
                }
            })
            .collect();
        let swept = covered_areas(&footprints);
        for (i, far) in footprints.iter().enumerate() {
            let every_pair = footprints[i + 1..]
                .iter()
                .filter(|near| near.area > 0.0 && far.area > 0.0)
                .filter(|near| near.distance + near.radius <= far.distance)
                .map(|near| overlap(far, near))
                .sum::<f64>()
                .min(far.area);
            assert!(
                (swept[i] - every_pair).abs() <= 1e-9 * (1.0 + every_pair),
                "footprint {i}: {} against {every_pair}",
                swept[i]
            );
        }
        assert!(swept.iter().filter(|&&c| c > 0.0).count() > 20);
    }

    fn plan(scene: &Scene) -> (DepthPrepassRule, FramePlan) {
        let geometry = SceneGeometry::new(scene).unwrap();
        let plan = FramePlan::new(scene, &geometry, false);
        (DepthPrepassRule::of(scene, &geometry, &plan.opaque), plan)
    }

    fn example(file: &str) -> Scene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
        Scene::load(&path).unwrap()
    }

    /// Four spheres one behind another, each in a pipeline group drawn
    /// before the nearer one's (Phong before toon, one-sided before
    /// two-sided), lit by `lights` lights, tessellated `segments` around
    /// and half that from pole to pole: every layer shaded, then covered.
    fn layered(lights: usize, segments: u32) -> Scene {
        let mut toml = String::from(
            "ambient = [0.1, 0.1, 0.1]\nlight_cutoff = 0.0\n\
             [output]\nwidth = 320\nheight = 180\n\
             [camera]\neye = [0.0, 0.0, 12.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 40.0\n\
             [[materials]]\nname = \"phong\"\nkd = [0.7, 0.5, 0.3]\n\
             [[materials]]\nname = \"toon\"\nkd = [0.3, 0.5, 0.7]\nshading = \"toon\"\n",
        );
        for i in 0..lights {
            toml += &format!(
                "[[lights]]\ntype = \"point\"\nposition = [{}.0, 4.0, 6.0]\n\
                 color = [0.2, 0.2, 0.2]\n",
                i as i32 - 8
            );
        }
        for (i, (material, two_sided, z, radius)) in [
            ("phong", false, -9.0, 4.0),
            ("phong", true, -6.0, 3.4),
            ("toon", false, -3.0, 2.8),
            ("toon", true, 0.0, 2.2),
        ]
        .into_iter()
        .enumerate()
        {
            toml += &format!(
                "[[objects]]\nname = \"layer {i}\"\nmaterial = \"{material}\"\n\
                 two_sided = {two_sided}\nshape = {{ type = \"sphere\", radius = {radius} }}\n\
                 tessellation = [{segments}, {}]\ntranslate = [0.0, 0.0, {z}]\n",
                segments / 2
            );
        }
        Scene::from_toml(&toml, "layered.toml", Path::new(".")).unwrap()
    }

    /// The measured scenes (docs/performance.md, "Depth pre-pass"), where
    /// the pre-pass cost more instructions than it saved, stay off; the
    /// layered spheres with 16 lights from the block, where it halved the
    /// frame's instructions, turn it on.
    #[test]
    fn auto_turns_the_prepass_on_only_where_it_was_measured_to_pay() {
        for file in [
            "assets/bench/many_lights.toml",
            "assets/bench/hdr.toml",
            "assets/scenes/flag.toml",
            "assets/scenes/default.toml",
        ] {
            let (rule, plan) = plan(&example(file));
            assert!(!rule.pays(), "{file}: {rule:?}");
            assert!(!plan.has(depth_prepass::PASS), "{file}");
        }
        let (rule, plan) = plan(&layered(16, 32));
        assert!(rule.pays(), "{rule:?}");
        assert!(rule.overdrawn > 0.3, "{rule:?}");
        assert!(plan.has(depth_prepass::PASS));
        // Eight constant lights: near break-even at 320x180 (measured 3 %
        // dearer with the pre-pass), so off.
        assert!(!plan_rule(&layered(8, 48)).pays());
    }

    fn plan_rule(scene: &Scene) -> DepthPrepassRule {
        plan(scene).0
    }

    /// Deferred lighting and debug views keep it off whatever the
    /// overdraw; "on" and "off" override the rule.
    #[test]
    fn the_setting_overrides_the_rule_and_deferred_frames_stay_off() {
        let mut scene = layered(16, 32);
        scene.output.debug_view = Some(crate::scene::DebugView::Normals);
        assert!(!plan_rule(&scene).pays());
        let mut scene = layered(16, 32);
        scene.output.lighting = crate::scene::Lighting::Deferred;
        assert!(!plan_rule(&scene).pays());
        scene.output.depth_prepass = DepthPrepass::On;
        let (_, on) = plan(&scene);
        assert_eq!(
            on.pass_names(),
            [
                "depth prepass",
                "gbuffer",
                "lighting",
                "tonemap",
                "readback"
            ]
        );
        let mut scene = layered(16, 32);
        scene.output.depth_prepass = DepthPrepass::Off;
        assert!(!plan(&scene).1.has(depth_prepass::PASS));
    }

    /// A frame without opaque draws has no pre-pass even when asked for.
    #[test]
    fn no_opaque_draws_no_prepass() {
        let mut scene = example("assets/scenes/earth_noon.toml");
        scene.output.depth_prepass = DepthPrepass::On;
        assert!(!plan(&scene).1.has(depth_prepass::PASS));
    }
}
