//! A scene built around one model file, for `aerial render MODEL.obj`,
//! `aerial view MODEL.obj` and `aerial scene MODEL.obj`.
//!
//! The scene is written as scene-file TOML and parsed like any scene file,
//! so what `aerial scene` writes is exactly what `render` draws:
//!
//! - the camera looks at the centre of the model's bounding sphere from a
//!   three-quarter view (35 degrees to the right of the model's front, +Z,
//!   and 25 degrees above), with a 40 degree vertical field of view and at
//!   the distance where the whole sphere fits the narrower side of the
//!   image, with a margin. An open model whose faces mostly face away from
//!   that view (a single one-sided sheet, say) is seen from behind or below
//!   instead, whichever shows the most front-facing area;
//! - three directional lights, so the rig does not depend on the model's
//!   size: a warm key light from 75 degrees left of the camera and 40
//!   degrees up (intensity 0.9), a dim cool fill from 60 degrees right,
//!   near the horizon (0.25), and a rim light from behind (165 degrees
//!   round, 30 up, 1.0) that outlines the silhouette; plus ambient 0.04,
//!   and ACES tone mapping;
//! - the model's MTL materials, or one plain grey material;
//! - for an open model (one with boundary edges: an edge of exactly one
//!   triangle, corners welded as the model's object welds them), both
//!   sides of its faces drawn (`two_sided = true` on the object), so the
//!   back of a sheet or the inside of a band is lit rather than missing;
//! - optionally a grey ground plane under the model (at the bottom of its
//!   bounding box, 16 sphere radii across).
//!
//! Because every placement is relative to the bounding sphere, models of
//! any size (millimetres to thousands of kilometres) and any offset are
//! framed alike.

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec3;

use super::{Scene, SceneError};
use crate::mesh::obj;
use crate::mesh::smoothing::Smoothing;

/// Vertical field of view of the generated camera, degrees.
pub const MODEL_FOV_Y: f64 = 40.0;
/// Camera direction from the model: degrees around +Y from the front (+Z)
/// towards +X, and degrees above the horizon.
pub const MODEL_VIEW_AZIMUTH: f64 = 35.0;
/// See [`MODEL_VIEW_AZIMUTH`].
pub const MODEL_VIEW_ELEVATION: f64 = 25.0;
/// The bounding sphere fills at most this fraction of the narrower half
/// field of view's sine (a margin around the model).
const FILL: f64 = 0.9;

/// What to build around the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelSceneOptions {
    /// Output size in pixels.
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// The object's `smoothing` (`None`: the scene file's default).
    pub smoothing: Option<Smoothing>,
    /// Draw the model in one plain grey material instead of its MTL
    /// materials (whose textures are then never opened).
    pub grey: bool,
    /// Add a ground plane under the model.
    pub ground: bool,
}

impl Default for ModelSceneOptions {
    fn default() -> Self {
        ModelSceneOptions {
            width: 640,
            height: 360,
            smoothing: None,
            grey: false,
            ground: false,
        }
    }
}

/// True when `path` is a model rather than a scene file: by its extension
/// (`.obj`, any case; `.toml` is a scene), otherwise by its first
/// statement (`v`, `f`, `o`, `g`, `mtllib`, ... are OBJ; a scene file
/// starts with a `[table]` or `key = value`).
pub fn is_model_file(path: &Path) -> bool {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("obj") => return true,
        Some(e) if e.eq_ignore_ascii_case("toml") => return false,
        _ => {}
    }
    // Only a regular file is looked into: reading a pipe would consume
    // what the loader must read, and a device may never end. Others are
    // scene files unless their extension says otherwise.
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return false;
    }
    let mut head = Vec::new();
    let read = std::fs::File::open(path).and_then(|f| {
        std::io::Read::read_to_end(&mut std::io::Read::take(f, 64 * 1024), &mut head)
    });
    if read.is_err() {
        return false;
    }
    let head = &head[..];
    let Ok(text) = obj::decode_text(head) else {
        // UTF-16: only OBJ files are written that way here; the loader
        // reports it.
        return true;
    };
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        let Some(word) = line.split_whitespace().next() else {
            continue;
        };
        if line.contains('=') || line.starts_with('[') {
            return false;
        }
        return matches!(
            word,
            "v" | "vt" | "vn" | "vp" | "f" | "o" | "g" | "s" | "l" | "p" | "mtllib" | "usemtl"
        );
    }
    false
}

