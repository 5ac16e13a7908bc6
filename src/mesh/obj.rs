//! Wavefront OBJ models: every object and group of a file as a triangle
//! soup (one position, UV and normal per corner), with its MTL material.
//!
//! Parsing is done by `tobj`; a line-aware pre-scan comes first so that bad
//! input (non-finite numbers, indices out of range, an empty file) is
//! reported with the file and line rather than a bare parser error code, and
//! so that nothing non-finite ever reaches a vertex.
//!
//! Missing or broken material assets do not refuse the model: an MTL
//! library that cannot be read or parsed, a `newmtl` without a name and a
//! `usemtl` naming no loaded material are [`AssetWarning`]s on the model,
//! and the groups concerned get the default material. Texture files are
//! only resolved here, never opened: whoever draws the model decides what a
//! missing one means (see `crate::scene`).

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec2, Vec3};

use super::mikktspace::build_mesh_mikktspace;
use super::smoothing::{smooth_normals_indexed, PositionNumbers, Smoothing, SmoothingOptions};
use super::tangents::{build_mesh_in, MeshBuffers, MeshScratch, TangentStats};
use super::weld::finite_bounds;
use super::Mesh;

/// Why a model could not be loaded. The message names the file and, where
/// there is one, the line.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    /// The file could not be read.
    #[error("{file}: cannot read model: {reason}")]
    Io {
        /// The model file.
        file: String,
        /// The underlying error.
        reason: std::io::Error,
    },
    /// A line of the file is unacceptable.
    #[error("{file}:{line}: {reason}")]
    Line {
        /// The model file.
        file: String,
        /// One-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// The file as a whole is unacceptable (no triangles, parser failure).
    #[error("{file}: {reason}")]
    File {
        /// The model file.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// The memory budget cannot be read: its setting
    /// ([`crate::budget::ENV`]) is bad. No fault of the model's, so the
    /// message names the setting alone.
    #[error(transparent)]
    Budget(crate::budget::BudgetError),
    /// The smoothing mode asked for does not suit the file (`file`
    /// normals where faces have none): the option is at fault, not the
    /// file.
    #[error("{file}: {reason}")]
    Smoothing {
        /// The model file.
        file: String,
        /// What is wrong.
        reason: String,
    },
}

/// A problem with a model's assets that loading worked around. `problem`
/// is the error `--strict` reports; `fallback` says what was done instead.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AssetWarning {
    /// What is wrong, starting with the file it is in.
    pub problem: String,
    /// What is drawn instead.
    pub fallback: String,
}

impl std::fmt::Display for AssetWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}; {}", self.problem, self.fallback)
    }
}

/// What groups get when their MTL material is not available.
pub const DEFAULT_MATERIAL_FALLBACK: &str = "the groups using its materials get the default \
     material (grey, kd 0.8)";

/// An MTL material, with texture paths resolved against the OBJ's folder.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjMaterial {
    /// Name in the MTL file.
    pub name: String,
    /// Where it is defined, `library.mtl:line` (of its `newmtl`), for
    /// messages about its values.
    pub origin: String,
    /// `Ka`, if given.
    pub ka: Option<Vec3>,
    /// `Kd` (default 0.8 grey, the MTL convention when absent).
    pub kd: Vec3,
    /// `Ks` (default black).
    pub ks: Vec3,
    /// `Ns` (default 32), as written: [`crate::scene`] checks the values
    /// against the same bounds as a scene material's.
    pub shininess: f32,
    /// `d` (default 1, opaque), as written.
    pub opacity: f32,
    /// Its texture statements ([`TEXTURE_STATEMENTS`] that it has, in that
    /// order) with their files resolved against the OBJ's folder (not
    /// checked: the file may be missing). Which map kind each one feeds is
    /// the scene's business (`scene::material_maps`).
    pub maps: Vec<(&'static str, PathBuf)>,
}

/// The MTL statements that name a texture file. `tobj` reads `map_Bump`
/// and `bump` into one field, so a material with either has both.
pub const TEXTURE_STATEMENTS: &[&str] = &[
    "map_Ka", "map_Kd", "map_Ks", "map_Ns", "map_d", "map_Bump", "bump", "norm", "disp", "decal",
    "refl",
];

impl ObjMaterial {
    /// The file of texture statement `statement`, if the material has it.
    pub fn map(&self, statement: &str) -> Option<&Path> {
        self.maps
            .iter()
            .find(|(s, _)| *s == statement)
            .map(|(_, path)| path.as_path())
    }
}

/// One object or group of the file, triangulated: three corners per
/// triangle, counter-clockwise (the OBJ convention).
#[derive(Clone, Debug, PartialEq)]
pub struct ObjPart {
    /// The object/group name (may be empty).
    pub name: String,
    /// Corner positions.
    pub positions: Vec<Vec3>,
    /// The vertex index of each corner, when known: corners with equal
    /// indices have bit-identical positions (they come from one `v` line
    /// of the file). Welding then looks up each vertex's position once
    /// rather than each corner's; `None` makes no difference to the
    /// results.
    pub vertex_indices: Option<Vec<u32>>,
    /// Corner texture coordinates, `None` when any face of the file lacks
    /// them.
    pub uvs: Option<Vec<Vec2>>,
    /// Corner normals from the file, `None` when any face of the file
    /// lacks them.
    pub normals: Option<Vec<Vec3>>,
    /// Index into [`ObjModel::materials`].
    pub material: Option<usize>,
}

impl ObjPart {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.positions.len() / 3
    }
}

/// A loaded OBJ file.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjModel {
    /// The parts with at least one triangle, in file order.
    pub parts: Vec<ObjPart>,
    /// Materials of the MTL libraries the file names.
    pub materials: Vec<ObjMaterial>,
    /// What was wrong with the MTL libraries and material references, in
    /// file order, each once.
    pub warnings: Vec<AssetWarning>,
    /// Every file the model was read from or refers to: the OBJ itself
    /// (when loaded with [`load_obj`]), its MTL libraries and their
    /// textures. A command must never write over one of them.
    pub files: Vec<PathBuf>,
    /// What the positions are measured from: the file's coordinates are
    /// `origin + position`, in f64. Zero, unless the model lies far from
    /// the file's origin for its size ([`RECENTRE_RATIO`]): then the centre
    /// of its bounding box, subtracted in f64 before the positions are
    /// rounded to 32 bits, so a model a billion metres out keeps the
    /// detail it has at the origin. Whoever places the model adds it back
    /// in f64 (as `crate::scene` does in the object's translation).
    pub origin: DVec3,
}

