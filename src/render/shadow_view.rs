//! Where the shadow map looks from: for a directional light or the sun,
//! orthographic views along the light (one per cascade of the view's
//! depth), fitted to the casters that can shadow what the camera sees; for
//! a point light, the six faces of a cube around it. Each view is a tile
//! of the one map ([`tiles`]).
//!
//! The map covers, across the light, the intersection of three boxes in
//! the light's frame: the camera's frustum (cut at the far side of the
//! farthest object in view), the objects in view (the receivers) and the
//! casters. Nothing outside the first two is ever looked up, and nothing
//! outside the last is ever in shadow, so every texel the lookup can reach
//! is spent where a shadow can fall. Along the light it spans from the
//! caster nearest the light to the farthest receiver, so no caster is
//! clipped (a caster behind the camera still shadows what is in view).
//! For the sun, whose shadows also fall on the planet's ground, the map
//! covers the casters whole, and ground beyond its far side compares as
//! its farthest depth (`shadow_map.glsl` clamps), so it is shadowed
//! exactly where a caster covers the texel.
//! Texels are not snapped to a world grid: each frame is fitted on its own
//! (a moving camera's shadows may shimmer by a texel).

use super::draw_list::Draw;
use super::geometry::SceneGeometry;
use super::sky_resources::ray_basis;
use crate::scene::{Light, Scene, ShadowCascades, ShadowLight, Shape, MAX_SHADOW_CASCADES};
use crate::shader_ids::{
    SPEC_SHADOW_SUN, SPEC_SHADOW_TAPS, SPEC_SHADOW_TILES_ACROSS, SPEC_SHADOW_TILES_DOWN,
    SPEC_SHADOW_TILE_TEXEL, SPEC_SHADOW_VIEWS,
};
use glam::{DMat4, DVec3, DVec4};

/// The shadow map's views for one frame: one per cascade, each in its
/// tile of the map.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowView {
    /// Nearest first.
    pub cascades: Vec<Cascade>,
    /// The map's tiles across and down (cascade i in column i % across,
    /// row i / across).
    pub tiles: (u32, u32),
    /// Whether the light is the atmosphere's sun (else a scene light).
    pub sun: bool,
    /// A point light's world position: the views are then the six faces
    /// of a cube around it (+x, -x, +y, -y, +z, -z), not cascades.
    pub point: Option<DVec3>,
    /// The faces' perspective projection (glam's `perspective_rh`, depth
    /// 0 to 1): its x and y scale, `far / (near - far)` and that times
    /// `near`; zeros for cascades. The lookup projects with these and the
    /// face's axes (fixed), not the six matrices.
    pub face_projection: [f64; 3],
    /// The draws drawn into the map: every opaque draw, in view or not,
    /// whose objects cast shadows (and may shadow something in view).
    pub casters: Vec<Draw>,
    /// A tile's width in texels (`[output] shadow_map`).
    pub side: u32,
    /// Texels across the lookup's filter (`[output] shadow_filter`).
    pub taps: u32,
}

impl ShadowView {
    /// The specialization constants of the shaders that look the map up:
    /// the filter's taps, the number of views (cascades or cube faces),
    /// which lets them read the shadow block with constant indices,
    /// whether the sun casts the shadows, and the map's tiles. What the
    /// plan fixes is a constant, not a value read from the block per pixel
    /// (see `glsl/include/shadow_map.glsl`); the block holds what follows
    /// the view.
    pub fn constants(&self) -> [(u32, u32); 6] {
        [
            (SPEC_SHADOW_TAPS, self.taps),
            (SPEC_SHADOW_VIEWS, self.cascades.len() as u32),
            (SPEC_SHADOW_SUN, u32::from(self.sun)),
            (SPEC_SHADOW_TILE_TEXEL, (1.0 / self.side as f32).to_bits()),
            (SPEC_SHADOW_TILES_ACROSS, self.tiles.0),
            (SPEC_SHADOW_TILES_DOWN, self.tiles.1),
        ]
    }
}

/// One cascade: the part of the view up to some distance from the camera,
/// seen from the light.
#[derive(Clone, Debug, PartialEq)]
pub struct Cascade {
    /// Camera-relative position (as every position the GPU sees) to the
    /// light's clip space: x, y in [-1, 1] across the cascade's tile, z in
    /// [0, 1] from the caster nearest the light.
    pub view_projection: DMat4,
    /// The world-space width of one texel (the larger of its two sides);
    /// for a cube face, per unit of distance from the light.
    pub texel: f64,
    /// The distance from the camera where the cascade ends (the last one:
    /// everywhere beyond).
    pub reach: f64,
    /// The casters drawn into this view, as indices into
    /// [`ShadowView::casters`]; `None` for every one. A cube face lists
    /// those whose bounding spheres reach into it (a cascade's box is
    /// fitted to the casters, so it takes them all).
    pub drawn: Option<Vec<usize>>,
}

