//! OBJ models in a scene, read after the scene file is parsed: an `obj`
//! object of the [`Description`] becomes one object per object or group
//! of the file, each with its MTL material (checked against a scene
//! material's bounds) unless the scene names one; missing or broken assets
//! are warnings with visible fallbacks.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;

use super::file::{
    Description, MaterialRef, ModelObject, ObjectDescription, PendingMaterial, DEFAULT_TESSELLATION,
};
use super::material_maps::{MapKind, MapSource, MaterialMaps, MAP_KINDS};
use super::value_checks::{Check, Result, MAX_COLOUR};
use super::{
    AssetWarning, Material, Object, Scene, SceneError, SceneWarning, ShadingModel, Shape, Transform,
};
use crate::mesh::obj;
use crate::mesh::tangents::TangentStats;
use crate::mesh::Mesh;

impl Check<'_> {
    /// The scene a parsed file describes: every OBJ model it names is
    /// read, smoothed and given tangent frames here, once, in file order
    /// (so the models' materials follow the scene's in the same order
    /// every time). The models' warnings come before the sky's; the files
    /// read are listed in [`Scene::files`].
    pub(super) fn load_models(&self, description: Description) -> Result<Scene> {
        let Description { mut scene, objects } = description;
        let mut by_name: HashMap<String, usize> = scene
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| (m.name.clone(), i))
            .collect();
        let mut warnings = Vec::new();
        let mut files = Vec::new();
        for object in objects {
            match object {
                ObjectDescription::Shape(object) => scene.objects.push(object),
                ObjectDescription::ShapeWithModelMaterial(mut object, pending) => {
                    object.material =
                        self.pending_material(&pending, &scene.materials, &by_name)?;
                    scene.objects.push(object);
                }
                ObjectDescription::Model(model) => {
                    let parts = self.model_objects(
                        model,
                        &mut scene.materials,
                        &mut by_name,
                        &mut warnings,
                        &mut files,
                    )?;
                    scene.objects.extend(parts);
                }
            }
        }
        warnings.append(&mut scene.warnings);
        scene.warnings = warnings;

        for m in &scene.materials {
            files.extend(m.maps.files().map(Path::to_path_buf));
        }
        let mut seen = std::collections::HashSet::new();
        files.retain(|f| seen.insert(f.clone()));
        scene.files = files;

        scene.warn_unused_maps(self.file);
        Ok(scene)
    }

    /// The objects of one `obj` object: one per object/group of the file
    /// (named `name/group`), each with its MTL material unless the scene
    /// object names one (then the MTL's textures are never opened, and its
    /// problems are no concern of the scene's). Missing MTL libraries and
    /// textures are `warnings` (see [`Check::mtl_material`]); the files
    /// read are added to `files`.
    fn model_objects(
        &self,
        model: ModelObject,
        materials: &mut Vec<Material>,
        by_name: &mut HashMap<String, usize>,
        warnings: &mut Vec<SceneWarning>,
        files: &mut Vec<PathBuf>,
    ) -> Result<Vec<Object>> {
        let field = |name: &str| format!("{}.{name}", model.field);
        let resolved = &model.path;
        let (loaded, meshes) = self.read_model(&model, files)?;
        let over = match &model.material {
            None => None,
            Some(MaterialRef::Index(i)) => Some(*i),
            Some(MaterialRef::Pending(p)) => Some(self.pending_material(p, materials, by_name)?),
        };
        let mut warn = |warning: AssetWarning| {
            warnings.push(SceneWarning {
                file: self.file.to_owned(),
                field: field("shape.path"),
                warning,
            })
        };
        if over.is_none() {
            loaded.warnings.iter().cloned().for_each(&mut warn);
        }
        let transform = placed_transform(model.transform, loaded.origin);
        // The model's own materials, added on first use as `name/material`.
        let mut own: HashMap<Option<usize>, usize> = HashMap::new();
        let mut objects = Vec::with_capacity(meshes.len());
        for (i, (part, (mesh, _))) in loaded.parts.iter().zip(meshes).enumerate() {
            // A group whose faces all collapsed draws nothing; an empty
            // vertex buffer is not a valid draw.
            if mesh.indices.is_empty() {
                continue;
            }
            let material = match over {
                Some(m) => m,
                None => match own.get(&part.material) {
                    Some(&m) => m,
                    None => {
                        let m = self.mtl_material(
                            &field("shape.path"),
                            &model.name,
                            part.material.map(|m| &loaded.materials[m]),
                            &resolved.display().to_string(),
                            materials,
                            by_name,
                            &mut warn,
                        )?;
                        own.insert(part.material, m);
                        m
                    }
                },
            };
            let part_name = if part.name.is_empty() {
                format!("{i}")
            } else {
                part.name.clone()
            };
            if part.uvs.is_none() {
                self.check_no_tangent_map(&model, &part_name, &materials[material])?;
            }
            objects.push(Object {
                name: format!("{}/{part_name}", model.name),
                shape: Shape::Mesh {
                    mesh: Arc::new(mesh),
                },
                // Unused for a mesh; kept only because every object has one.
                tessellation: (DEFAULT_TESSELLATION[0], DEFAULT_TESSELLATION[1]),
                auto_tessellation: false,
                material,
                transform,
                two_sided: model.two_sided,
                casts_shadows: model.casts_shadows,
            });
        }
        if objects.is_empty() {
            return Err(self.invalid(
                field("shape.path"),
                format!(
                    "{}: every triangle is collapsed to a line or a point",
                    resolved.display()
                ),
            ));
        }
        Ok(objects)
    }

    /// Reads `model`'s file (adding the files read to `files`) and makes
    /// its meshes: smoothed, with tangent frames.
    fn read_model(
        &self,
        model: &ModelObject,
        files: &mut Vec<PathBuf>,
    ) -> Result<(obj::ObjModel, Vec<(Mesh, TangentStats)>)> {
        let field = |name: &str| format!("{}.{name}", model.field);
        let resolved = &model.path;
        // A bad budget setting is the setting's fault, not the model's: its
        // error names the setting alone.
        let model_error = |e: obj::ObjError| match e {
            obj::ObjError::Budget(_) => SceneError::Model(e),
            e => self.invalid(field("shape.path"), e.to_string()),
        };
        // A model is parsed, smoothed and given frames when the scene is
        // loaded, before the renderer's own memory estimate: refuse here,
        // from the file's size, what cannot fit the budget.
        if let Ok(meta) = std::fs::metadata(resolved) {
            let budget = crate::budget::MemoryBudget::from_env()
                .map_err(|e| model_error(obj::ObjError::Budget(e)))?;
            budget
                .check(
                    format!("model {}", resolved.display()),
                    meta.len().saturating_mul(obj::MEMORY_PER_FILE_BYTE),
                )
                .map_err(|e| self.invalid(field("shape.path"), e.to_string()))?;
        }
        // Parsing, smoothing and tangent frames each reuse the memory the
        // stage before freed, and the free memory goes back to the system
        // once the meshes are made.
        let _reuse = crate::mesh::heap::HeapReuse::enter();
        let loaded = obj::load_obj(resolved).map_err(model_error)?;
        files.extend(loaded.files.iter().cloned());
        let meshes = obj::model_meshes(&loaded, &model.options, &resolved.display().to_string())
            .map_err(|e| {
                // Only a smoothing mode the file cannot satisfy is the
                // option's fault; anything else is the model's.
                match e {
                    obj::ObjError::Smoothing { .. } => {
                        self.invalid(field("smoothing"), e.to_string())
                    }
                    e => model_error(e),
                }
            })?;
        Ok((loaded, meshes))
    }

    /// Refuses `material` on `model`'s part `part_name`, which has faces
    /// without texture coordinates, when it has a map that needs tangents:
    /// without UVs there is no tangent space to read the map in.
    fn check_no_tangent_map(
        &self,
        model: &ModelObject,
        part_name: &str,
        material: &Material,
    ) -> Result<()> {
        let Some((kind, _)) = material
            .maps
            .iter()
            .find(|(kind, _)| kind.info().needs_tangents)
        else {
            return Ok(());
        };
        Err(self.invalid(
            format!("{}.shape.path", model.field),
            format!(
                "{}: object \"{part_name}\" has faces without texture coordinates, \
                 but its material \"{}\" has a {}",
                model.path.display(),
                material.name,
                kind.info().mtl_name
            ),
        ))
    }

    /// The index of a material named after a model, among the materials
    /// known now (the scene's and those of the models read so far).
    fn pending_material(
        &self,
        pending: &PendingMaterial,
        materials: &[Material],
        by_name: &HashMap<String, usize>,
    ) -> Result<usize> {
        self.material_index(&pending.field, Some(&pending.name), materials, by_name)
    }

    /// Adds the scene material for an MTL material (or the default grey for
    /// faces without one) and returns its index. A texture that is missing
    /// or not a readable PNG or JPEG (by its header) is a warning: the base
    /// colour becomes the magenta/black checker placeholder, a normal map
    /// the flat normal (0, 0, 1), which is the same as leaving it out.
    #[allow(clippy::too_many_arguments)]
    fn mtl_material(
        &self,
        field: &str,
        object: &str,
        mtl: Option<&obj::ObjMaterial>,
        model: &str,
        materials: &mut Vec<Material>,
        by_name: &mut HashMap<String, usize>,
        warn: &mut dyn FnMut(AssetWarning),
    ) -> Result<usize> {
        let default = obj::ObjMaterial {
            name: "default".into(),
            origin: model.to_owned(),
            ka: None,
            kd: Vec3::splat(0.8),
            ks: Vec3::ZERO,
            shininess: 32.0,
            opacity: 1.0,
            maps: Vec::new(),
        };
        let mtl = mtl.unwrap_or(&default);
        let name = format!("{object}/{}", mtl.name);
        if by_name.contains_key(&name) {
            return Err(self.invalid(
                field,
                format!("the model's material \"{name}\" clashes with a scene material name"),
            ));
        }
        let values = checked_mtl_values(mtl, warn);
        let mut maps = MaterialMaps::default();
        for info in MAP_KINDS {
            if let Some(path) = info.mtl.iter().find_map(|statement| mtl.map(statement)) {
                maps.set(
                    info.kind,
                    usable_map(info.kind, path, model, &mtl.name, warn),
                );
            }
        }
        materials.push(Material {
            name: name.clone(),
            ka: values.ka,
            kd: values.kd,
            ks: values.ks,
            shininess: values.shininess,
            maps,
            opacity: values.opacity,
            shading: ShadingModel::Phong,
            two_sided: false,
        });
        by_name.insert(name, materials.len() - 1);
        Ok(materials.len() - 1)
    }
}