impl ObjModel {
    /// True when every corner of every part has a file normal.
    pub fn has_all_normals(&self) -> bool {
        self.parts.iter().all(|p| p.normals.is_some())
    }

    /// Length of the diagonal of the bounding box of all positions.
    pub fn diagonal(&self) -> f32 {
        if self.parts.iter().all(|p| p.positions.is_empty()) {
            return 0.0;
        }
        // Positions are finite (checked when parsed), so the finite bounds
        // are the bounds.
        let (low, high) = self
            .parts
            .iter()
            .map(|p| finite_bounds(&p.positions))
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), (pl, ph)| {
                (l.min(pl), h.max(ph))
            });
        (high - low).length()
    }

    /// The number of open boundary edges: edges of exactly one triangle,
    /// corners within `weld_tolerance` times [`Self::diagonal`] of one
    /// another (in any part) being one point. A closed surface has none;
    /// a sheet or a band has its rim. A collapsed triangle's edge between
    /// two corners at one point is no edge.
    pub fn open_edges(&self, weld_tolerance: f32) -> usize {
        let points: Vec<Vec3> = self
            .parts
            .iter()
            .flat_map(|p| p.positions.iter().copied())
            .collect();
        let group = super::smoothing::weld(&points, weld_tolerance * self.diagonal());
        drop(points);
        // Each edge as its two groups, smaller first, packed in one word
        // (groups are below the number of corners, which fits 32 bits).
        let mut edges: Vec<u64> = Vec::with_capacity(group.len());
        for t in group.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                if a != b {
                    edges.push(((a.min(b) as u64) << 32) | a.max(b) as u64);
                }
            }
        }
        drop(group);
        edges.sort_unstable();
        edges
            .chunk_by(|a, b| a == b)
            .filter(|run| run.len() == 1)
            .count()
    }
}

/// Memory of reading and parsing a model's text, per byte of the file (the
/// bytes, their decoded copy, a copy without nameless `usemtl` lines, and
/// the parser's vertex arrays), an upper bound: the part of
/// [`memory_needed`] known from the file's size alone.
pub const MEMORY_PER_FILE_BYTE: u64 = 6;

/// Memory per triangle (after splitting polygons) of parsing, smoothing
/// and tangent frames, an upper bound: the parser's index arrays, the
/// corner soup (position, UV, normal), face data, welding and grouping
/// tables, shading normals, and the indexed mesh with its hash table, each
/// at its worst (every corner its own vertex, vectors at twice their
/// length after growth). Measured against the allocator's peak on
/// adversarial shapes in `tests/obj_memory.rs`.
pub const MEMORY_PER_TRIANGLE: u64 = 800;

/// Upper bound on the peak memory of loading a model of `file_bytes` bytes
/// and `triangles` triangles and making its meshes.
pub fn memory_needed(file_bytes: u64, triangles: u64) -> u64 {
    file_bytes
        .saturating_mul(MEMORY_PER_FILE_BYTE)
        .saturating_add(triangles.saturating_mul(MEMORY_PER_TRIANGLE))
}

/// The memory budget; a bad setting of it is [`ObjError::Budget`].
fn budget() -> Result<crate::budget::MemoryBudget, ObjError> {
    crate::budget::MemoryBudget::from_env().map_err(ObjError::Budget)
}

/// The bytes of `path` if the memory budget allows reading them at
/// `per_byte` bytes of memory per file byte; `what` names the file kind.
fn read_within_budget(
    path: &Path,
    file: &str,
    what: &str,
    per_byte: u64,
) -> Result<Vec<u8>, ObjError> {
    let budget = budget()?;
    let limit = budget.bytes / per_byte;
    crate::safe_files::read_limited(path, limit).map_err(|e| match e {
        Some(reason) => ObjError::Io {
            file: file.to_owned(),
            reason,
        },
        None => ObjError::File {
            file: file.to_owned(),
            reason: format!(
                "{what} longer than {} is more than the memory budget of {} allows \
                 (reading stopped there); set {} higher if the machine has the memory",
                crate::budget::Bytes(limit),
                crate::budget::Bytes(budget.bytes),
                crate::budget::ENV
            ),
        },
    })
}

/// Loads `path`: pre-scan, then `tobj` with triangulation, then the MTL
/// libraries it names (relative to the OBJ's folder). Refused before the
/// work when [`memory_needed`] exceeds the memory budget; reading stops at
/// the budget, so an endless input is refused too.
pub fn load_obj(path: &Path) -> Result<ObjModel, ObjError> {
    let file = path.display().to_string();
    let bytes = read_within_budget(path, &file, "a model", MEMORY_PER_FILE_BYTE)?;
    let text = decode_text(&bytes).map_err(|reason| ObjError::File {
        file: file.clone(),
        reason,
    })?;
    let corners = prescan(&text, &file)?;
    let triangles = corners.triangles;
    let origin = corners.origin(&text);
    // A far-off model's text is written again with its positions
    // re-centred (see `rewritten`): at most this much more.
    let rewrite = if origin == DVec3::ZERO {
        0
    } else {
        (text.len() as u64).saturating_add((corners.used.len() as u64).saturating_mul(64))
    };
    let need = memory_needed(bytes.len() as u64, triangles).saturating_add(rewrite);
    drop(bytes);
    budget()?
        .check(format!("model {file} ({triangles} triangles)"), need)
        .map_err(|e| ObjError::File {
            file: file.clone(),
            reason: e.to_string(),
        })?;
    let base_dir = path.parent().unwrap_or_else(|| Path::new(""));
    let mut model = parse_scanned(&text, &file, base_dir, corners, origin)?;
    model.files.insert(0, path.to_path_buf());
    // Its MTL libraries and the textures they name are inputs too, read or
    // not (see `crate::safe_files::note_inputs`).
    crate::safe_files::note_inputs(&model.files);
    Ok(model)
}