/// The map's tiles across and down for `count` views: one, two side by
/// side, two rows of two (three or four cascades), or two rows of three
/// (a point light's cube faces).
pub fn tiles(count: u32) -> (u32, u32) {
    match count {
        0 | 1 => (1, 1),
        2 => (2, 1),
        3 | 4 => (2, 2),
        _ => (3, 2),
    }
}

/// The views a shadow map holds: a point light's six cube faces, or the
/// cascades [`cascade_count`] gives (`depths`: the casters' in view; with
/// `None`, before any view is known, `auto` counts as the most it can
/// give, the largest map the frame may need).
pub fn view_count(scene: &Scene, depths: Option<(f64, f64)>) -> u32 {
    match (
        scene.shadow_light.and_then(|l| point_light(scene, l)),
        depths,
    ) {
        (Some(_), _) => 6,
        (None, Some(depths)) => cascade_count(scene, depths),
        (None, None) => match scene.output.shadow_cascades {
            ShadowCascades::Count(n) => n,
            ShadowCascades::Auto => MAX_SHADOW_CASCADES,
        },
    }
}

/// The position of `light` when it is a point light.
pub fn point_light(scene: &Scene, light: ShadowLight) -> Option<DVec3> {
    let ShadowLight::Light(i) = light else {
        return None;
    };
    match scene.lights.get(i)? {
        Light::Point { position, .. } => Some(*position),
        Light::Directional { .. } => None,
    }
}

/// How many cascades `scene` asks for: its count, or with `auto` one
/// while the farthest caster in view (`depths`, [`caster_depths`]) is
/// within 30 times the nearest one's distance, and one more per further
/// factor of ten, at most [`MAX_SHADOW_CASCADES`].
pub fn cascade_count(scene: &Scene, depths: (f64, f64)) -> u32 {
    match scene.output.shadow_cascades {
        ShadowCascades::Count(n) => n,
        ShadowCascades::Auto => {
            let ratio = depths.1 / depths.0;
            if ratio < 30.0 {
                1
            } else {
                (1 + (ratio / 30.0).log10().ceil() as u32).min(MAX_SHADOW_CASCADES)
            }
        }
    }
}

/// The nearest and farthest distances from the camera of the casters'
/// objects `in_view` (each by the box around its vertices, not its
/// bounding sphere, which a ground plane would stretch to the camera);
/// the nearest at least the near plane's. Where the cascades split.
pub fn caster_depths(
    scene: &Scene,
    geometry: &SceneGeometry,
    in_view: &[usize],
    casters: &[Draw],
) -> (f64, f64) {
    let near_plane = f64::from(scene.camera.near);
    let (mut near, mut far) = (f64::INFINITY, near_plane);
    let eye = scene.camera.eye;
    let mut seen = vec![false; scene.objects.len()];
    for &o in in_view {
        seen[o] = true;
    }
    for &o in casters
        .iter()
        .flat_map(|d| d.objects())
        .filter(|&&o| seen[o])
    {
        let (lo, hi) = geometry.world_box(scene, o);
        near = near.min(eye.clamp(lo, hi).distance(eye));
        // The box's corner farthest from the eye.
        far = far.max((eye - lo).abs().max((hi - eye).abs()).length());
    }
    (near.max(near_plane).min(far), far)
}

/// The unit direction `light` travels in `scene`.
pub fn light_direction(scene: &Scene, light: ShadowLight) -> Option<DVec3> {
    match light {
        ShadowLight::Light(i) => match scene.lights.get(i)? {
            Light::Directional { direction, .. } => Some(direction.as_dvec3().normalize()),
            Light::Point { .. } => None,
        },
        ShadowLight::Sun => Some(-scene.sky.as_ref()?.sun.direction.normalize()),
    }
}