/// The transform of a model whose positions are measured from `origin`
/// (`ObjModel::origin`): a far-off model's centre goes into the
/// translation, in f64, where the renderer keeps world positions exact.
fn placed_transform(transform: Transform, origin: glam::DVec3) -> Transform {
    let mut placed = transform;
    if origin != glam::DVec3::ZERO {
        placed.translate = transform.matrix_f64().transform_point3(origin);
    }
    placed
}

/// A model's map of `kind` at `path` (of `material` in `model`), or, when
/// the file is missing or not a readable PNG or JPEG (by its header), a
/// warning and the kind's placeholder or nothing.
fn usable_map(
    kind: MapKind,
    path: &Path,
    model: &str,
    material: &str,
    warn: &mut dyn FnMut(AssetWarning),
) -> Option<MapSource> {
    let problem = match crate::safe_files::input_file_problem(path) {
        Some(problem) => problem,
        None => match crate::image_io::inspect_texture(path) {
            Ok(_) => return Some(MapSource::file(path.to_path_buf())),
            Err(e) => format!("is not usable: {e}"),
        },
    };
    let info = kind.info();
    warn(AssetWarning {
        problem: format!(
            "{model}: material \"{material}\": {} {problem}",
            info.mtl_name
        ),
        fallback: info.missing_fallback.to_owned(),
    });
    info.placeholder_when_missing.then(MapSource::placeholder)
}

