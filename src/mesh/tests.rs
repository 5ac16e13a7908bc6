//! Tests for the tessellator and the analytic surfaces: derivatives against
//! finite differences, vertices on the surface, unit non-NaN frames and
//! counter-clockwise winding as seen from the normal side.

use super::*;
use glam::{DVec3, Vec3};

/// A repeatable stream of numbers in [0, 1) (xorshift64 from `seed`), for
/// the randomised tests of the welding and tangent code.
pub(super) fn uniform_stream(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// One of every surface, plus awkward variants (spindle torus, steep flag).
fn surfaces() -> Vec<(&'static str, Box<dyn ParametricSurface>)> {
    vec![
        ("sphere", Box::new(SphereSurface { radius: 1.7 })),
        (
            "torus",
            Box::new(TorusSurface {
                major_radius: 1.0,
                minor_radius: 0.35,
            }),
        ),
        (
            "spindle torus",
            Box::new(TorusSurface {
                major_radius: 0.5,
                minor_radius: 0.8,
            }),
        ),
        (
            "plane",
            Box::new(PlaneSurface {
                width: 4.0,
                depth: 2.5,
            }),
        ),
        (
            "cylinder",
            Box::new(CylinderSurface {
                radius: 0.6,
                height: 2.0,
            }),
        ),
        (
            "flag",
            Box::new(FlagSurface {
                width: 3.0,
                height: 2.0,
                amplitude: 0.25,
                frequency: 9.0,
                phase: 0.7,
            }),
        ),
    ]
}

/// Interior parameter samples, away from the sphere poles and seams.
fn interior_samples() -> impl Iterator<Item = (f64, f64)> {
    (1..10).flat_map(|i| (1..10).map(move |j| (f64::from(i) / 10.0, f64::from(j) / 10.0)))
}

fn central_du(s: &dyn ParametricSurface, u: f64, v: f64, h: f64) -> DVec3 {
    (s.position(u + h, v) - s.position(u - h, v)) / (2.0 * h)
}

fn central_dv(s: &dyn ParametricSurface, u: f64, v: f64, h: f64) -> DVec3 {
    (s.position(u, v + h) - s.position(u, v - h)) / (2.0 * h)
}

#[test]
fn analytic_derivatives_match_finite_differences() {
    // h = 1e-5 balances the O(h^2) truncation error (~1e-8 for these sizes)
    // against f64 cancellation (~1e-11).
    let h = 1e-5;
    for (name, s) in surfaces() {
        for (u, v) in interior_samples() {
            let (du, fd_du) = (s.du(u, v), central_du(s.as_ref(), u, v, h));
            let (dv, fd_dv) = (s.dv(u, v), central_dv(s.as_ref(), u, v, h));
            let scale = 1.0 + du.length().max(dv.length());
            assert!(
                (du - fd_du).length() < 1e-6 * scale,
                "{name} du at ({u}, {v}): {du} vs {fd_du}"
            );
            assert!(
                (dv - fd_dv).length() < 1e-6 * scale,
                "{name} dv at ({u}, {v}): {dv} vs {fd_dv}"
            );
        }
    }
}

#[test]
fn analytic_normals_match_finite_difference_cross_products() {
    let h = 1e-5;
    for (name, s) in surfaces() {
        for (u, v) in interior_samples() {
            let fd = central_du(s.as_ref(), u, v, h).cross(central_dv(s.as_ref(), u, v, h));
            let Some(fd) = surface::unit(fd) else {
                continue; // the spindle torus's pinch ring, where no normal exists
            };
            let n = s.normal(u, v);
            assert!(
                (n - fd).length() < 1e-6,
                "{name} normal at ({u}, {v}): {n} vs {fd}"
            );
        }
    }
}

#[test]
fn tessellated_vertices_lie_on_the_surface() {
    for (name, s) in surfaces() {
        let mesh = tessellate(s.as_ref(), 24, 13);
        for vertex in &mesh.vertices {
            let [u, v] = vertex.uv.map(f64::from);
            let expected = s.position(u, v).as_vec3();
            let got = Vec3::from(vertex.position);
            assert!(
                got.distance(expected) < 1e-5,
                "{name}: vertex {got} at uv ({u}, {v}) is off the surface ({expected})"
            );
        }
    }
}

#[test]
fn vertices_satisfy_the_implicit_equations() {
    // Independent of the parameterisation: checks the shapes themselves.
    let sphere = tessellate(&SphereSurface { radius: 1.7 }, 32, 16);
    for p in sphere.vertices.iter().map(|v| Vec3::from(v.position)) {
        assert!((p.length() - 1.7).abs() < 1e-5, "sphere {p}");
    }
    let (big, small) = (1.0_f32, 0.35_f32);
    let torus = tessellate(
        &TorusSurface {
            major_radius: big.into(),
            minor_radius: small.into(),
        },
        32,
        16,
    );
    for p in torus.vertices.iter().map(|v| Vec3::from(v.position)) {
        let ring = (p.x * p.x + p.z * p.z).sqrt() - big;
        assert!(
            ((ring * ring + p.y * p.y).sqrt() - small).abs() < 1e-5,
            "torus {p}"
        );
    }
    let plane = tessellate(
        &PlaneSurface {
            width: 4.0,
            depth: 2.5,
        },
        4,
        4,
    );
    for p in plane.vertices.iter().map(|v| Vec3::from(v.position)) {
        assert!(
            p.y == 0.0 && p.x.abs() <= 2.0 && p.z.abs() <= 1.25,
            "plane {p}"
        );
    }
    let cylinder = tessellate(
        &CylinderSurface {
            radius: 0.6,
            height: 2.0,
        },
        16,
        3,
    );
    for p in cylinder.vertices.iter().map(|v| Vec3::from(v.position)) {
        assert!(
            ((p.x * p.x + p.z * p.z).sqrt() - 0.6).abs() < 1e-6,
            "cyl {p}"
        );
        assert!(p.y.abs() <= 1.0 + 1e-6, "cyl {p}");
    }
    let flag = FlagSurface {
        width: 3.0,
        height: 2.0,
        amplitude: 0.25,
        frequency: 9.0,
        phase: 0.7,
    };
    for p in tessellate(&flag, 40, 4)
        .vertices
        .iter()
        .map(|v| Vec3::from(v.position))
    {
        let z = 0.25 * (9.0 * f64::from(p.x) / 3.0 + 0.7).sin();
        assert!((f64::from(p.z) - z).abs() < 1e-5, "flag {p}");
    }
}

#[test]
fn frames_are_unit_orthogonal_and_never_nan() {
    for (name, s) in surfaces() {
        // Odd and tiny segment counts hit the poles, seams and the spindle
        // torus's pinch ring exactly.
        for (us, vs) in [(3, 3), (7, 5), (64, 32), (1, 1)] {
            for vertex in tessellate(s.as_ref(), us, vs).vertices {
                let n = Vec3::from(vertex.normal);
                let t = Vec3::from_slice(&vertex.tangent[..3]);
                let w = vertex.tangent[3];
                assert!(
                    n.is_finite() && t.is_finite() && w.is_finite(),
                    "{name} NaN"
                );
                assert!(
                    (n.length() - 1.0).abs() < 1e-5,
                    "{name} |n| = {}",
                    n.length()
                );
                assert!(
                    (t.length() - 1.0).abs() < 1e-5,
                    "{name} |t| = {}",
                    t.length()
                );
                assert!(n.dot(t).abs() < 1e-5, "{name} n.t = {}", n.dot(t));
                assert!(w == 1.0 || w == -1.0, "{name} w = {w}");
            }
        }
    }
}

#[test]
fn bitangent_follows_plus_v() {
    for (name, s) in surfaces() {
        for (u, v) in interior_samples() {
            let mesh_frame = frame(s.as_ref(), u, v);
            let (n, t) = mesh_frame;
            let bitangent = n.cross(t.truncate()) * t.w;
            assert!(bitangent.dot(s.dv(u, v)) >= 0.0, "{name} at ({u}, {v})");
        }
    }
}

#[test]
fn tangents_follow_plus_u() {
    for (name, s) in surfaces() {
        for (u, v) in interior_samples() {
            let t = frame(s.as_ref(), u, v).1.truncate();
            let du = s.du(u, v);
            if let Some(du) = surface::unit(du) {
                assert!((t - du).length() < 1e-9, "{name} at ({u}, {v})");
            }
        }
    }
}

#[test]
fn triangles_wind_counter_clockwise_seen_from_the_normal_side() {
    for (name, s) in surfaces() {
        for (us, vs) in [(3, 3), (8, 5), (48, 24)] {
            let mesh = tessellate(s.as_ref(), us, vs);
            assert!(mesh.triangle_count() > 0, "{name} has no triangles");
            let mut straddling = 0;
            for tri in mesh.indices.chunks_exact(3) {
                let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| mesh.vertices[i as usize]);
                // Signed distance from the Y axis of the spindle torus
                // (major 0.5, minor 0.8) at each vertex's v.
                let ring = [a, b, c].map(|v| 0.5 + 0.8 * (std::f32::consts::TAU * v.uv[1]).cos());
                let crosses = ring.iter().any(|r| *r < 0.0) && ring.iter().any(|r| *r > 0.0);
                if name == "spindle torus" && crosses {
                    // A triangle across the spindle torus's pinch ring joins
                    // the outer and the (flipped) inner sheet: no winding can
                    // agree with both, and the surface self-intersects there
                    // anyway. Everywhere else the rule must hold.
                    straddling += 1;
                    continue;
                }
                let [pa, pb, pc] = [a, b, c].map(|v| Vec3::from(v.position));
                let facet = (pb - pa).cross(pc - pa);
                assert!(facet.length() > 0.0, "{name}: degenerate triangle kept");
                for vertex in [a, b, c] {
                    assert!(
                        facet.dot(Vec3::from(vertex.normal)) > 0.0,
                        "{name} {us}x{vs}: triangle {tri:?} winds against its normal"
                    );
                }
            }
            // Only the two v-rows touching the pinch ring may straddle it.
            assert!(straddling <= 2 * 2 * us, "{name}: {straddling} straddling");
        }
    }
}

