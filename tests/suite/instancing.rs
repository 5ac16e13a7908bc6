//! Instanced batches and frustum culling: objects that differ only in
//! their transform are drawn as one instanced draw, which must draw what
//! separate draws draw, bit for bit; objects wholly outside the view cost
//! no vertex work and change no pixel; and a live renderer whose view
//! brings culled objects in keeps its resources and draws what a new
//! renderer draws. Every render is under validation.

use crate::common;

use aerial::render::{FramePlan, Renderer, SceneGeometry, ViewChange};
use aerial::render_run::{self, RenderSettings};
use aerial::scene::{Knob, Scene};

/// A scene of a 4x4 grid of spheres on the xz plane, each turned and
/// squashed differently (so the normal matrix matters), plus a torus of
/// the same material, two Gouraud cylinders and two textured, normal-mapped
/// ones (tangents move with the instance's model matrix); `own_materials` gives each
/// sphere its own (identical) material, which keeps them from batching.
fn grid(own_materials: bool, eye: [f64; 3], look_at: [f64; 3]) -> Scene {
    let mut text = format!(
        "[output]\nwidth = 96\nheight = 64\n\
         [camera]\neye = {eye:?}\nlook_at = {look_at:?}\n\
         [[lights]]\ntype = \"directional\"\ndirection = [-0.3, -1.0, -0.5]\ncolor = [1.0, 1.0, 1.0]\n\
         [[lights]]\ntype = \"point\"\nposition = [0.0, 3.0, 0.0]\ncolor = [2.0, 2.0, 2.0]\n\
         [[materials]]\nname = \"clay\"\nkd = [0.7, 0.3, 0.2]\nks = [0.5, 0.5, 0.5]\nshininess = 24\n\
         [[materials]]\nname = \"chalk\"\nkd = [0.3, 0.6, 0.8]\nshading = \"gouraud\"\n\
         [[materials]]\nname = \"bumpy\"\nkd = [0.8, 0.8, 0.8]\ntexture = \"assets/textures/checker.png\"\n\
         normal_map = \"assets/models/bumps.png\"\n"
    );
    for i in 0..16 {
        let material = if own_materials {
            text += &format!(
                "[[materials]]\nname = \"clay{i}\"\nkd = [0.7, 0.3, 0.2]\nks = [0.5, 0.5, 0.5]\nshininess = 24\n"
            );
            format!("clay{i}")
        } else {
            "clay".to_string()
        };
        let (x, z) = ((i % 4) as f64 * 1.5 - 2.25, (i / 4) as f64 * 1.5 - 2.25);
        text += &format!(
            "[[objects]]\nname = \"s{i}\"\nmaterial = \"{material}\"\n\
             shape = {{ type = \"sphere\", radius = 0.5 }}\ntessellation = [24, 12]\n\
             translate = [{x:?}, 0.0, {z:?}]\n\
             rotate = {{ axis = [1.0, {:?}, 0.3], degrees = {:?} }}\nscale = [1.0, {:?}, 0.8]\n",
            0.2 * i as f64,
            25.0 * i as f64,
            0.6 + 0.05 * i as f64
        );
    }
    text += "[[objects]]\nname = \"ring\"\nmaterial = \"clay\"\n\
             shape = { type = \"torus\", major_radius = 0.6, minor_radius = 0.2 }\n\
             translate = [0.0, 1.2, 0.0]\n";
    for (x, material) in [
        (-3.5, "chalk"),
        (3.5, "chalk"),
        (-3.0, "bumpy"),
        (3.0, "bumpy"),
    ] {
        text += &format!(
            "[[objects]]\nname = \"post{x}\"\nmaterial = \"{material}\"\n\
             shape = {{ type = \"cylinder\", radius = 0.3, height = 1.5 }}\n\
             translate = [{x:?}, 0.0, -2.5]\nrotate = {{ axis = [0.0, 1.0, 0.0], degrees = {:?} }}\n",
            x * 20.0
        );
    }
    common::scene(&text)
}

fn plan(scene: &Scene) -> FramePlan {
    FramePlan::new(scene, &SceneGeometry::new(scene).unwrap(), false)
}

/// The instance counts of the plan's instanced draws, largest first.
fn batches(plan: &FramePlan) -> Vec<usize> {
    let mut sizes: Vec<usize> = plan
        .draws()
        .filter_map(|d| d.instances.as_ref().map(|i| i.members.len()))
        .collect();
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    sizes
}

fn render_counted(scene: &Scene) -> render_run::RenderRun {
    let run = render_run::render(
        scene,
        &RenderSettings {
            keep_hdr: true,
            count_work: true,
            ..common::validated_settings()
        },
    )
    .unwrap_or_else(|e| panic!("render failed: {e}"));
    common::assert_no_validation_messages(&run);
    run
}