/// Whether any of `objects` (a draw's) may shadow something in view
/// (`in_view`): false only for a flat caster (a plane, which cannot shadow
/// itself) with every other object in view on its lit side, or behind it
/// only where the plane hides it from the camera. The sun's planet ground
/// may lie behind any caster, so under the sun every caster may shadow.
/// Drawing such a plane into the map (a ground plane under the objects,
/// say) would fill every texel for nothing.
pub fn may_shadow(
    scene: &Scene,
    geometry: &SceneGeometry,
    in_view: &[usize],
    objects: &[usize],
) -> bool {
    let Some(light) = scene.shadow_light else {
        return false;
    };
    // A point light's rays diverge: no half-space test here.
    let Some(direction) = light_direction(scene, light) else {
        return true;
    };
    if light == ShadowLight::Sun {
        return true;
    }
    objects.iter().any(|&o| {
        let object = &scene.objects[o];
        let Shape::Plane { width, depth } = object.shape else {
            return true;
        };
        let normal = (object.transform.normal_matrix() * glam::Vec3::Y)
            .as_dvec3()
            .normalize();
        // The side the light comes from.
        let lit_side = if normal.dot(direction) < 0.0 {
            normal
        } else {
            -normal
        };
        let plane = FlatCaster {
            origin: object.transform.translate,
            lit_side,
            // A vertex this far behind the plane (relative to the scene's
            // size) still counts as on it: objects resting on a plane
            // touch it.
            tolerance: 1e-6 * f64::from(geometry.bounds[o].1),
            world_to_plane: object.transform.matrix_f64().inverse(),
            half_extent: (f64::from(width) / 2.0, f64::from(depth) / 2.0),
        };
        // The plane hides what is behind it only from its front (a
        // one-sided plane seen from behind is not drawn), only when it is
        // opaque, and only from the lit side.
        let eye = scene.camera.eye;
        let hides = scene.materials[object.material].opacity >= 1.0
            && (eye - plane.origin).dot(normal) > 0.0
            && plane.height(eye) > 0.0;
        in_view.iter().filter(|&&r| r != o).any(|&r| {
            // Wholly on the lit side by its bounding sphere: no vertex to
            // look at (the usual case, a plan for every frame).
            let (centre, radius) = geometry.bounds[r];
            if plane.height(centre) >= f64::from(radius) {
                return false;
            }
            let model = scene.objects[r].transform.matrix_f64();
            let behind = geometry.meshes[r].vertices.iter().any(|v| {
                let p = model.transform_point3(glam::Vec3::from(v.position).as_dvec3());
                plane.height(p) < -plane.tolerance
            });
            behind && !(hides && plane.hides_from(eye, geometry.world_box(scene, r)))
        })
    })
}

/// A plane that may cast shadows, as `may_shadow` tests it.
struct FlatCaster {
    origin: DVec3,
    /// Its unit normal on the side the light comes from.
    lit_side: DVec3,
    tolerance: f64,
    world_to_plane: DMat4,
    /// Half its width (object x) and depth (object z).
    half_extent: (f64, f64),
}

impl FlatCaster {
    /// Signed distance of `p` from the plane, positive on the lit side.
    fn height(&self, p: DVec3) -> f64 {
        (p - self.origin).dot(self.lit_side)
    }

    /// Whether the point `x` on the plane is on its rectangle.
    fn covers(&self, x: DVec3) -> bool {
        let local = self.world_to_plane.transform_point3(x);
        local.x.abs() <= self.half_extent.0 - self.tolerance
            && local.z.abs() <= self.half_extent.1 - self.tolerance
    }

    /// Whether every point of the box `(min, max)` behind the plane is
    /// hidden from `eye` (on the lit side) by the rectangle: whether the
    /// segment from the eye to it crosses the rectangle. The points behind
    /// the rectangle seen from the eye form a convex region, and the part
    /// of the box behind the plane is a convex polytope whose vertices are
    /// the box's corners behind the plane and its edges' crossings of it,
    /// so those vertices decide.
    fn hides_from(&self, eye: DVec3, (min, max): (DVec3, DVec3)) -> bool {
        let corner = |k: usize| {
            DVec3::new(
                if k & 1 == 0 { min.x } else { max.x },
                if k & 2 == 0 { min.y } else { max.y },
                if k & 4 == 0 { min.z } else { max.z },
            )
        };
        let eye_height = self.height(eye);
        let corners_hidden = (0..8).map(corner).all(|p| {
            let h = self.height(p);
            // On the plane's level is where the segment ends.
            h >= 0.0 || self.covers(eye + (p - eye) * (eye_height / (eye_height - h)))
        });
        // The box's 12 edges join corners differing in one bit.
        let crossings_covered = (0..8).all(|a: usize| {
            [1, 2, 4].into_iter().filter(|bit| a & bit == 0).all(|bit| {
                let (p, q) = (corner(a), corner(a | bit));
                let (hp, hq) = (self.height(p), self.height(q));
                if (hp < 0.0) == (hq < 0.0) {
                    return true;
                }
                self.covers(p + (q - p) * (hp / (hp - hq)))
            })
        });
        corners_hidden && crossings_covered
    }
}