/// The text of an OBJ or MTL file. OBJ is ASCII; bytes outside UTF-8
/// (Latin-1 comments and names from older exporters) only ever occur in
/// comments and names, so they are replaced rather than refusing the file.
/// A UTF-8 byte-order mark is skipped; UTF-16 files (with a byte-order
/// mark, as Windows tools write them) are decoded.
pub fn decode_text(bytes: &[u8]) -> Result<String, String> {
    let utf16 = |big_endian: bool| -> Result<String, String> {
        let body = &bytes[2..];
        if !body.len().is_multiple_of(2) {
            return Err("UTF-16 encoded but with an odd number of bytes: convert to UTF-8".into());
        }
        let units = body.chunks_exact(2).map(|c| {
            if big_endian {
                u16::from_be_bytes([c[0], c[1]])
            } else {
                u16::from_le_bytes([c[0], c[1]])
            }
        });
        char::decode_utf16(units)
            .collect::<Result<String, _>>()
            .map_err(|_| "UTF-16 encoded with an unpaired surrogate: convert to UTF-8".to_owned())
    };
    match bytes {
        [0xFF, 0xFE, ..] => utf16(false),
        [0xFE, 0xFF, ..] => utf16(true),
        [0xEF, 0xBB, 0xBF, rest @ ..] => Ok(String::from_utf8_lossy(rest).into_owned()),
        _ => Ok(String::from_utf8_lossy(bytes).into_owned()),
    }
}

/// The MTL libraries an `mtllib` statement names (`names`, the rest of its
/// line): the names separated by white space, as the format has it (`mtllib
/// a.mtl b.mtl` names two), or the whole rest of the line when a file of
/// that name exists (exporters write names with spaces in them).
fn library_names(names: &Path, base_dir: &Path) -> Vec<PathBuf> {
    let whole = names.to_string_lossy();
    let words: Vec<&str> = whole.split_whitespace().collect();
    if words.len() <= 1 || base_dir.join(whole.replace('\\', "/")).is_file() {
        return vec![names.to_path_buf()];
    }
    words.into_iter().map(PathBuf::from).collect()
}

/// Reads the MTL library `name` (as written after `mtllib`) from `base_dir`:
/// its materials, or a warning and none.
fn read_mtl(
    file: &str,
    name: &Path,
    base_dir: &Path,
    warnings: &mut Vec<AssetWarning>,
    origins: &mut Vec<String>,
) -> tobj::MTLLoadResult {
    let nothing = || Ok((Vec::new(), Default::default()));
    if name.as_os_str().is_empty() {
        warnings.push(AssetWarning {
            problem: format!("{file}: mtllib without a file name"),
            fallback: DEFAULT_MATERIAL_FALLBACK.to_owned(),
        });
        return nothing();
    }
    let path = base_dir.join(name.to_string_lossy().replace('\\', "/"));
    let failed = |reason: String| AssetWarning {
        problem: format!(
            "{file}: cannot load its MTL library \"{}\" ({}): {reason}",
            name.display(),
            path.display()
        ),
        fallback: DEFAULT_MATERIAL_FALLBACK.to_owned(),
    };
    let text = match read_mtl_text(&path) {
        Ok(text) => text,
        Err(reason) => {
            warnings.push(failed(reason));
            return nothing();
        }
    };
    let (fixed, defined) = fix_mtl_text(&text, &path, warnings, origins);
    let first_origin = origins.len() - defined;
    match tobj::load_mtl_buf(&mut std::io::BufReader::new(fixed.as_bytes())) {
        Ok(loaded) => Ok(loaded),
        Err(e) => {
            origins.truncate(first_origin);
            warnings.push(failed(format!("cannot parse it: {e}")));
            nothing()
        }
    }
}

/// The text of the MTL library at `path`, or why it cannot be read. Read
/// within the budget: an endless file is refused like an unreadable one. A
/// library is read, decoded and rewritten once each.
fn read_mtl_text(path: &Path) -> Result<String, String> {
    let bytes = match read_within_budget(path, &path.display().to_string(), "an MTL library", 4) {
        Ok(bytes) => bytes,
        Err(ObjError::Io { reason, .. }) => return Err(reason.to_string()),
        Err(e @ ObjError::Budget(_)) => return Err(e.to_string()),
        Err(e) => {
            let message = e.to_string();
            let reason = message.split_once(": ").map_or(message.as_str(), |x| x.1);
            return Err(reason.to_owned());
        }
    };
    decode_text(&bytes)
}

/// The MTL library `text` (of `path`) with what `tobj` cannot take fixed,
/// and the number of its `newmtl` lines, whose origins are added to
/// `origins`.
///
/// `tobj` refuses a whole library for one `newmtl` without a name; that
/// material cannot be used by any `usemtl`, so it is named here and the
/// rest of the library loads. A colour statement with one number or a
/// scalar statement that is not a number is fixed or left out by
/// [`fixed_number_statement`].
fn fix_mtl_text(
    text: &str,
    path: &Path,
    warnings: &mut Vec<AssetWarning>,
    origins: &mut Vec<String>,
) -> (String, usize) {
    let mut fixed = String::with_capacity(text.len());
    let mut newmtl_lines: Vec<(String, usize)> = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let keyword = words.next();
        if let Some(replacement) = fixed_number_statement(keyword, line, path, number, warnings) {
            fixed.push_str(&replacement);
            continue;
        }
        if keyword == Some("newmtl") {
            origins.push(format!("{}:{}", path.display(), number + 1));
            let defined = line
                .split_whitespace()
                .skip(1)
                .collect::<Vec<_>>()
                .join(" ");
            if let Some(first) = newmtl_lines.iter().find(|(n, _)| *n == defined) {
                warnings.push(AssetWarning {
                    problem: format!(
                        "{}:{}: material \"{defined}\" is defined again (first at line {})",
                        path.display(),
                        number + 1,
                        first.1
                    ),
                    fallback: "the later definition is used".into(),
                });
            }
            newmtl_lines.push((defined, number + 1));
        }
        if keyword == Some("newmtl") && words.next().is_none() {
            let name = format!("unnamed (line {})", number + 1);
            warnings.push(AssetWarning {
                problem: format!("{}:{}: newmtl without a name", path.display(), number + 1),
                fallback: format!("the material is kept as \"{name}\", which no usemtl can name"),
            });
            fixed.push_str("newmtl ");
            fixed.push_str(&name);
        } else {
            fixed.push_str(line);
        }
        fixed.push('\n');
    }
    (fixed, newmtl_lines.len())
}