#[test]
fn indices_are_in_range_and_counts_match_the_grid() {
    let plane = tessellate(
        &PlaneSurface {
            width: 1.0,
            depth: 1.0,
        },
        5,
        3,
    );
    assert_eq!(plane.vertices.len(), 6 * 4);
    assert_eq!(plane.triangle_count(), 2 * 5 * 3);
    // The sphere loses one collapsed triangle per cell in each pole row.
    let sphere = tessellate(&SphereSurface { radius: 1.0 }, 12, 6);
    assert_eq!(sphere.vertices.len(), 13 * 7);
    assert_eq!(sphere.triangle_count(), 2 * 12 * 6 - 2 * 12);
    for mesh in [plane, sphere] {
        let n = mesh.vertices.len() as u32;
        assert!(mesh.indices.iter().all(|&i| i < n));
    }
}

#[test]
fn zero_segments_are_clamped_to_one() {
    let mesh = tessellate(
        &PlaneSurface {
            width: 1.0,
            depth: 1.0,
        },
        0,
        0,
    );
    assert_eq!(mesh.vertices.len(), 4);
    assert_eq!(mesh.triangle_count(), 2);
}

#[test]
fn sphere_normals_are_the_normalised_positions() {
    let mesh = tessellate(&SphereSurface { radius: 2.5 }, 33, 17);
    for vertex in &mesh.vertices {
        let p = Vec3::from(vertex.position).normalize();
        assert!(
            p.distance(Vec3::from(vertex.normal)) < 1e-6,
            "normal {:?} at {p}",
            vertex.normal
        );
    }
}