/// An axis-aligned box in the light's frame (x, y across, z along).
#[derive(Clone, Copy, Debug)]
struct LightBox {
    min: DVec3,
    max: DVec3,
}

impl LightBox {
    const EMPTY: LightBox = LightBox {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    fn add(&mut self, p: DVec3, radius: f64) {
        self.min = self.min.min(p - radius);
        self.max = self.max.max(p + radius);
    }

    fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y
    }

    /// The overlap across the light (z is kept from `self`).
    fn intersect(&self, other: &LightBox) -> LightBox {
        LightBox {
            min: DVec3::new(
                self.min.x.max(other.min.x),
                self.min.y.max(other.min.y),
                self.min.z,
            ),
            max: DVec3::new(
                self.max.x.min(other.max.x),
                self.max.y.min(other.max.y),
                self.max.z,
            ),
        }
    }
}

/// The light's frame: x and y across the light, z along it.
struct LightFrame {
    x_axis: DVec3,
    y_axis: DVec3,
    z_axis: DVec3,
}

impl LightFrame {
    fn along(direction: DVec3) -> LightFrame {
        let helper = if direction.y.abs() < 0.9 {
            DVec3::Y
        } else {
            DVec3::X
        };
        let x_axis = helper.cross(direction).normalize();
        LightFrame {
            x_axis,
            y_axis: direction.cross(x_axis),
            z_axis: direction,
        }
    }

    fn of(&self, p: DVec3) -> DVec3 {
        DVec3::new(p.dot(self.x_axis), p.dot(self.y_axis), p.dot(self.z_axis))
    }

    /// World to the light's frame.
    fn matrix(&self) -> DMat4 {
        DMat4::from_cols(
            self.x_axis.extend(0.0),
            self.y_axis.extend(0.0),
            self.z_axis.extend(0.0),
            DVec4::W,
        )
        .transpose()
    }
}

/// What every cascade is fitted from.
struct Fitting<'a> {
    scene: &'a Scene,
    frame: LightFrame,
    /// The far side of the farthest object in view.
    farthest: f64,
    sun: bool,
    bounds: &'a [(DVec3, f32)],
    in_view: &'a [usize],
    casters: LightBox,
    side: u32,
}

impl ShadowView {
    /// The views for `scene`'s shadow light in `count` cascades split
    /// over `depths` ([`caster_depths`]), or `None` when it casts none
    /// (no such light). `bounds` are the objects' world bounding spheres,
    /// `in_view` the objects on screen, `casters` the draws drawn into the
    /// map, `side` a tile's width in texels.
    pub fn fit(
        scene: &Scene,
        bounds: &[(DVec3, f32)],
        in_view: &[usize],
        casters: Vec<Draw>,
        side: u32,
        (count, depths): (u32, (f64, f64)),
    ) -> Option<ShadowView> {
        let light = scene.shadow_light?;
        if let Some(position) = point_light(scene, light) {
            return Some(cube_faces(scene, bounds, in_view, casters, side, position));
        }
        let frame = LightFrame::along(light_direction(scene, light)?);
        let mut caster_box = LightBox::EMPTY;
        for d in &casters {
            for &o in d.objects() {
                let (c, r) = bounds[o];
                caster_box.add(frame.of(c), f64::from(r));
            }
        }
        // The last cascade's frustum reaches the farthest object in view.
        let farthest = in_view
            .iter()
            .map(|&o| bounds[o].0.distance(scene.camera.eye) + f64::from(bounds[o].1))
            .fold(0.0, f64::max);
        let fitting = Fitting {
            scene,
            frame,
            farthest,
            sun: light == ShadowLight::Sun,
            bounds,
            in_view,
            casters: caster_box,
            side,
        };
        let splits = splits(scene, depths, count.max(1));
        let cascades = splits
            .windows(2)
            .enumerate()
            .map(|(i, w)| fitting.cascade(w[0], w[1], i + 2 == splits.len()))
            .collect::<Vec<_>>();
        Some(ShadowView {
            tiles: tiles(cascades.len() as u32),
            cascades,
            sun: fitting.sun,
            point: None,
            face_projection: [0.0; 3],
            casters,
            side,
            taps: scene.output.shadow_filter.taps(),
        })
    }
}