/// The replacement for line `number` (zero-based) of `path` when it is a
/// statement of numbers `tobj` would mishandle, with a warning naming the
/// line when it is left out; `None` to keep the line.
///
/// A colour statement (`Kd r g b`) may give one number for all three
/// (`Kd 0.5`, the MTL rule); `tobj` panics on fewer than three, so the one
/// number is repeated, and a statement with two numbers or in another form
/// (`Kd spectral file.rfl`, `Kd xyz x y z`) is left out. A scalar `tobj`
/// would refuse the whole library for is left out too, and the rest loads.
fn fixed_number_statement(
    keyword: Option<&str>,
    line: &str,
    path: &Path,
    number: usize,
    warnings: &mut Vec<AssetWarning>,
) -> Option<String> {
    let values: Vec<&str> = line
        .split('#')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .skip(1)
        .collect();
    let mut left_out = |problem: String| {
        warnings.push(AssetWarning {
            problem: format!("{}:{}: {problem}", path.display(), number + 1),
            fallback: "the statement is left out".into(),
        });
        Some("\n".to_owned())
    };
    match keyword {
        Some(colour @ ("Ka" | "Kd" | "Ks" | "Ke")) => {
            let numbers = values.iter().all(|v| v.parse::<f32>().is_ok());
            match values.as_slice() {
                [one] if numbers => Some(format!("{colour} {one} {one} {one}\n")),
                [_, _, _, ..] if numbers => None,
                _ => left_out(format!(
                    "{colour} needs one or three numbers, got \"{}\"",
                    values.join(" ")
                )),
            }
        }
        Some(scalar @ ("Ns" | "Ni" | "d" | "Tr")) => {
            let value = values.first().copied();
            if value.and_then(|v| v.parse::<f32>().ok()).is_some() {
                return None;
            }
            left_out(format!(
                "{scalar} needs a number, got \"{}\"",
                value.unwrap_or("")
            ))
        }
        _ => None,
    }
}

/// [`load_obj`] on text already read; `file` is only used in messages and
/// `base_dir` is where MTL libraries and textures are looked for.
pub fn parse_obj(text: &str, file: &str, base_dir: &Path) -> Result<ObjModel, ObjError> {
    let corners = prescan(text, file)?;
    let origin = corners.origin(text);
    parse_scanned(text, file, base_dir, corners, origin)
}

/// [`parse_obj`] after the pre-scan, with the positions measured from
/// `origin` (see [`ObjModel::origin`]).
fn parse_scanned(
    text: &str,
    file: &str,
    base_dir: &Path,
    corners: Corners,
    origin: DVec3,
) -> Result<ObjModel, ObjError> {
    let mut warnings = Vec::new();
    warnings.extend(empty_usemtl_warning(file, &corners.empty_usemtl));
    let text: std::borrow::Cow<str> = if corners.empty_usemtl.is_empty() && origin == DVec3::ZERO {
        text.into()
    } else {
        rewritten(text, &corners.empty_usemtl, origin).into()
    };
    drop(corners.used);
    let LoadedObj {
        models,
        materials,
        mut warnings,
        origins,
        libraries,
    } = load_obj_text(&text, file, base_dir, warnings)?;
    let materials: Vec<ObjMaterial> = materials
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let origin = origins.get(i).cloned().unwrap_or_else(|| file.to_owned());
            material(m, origin, base_dir)
        })
        .collect();
    let unknown = unknown_materials_warning(file, &corners.usemtl, &materials, &warnings);
    warnings.extend(unknown);
    let mut parts = Vec::new();
    for model in models {
        let part = obj_part(
            model,
            file,
            corners.all_uv,
            corners.all_normal,
            materials.len(),
        )?;
        parts.extend(part);
    }
    if parts.is_empty() {
        return Err(ObjError::File {
            file: file.to_owned(),
            reason: "no faces (an OBJ model needs at least one triangle)".into(),
        });
    }
    let mut files = libraries;
    for m in &materials {
        files.extend(m.maps.iter().map(|(_, path)| path.clone()));
    }
    Ok(ObjModel {
        parts,
        materials,
        warnings,
        files,
        origin,
    })
}

/// `tobj` refuses a `usemtl` without a name; it names no material, so
/// the line is left out (its faces keep the material before it), with
/// one warning naming the lines.
fn empty_usemtl_warning(file: &str, empty_usemtl: &[usize]) -> Option<AssetWarning> {
    if empty_usemtl.is_empty() {
        return None;
    }
    let lines: Vec<String> = empty_usemtl.iter().map(|n| (n + 1).to_string()).collect();
    Some(AssetWarning {
        problem: format!(
            "{file}: usemtl without a material name (line {})",
            lines.join(", ")
        ),
        fallback: "left out: the faces after it keep the material before it".into(),
    })
}

/// What `tobj` loads of an OBJ file and its MTL libraries.
struct LoadedObj {
    models: Vec<tobj::Model>,
    materials: Vec<tobj::Material>,
    /// The warnings so far, the libraries' appended.
    warnings: Vec<AssetWarning>,
    /// Each loaded material's `library:line`, in the order `tobj` appends
    /// the materials (every library's `newmtl`s in file order).
    origins: Vec<String>,
    /// Every MTL library named, as a path.
    libraries: Vec<PathBuf>,
}