/// The bounding sphere `(centre, radius)` of every vertex of the model's
/// faces, in f64 and in the file's coordinates (the positions plus the
/// model's origin, see [`obj::ObjModel::origin`]): the centre of the
/// axis-aligned box, and the largest distance from it. Also the bottom of
/// the box (least y).
fn bounds(model: &obj::ObjModel) -> (DVec3, f64, f64) {
    let mut points = model
        .parts
        .iter()
        .flat_map(|p| p.positions.iter().map(|v| v.as_dvec3()));
    let Some(first) = points.next() else {
        return (model.origin, 1.0, model.origin.y - 1.0);
    };
    let (lo, hi) = points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let centre = (lo + hi) * 0.5;
    let radius = model
        .parts
        .iter()
        .flat_map(|p| p.positions.iter())
        .map(|v| v.as_dvec3().distance(centre))
        .fold(0.0_f64, f64::max);
    (model.origin + centre, radius, model.origin.y + lo.y)
}

/// A number for the TOML text of a field the parser narrows to f32: the
/// f32 it will make of it, written exactly (so the text parses back to
/// the same scene).
fn num(x: f64) -> String {
    format!("{:?}", f64::from(x as f32))
}

/// A world position for the TOML text (the parser keeps those in f64):
/// written exactly, so a model a billion metres out is framed as well as
/// one at the origin.
fn position(v: DVec3) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

fn vec3(v: DVec3) -> String {
    format!("[{}, {}, {}]", num(v.x), num(v.y), num(v.z))
}

/// A unit direction `degrees_around` +Y from +Z towards +X and
/// `degrees_up` above the horizon.
fn direction(degrees_around: f64, degrees_up: f64) -> DVec3 {
    let (a, e) = (degrees_around.to_radians(), degrees_up.to_radians());
    DVec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos())
}