/// An MTL material's colours, exponent and opacity after the checks.
struct MtlValues {
    ka: Vec3,
    kd: Vec3,
    ks: Vec3,
    shininess: f32,
    opacity: f32,
}

/// Checks an MTL material's values against the bounds of a scene
/// material (colours finite, at least 0 and at most [`MAX_COLOUR`];
/// `d` from 0 to 1), with one warning for each value out of them and the
/// fallback taken: a colour that is not a finite non-negative number gets
/// the MTL default (Kd 0.8 grey, Ks black, Ka = Kd), one above the bound
/// is clamped, `d` outside 0..1 is drawn opaque. `Ns 0` is common in
/// exported files for "no highlight" and becomes 1 without a warning
/// (`pow(0, 0)` is undefined in GLSL).
fn checked_mtl_values(mtl: &obj::ObjMaterial, warn: &mut dyn FnMut(AssetWarning)) -> MtlValues {
    let max = MAX_COLOUR as f32;
    let mut warn_value = |what: &str, reason: String, fallback: String| {
        warn(AssetWarning {
            problem: format!("{}: material \"{}\": {what} {reason}", mtl.origin, mtl.name),
            fallback,
        })
    };
    let mut colour = |what: &str, v: Vec3, default: Vec3| -> Vec3 {
        let c = v.to_array();
        if let Some(i) = c.iter().position(|x| !x.is_finite() || *x < 0.0) {
            warn_value(
                what,
                format!(
                    "component {i} must be finite and at least 0, got {:e}",
                    c[i]
                ),
                format!("{what} {} is used instead", default.x),
            );
            default
        } else if let Some(i) = c.iter().position(|&x| x > max) {
            warn_value(
                what,
                format!(
                    "component {i} must be at most {MAX_COLOUR:e}, got {:e}",
                    c[i]
                ),
                format!("clamped to {MAX_COLOUR:e}"),
            );
            v.min(Vec3::splat(max))
        } else {
            v
        }
    };
    let kd = colour("Kd", mtl.kd, Vec3::splat(0.8));
    let ks = colour("Ks", mtl.ks, Vec3::ZERO);
    let ka = match mtl.ka {
        Some(ka) => colour("Ka", ka, kd),
        None => kd,
    };
    let shininess = if !mtl.shininess.is_finite() || mtl.shininess < 0.0 {
        warn_value(
            "Ns",
            format!("must be finite and at least 0, got {:e}", mtl.shininess),
            "Ns 32 is used instead".into(),
        );
        32.0
    } else if mtl.shininess > max {
        warn_value(
            "Ns",
            format!("must be at most {MAX_COLOUR:e}, got {:e}", mtl.shininess),
            format!("clamped to {MAX_COLOUR:e}"),
        );
        max
    } else {
        mtl.shininess.max(1.0)
    };
    let opacity = if (0.0..=1.0).contains(&mtl.opacity) {
        mtl.opacity
    } else {
        warn_value(
            "d",
            format!("must be from 0 to 1, got {:e}", mtl.opacity),
            "drawn opaque (d 1)".into(),
        );
        1.0
    };
    MtlValues {
        ka,
        kd,
        ks,
        shininess,
        opacity,
    }
}