/// Loads the OBJ `text` with `tobj`, reading its MTL libraries from
/// `base_dir`; `warnings` are those so far.
fn load_obj_text(
    text: &str,
    file: &str,
    base_dir: &Path,
    warnings: Vec<AssetWarning>,
) -> Result<LoadedObj, ObjError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = std::io::BufReader::new(text.as_bytes());
    // A library that cannot be read or parsed is a warning and no
    // materials (see `read_mtl`), so `tobj` never sees a failed load.
    let warnings = std::cell::RefCell::new(warnings);
    let libraries = std::cell::RefCell::new(Vec::new());
    let origins = std::cell::RefCell::new(Vec::new());
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, |names| {
        // One `mtllib` may name several libraries: read each, their
        // materials in order as if named on lines of their own.
        let read = |mtl: &Path| {
            libraries
                .borrow_mut()
                .push(base_dir.join(mtl.to_string_lossy().replace('\\', "/")));
            read_mtl(
                file,
                mtl,
                base_dir,
                &mut warnings.borrow_mut(),
                &mut origins.borrow_mut(),
            )
        };
        let mut libraries = library_names(names, base_dir).into_iter();
        let first = libraries.next().unwrap_or_default();
        let (mut materials, mut by_name) = read(&first)?;
        for mtl in libraries {
            let (mut more, more_by_name) = read(&mtl)?;
            let offset = materials.len();
            by_name.extend(more_by_name.into_iter().map(|(k, i)| (k, i + offset)));
            materials.append(&mut more);
        }
        Ok((materials, by_name))
    })
    .map_err(|e| ObjError::File {
        file: file.to_owned(),
        reason: format!("cannot parse OBJ: {e}"),
    })?;
    let warnings = warnings.into_inner();
    let materials = materials.map_err(|e| ObjError::File {
        file: file.to_owned(),
        reason: format!("cannot load its MTL library: {e}"),
    })?;
    Ok(LoadedObj {
        models,
        materials,
        warnings,
        origins: origins.into_inner(),
        libraries: libraries.into_inner(),
    })
}

/// `usemtl` lines naming no loaded material: their groups get the
/// default. One warning for the file, and none when a library that
/// failed to load already explains it.
fn unknown_materials_warning(
    file: &str,
    usemtl: &[(usize, String)],
    materials: &[ObjMaterial],
    warnings: &[AssetWarning],
) -> Option<AssetWarning> {
    let library_failed = warnings
        .iter()
        .any(|w| w.fallback == DEFAULT_MATERIAL_FALLBACK);
    let unknown: Vec<String> = usemtl
        .iter()
        .filter(|(_, name)| !materials.iter().any(|m| &m.name == name))
        .map(|(line, name)| format!("\"{name}\" (line {line})"))
        .collect();
    if unknown.is_empty() || library_failed {
        return None;
    }
    Some(AssetWarning {
        problem: format!(
            "{file}: usemtl names materials no MTL library defines: {}",
            unknown.join(", ")
        ),
        fallback: "their groups get the default material (grey, kd 0.8)".into(),
    })
}

/// The corner's values in `array` (`n` per vertex), if in range.
fn corner(array: &[f32], index: u32, n: usize) -> Option<&[f32]> {
    let start = index as usize * n;
    array.get(start..start + n)
}

/// One loaded object as a part, or `None` if it has no faces. Texture
/// coordinates and normals are kept only where the pre-scan saw them on
/// every corner of the file (`all_uv`, `all_normal`).
fn obj_part(
    mut model: tobj::Model,
    file: &str,
    all_uv: bool,
    all_normal: bool,
    material_count: usize,
) -> Result<Option<ObjPart>, ObjError> {
    let vertex_indices = std::mem::take(&mut model.mesh.indices);
    let mesh = &model.mesh;
    if vertex_indices.is_empty() {
        return Ok(None);
    }
    let out_of_range = |what: &str| ObjError::File {
        file: file.to_owned(),
        reason: format!("object \"{}\": {what} index out of range", model.name),
    };
    let positions = vertex_indices
        .iter()
        .map(|&i| corner(&mesh.positions, i, 3).map(|p| Vec3::new(p[0], p[1], p[2])))
        .collect::<Option<Vec<_>>>()
        .ok_or_else(|| out_of_range("vertex"))?;
    let full = |indices: &[u32]| indices.len() == vertex_indices.len();
    // `tobj` fills a corner without an index with a neighbour's value,
    // so attributes are only used when the pre-scan saw them on every
    // corner of the file.
    let uvs = if all_uv && full(&mesh.texcoord_indices) && !mesh.texcoords.is_empty() {
        Some(
            mesh.texcoord_indices
                .iter()
                .map(|&i| corner(&mesh.texcoords, i, 2).map(|t| Vec2::new(t[0], t[1])))
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| out_of_range("texture coordinate"))?,
        )
    } else {
        None
    };
    let normals = if all_normal && full(&mesh.normal_indices) && !mesh.normals.is_empty() {
        Some(
            mesh.normal_indices
                .iter()
                .map(|&i| corner(&mesh.normals, i, 3).map(|n| Vec3::new(n[0], n[1], n[2])))
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| out_of_range("normal"))?,
        )
    } else {
        None
    };
    Ok(Some(ObjPart {
        name: model.name.clone(),
        positions,
        vertex_indices: Some(vertex_indices),
        uvs,
        normals,
        material: mesh.material_id.filter(|&m| m < material_count),
    }))
}

fn material(m: &tobj::Material, origin: String, base_dir: &Path) -> ObjMaterial {
    let texture = |name: &String| -> Option<PathBuf> {
        // Texture statements may carry options (`-bm 1.0 file.png`); the
        // file name is the last word.
        let last = name.split_whitespace().last()?;
        // Windows exporters write `.\\dir\\file.jpg`.
        Some(base_dir.join(last.replace('\\', "/")))
    };
    let maps = TEXTURE_STATEMENTS
        .iter()
        .filter_map(|&statement| Some((statement, texture(mtl_statement(m, statement)?)?)))
        .collect();
    ObjMaterial {
        name: m.name.clone(),
        origin,
        ka: m.ambient.map(Vec3::from),
        kd: m.diffuse.map_or(Vec3::splat(0.8), Vec3::from),
        ks: m.specular.map_or(Vec3::ZERO, Vec3::from),
        shininess: m.shininess.unwrap_or(32.0),
        opacity: m.dissolve.unwrap_or(1.0),
        maps,
    }
}