#[test]
fn sphere_poles_have_radial_normals_and_valid_tangents() {
    let sphere = SphereSurface { radius: 1.0 };
    for u in [0.0, 0.13, 0.5, 0.77, 1.0] {
        for (v, pole) in [(0.0, -DVec3::Y), (1.0, DVec3::Y)] {
            assert!((sphere.normal(u, v) - pole).length() < 1e-12);
            // The generic fallback (used by surfaces without a closed-form
            // normal) must find the same limit.
            assert!((derived_normal(&sphere, u, v) - pole).length() < 1e-5);
            let (n, t) = frame(&sphere, u, v);
            assert!((n - pole).length() < 1e-12);
            assert!((t.truncate().length() - 1.0).abs() < 1e-12);
            assert!(t.truncate().dot(n).abs() < 1e-12);
            // The pole tangent continues the ring tangent just beside it.
            let beside = sphere.du(u, if v == 0.0 { 1e-3 } else { 1.0 - 1e-3 });
            assert!((t.truncate() - beside.normalize()).length() < 1e-9);
            assert!((derived_tangent(&sphere, u, v) - beside.normalize()).length() < 1e-9);
        }
    }
}

#[test]
fn normals_point_outward_or_to_the_front() {
    let sphere = SphereSurface { radius: 1.0 };
    let torus = TorusSurface {
        major_radius: 1.0,
        minor_radius: 0.3,
    };
    let cylinder = CylinderSurface {
        radius: 1.0,
        height: 1.0,
    };
    let plane = PlaneSurface {
        width: 1.0,
        depth: 1.0,
    };
    for (u, v) in interior_samples() {
        assert!(sphere.normal(u, v).dot(sphere.position(u, v)) > 0.0);
        let p = torus.position(u, v);
        let tube_centre = DVec3::new(p.x, 0.0, p.z).normalize() * torus.major_radius;
        assert!(torus.normal(u, v).dot(p - tube_centre) > 0.0);
        let p = cylinder.position(u, v);
        assert!(cylinder.normal(u, v).dot(DVec3::new(p.x, 0.0, p.z)) > 0.0);
        assert_eq!(plane.normal(u, v), DVec3::Y);
    }
}