fn same_bits(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// The 16 spheres of one material are one instanced draw, the Gouraud
/// posts another, the textured posts a third, the torus stays a plain
/// draw; with a material each, no sphere batches. Both draw the same HDR
/// image, bit for bit, with the same vertex and fragment work, lit
/// forward and deferred.
#[test]
fn an_instanced_batch_draws_what_separate_draws_draw() {
    let eye = [0.0, 3.5, 4.5];
    for lighting in ["forward", "deferred"] {
        let knob = |mut scene: Scene| {
            Knob::find("lighting")
                .unwrap()
                .set(&mut scene, lighting)
                .unwrap();
            scene
        };
        let batched = knob(grid(false, eye, [0.0, 0.0, 0.0]));
        let separate = knob(grid(true, eye, [0.0, 0.0, 0.0]));
        assert_eq!(batches(&plan(&batched)), [16, 2, 2], "{lighting}");
        assert_eq!(batches(&plan(&separate)), [2, 2], "{lighting}");
        let a = render_counted(&batched);
        let b = render_counted(&separate);
        common::assert_not_blank(&a.output, 0.25);
        let (ha, hb) = (a.hdr.as_ref().unwrap(), b.hdr.as_ref().unwrap());
        assert!(
            same_bits(&ha.data, &hb.data),
            "{lighting}: the HDR images differ"
        );
        assert_eq!(a.frames[0].work, b.frames[0].work, "{lighting}");
        assert_buffers(&batched, &a, &b);
    }
}

/// The geometry holds each distinct mesh once (sphere, torus, cylinder)
/// whether batched or not; the instance buffer holds the batched objects'
/// transforms (100 bytes each): 20 with the spheres' batch (`a`), 4
/// without (`b`, the posts are batches in both).
fn assert_buffers(scene: &Scene, a: &render_run::RenderRun, b: &render_run::RenderRun) {
    let measure = |run: &render_run::RenderRun, name: &str| {
        run.setup.iter().find(|(n, _)| *n == name).unwrap().1 * 1024.0
    };
    let geometry = SceneGeometry::new(scene).unwrap();
    let distinct_bytes: f64 = [0, 16, 17]
        .iter()
        .map(|&i| {
            let m = &geometry.meshes[i];
            (m.vertices.len() * std::mem::size_of_val(&m.vertices[0]) + m.indices.len() * 4) as f64
        })
        .sum();
    for run in [a, b] {
        let bytes = measure(run, "geometry_kib");
        assert!(
            bytes >= distinct_bytes && bytes <= distinct_bytes + 16.0,
            "{bytes} {distinct_bytes}"
        );
    }
    assert_eq!(measure(a, "instances_kib"), 20.0 * 100.0);
    assert_eq!(measure(b, "instances_kib"), 4.0 * 100.0);
}

/// Half the grid behind the camera: the plan keeps those spheres out of
/// the instanced draw, so the frame's vertex work is that of the scene
/// without them, and its image is the same.
#[test]
fn objects_outside_the_view_cost_no_vertex_work() {
    // At the grid's middle row, looking along +z: the rows at z < 0 are
    // behind (or beside) the camera.
    let eye = [0.0, 0.6, 0.2];
    let look_at = [0.0, 0.0, 5.0];
    let full = grid(false, eye, look_at);
    let p = plan(&full);
    let batch = p
        .draws()
        .find_map(|d| d.instances.as_ref().filter(|i| i.members.len() == 16))
        .expect("the spheres' batch");
    assert!(
        !batch.visible.is_empty() && batch.visible.len() < 16,
        "{batch:?}"
    );
    // The same scene without the spheres the frustum leaves out (and
    // without the posts and torus, which are out of view or not: they are
    // removed from both, so only the spheres count).
    let keep_spheres = |scene: &Scene, keep: &dyn Fn(usize) -> bool| {
        let mut s = scene.clone();
        let names: Vec<String> = (0..16)
            .filter(|&i| keep(i))
            .map(|i| format!("s{i}"))
            .collect();
        s.objects.retain(|o| names.contains(&o.name));
        s
    };
    let visible: Vec<String> = batch
        .visible
        .iter()
        .map(|&o| full.objects[o].name.clone())
        .collect();
    let all = keep_spheres(&full, &|_| true);
    let seen = keep_spheres(&full, &|i| visible.contains(&format!("s{i}")));
    let a = render_counted(&all);
    let b = render_counted(&seen);
    common::assert_not_blank(&a.output, 0.05);
    let (wa, wb) = (a.frames[0].work[0], b.frames[0].work[0]);
    assert_eq!(wa.input_primitives, wb.input_primitives, "{wa:?} {wb:?}");
    assert_eq!(wa.vertex_invocations, wb.vertex_invocations);
    // Only the spheres in view: each sphere's triangles (its poles'
    // degenerate ones dropped) times those in view.
    let sphere = SceneGeometry::new(&full).unwrap().meshes[0].indices.len() as u64 / 3;
    assert_eq!(wa.input_primitives, visible.len() as u64 * sphere);
    let (ha, hb) = (a.hdr.as_ref().unwrap(), b.hdr.as_ref().unwrap());
    assert!(same_bits(&ha.data, &hb.data), "culling changed the image");
}

/// A live renderer turned from a view that culls most of the grid to one
/// that sees all of it keeps its pipelines and buffers (the frame is only
/// recorded again) and draws what a new renderer for that view draws.
#[test]
fn turning_towards_culled_objects_draws_what_a_new_renderer_draws() {
    let ctx = common::validated_context();
    let log = ctx.validation_log().expect("validation on");
    let away = grid(false, [0.0, 0.6, 3.5], [0.0, 0.6, 10.0]);
    let towards = grid(false, [0.0, 5.0, 7.0], [0.0, 0.0, 0.0]);
    assert!(plan(&away).draws().all(|d| d
        .instances
        .as_ref()
        .is_none_or(|i| i.visible.len() < i.members.len())));
    let mut live = Renderer::new(&ctx, &away, true).unwrap();
    live.render_frame().unwrap();
    let change = live.set_view(&towards).unwrap();
    live.render_frame().unwrap();
    let after = live.hdr().unwrap();
    drop(live);
    let mut fresh = Renderer::new(&ctx, &towards, true).unwrap();
    fresh.render_frame().unwrap();
    let expected = fresh.hdr().unwrap();
    drop(fresh);
    assert_eq!(change, ViewChange::Recorded);
    assert!(same_bits(&after.data, &expected.data));
    drop(ctx);
    let messages = log.messages();
    assert!(messages.is_empty(), "{messages:?}");
}
