//! Exact hard shadows of the scene's shadow-casting light
//! ([`Scene::shadow_light`]) in the CPU reference.
//!
//! The GPU approximates that light's visibility with a shadow map
//! (resolution, depth bias, filtering); the reference casts a ray from the
//! shaded point towards the light (up to it, for a point light) and asks
//! whether any opaque object with
//! `casts_shadows` meets it, so a sweep measures the shadow map's error
//! against the true shadow. A [`bvh`] over the casters' world-space boxes
//! finds the candidates, and the analytic intersection
//! ([`Surface::blocks`], either face) decides.
//!
//! The shaded object itself is never tested: every surface the reference
//! has is flat or convex (sphere, plane, open cylinder, under any affine
//! transform), so a ray leaving its lit side cannot meet it again. That is
//! exact where an epsilon along the ray would be a guess, whatever the
//! scene's scale. Other objects count from `t > 0`.

use bvh::aabb::{Aabb, Bounded, IntersectsAabb};
use bvh::bounding_hierarchy::BHShape;
use bvh::bvh::Bvh;
use glam::{DMat4, DVec3};

use super::{model_matrix, Surface};
use crate::scene::Scene;

/// One object that casts shadows, in double precision.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Caster {
    /// Index into `Scene::objects`.
    object: usize,
    surface: Surface,
    world_to_object: DMat4,
    /// World-space box, a little wider than the surface.
    bounds: Aabb<f64, 3>,
    /// The BVH's node for it (set when the BVH is built).
    node: usize,
}

/// The casters of `scene`: opaque objects with `casts_shadows` whose
/// shape the reference can intersect (the others are refused elsewhere).
pub(super) fn casters(scene: &Scene) -> Vec<Caster> {
    let opaque = |material: usize| {
        scene
            .materials
            .get(material)
            .is_some_and(|m| !m.is_transparent())
    };
    scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.casts_shadows && opaque(o.material))
        .filter_map(|(object, o)| {
            let surface = Surface::of(&o.shape)?;
            let model = model_matrix(&o.transform);
            Some(Caster {
                object,
                surface,
                world_to_object: model.inverse(),
                bounds: world_box(surface, model),
                node: 0,
            })
        })
        .collect()
}

/// A box around `surface` moved by `model`: its object-space box's
/// corners transformed, widened by a part in 1e9 so that rounding in the
/// box test can never drop a ray that meets the surface.
fn world_box(surface: Surface, model: DMat4) -> Aabb<f64, 3> {
    let half = match surface {
        Surface::Sphere { radius } => DVec3::splat(radius),
        Surface::Plane { width, depth } => DVec3::new(width, 0.0, depth) * 0.5,
        Surface::Cylinder { radius, height } => DVec3::new(radius, height * 0.5, radius),
    };
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for i in 0..8 {
        let sign = DVec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { -1.0 } else { 1.0 },
        );
        let corner = model.transform_point3(half * sign);
        min = min.min(corner);
        max = max.max(corner);
    }
    let pad = 1e-9 * (max - min).max(min.abs()).max(max.abs()).max_element();
    Aabb::with_bounds((min - pad).to_array().into(), (max + pad).to_array().into())
}

impl Bounded<f64, 3> for Caster {
    fn aabb(&self) -> Aabb<f64, 3> {
        self.bounds
    }
}

impl BHShape<f64, 3> for Caster {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }

    fn bh_node_index(&self) -> usize {
        self.node
    }
}

/// The half-line `origin + t * direction`, `t >= 0`, as a BVH query.
struct ShadowRay {
    origin: DVec3,
    direction: DVec3,
}

impl IntersectsAabb<f64, 3> for ShadowRay {
    /// The slab test, with a zero direction component meaning "inside the
    /// slab or not" (the crate's own ray calls `0 * inf` a miss, which a
    /// point on a box face along an axis-aligned light would hit).
    fn intersects_aabb(&self, aabb: &Aabb<f64, 3>) -> bool {
        let (mut near, mut far) = (0.0f64, f64::INFINITY);
        for axis in 0..3 {
            let (o, d) = (self.origin[axis], self.direction[axis]);
            let (lo, hi) = (aabb.min[axis], aabb.max[axis]);
            if d == 0.0 {
                if o < lo || o > hi {
                    return false;
                }
                continue;
            }
            let (t0, t1) = ((lo - o) / d, (hi - o) / d);
            near = near.max(t0.min(t1));
            far = far.min(t0.max(t1));
        }
        near <= far
    }
}

/// The casters with a BVH over them, for one render.
pub(super) struct Occluders {
    casters: Vec<Caster>,
    bvh: Bvh<f64, 3>,
}

impl Occluders {
    pub(super) fn new(mut casters: Vec<Caster>) -> Occluders {
        let bvh = Bvh::build(&mut casters);
        Occluders { casters, bvh }
    }

    /// 1 when nothing but object `own` (`Scene::objects` index) meets the
    /// ray from the world point `p` along `to_light`, else 0.
    pub(super) fn visibility(&self, own: usize, p: DVec3, to_light: DVec3) -> f64 {
        self.visibility_along(own, p, to_light, f64::INFINITY)
    }

    /// 1 when nothing but object `own` meets the segment from the world
    /// point `p` to the point light at `light`, else 0.
    pub(super) fn visibility_to(&self, own: usize, p: DVec3, light: DVec3) -> f64 {
        self.visibility_along(own, p, light - p, 1.0)
    }

    /// 1 when nothing but object `own` meets `p + t d` for `0 < t < t_max`.
    fn visibility_along(&self, own: usize, p: DVec3, d: DVec3, t_max: f64) -> f64 {
        let ray = ShadowRay {
            origin: p,
            direction: d,
        };
        // `traverse` rather than `traverse_iterator`: the iterator's stack
        // has a fixed 32 entries, which a deep tree would overflow.
        let blocked = self
            .bvh
            .traverse(&ray, &self.casters)
            .into_iter()
            .filter(|caster| caster.object != own)
            .any(|caster| caster.blocks_within(p, d, t_max));
        if blocked {
            0.0
        } else {
            1.0
        }
    }
}

impl Caster {
    /// Whether the surface meets the world-space ray `p + t d` for
    /// `0 < t < t_max`.
    fn blocks_within(&self, p: DVec3, d: DVec3, t_max: f64) -> bool {
        let o = self.world_to_object.transform_point3(p);
        let d = self.world_to_object.transform_vector3(d);
        self.surface.blocks(o, d, 0.0, t_max)
    }
}