#[test]
fn flag_normal_is_proportional_to_the_closed_form() {
    let flag = FlagSurface {
        width: 3.0,
        height: 2.0,
        amplitude: 0.25,
        frequency: 9.0,
        phase: 0.7,
    };
    for (u, v) in interior_samples() {
        let k_d_cos = flag.frequency * flag.amplitude * (flag.frequency * u + flag.phase).cos();
        let expected = DVec3::new(-k_d_cos, 0.0, flag.width).normalize();
        assert!((flag.normal(u, v) - expected).length() < 1e-12);
        assert!(flag.normal(u, v).z > 0.0);
    }
}

#[test]
fn seams_close_the_closed_surfaces() {
    for (name, s) in surfaces() {
        if name == "plane" || name == "flag" {
            continue;
        }
        for j in 0..=8 {
            let v = f64::from(j) / 8.0;
            assert!(
                (s.position(0.0, v) - s.position(1.0, v)).length() < 1e-12,
                "{name}"
            );
            // Seam on -Z, away from a camera on +Z (the spindle torus's
            // inner sheet has passed through the axis, so it is excluded).
            assert!(s.position(0.0, v).x.abs() < 1e-12, "{name}");
            if name != "spindle torus" {
                assert!(s.position(0.0, v).z <= 1e-12, "{name}");
            }
        }
    }
}

#[test]
fn bounding_sphere_encloses_every_vertex() {
    for (name, s) in surfaces() {
        let mesh = tessellate(s.as_ref(), 20, 10);
        let (centre, radius) = mesh.bounding_sphere();
        for vertex in &mesh.vertices {
            assert!(Vec3::from(vertex.position).distance(centre) <= radius * (1.0 + 1e-6));
        }
        assert!(radius > 0.0, "{name}");
    }
    let (centre, radius) = tessellate(&SphereSurface { radius: 3.0 }, 32, 16).bounding_sphere();
    assert!(centre.length() < 1e-5 && (radius - 3.0).abs() < 1e-5);
    assert_eq!(Mesh::default().bounding_sphere(), (Vec3::ZERO, 0.0));
}

#[test]
fn vertex_layout_is_tightly_packed() {
    assert_eq!(std::mem::size_of::<Vertex>(), 48);
    let mesh = tessellate(&SphereSurface { radius: 1.0 }, 4, 3);
    let bytes: &[u8] = bytemuck::cast_slice(&mesh.vertices);
    assert_eq!(bytes.len(), mesh.vertices.len() * 48);
}

/// The bounding-box diagonal, taken four points at a time, is the one a
/// point-at-a-time fold finds (minima and maxima are exact, so equal to
/// the bit): parts of every length from 0 to 14 points (every remainder
/// of the four-point steps), spread over signs and magnitudes, with
/// `-0.0` among them.
#[test]
fn model_diagonal_matches_a_point_at_a_time_fold() {
    use super::obj::{ObjModel, ObjPart};
    let mut next = uniform_stream(0x5eed_d1a9);
    for round in 0..50 {
        let parts: Vec<ObjPart> = (0..(round % 4) + 1)
            .map(|p| ObjPart {
                name: String::new(),
                positions: (0..(round * 3 + p * 5) % 15)
                    .map(|_| {
                        let scale = 10f32.powi((next() * 12.0) as i32 - 6);
                        let p = (Vec3::new(next(), next(), next()) * 2.0 - 1.0) * scale;
                        if next() < 0.1 {
                            Vec3::new(-0.0, p.y, p.z)
                        } else {
                            p
                        }
                    })
                    .collect(),
                vertex_indices: None,
                uvs: None,
                normals: None,
                material: None,
            })
            .collect();
        let points: Vec<Vec3> = parts.iter().flat_map(|p| p.positions.clone()).collect();
        let expected = match points.first() {
            None => 0.0,
            Some(&first) => {
                let (lo, hi) = points
                    .iter()
                    .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
                (hi - lo).length()
            }
        };
        let model = ObjModel {
            parts,
            materials: Vec::new(),
            warnings: Vec::new(),
            files: Vec::new(),
            origin: glam::DVec3::ZERO,
        };
        assert_eq!(
            model.diagonal().to_bits(),
            expected.to_bits(),
            "round {round}"
        );
    }
}