/// The scene-file text of the scene around `model`. The model is named by
/// its absolute path, so the text works from any folder.
///
/// # Errors
///
/// [`SceneError::Model`] when the model cannot be read or parsed (the
/// loader's message: file, line and reason).
pub fn model_scene_toml(model: &Path, options: &ModelSceneOptions) -> Result<String, SceneError> {
    let invalid = |reason: String| SceneError::Invalid {
        file: model.display().to_string(),
        field: "model".into(),
        reason,
    };
    let loaded = obj::load_obj(model)?;
    let absolute = std::path::absolute(model).map_err(|e| {
        invalid(format!(
            "cannot make the path absolute ({e}): {}",
            model.display()
        ))
    })?;
    let (centre, mut radius, bottom) = bounds(&loaded);
    if !(radius.is_finite() && radius > 0.0) {
        // A single point: nothing to frame; the loader refuses it later.
        radius = 1.0;
    }

    let aspect = f64::from(options.width) / f64::from(options.height.max(1));
    let half_y = (MODEL_FOV_Y / 2.0).to_radians();
    let half_x = (aspect * half_y.tan()).atan();
    let half = half_y.min(half_x);
    // The camera's distance and near plane, per unit of the radius.
    let away = 1.0 / (FILL * half.sin());
    // Close to the front of the sphere, for depth precision; the ground
    // may reach nearer than that, and is cut there.
    let near_factor = ((away - 1.0) * 0.5).max(away * 1e-3);
    let distance = radius * away;
    let near = radius * near_factor;
    let (azimuth, elevation) = view_angles(&loaded);
    let eye = centre + direction(azimuth, elevation) * distance;
    frameable(centre, radius, near, eye, near_factor).map_err(invalid)?;

    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Generated by `aerial scene` for {}\n# (bounding sphere: centre {}, radius {}).",
        model.display(),
        position(centre),
        num(radius)
    );
    let _ = writeln!(s, "ambient = [0.04, 0.04, 0.04]\n");
    let _ = writeln!(
        s,
        "[output]\nwidth = {}\nheight = {}\n",
        options.width, options.height
    );
    let _ = writeln!(
        s,
        "[camera]\neye = {}\nlook_at = {}\nfov_y = {}\nnear = {}\n",
        position(eye),
        position(centre),
        num(MODEL_FOV_Y),
        num(near)
    );
    let _ = writeln!(s, "[tone_map]\noperator = \"aces\"\nexposure = 1.0\n");
    // Directions the light travels: from the light towards the model.
    let lights = [
        ("key", azimuth - 75.0, 40.0, [1.0, 0.95, 0.88], 0.9),
        ("fill", azimuth + 60.0, 5.0, [0.8, 0.88, 1.0], 0.25),
        ("rim", azimuth + 165.0, 30.0, [1.0, 1.0, 1.0], 1.0),
    ];
    for (name, around, up, colour, intensity) in lights {
        let _ = writeln!(
            s,
            "[[lights]] # {name}\ntype = \"directional\"\ndirection = {}\ncolor = {colour:?}\n\
             intensity = {intensity:?}\n",
            vec3(-direction(around, up))
        );
    }
    if options.grey {
        let _ = writeln!(
            s,
            "[[materials]]\nname = \"grey\"\nkd = [0.7, 0.7, 0.7]\nks = [0.25, 0.25, 0.25]\n\
             shininess = 48.0\n"
        );
    }
    if options.ground {
        let _ = writeln!(
            s,
            "[[materials]]\nname = \"ground\"\nkd = [0.45, 0.45, 0.45]\n"
        );
    }
    let _ = writeln!(
        s,
        "[[objects]]\nname = \"model\"\nshape = {{ type = \"obj\", path = {} }}",
        toml_string(&absolute.to_string_lossy())
    );
    if options.grey {
        let _ = writeln!(s, "material = \"grey\"");
    }
    let open_edges = loaded.open_edges(obj::DEFAULT_WELD_TOLERANCE);
    if open_edges > 0 {
        let _ = writeln!(
            s,
            "# Open model ({open_edges} boundary edges): both sides of its faces drawn.\n\
             two_sided = true"
        );
    }
    if let Some(smoothing) = options.smoothing {
        let _ = writeln!(s, "smoothing = \"{}\"", smoothing.name());
    }
    if options.ground {
        // At most the largest length a scene file accepts.
        let size = (radius * 16.0).min(super::value_checks::MAX_LENGTH);
        let _ = writeln!(
            s,
            "\n[[objects]]\nname = \"ground\"\nmaterial = \"ground\"\n\
             shape = {{ type = \"plane\", width = {}, depth = {} }}\ntessellation = [4, 4]\n\
             translate = {}",
            num(size),
            num(size),
            position(DVec3::new(centre.x, bottom, centre.z))
        );
    }
    Ok(s)
}

/// Whether the camera a model scene places for a model with bounding
/// sphere `centre`, `radius` (at `eye`, near plane `near`, which is
/// `near_factor` times the radius) is one a scene accepts; if not, why,
/// in terms of the model: its size or its place, not the camera fields
/// the user never wrote.
fn frameable(
    centre: DVec3,
    radius: f64,
    near: f64,
    eye: DVec3,
    near_factor: f64,
) -> Result<(), String> {
    use super::value_checks::{MAX_COORDINATE, MAX_LENGTH, MIN_LENGTH};
    let across = 2.0 * radius;
    if near < MIN_LENGTH {
        return Err(format!(
            "the model is too small to frame: it is {across:.3e} across (its bounding sphere's \
             diameter), and the smallest a generated scene frames is {:.3e} (its camera's near \
             plane, {near_factor:.2} times the radius, must be at least {MIN_LENGTH:e}); scale \
             it up with `scale` in a scene file",
            2.0 * MIN_LENGTH / near_factor
        ));
    }
    if near > MAX_LENGTH {
        return Err(format!(
            "the model is too large to frame: it is {across:.3e} across (its bounding sphere's \
             diameter), and the largest a generated scene frames is {:.3e} (its camera's near \
             plane, {near_factor:.2} times the radius, must be at most {MAX_LENGTH:e})",
            2.0 * MAX_LENGTH / near_factor
        ));
    }
    if let Some(i) = (0..3).find(|&i| centre[i].abs() > MAX_COORDINATE) {
        return Err(format!(
            "the model lies too far from the origin to frame: its centre's coordinate {i} is \
             {:.3e}, beyond the renderer's limit for world positions (±{MAX_COORDINATE:e}); \
             move it nearer the origin",
            centre[i]
        ));
    }
    if let Some(i) = (0..3).find(|&i| eye[i].abs() > MAX_COORDINATE) {
        return Err(format!(
            "the model is too large or too far out to frame: it is {across:.3e} across, centred \
             at {centre}, and a camera that sees all of it would stand at coordinate {i} = \
             {:.3e}, beyond the renderer's limit for world positions (±{MAX_COORDINATE:e})",
            eye[i]
        ));
    }
    Ok(())
}

