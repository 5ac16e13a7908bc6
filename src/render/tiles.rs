//! Light culling for deferred lighting: which lights reach which screen
//! tiles.
//!
//! A point light reaches the distances where its attenuated strength is at
//! least the scene's `light_cutoff` (`Light::range`), a sphere around it.
//! The sphere's bounding box is projected to the screen, and the light is
//! listed for every tile that rectangle touches (conservative: a light can
//! be listed for a tile whose pixels it does not reach, never the other
//! way round). Tiles with the same light list form a group, drawn with one
//! pipeline whose light count is a specialization constant, exactly as
//! forward draws are per object.

use crate::scene::{LightRange, Scene};
use glam::Vec4Swizzles;
use std::collections::BTreeMap;

/// Tile edge in pixels.
pub const TILE_SIZE: u32 = 32;

/// A pixel rectangle `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl PixelRect {
    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }
}

/// Tiles lit by the same lights.
#[derive(Clone, Debug, PartialEq)]
pub struct TileGroup {
    /// Indices into `Scene::lights`, ascending.
    pub lights: Vec<usize>,
    /// The group's tiles, merged into horizontal runs, in pixels (clipped
    /// to the image).
    pub rects: Vec<PixelRect>,
}

/// The pixel rectangle a light can reach on a `width`×`height` image, or
/// `None` if it reaches no pixel.
pub fn light_screen_rect(
    scene: &Scene,
    light: usize,
    width: u32,
    height: u32,
) -> Option<PixelRect> {
    let full = PixelRect {
        x0: 0,
        y0: 0,
        x1: width,
        y1: height,
    };
    let l = &scene.lights[light];
    let (centre, radius) = match (l, l.range(scene.light_cutoff)) {
        (_, LightRange::Nowhere) => return None,
        (_, LightRange::Everywhere) => return Some(full),
        (crate::scene::Light::Point { position, .. }, LightRange::Within(r)) => (*position, r),
        (crate::scene::Light::Directional { .. }, LightRange::Within(_)) => return Some(full),
    };
    let camera = &scene.camera;
    if centre.distance(camera.eye) <= f64::from(radius + camera.near) {
        return Some(full);
    }
    // Camera-relative in f64, like the GPU's positions.
    let centre = camera.relative(centre);
    let radius = f64::from(radius);
    let vp = camera.view_projection_f64(scene.output.aspect());
    let (mut lo, mut hi) = (
        glam::Vec2::splat(f32::INFINITY),
        glam::Vec2::splat(f32::NEG_INFINITY),
    );
    for i in 0..8 {
        let corner = centre
            + radius
                * glam::DVec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                );
        let clip = vp * corner.extend(1.0);
        // A corner behind (or at) the eye projects nowhere useful; the
        // box then spans the eye plane and may cover any pixel.
        if clip.w <= f64::from(camera.near) * 0.5 {
            return Some(full);
        }
        let ndc = (clip.xy() / clip.w).as_vec2();
        lo = lo.min(ndc);
        hi = hi.max(ndc);
    }
    let to_px = |ndc: f32, size: u32| ((ndc + 1.0) * 0.5 * size as f32).clamp(0.0, size as f32);
    let rect = PixelRect {
        x0: to_px(lo.x, width).floor() as u32,
        y0: to_px(lo.y, height).floor() as u32,
        x1: to_px(hi.x, width).ceil() as u32,
        y1: to_px(hi.y, height).ceil() as u32,
    };
    (rect.x0 < rect.x1 && rect.y0 < rect.y1).then_some(rect)
}

/// Groups the `width`×`height` image's tiles by the lights that reach them;
/// tiles no light reaches are in no group.
pub fn group_lights(scene: &Scene, width: u32, height: u32) -> Vec<TileGroup> {
    let tiles_x = width.div_ceil(TILE_SIZE);
    let tiles_y = height.div_ceil(TILE_SIZE);
    let mut per_tile: Vec<Vec<usize>> = vec![Vec::new(); (tiles_x * tiles_y) as usize];
    for light in 0..scene.lights.len() {
        let Some(r) = light_screen_rect(scene, light, width, height) else {
            continue;
        };
        for ty in r.y0 / TILE_SIZE..r.y1.div_ceil(TILE_SIZE) {
            for tx in r.x0 / TILE_SIZE..r.x1.div_ceil(TILE_SIZE) {
                per_tile[(ty * tiles_x + tx) as usize].push(light);
            }
        }
    }
    let mut groups: BTreeMap<Vec<usize>, Vec<PixelRect>> = BTreeMap::new();
    for ty in 0..tiles_y {
        let mut tx = 0;
        while tx < tiles_x {
            let lights = &per_tile[(ty * tiles_x + tx) as usize];
            // A run of neighbouring tiles with the same lights is one rect.
            let mut end = tx + 1;
            while end < tiles_x && per_tile[(ty * tiles_x + end) as usize] == *lights {
                end += 1;
            }
            if !lights.is_empty() {
                groups.entry(lights.clone()).or_default().push(PixelRect {
                    x0: tx * TILE_SIZE,
                    y0: ty * TILE_SIZE,
                    x1: (end * TILE_SIZE).min(width),
                    y1: ((ty + 1) * TILE_SIZE).min(height),
                });
            }
            tx = end;
        }
    }
    groups
        .into_iter()
        .map(|(lights, rects)| TileGroup { lights, rects })
        .collect()
}