/// The distances from the camera where cascades begin and end: the near
/// plane, then (with several) a blend of logarithmic and even steps
/// (four parts to one) between the nearest and farthest casters in view
/// (`depths`), then the farthest (the last cascade reaches beyond).
fn splits(scene: &Scene, depths: (f64, f64), count: u32) -> Vec<f64> {
    let (near, far) = depths;
    let mut splits = vec![f64::from(scene.camera.near)];
    for i in 1..count {
        let f = f64::from(i) / f64::from(count);
        let logarithmic = near * (far / near).powf(f);
        let even = near + (far - near) * f;
        splits.push(0.8 * logarithmic + 0.2 * even);
    }
    splits.push(far);
    splits
}

impl Fitting<'_> {
    /// The cascade over distances `from..to` from the camera (`last`: and
    /// beyond).
    fn cascade(&self, from: f64, to: f64, last: bool) -> Cascade {
        let scene = self.scene;
        let single = from <= f64::from(scene.camera.near) && last;
        // The receivers in view that reach into this cascade's distances.
        let mut receivers = LightBox::EMPTY;
        for &o in self.in_view {
            let (c, r) = self.bounds[o];
            let d = c.distance(scene.camera.eye);
            let r = f64::from(r);
            if single || (d + r >= from && (last || d - r <= to)) {
                receivers.add(self.frame.of(c), r);
            }
        }
        // Across the light: where a shadow can fall on screen. The sun
        // also shadows the planet's ground, which lies under every caster
        // and may be seen beyond the farthest object: its map covers the
        // casters (a nearer cascade, those over its part of the view).
        let frustum_end = if last { self.farthest } else { to };
        let frustum = frustum_box(scene, from, frustum_end, &|p| self.frame.of(p));
        let mut across = match (self.sun, single || last) {
            (true, true) => self.casters,
            (true, false) => self.casters.intersect(&frustum),
            (false, _) => receivers.intersect(&frustum).intersect(&self.casters),
        };
        if across.is_empty() {
            // No caster over anything in view: any small map will do.
            across = if receivers.is_empty() {
                self.casters
            } else {
                receivers
            };
        }
        if across.is_empty() {
            // Nothing in view and nothing casting: a unit box at the
            // camera, which every lookup finds lit.
            let eye = self.frame.of(scene.camera.eye);
            across = LightBox {
                min: eye - 0.5,
                max: eye + 0.5,
            };
        }
        self.projection(&across, &receivers, to, last)
    }

    /// The orthographic view of `across` (x, y), from the caster nearest
    /// the light to the farthest of them and the `receivers` (z).
    fn projection(&self, across: &LightBox, receivers: &LightBox, to: f64, last: bool) -> Cascade {
        let casters = &self.casters;
        // Along it, a little beyond both ends so that nothing sits exactly
        // on a plane.
        let near = casters.min.z.min(receivers.min.z);
        let far = casters.max.z.max(receivers.max.z);
        let depth_pad = 1e-3 * (far - near).max(1e-6);
        let (near, far) = (near - depth_pad, far + depth_pad);
        // A texel's margin around the box, so the filter's taps at its
        // edge read the tile, not its neighbours or the border.
        let width = (across.max.x - across.min.x).max(across.max.y - across.min.y);
        let margin = 4.0 * width / f64::from(self.side);
        let (x0, x1) = (across.min.x - margin, across.max.x + margin);
        let (y0, y1) = (across.min.y - margin, across.max.y + margin);
        let ortho = DMat4::from_cols(
            DVec4::new(2.0 / (x1 - x0), 0.0, 0.0, 0.0),
            DVec4::new(0.0, 2.0 / (y1 - y0), 0.0, 0.0),
            DVec4::new(0.0, 0.0, 1.0 / (far - near), 0.0),
            DVec4::new(
                -(x1 + x0) / (x1 - x0),
                -(y1 + y0) / (y1 - y0),
                -near / (far - near),
                1.0,
            ),
        );
        let camera_relative = DMat4::from_translation(self.scene.camera.eye);
        Cascade {
            view_projection: ortho * self.frame.matrix() * camera_relative,
            texel: (x1 - x0).max(y1 - y0) / f64::from(self.side),
            reach: if last { f64::INFINITY } else { to },
            drawn: None,
        }
    }
}