/// The camera's azimuth and elevation: the three-quarter view, or when
/// the first of the four three-quarter views (front or back, above or
/// below) that sees at least half the front-facing area the best one sees
/// (faces are drawn one-sided: a closed model looks alike from all four,
/// a one-sided sheet only from its front).
fn view_angles(model: &obj::ObjModel) -> (f64, f64) {
    let candidates = [
        (MODEL_VIEW_AZIMUTH, MODEL_VIEW_ELEVATION),
        (MODEL_VIEW_AZIMUTH + 180.0, MODEL_VIEW_ELEVATION),
        (MODEL_VIEW_AZIMUTH, -MODEL_VIEW_ELEVATION),
        (MODEL_VIEW_AZIMUTH + 180.0, -MODEL_VIEW_ELEVATION),
    ];
    // Projected area of the faces turned towards each view (twice the
    // area; counter-clockwise faces are the front).
    let mut seen = [0.0_f64; 4];
    for part in &model.parts {
        for t in part.positions.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| v.as_dvec3());
            let normal = (b - a).cross(c - a);
            if !normal.is_finite() {
                continue;
            }
            for (area, (around, up)) in seen.iter_mut().zip(candidates) {
                *area += normal.dot(direction(around, up)).max(0.0);
            }
        }
    }
    let best = seen.iter().copied().fold(0.0, f64::max);
    candidates
        .into_iter()
        .zip(seen)
        .find(|&(_, area)| area >= 0.5 * best)
        .map_or(candidates[0], |(angles, _)| angles)
}

/// `text` as a TOML basic string.
fn toml_string(text: &str) -> String {
    let mut out = String::from("\"");
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

impl Scene {
    /// The scene around the model at `path` (see the module documentation):
    /// [`model_scene_toml`] parsed as a scene file.
    pub fn from_model(path: &Path, options: &ModelSceneOptions) -> Result<Scene, SceneError> {
        let text = model_scene_toml(path, options)?;
        let name = format!("scene generated for {}", path.display());
        Scene::from_toml(&text, &name, path.parent().unwrap_or_else(|| Path::new("")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn models_are_told_from_scene_files_by_extension_or_content() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, text: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            p
        };
        assert!(is_model_file(&write("a.OBJ", "[camera]\n")));
        assert!(!is_model_file(&write("a.toml", "v 0 0 0\n")));
        assert!(is_model_file(&write(
            "model.txt",
            "# exported\n\nmtllib m.mtl\nv 0 0 0\n"
        )));
        assert!(!is_model_file(&write(
            "scene.txt",
            "# a scene\n[camera]\neye = [0, 0, 1]\n"
        )));
        assert!(!is_model_file(&write("top.txt", "ambient = [0, 0, 0]\n")));
    }

    #[test]
    fn toml_strings_escape_quotes_and_backslashes() {
        assert_eq!(toml_string("a\"b\\c"), "\"a\\\"b\\\\c\"");
        let parsed: toml::Value =
            toml::from_str(&format!("x = {}", toml_string("é\"\\\t"))).unwrap();
        assert_eq!(parsed["x"].as_str(), Some("é\"\\\t"));
    }
}