/// The value of the texture statement `name` in `m`: `tobj` keeps the ones
/// it knows in fields (`map_Bump` and `bump` in one), the others by name.
fn mtl_statement<'a>(m: &'a tobj::Material, name: &str) -> Option<&'a String> {
    match name {
        "map_Ka" => m.ambient_texture.as_ref(),
        "map_Kd" => m.diffuse_texture.as_ref(),
        "map_Ks" => m.specular_texture.as_ref(),
        "map_Ns" => m.shininess_texture.as_ref(),
        "map_d" => m.dissolve_texture.as_ref(),
        "map_Bump" | "bump" => m.normal_texture.as_ref(),
        _ => m.unknown_param.get(name),
    }
}

/// Which attributes every face corner of a file has, and the materials
/// its `usemtl` lines name (with their line numbers, each name once).
struct Corners {
    /// Triangles after splitting polygons.
    triangles: u64,
    all_uv: bool,
    all_normal: bool,
    usemtl: Vec<(usize, String)>,
    /// Zero-based numbers of `usemtl` lines without a name.
    empty_usemtl: Vec<usize>,
    /// The least and greatest coordinates of every `v` line, in f64 as
    /// written (divided by the weight `w` where there is one).
    bounds: (DVec3, DVec3),
    /// Whether each vertex (in file order) is a corner of some face.
    used: Vec<bool>,
}

/// A model whose bounding box's centre is farther from the file's origin
/// than this many times the box's diagonal has its positions measured
/// from that centre (see [`ObjModel::origin`]). A 32-bit float keeps about
/// 7 digits, so at this ratio the rounding of positions written relative
/// to the file's origin is below a millionth of the model's size, well
/// below the weld tolerance (1e-5 of the diagonal): nearer models are read
/// exactly as before.
pub const RECENTRE_RATIO: f64 = 16.0;

impl Corners {
    /// What the model's positions are measured from: the centre of the
    /// bounding box of the vertices its faces use, when the model lies
    /// farther from the file's origin than [`RECENTRE_RATIO`] times its
    /// size; otherwise the file's origin.
    fn origin(&self, text: &str) -> DVec3 {
        let (lo, hi) = if self.used.iter().all(|&u| u) {
            self.bounds
        } else {
            used_bounds(text, &self.used)
        };
        if !lo.cmple(hi).all() {
            return DVec3::ZERO;
        }
        let centre = (lo + hi) * 0.5;
        if centre.abs().max_element() > RECENTRE_RATIO * (hi - lo).length() {
            centre
        } else {
            DVec3::ZERO
        }
    }
}

/// The numbers of a `v` line (already checked by [`prescan`]), or `None`
/// for any other line.
fn vertex_numbers(line: &str) -> Option<Vec<f64>> {
    let code = line.split('#').next().unwrap_or("");
    let mut words = code.split_whitespace();
    (words.next() == Some("v")).then(|| words.filter_map(|w| w.parse().ok()).collect())
}

/// The bounds of the vertices a face uses (`used`, in file order), in f64.
fn used_bounds(text: &str, used: &[bool]) -> (DVec3, DVec3) {
    let mut bounds = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let mut used = used.iter();
    for line in text.lines() {
        if let Some(values) = vertex_numbers(line) {
            if used.next() == Some(&true) {
                let p = position(&values);
                bounds = (bounds.0.min(p), bounds.1.max(p));
            }
        }
    }
    bounds
}