/// Texels of margin around each cube face: its view is that much wider
/// than 90°, so the filter's taps at a face's edge read the face's own
/// tile (no seam where two faces meet).
const FACE_MARGIN: f64 = 4.0;

/// The six 90°-and-a-margin perspective views of a point light at
/// `position`, from a little in front of the nearest caster to the
/// farthest object.
fn cube_faces(
    scene: &Scene,
    bounds: &[(DVec3, f32)],
    in_view: &[usize],
    casters: Vec<Draw>,
    side: u32,
    position: DVec3,
) -> ShadowView {
    let reach = |o: usize| {
        let (c, r) = bounds[o];
        (
            c.distance(position) - f64::from(r),
            c.distance(position) + f64::from(r),
        )
    };
    let caster_objects = casters.iter().flat_map(|d| d.objects().iter().copied());
    let far = in_view
        .iter()
        .copied()
        .chain(caster_objects.clone())
        .map(|o| reach(o).1)
        .fold(1e-3, f64::max);
    let nearest = caster_objects
        .map(|o| reach(o).0)
        .fold(f64::INFINITY, f64::min);
    let near = (0.5 * nearest).clamp(1e-4 * far, 0.5 * far);
    // tan of the half-angle: 1 at the tile's inner edge, FACE_MARGIN
    // texels more at its border.
    let half = f64::from(side) / (f64::from(side) - 2.0 * FACE_MARGIN);
    let projection = DMat4::perspective_rh(2.0 * half.atan(), 1.0, near, far);
    let camera_relative = DMat4::from_translation(scene.camera.eye);
    let faces = [
        (DVec3::X, DVec3::Y),
        (DVec3::NEG_X, DVec3::Y),
        (DVec3::Y, DVec3::Z),
        (DVec3::NEG_Y, DVec3::Z),
        (DVec3::Z, DVec3::Y),
        (DVec3::NEG_Z, DVec3::Y),
    ];
    let cascades = faces
        .iter()
        .map(|&(axis, up)| Cascade {
            view_projection: projection
                * DMat4::look_at_rh(position, position + axis, up)
                * camera_relative,
            texel: 2.0 * half / f64::from(side),
            reach: f64::INFINITY,
            drawn: Some(
                (0..casters.len())
                    .filter(|&i| {
                        casters[i].objects().iter().any(|&o| {
                            let (centre, radius) = bounds[o];
                            reaches_face(centre - position, f64::from(radius), axis, up, half)
                        })
                    })
                    .collect(),
            ),
        })
        .collect();
    ShadowView {
        cascades,
        tiles: tiles(6),
        sun: false,
        point: Some(position),
        face_projection: [
            projection.x_axis.x,
            projection.z_axis.z,
            projection.w_axis.z,
        ],
        casters,
        side,
        taps: scene.output.shadow_filter.taps(),
    }
}

/// Whether a sphere of `radius` at `d` from a point light reaches into
/// the cube face looking along `axis` (up `up`) whose half-angle's tangent
/// is `half`: whether it is within `radius` of the inner side of each of
/// the face's four side planes (a test that may keep a sphere near an
/// edge of the pyramid outside it, never drop one inside).
fn reaches_face(d: DVec3, radius: f64, axis: DVec3, up: DVec3, half: f64) -> bool {
    let across = axis.cross(up);
    // The planes' outward normals are (e - half axis) / |e - half axis|,
    // e one of +-across, +-up (unit, at right angles to the axis).
    let norm = (1.0 + half * half).sqrt();
    [across, -across, up, -up]
        .into_iter()
        .all(|e| (d.dot(e) - half * d.dot(axis)) / norm <= radius)
}

/// The light-frame box around the camera's frustum between view depths
/// `from` and `to` (clamped to at least the near plane).
fn frustum_box(scene: &Scene, from: f64, to: f64, to_light: &dyn Fn(DVec3) -> DVec3) -> LightBox {
    let camera = &scene.camera;
    let aspect = f64::from(scene.output.width) / f64::from(scene.output.height);
    let (forward, right, up) = ray_basis(camera, aspect);
    let near = f64::from(camera.near);
    let mut frustum = LightBox::EMPTY;
    // The corners' rays have length |corner| per unit of view depth, so
    // depth `to` along them reaches at least `to` from the eye.
    for depth in [from.max(near), to.max(near)] {
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                let p = camera.eye + (forward + right * sx + up * sy) * depth;
                frustum.add(to_light(p), 0.0);
            }
        }
    }
    frustum
}
