//! Every example scene under assets/scenes renders under validation with
//! zero messages and produces a real image; rendering is deterministic.

use crate::common;

use aerial::scene::Scene;
use std::path::PathBuf;

fn example_scenes() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("assets/scenes exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    scenes
}

#[test]
fn every_example_scene_renders_cleanly() {
    let scenes = example_scenes();
    assert!(
        scenes.len() >= 5,
        "expected the example scenes, found {scenes:?}"
    );
    for path in scenes {
        let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        // Small, so the suite stays fast; the shading is resolution-independent.
        scene.set_output_size(Some(320), Some(180)).unwrap();
        let run = common::render(&scene, false);
        eprintln!("{}: ok", path.display());
        common::assert_not_blank(&run.output, 0.2);
    }
}

#[test]
fn the_embedded_default_scene_renders() {
    let run = common::render(&Scene::default_scene(), false);
    common::assert_not_blank(&run.output, 0.2);
}

#[test]
fn two_renders_are_bit_identical() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/transparency.toml");
    let mut scene = Scene::load(&path).unwrap();
    scene.set_output_size(Some(320), Some(180)).unwrap();
    let a = common::render(&scene, true);
    let b = common::render(&scene, true);
    assert_eq!(
        a.output.data, b.output.data,
        "tone-mapped output differs between runs"
    );
    let (ha, hb) = (a.hdr.unwrap(), b.hdr.unwrap());
    let bits =
        |p: &aerial::render::Pixels<f32>| p.data.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&ha), bits(&hb), "HDR output differs between runs");
}