/// The text `tobj` reads: the lines `comment_out` (zero-based) replaced by
/// a comment, and, unless `origin` is zero, every position written
/// relative to `origin`, computed in f64 and only then rounded to the
/// 32-bit float the parser reads (written so that it reads back exactly).
/// A colour after the position is kept; a weight is applied. Every line
/// stays on its line, so the parser's view matches the file's numbering.
fn rewritten(text: &str, comment_out: &[usize], origin: DVec3) -> String {
    use std::fmt::Write as _;
    let mut out = String::with_capacity(text.len());
    for (n, line) in text.lines().enumerate() {
        if comment_out.contains(&n) {
            out.push('#');
        } else if let Some(values) = vertex_numbers(line).filter(|_| origin != DVec3::ZERO) {
            let p = (position(&values) - origin).as_vec3();
            let _ = write!(out, "v {:?} {:?} {:?}", p.x, p.y, p.z);
            if let [_, _, _, r, g, b] = values[..] {
                let _ = write!(out, " {r:?} {g:?} {b:?}");
            }
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    out
}

/// The position of a `v` line's numbers (checked: 3, 4 or 6 of them, a
/// weight not 0): x y z, divided by the weight w when there is one.
fn position(values: &[f64]) -> DVec3 {
    let p = DVec3::new(values[0], values[1], values[2]);
    match values {
        [_, _, _, w] => p / *w,
        _ => p,
    }
}

/// Checks every `v`, `vt`, `vn` and `f` line: numbers finite, indices
/// (1-based, or negative for relative) within the elements defined so far,
/// and at least one face.
fn prescan(text: &str, file: &str) -> Result<Corners, ObjError> {
    let mut counts = [0usize; 3]; // v, vt, vn
    let mut faces = 0usize;
    let mut all = Corners {
        all_uv: true,
        all_normal: true,
        usemtl: Vec::new(),
        empty_usemtl: Vec::new(),
        triangles: 0,
        bounds: (DVec3::INFINITY, DVec3::NEG_INFINITY),
        used: Vec::new(),
    };
    for (number, line) in text.lines().enumerate() {
        let error = |reason: String| ObjError::Line {
            file: file.to_owned(),
            line: number + 1,
            reason,
        };
        let line = line.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let (slot, least) = match keyword {
            "usemtl" => {
                all.scan_usemtl(line, number);
                continue;
            }
            "v" => (0, 3),
            // The parser reads two (`vt u` alone, which the format allows,
            // is refused here with its line rather than by the parser without).
            "vt" => (1, 2),
            "vn" => (2, 3),
            "f" => {
                all.scan_face(words, &counts, &error)?;
                faces += 1;
                continue;
            }
            _ => continue,
        };
        let values = scan_numbers(words, slot, least, &error)?;
        if slot == 0 {
            let p = position(&values);
            all.bounds = (all.bounds.0.min(p), all.bounds.1.max(p));
            all.used.push(false);
        }
        counts[slot] += 1;
    }
    if faces == 0 {
        return Err(ObjError::File {
            file: file.to_owned(),
            reason: "no faces (an OBJ model needs at least one triangle)".into(),
        });
    }
    Ok(all)
}

impl Corners {
    /// Notes a `usemtl` line (zero-based `number`): its name the first
    /// time it is used, or the line if it names nothing.
    fn scan_usemtl(&mut self, line: &str, number: usize) {
        // The name is the rest of the line, as `tobj` reads it.
        let name = line.trim_start()["usemtl".len()..].trim();
        if name.is_empty() {
            self.empty_usemtl.push(number);
            return;
        }
        if !self.usemtl.iter().any(|(_, n)| n == name) {
            self.usemtl.push((number + 1, name.to_owned()));
        }
    }

    /// Checks the corners (`words`) of an `f` line against the `counts` of
    /// vertices, texture coordinates and normals defined so far, and notes
    /// its triangles, the vertices it uses and the attributes it lacks.
    fn scan_face<'a>(
        &mut self,
        words: impl Iterator<Item = &'a str>,
        counts: &[usize; 3],
        error: &dyn Fn(String) -> ObjError,
    ) -> Result<(), ObjError> {
        let mut corners = 0;
        for word in words {
            corners += 1;
            let mut slots = word.split('/');
            slots.next();
            self.all_uv &= slots.next().is_some_and(|t| !t.is_empty());
            self.all_normal &= slots.next().is_some_and(|n| !n.is_empty());
            for (k, index) in word.split('/').enumerate().take(3) {
                if index.is_empty() {
                    if k == 0 {
                        return Err(error(format!("face corner \"{word}\" has no vertex index")));
                    }
                    continue;
                }
                let what = ["vertex", "texture coordinate", "normal"][k];
                let i: i64 = index.parse().map_err(|_| {
                    error(format!(
                        "face corner \"{word}\": \"{index}\" is not an integer"
                    ))
                })?;
                let defined = counts[k] as i64;
                // unsigned_abs: -i overflows for i64::MIN (found by
                // the fuzzer).
                let valid = if i > 0 {
                    i <= defined
                } else {
                    i < 0 && i.unsigned_abs() <= defined as u64
                };
                if !valid {
                    return Err(error(format!(
                        "face corner \"{word}\": {what} index {i} is out of range \
                         ({defined} defined so far)"
                    )));
                }
                if k == 0 {
                    let vertex = if i > 0 { i - 1 } else { defined + i };
                    self.used[vertex as usize] = true;
                }
            }
        }
        if corners < 3 {
            return Err(error(format!(
                "a face needs at least 3 corners, got {corners}"
            )));
        }
        self.triangles += corners as u64 - 2;
        Ok(())
    }
}

/// The numbers of a `v` (`slot` 0), `vt` (1) or `vn` (2) line, at least
/// `least` of them, each finite in f32; a position is x y z, then either a
/// weight w (not 0) or a colour r g b.
fn scan_numbers<'a>(
    words: impl Iterator<Item = &'a str>,
    slot: usize,
    least: usize,
    error: &dyn Fn(String) -> ObjError,
) -> Result<Vec<f64>, ObjError> {
    let name = ["vertex", "texture coordinate", "normal"][slot];
    let mut values = Vec::new();
    for word in words {
        let x: f64 = word
            .parse()
            .map_err(|_| error(format!("{name}: \"{word}\" is not a number")))?;
        if !x.is_finite() || (x as f32).is_infinite() {
            return Err(error(format!("{name}: \"{word}\" is not a finite number")));
        }
        values.push(x);
    }
    let n = values.len();
    if n < least {
        return Err(error(format!(
            "{name} needs at least {least} numbers, got {n}"
        )));
    }
    // A position is x y z, then either a weight w or a colour r g b.
    if slot == 0 && !matches!(n, 3 | 4 | 6) {
        return Err(error(format!(
            "vertex needs 3 numbers (x y z), 4 (with a weight w) or 6 (with a colour \
             r g b), got {n}"
        )));
    }
    if slot == 0 && n == 4 && values[3] == 0.0 {
        return Err(error(
            "vertex weight w is 0 (the position is x/w, y/w, z/w)".into(),
        ));
    }
    Ok(values)
}

/// How an [`ObjModel`] becomes meshes (`smoothing`, `crease_angle`,
/// `weld_tolerance` in the scene file).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelOptions {
    /// Smoothing mode; `None` picks `File` when every corner has a file
    /// normal, otherwise `Model`.
    pub smoothing: Option<Smoothing>,
    /// Crease angle in degrees.
    pub crease_degrees: f32,
    /// Weld tolerance relative to the bounding-box diagonal.
    pub weld_tolerance: f32,
    /// How tangent frames are made.
    pub tangents: TangentMethod,
}

/// How tangent frames are made (`tangents` in the scene file).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum TangentMethod {
    /// Per-triangle frames from UV deltas, averaged per vertex by corner
    /// angle (`src/mesh/tangents.rs`).
    #[default]
    Aerial,
    /// Mikkelsen's MikkTSpace, which normal maps baked by common tools
    /// expect (`src/mesh/mikktspace.rs`).
    Mikktspace,
}

/// Default crease angle, degrees: smooth curvature (tessellated spheres and
/// tori differ by far less between neighbouring faces) is averaged, the
/// edges of boxes and prisms (90 degrees) stay sharp.
pub const DEFAULT_CREASE_DEGREES: f32 = 60.0;
/// Default weld tolerance, relative to the bounding-box diagonal: well above
/// f32 round-off of exported coordinates, well below any real feature.
pub const DEFAULT_WELD_TOLERANCE: f32 = 1e-5;

impl Default for ModelOptions {
    fn default() -> Self {
        ModelOptions {
            smoothing: None,
            crease_degrees: DEFAULT_CREASE_DEGREES,
            weld_tolerance: DEFAULT_WELD_TOLERANCE,
            tangents: TangentMethod::Aerial,
        }
    }
}

/// One indexed mesh per part of `model`, with shading normals and tangent
/// frames. `file` names the model in messages.
pub fn model_meshes(
    model: &ObjModel,
    options: &ModelOptions,
    file: &str,
) -> Result<Vec<(Mesh, TangentStats)>, ObjError> {
    let smoothed = model_normals_numbered(model, options, file)?;
    Ok(model_frames_numbered(
        model,
        smoothed.normals,
        smoothed.positions.as_ref(),
        options.tangents,
    ))
}

