//! Height maps to tangent-space normal maps.
//!
//! Convention: heights are in 0..1 (8-bit or 16-bit grey, read at their
//! full precision) and the full range 0..1 spans `scale` texel widths, so
//! with per-texel derivatives the normal is
//! `n = normalize(-scale * dh/dx, -scale * dh/dy, 1)`, x to the right of
//! the image and y to its top (the OBJ convention, v up). A normal map
//! stores `0.5 + 0.5 * n` per channel; `GreenAxis::Down` stores y pointing
//! down the image (DirectX-style maps).

use glam::Vec3;
use std::path::Path;

/// How the derivatives are estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum HeightFilter {
    /// Central differences of the two neighbours.
    Central,
    /// The 3×3 Sobel operator (normalised to a per-texel slope), which
    /// smooths noise across the other axis.
    Sobel,
}

/// What lies beyond the image's edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum HeightEdge {
    /// The image repeats (tiling textures).
    Wrap,
    /// The edge texel repeats.
    Clamp,
}

/// Which way the map's green channel points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum GreenAxis {
    /// Towards the top of the image (OpenGL-style, the OBJ convention).
    Up,
    /// Towards the bottom (DirectX-style).
    Down,
}

/// A grey image of heights in 0..1, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightMap {
    pub width: u32,
    pub height: u32,
    pub heights: Vec<f32>,
}

#[derive(Debug, thiserror::Error)]
pub enum HeightError {
    #[error("{path}: {reason}")]
    Read { path: String, reason: String },
    #[error("height scale must be finite and > 0, got {0}")]
    Scale(f32),
}

impl HeightMap {
    /// Reads a PNG (format from the content) as grey heights: 16-bit
    /// images keep their 16 bits, colour images are reduced to luma.
    pub fn load(path: &Path) -> Result<HeightMap, HeightError> {
        let err = |reason: String| HeightError::Read {
            path: path.display().to_string(),
            reason,
        };
        let image = crate::image_io::decode(path).map_err(err)?;
        let grey = image.to_luma16();
        let (width, height) = grey.dimensions();
        if width == 0 || height == 0 {
            return Err(err("the image is empty".into()));
        }
        Ok(HeightMap {
            width,
            height,
            heights: grey
                .as_raw()
                .iter()
                .map(|&h| f32::from(h) / 65535.0)
                .collect(),
        })
    }

    fn at(&self, x: i64, y: i64, edge: HeightEdge) -> f32 {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let (x, y) = match edge {
            HeightEdge::Wrap => (x.rem_euclid(w), y.rem_euclid(h)),
            HeightEdge::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
        };
        self.heights[(y * w + x) as usize]
    }

    /// The unit normal of every texel, row-major, top row first, with y
    /// pointing up the image (whatever the green axis of a stored map).
    pub fn normals(
        &self,
        scale: f32,
        filter: HeightFilter,
        edge: HeightEdge,
    ) -> Result<Vec<Vec3>, HeightError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(HeightError::Scale(scale));
        }
        let mut out = Vec::with_capacity(self.heights.len());
        for row in 0..i64::from(self.height) {
            for x in 0..i64::from(self.width) {
                let h = |dx: i64, dy: i64| self.at(x + dx, row + dy, edge);
                // Rows grow downwards; slopes are per texel with y up.
                let (dx, dy) = match filter {
                    HeightFilter::Central => {
                        ((h(1, 0) - h(-1, 0)) * 0.5, (h(0, -1) - h(0, 1)) * 0.5)
                    }
                    HeightFilter::Sobel => {
                        let gx = (h(1, -1) + 2.0 * h(1, 0) + h(1, 1))
                            - (h(-1, -1) + 2.0 * h(-1, 0) + h(-1, 1));
                        let gy = (h(-1, -1) + 2.0 * h(0, -1) + h(1, -1))
                            - (h(-1, 1) + 2.0 * h(0, 1) + h(1, 1));
                        // Weights sum to 4 per side, over a distance of 2.
                        (gx / 8.0, gy / 8.0)
                    }
                };
                // Normalised in f64: in f32 the squared length of a steep
                // slope at a large scale overflows, and the normal would
                // come out as zero (any finite f32 scale fits in f64).
                let s = f64::from(scale);
                let n = glam::DVec3::new(-s * f64::from(dx), -s * f64::from(dy), 1.0).normalize();
                out.push(n.as_vec3());
            }
        }
        Ok(out)
    }
}

