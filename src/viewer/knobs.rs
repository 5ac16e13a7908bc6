//! The knobs the viewer cycles with the number keys: the scene's quality
//! and cost settings from [`crate::scene::KNOBS`] that apply to the scene,
//! each with the values a key steps through.

use crate::scene::{Knob, KnobError, Scene};

/// A knob and the values its key cycles through.
#[derive(Debug)]
pub struct Cycle {
    pub name: &'static str,
    pub values: &'static [&'static str],
    /// Whether it changes anything in this scene.
    applies: fn(&Scene) -> bool,
}

fn has_objects(s: &Scene) -> bool {
    !s.objects.is_empty()
}

fn has_textures(s: &Scene) -> bool {
    s.materials.iter().any(|m| !m.maps.is_empty())
}

fn has_sky(s: &Scene) -> bool {
    s.sky.is_some()
}

/// Aerial perspective is the air in front of objects.
fn has_sky_and_objects(s: &Scene) -> bool {
    has_sky(s) && has_objects(s)
}

/// Every knob the viewer can cycle, in key order before filtering.
const CYCLES: &[Cycle] = &[
    Cycle {
        name: "shading",
        values: &["phong", "gouraud", "toon"],
        applies: has_objects,
    },
    Cycle {
        name: "lighting",
        values: &["forward", "deferred"],
        applies: has_objects,
    },
    Cycle {
        name: "texture_filter",
        values: &["trilinear", "bilinear", "nearest"],
        applies: has_textures,
    },
    Cycle {
        name: "hdr_format",
        values: &["rgba16f", "rgba32f"],
        applies: |_| true,
    },
    Cycle {
        name: "tone_map",
        values: &["reinhard", "aces", "none"],
        applies: |_| true,
    },
    Cycle {
        name: "atmosphere_samples",
        values: &["4", "8", "16", "32", "64"],
        applies: has_sky,
    },
    Cycle {
        name: "aerial_perspective",
        values: &["march", "volume"],
        applies: has_sky_and_objects,
    },
    Cycle {
        name: "aerial_volume",
        values: &["16x16x16", "32x32x32", "64x64x64"],
        applies: has_sky_and_objects,
    },
    Cycle {
        name: "multiple_scattering",
        values: &["on", "off"],
        applies: has_sky,
    },
    Cycle {
        name: "ms_table_size",
        values: &["8x8", "32x32", "64x64"],
        applies: has_sky,
    },
    Cycle {
        name: "irradiance_table_size",
        values: &["16x4", "64x16", "128x32"],
        applies: has_sky,
    },
    Cycle {
        name: "od_filter",
        values: &["manual", "nearest", "hardware"],
        applies: has_sky,
    },
    Cycle {
        name: "od_table_mapping",
        values: &["horizon", "linear"],
        applies: has_sky,
    },
    Cycle {
        name: "od_table_size",
        values: &["32x8", "64x16", "256x64", "1024x256"],
        applies: has_sky,
    },
    Cycle {
        name: "sky_view",
        values: &["off", "64x128", "128x256"],
        applies: has_sky,
    },
    Cycle {
        name: "od_ozone",
        values: &["exact", "table"],
        applies: has_sky,
    },
    // Last, so the keys of the knobs above keep their numbers.
    Cycle {
        name: "depth_prepass",
        values: &["auto", "off", "on"],
        applies: has_objects,
    },
    Cycle {
        name: "exposure",
        values: &["1", "auto"],
        applies: |_| true,
    },
    Cycle {
        name: "shadow_map",
        values: &["512", "1024", "2048", "4096"],
        applies: casts_shadows,
    },
    Cycle {
        name: "shadow_filter",
        values: &["none", "pcf3", "pcf5"],
        applies: casts_shadows,
    },
    Cycle {
        name: "shadow_cascades",
        values: &["auto", "1", "2", "4"],
        applies: casts_shadows,
    },
];

/// Shadow settings matter only with a shadow-casting light.
fn casts_shadows(s: &Scene) -> bool {
    s.shadow_light.is_some()
}

/// The knobs that apply to `scene`; key N cycles entry N-1 (key 0 the
/// tenth, F2 to F11 the eleventh to the twentieth).
pub fn applicable(scene: &Scene) -> Vec<&'static Cycle> {
    CYCLES.iter().filter(|c| (c.applies)(scene)).collect()
}

impl Cycle {
    /// The knob's current value in `scene`.
    pub fn current(&self, scene: &Scene) -> Result<String, KnobError> {
        Ok((Knob::find(self.name)?.read)(scene))
    }

    /// Sets the value after the current one (the first when the current
    /// one is not in the list, e.g. mixed shading models) and returns it.
    pub fn advance(&self, scene: &mut Scene) -> Result<&'static str, KnobError> {
        let knob = Knob::find(self.name)?;
        let current = (knob.read)(scene);
        let next = match self.values.iter().position(|v| *v == current) {
            Some(i) => self.values[(i + 1) % self.values.len()],
            None => self.values[0],
        };
        knob.set(scene, next)?;
        Ok(next)
    }
}

/// One line per applicable knob: `N name=value`.
pub fn listing(scene: &Scene) -> String {
    applicable(scene)
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let value = c.current(scene).unwrap_or_else(|e| e.to_string());
            let key = crate::viewer::input::knob_key(i + 1).unwrap_or_else(|| "-".into());
            format!("  {key} {}={value} ({})", c.name, c.values.join("|"))
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_cycle_names_a_knob_and_its_values_apply() {
        let mut scene = Scene::default_scene();
        for c in applicable(&scene.clone()) {
            for _ in 0..c.values.len() {
                c.advance(&mut scene).unwrap();
            }
            // A full cycle comes back to where it started (the first value
            // when the scene's own was not listed).
            let v = c.current(&scene).unwrap();
            assert!(c.values.contains(&v.as_str()), "{}: {v}", c.name);
        }
    }

    #[test]
    fn atmosphere_knobs_only_for_scenes_with_a_sky() {
        let scene = Scene::default_scene();
        let names: Vec<_> = applicable(&scene).iter().map(|c| c.name).collect();
        assert!(names.contains(&"shading") && !names.contains(&"atmosphere_samples"));
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/earth_orbit.toml");
        let mut earth = Scene::load(&path).unwrap();
        let names: Vec<_> = applicable(&earth).iter().map(|c| c.name).collect();
        assert!(names.contains(&"atmosphere_samples") && !names.contains(&"shading"));
        let samples = applicable(&earth)
            .into_iter()
            .find(|c| c.name == "atmosphere_samples")
            .unwrap();
        let before = samples.current(&earth).unwrap();
        let after = samples.advance(&mut earth).unwrap();
        assert_ne!(before, after);
        assert_eq!(samples.current(&earth).unwrap(), after);
        assert!(
            applicable(&earth).len() <= crate::viewer::input::KNOB_KEYS,
            "one key each"
        );
        // Aerial perspective needs objects under the sky.
        assert!(!names.contains(&"aerial_perspective"));
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/scenes/earth_objects.toml");
        let objects = Scene::load(&path).unwrap();
        let names: Vec<_> = applicable(&objects).iter().map(|c| c.name).collect();
        assert!(names.contains(&"aerial_perspective") && names.contains(&"aerial_volume"));
        assert!(applicable(&objects).len() <= crate::viewer::input::KNOB_KEYS);
    }
}