/// What [`model_normals_numbered`] hands to [`model_frames_numbered`].
pub struct SmoothedModel {
    /// The mode used.
    pub mode: Smoothing,
    /// Each part's per-corner shading normals (unit length, never NaN).
    pub normals: Vec<Vec<Vec3>>,
    /// The exact position numbers smoothing's welding found, when it
    /// welded: the tangent stage joins corners into vertices from them.
    pub positions: Option<PositionNumbers>,
}

/// The smoothing stage: each part's per-corner shading normals (unit
/// length, never NaN), and the mode used.
pub fn model_normals(
    model: &ObjModel,
    options: &ModelOptions,
    file: &str,
) -> Result<(Smoothing, Vec<Vec<Vec3>>), ObjError> {
    let smoothed = model_normals_numbered(model, options, file)?;
    Ok((smoothed.mode, smoothed.normals))
}

/// [`model_normals`], with the position numbers of smoothing's welding,
/// for [`model_frames_numbered`].
pub fn model_normals_numbered(
    model: &ObjModel,
    options: &ModelOptions,
    file: &str,
) -> Result<SmoothedModel, ObjError> {
    let mode = options.smoothing.unwrap_or(if model.has_all_normals() {
        Smoothing::File
    } else {
        Smoothing::Model
    });
    if mode == Smoothing::File && !model.has_all_normals() {
        let part = model.parts.iter().find(|p| p.normals.is_none());
        return Err(ObjError::Smoothing {
            file: file.to_owned(),
            reason: format!(
                "smoothing = \"file\" but object \"{}\" has faces without normals \
                 (use \"model\", \"object\" or \"face\")",
                part.map_or("", |p| p.name.as_str())
            ),
        });
    }
    let diagonal = model.diagonal();
    if !diagonal.is_finite() {
        return Err(ObjError::File {
            file: file.to_owned(),
            reason: "the coordinates span a range too large to represent (the bounding box \
                     diagonal overflows)"
                .into(),
        });
    }
    let positions: Vec<&[Vec3]> = model.parts.iter().map(|p| p.positions.as_slice()).collect();
    let indices: Vec<Option<&[u32]>> = model
        .parts
        .iter()
        .map(|p| p.vertex_indices.as_deref())
        .collect();
    let (generated, numbers) = smooth_normals_indexed(
        &positions,
        &indices,
        &SmoothingOptions {
            mode,
            crease_degrees: options.crease_degrees,
            weld_distance: options.weld_tolerance * diagonal,
        },
    );
    let normals = model
        .parts
        .iter()
        .zip(generated)
        .map(|(part, generated)| match (&part.normals, mode) {
            // A file normal that cannot be normalised takes the face
            // normal instead, so that no vertex is ever NaN.
            (Some(file_normals), Smoothing::File) => file_normals
                .iter()
                .zip(&generated)
                .map(|(n, face)| n.try_normalize().unwrap_or(*face))
                .collect(),
            _ => generated,
        })
        .collect();
    Ok(SmoothedModel {
        mode,
        normals,
        positions: numbers,
    })
}

/// The tangent stage: each part as an indexed mesh with tangent frames,
/// from the normals of [`model_normals`].
pub fn model_frames(
    model: &ObjModel,
    normals: Vec<Vec<Vec3>>,
    method: TangentMethod,
) -> Vec<(Mesh, TangentStats)> {
    model_frames_numbered(model, normals, None, method)
}

/// [`model_frames`], joining corners into vertices from the position
/// numbers of [`model_normals_numbered`] when given (the same meshes).
pub fn model_frames_numbered(
    model: &ObjModel,
    normals: Vec<Vec<Vec3>>,
    numbers: Option<&PositionNumbers>,
    method: TangentMethod,
) -> Vec<(Mesh, TangentStats)> {
    let build = |(i, part): (usize, &ObjPart),
                 normals: &[Vec3],
                 buffers: Option<MeshBuffers>,
                 scratch: &mut MeshScratch| match (method, buffers) {
        (TangentMethod::Aerial, Some(buffers)) => build_mesh_in(
            &part.positions,
            normals,
            part.uvs.as_deref(),
            numbers.and_then(|n| n.part(i)),
            buffers,
            scratch,
        ),
        _ => build_mesh_mikktspace(&part.positions, normals, part.uvs.as_deref()),
    };
    // Each part's arrays, and each thread's working arrays, are reserved
    // here, before the threads start: they then reuse the memory smoothing
    // freed instead of faulting in fresh pages in each thread's own pool.
    let aerial = method == TangentMethod::Aerial;
    let buffers = model
        .parts
        .iter()
        .map(|part| aerial.then(|| MeshBuffers::for_corners(part.positions.len())));
    let largest = model.parts.iter().map(|p| p.positions.len()).max();
    let scratch = || match largest {
        Some(corners) if aerial => MeshScratch::for_corners(corners),
        _ => MeshScratch::default(),
    };
    // Parts are independent: spread them over the cores (in order).
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(model.parts.len());
    if threads <= 1 {
        let mut scratch = scratch();
        return model
            .parts
            .iter()
            .enumerate()
            .zip(&normals)
            .zip(buffers)
            .map(|((part, normals), buffers)| build(part, normals, buffers, &mut scratch))
            .collect();
    }
    let mut jobs: Vec<_> = model
        .parts
        .iter()
        .enumerate()
        .zip(&normals)
        .zip(buffers)
        .map(|((part, normals), buffers)| (part, normals, buffers))
        .collect();
    let chunk = jobs.len().div_ceil(threads);
    std::thread::scope(|scope| {
        let handles: Vec<_> = jobs
            .chunks_mut(chunk)
            .map(|chunk| {
                let build = &build;
                let mut scratch = scratch();
                scope.spawn(move || {
                    chunk
                        .iter_mut()
                        .map(|(part, normals, buffers)| {
                            build(*part, normals, buffers.take(), &mut scratch)
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            // A panic in a worker is a bug in the mesh code; re-raise it
            // here rather than lose the part.
            .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}
