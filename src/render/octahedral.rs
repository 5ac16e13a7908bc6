//! The G-buffer's normal encoding, mirrored from `glsl/include/octahedral.glsl`
//! so its precision can be tested on the CPU: a unit vector is projected
//! onto the octahedron |x| + |y| + |z| = 1, the lower half folded over the
//! upper, and the two coordinates in [-1, 1] stored as signed 16-bit
//! normalized integers (`R16G16_SNORM`).

use glam::{Vec2, Vec3};

fn sign_not_zero(v: Vec2) -> Vec2 {
    Vec2::new(
        if v.x >= 0.0 { 1.0 } else { -1.0 },
        if v.y >= 0.0 { 1.0 } else { -1.0 },
    )
}

/// Encodes unit vector `n` as two values in [-1, 1].
pub fn encode(n: Vec3) -> Vec2 {
    let p = Vec2::new(n.x, n.y) / (n.x.abs() + n.y.abs() + n.z.abs());
    if n.z >= 0.0 {
        p
    } else {
        (Vec2::ONE - Vec2::new(p.y, p.x).abs()) * sign_not_zero(p)
    }
}

/// Decodes two values in [-1, 1] to a unit vector.
pub fn decode(e: Vec2) -> Vec3 {
    let mut n = Vec3::new(e.x, e.y, 1.0 - e.x.abs() - e.y.abs());
    if n.z < 0.0 {
        let folded = (Vec2::ONE - Vec2::new(n.y, n.x).abs()) * sign_not_zero(Vec2::new(n.x, n.y));
        n.x = folded.x;
        n.y = folded.y;
    }
    n.normalize()
}

/// Rounds to the nearest value a signed 16-bit normalized channel holds, as
/// the G-buffer target stores it.
pub fn quantize_snorm16(v: Vec2) -> Vec2 {
    let q = |x: f32| (x.clamp(-1.0, 1.0) * 32767.0).round() / 32767.0;
    Vec2::new(q(v.x), q(v.y))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Normals spread over the whole sphere (a Fibonacci lattice) plus the
    /// axes and the octahedron's folds, where the encoding is least smooth.
    fn normals() -> Vec<Vec3> {
        let n = 200_000;
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let mut v: Vec<Vec3> = (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let phi = golden * i as f64;
                Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
            })
            .collect();
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            v.push(axis);
            v.push(-axis);
        }
        v.push(Vec3::new(1.0, 1.0, 0.0).normalize());
        v.push(Vec3::new(-1.0, 1.0, -1e-7).normalize());
        v
    }

    /// The angle between two vectors, accurate near zero (acos of a float
    /// dot product cannot resolve angles below about 5e-4 rad).
    fn angle(a: Vec3, b: Vec3) -> f64 {
        let (a, b) = (a.as_dvec3(), b.as_dvec3());
        a.cross(b).length().atan2(a.dot(b))
    }

    #[test]
    fn round_trip_error_is_below_a_thousandth_of_a_degree_without_quantization() {
        let worst = normals()
            .into_iter()
            .map(|n| angle(n, decode(encode(n))))
            .fold(0.0f64, f64::max);
        // float rounding only
        assert!(
            worst.to_degrees() < 1e-3,
            "worst {} deg",
            worst.to_degrees()
        );
    }

    #[test]
    fn round_trip_through_snorm16_is_within_a_hundredth_of_a_degree() {
        // One 16-bit step is 2/65534 of the octahedron's side; the
        // projection stretches it by at most about 1.8 on the sphere, so
        // the worst error is a few 1e-5 rad (measured: below 0.004 deg).
        let worst = normals()
            .into_iter()
            .map(|n| angle(n, decode(quantize_snorm16(encode(n)))))
            .fold(0.0f64, f64::max);
        assert!(
            worst.to_degrees() < 0.01,
            "worst {} deg",
            worst.to_degrees()
        );
        println!("snorm16 round trip: worst {:.5} deg", worst.to_degrees());
        assert!(worst > 0.0, "quantization must show");
    }
}