/// Encodes normals as an RGBA8 normal map: `0.5 + 0.5 * n`, green flipped
/// for `GreenAxis::Down`, alpha 255.
pub fn encode_normal_map(normals: &[Vec3], green: GreenAxis) -> Vec<u8> {
    let channel = |c: f32| ((0.5 + 0.5 * c) * 255.0).round().clamp(0.0, 255.0) as u8;
    normals
        .iter()
        .flat_map(|n| {
            let y = match green {
                GreenAxis::Up => n.y,
                GreenAxis::Down => -n.y,
            };
            [channel(n.x), channel(y), channel(n.z), 255]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// h(x) = 0.5 + 0.5 sin(2 pi x / period) along x, constant along y.
    fn sine(width: u32, height: u32, period: f32) -> HeightMap {
        let heights = (0..height)
            .flat_map(|_| {
                (0..width)
                    .map(move |x| 0.5 + 0.5 * (std::f32::consts::TAU * x as f32 / period).sin())
            })
            .collect();
        HeightMap {
            width,
            height,
            heights,
        }
    }

    #[test]
    fn a_sine_ridge_gives_the_closed_form_normal() {
        // Exact slope dh/dx = (pi / period) cos(2 pi x / period); central
        // differences over one texel on each side are within
        // (2 pi / period)^2 / 6 of it, relative (Taylor remainder).
        let (period, scale) = (64.0, 8.0);
        let map = sine(64, 4, period);
        for filter in [HeightFilter::Central, HeightFilter::Sobel] {
            let normals = map.normals(scale, filter, HeightEdge::Wrap).unwrap();
            for x in 0..64u32 {
                let slope = std::f32::consts::PI / period
                    * (std::f32::consts::TAU * x as f32 / period).cos();
                let exact = Vec3::new(-scale * slope, 0.0, 1.0).normalize();
                let n = normals[(64 + x) as usize];
                let angle = n.angle_between(exact).to_degrees();
                assert!(angle < 0.2, "{filter:?} x={x}: {angle} degrees off");
                assert!(n.y.abs() < 1e-6, "no slope along y");
            }
        }
    }

    #[test]
    fn every_finite_scale_gives_unit_normals_that_saturate_towards_the_slope() {
        // At huge scales the slope dominates: the normal lies flat, against
        // the slope, and still has length 1 (the squared length of the
        // unnormalised vector overflows f32 from about 1e19).
        let map = sine(64, 4, 64.0);
        for scale in [1.0, 1e10, 1e19, 1e20, 1e30, f32::MAX] {
            for filter in [HeightFilter::Central, HeightFilter::Sobel] {
                let normals = map.normals(scale, filter, HeightEdge::Wrap).unwrap();
                for (i, n) in normals.iter().enumerate() {
                    assert!(
                        (n.length() - 1.0).abs() < 1e-5,
                        "scale {scale:e} {filter:?} texel {i}: {n}"
                    );
                }
                // x = 0: rising at slope pi/64, so the normal tilts to -x.
                let n = normals[64];
                if scale >= 1e10 {
                    assert!(n.x < -0.999 && n.z >= 0.0, "scale {scale:e}: {n}");
                }
                let encoded = encode_normal_map(&normals, GreenAxis::Up);
                assert!(
                    encoded.chunks_exact(4).all(|p| p[..3] != [128, 128, 128]),
                    "scale {scale:e}: a zero-length normal was encoded"
                );
            }
        }
    }

    #[test]
    fn y_points_to_the_top_of_the_image() {
        // Heights grow towards the top row: the surface tilts away from +y.
        let heights = (0..8u32)
            .flat_map(|row| (0..8).map(move |_| 1.0 - row as f32 / 8.0))
            .collect();
        let map = HeightMap {
            width: 8,
            height: 8,
            heights,
        };
        let n = map
            .normals(1.0, HeightFilter::Central, HeightEdge::Clamp)
            .unwrap();
        let centre = n[4 * 8 + 4];
        assert!(centre.y < -0.1, "{centre}");
        let up = encode_normal_map(&[centre], GreenAxis::Up);
        let down = encode_normal_map(&[centre], GreenAxis::Down);
        assert!(up[1] < 128 && down[1] > 128, "{up:?} {down:?}");
    }

    #[test]
    fn flat_heights_encode_to_the_neutral_colour_and_bad_scale_is_refused() {
        let map = HeightMap {
            width: 3,
            height: 2,
            heights: vec![0.25; 6],
        };
        let n = map
            .normals(5.0, HeightFilter::Sobel, HeightEdge::Clamp)
            .unwrap();
        assert!(encode_normal_map(&n, GreenAxis::Up)
            .chunks(4)
            .all(|c| c == [128, 128, 255, 255]));
        assert!(map
            .normals(0.0, HeightFilter::Central, HeightEdge::Wrap)
            .is_err());
        assert!(map
            .normals(f32::NAN, HeightFilter::Central, HeightEdge::Wrap)
            .is_err());
    }
}
