//! Knobs: every quality/cost setting of the renderer, by name, applied to a
//! loaded scene.
//!
//! Benchmarks record every knob's setting, and sweeps render the cartesian
//! product of knob values. Adding an approximation to the renderer means
//! one entry in [`KNOBS`], its value names in the `named!` table below
//! when its values are an enum, and, for the viewer to cycle it, an entry
//! in `viewer::knobs`.

use super::{
    AerialPerspective, Bloom, DepthPrepass, Exposure, HdrFormat, Lighting, OzoneDepth, Scene,
    ShadingModel, ShadowFilter, Shape, TableFilter, TableMapping, TextureFilter, ToneMapOperator,
};

/// One named setting.
pub struct Knob {
    pub name: &'static str,
    /// What the values mean, for `--help` and reports.
    pub values: &'static str,
    /// Sets the knob on a scene.
    pub apply: fn(&mut Scene, &str) -> Result<(), String>,
    /// The value a sweep's reference image uses for this knob: the
    /// highest-quality setting.
    pub best: Best,
    /// The scene's current setting, in the same syntax `apply` takes (or a
    /// summary when objects differ).
    pub read: fn(&Scene) -> String,
}

#[derive(Debug, thiserror::Error)]
pub enum KnobError {
    #[error("unknown knob '{0}'; knobs: {1}")]
    Unknown(String, String),
    #[error("knob {knob}={value}: {reason}")]
    BadValue {
        knob: String,
        value: String,
        reason: String,
    },
}

/// Which value of a knob the error reference of a sweep is rendered with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Best {
    /// This value is the highest quality.
    Fixed(&'static str),
    /// The last value listed in the sweep (list values cheapest first).
    LastListed,
    /// The knob changes what is rendered, not how well (e.g. image size):
    /// the reference keeps the setting of the row it is compared with.
    Unchanged,
}

/// Every knob.
pub const KNOBS: &[Knob] = &[
    Knob {
        name: "size",
        best: Best::Unchanged,
        values: "WIDTHxHEIGHT, e.g. 1280x720",
        apply: |s, v| {
            let (w, h) = width_x_height(v, "expected WIDTHxHEIGHT")?;
            s.set_output_size(Some(w), Some(h))
                .map_err(|e| e.to_string())
        },
        read: |s| format!("{}x{}", s.output.width, s.output.height),
    },
    Knob {
        name: "shading",
        best: Best::Fixed("phong"),
        values: "phong | gouraud | toon (every material)",
        apply: |s, v| {
            let model = ShadingModel::parse(v)?;
            s.materials.iter_mut().for_each(|m| m.shading = model);
            s.warn_unused_maps(&format!("--knob shading={v}"));
            Ok(())
        },
        read: |s| {
            let mut names: Vec<&str> = s.materials.iter().map(|m| m.shading.name()).collect();
            names.sort_unstable();
            names.dedup();
            names.join("+")
        },
    },
    Knob {
        name: "lights",
        best: Best::LastListed,
        values: "N: keep the first N lights of the scene",
        apply: |s, v| {
            let n: usize = v.parse().map_err(|e| format!("{e}"))?;
            if n > s.lights.len() {
                return Err(format!("the scene has only {} lights", s.lights.len()));
            }
            s.lights.truncate(n);
            Ok(())
        },
        read: |s| s.lights.len().to_string(),
    },
    Knob {
        name: "tessellation",
        best: Best::LastListed,
        values: "F: multiply every object's tessellation by F (e.g. 0.25, 1, 2) | auto: every parametric object's grid chosen by screen-space error (max_pixel_error)",
        apply: |s, v| {
            if v == "auto" {
                for o in &mut s.objects {
                    o.auto_tessellation = !matches!(o.shape, Shape::Mesh { .. });
                }
                return Ok(());
            }
            let f: f64 = v
                .parse()
                .map_err(|e| format!("{e} (expected a factor or auto)"))?;
            scale_tessellation(s, f)
        },
        read: |s| {
            let tris: u64 = s
                .tessellations()
                .iter()
                .map(|&(u, v)| 2 * u as u64 * v as u64)
                .sum();
            // Two per grid cell, the cells that collapse at a sphere's
            // poles included: more than the frame draws.
            match s.objects.iter().any(|o| o.auto_tessellation) {
                true => format!("auto, {tris} grid triangles"),
                false => format!("{tris} grid triangles"),
            }
        },
    },
    Knob {
        name: "max_pixel_error",
        best: Best::LastListed,
        values: "P: pixels a tessellation = \"auto\" object's triangles may stray from its surface (list largest first, e.g. 2,1,0.5)",
        apply: |s, v| {
            let p: f32 = v.parse().map_err(|e| format!("{e}"))?;
            if !(p.is_finite() && p > 0.0) {
                return Err("must be a finite number of pixels > 0".into());
            }
            s.output.max_pixel_error = p;
            Ok(())
        },
        read: |s| s.output.max_pixel_error.to_string(),
    },
    Knob {
        name: "light_cutoff",
        best: Best::Fixed("0"),
        values: "C: leave a point light out of an object's block below this attenuated strength (0 = never)",
        apply: |s, v| {
            let c: f32 = v.parse().map_err(|e| format!("{e}"))?;
            if !(c.is_finite() && c >= 0.0) {
                return Err("must be finite and >= 0".into());
            }
            s.light_cutoff = c;
            Ok(())
        },
        read: |s| s.light_cutoff.to_string(),
    },
    Knob {
        name: "hdr_format",
        best: Best::Fixed("rgba32f"),
        values: "rgba16f | rgba32f",
        apply: |s, v| {
            s.output.hdr_format = HdrFormat::parse(v)?;
            Ok(())
        },
        read: |s| s.output.hdr_format.name().into(),
    },
    Knob {
        name: "static_lights",
        // The same image either way; only the cost changes.
        best: Best::Unchanged,
        values: "on | off (off: every light read from its uniform block, to measure the difference)",
        apply: |s, v| {
            s.output.static_lights = parse_on_off(v)?;
            Ok(())
        },
        read: |s| on_off(s.output.static_lights).into(),
    },
    Knob {
        name: "texture_filter",
        best: Best::Fixed("trilinear"),
        values: "nearest | bilinear | trilinear",
        apply: |s, v| {
            s.output.texture_filter = TextureFilter::parse(v)?;
            Ok(())
        },
        read: |s| s.output.texture_filter.name().into(),
    },
    Knob {
        name: "tone_map",
        // The operator changes what the output shows, not how well.
        best: Best::Unchanged,
        values: "reinhard | aces | none (none: LDR output, no HDR target without --hdr)",
        apply: |s, v| {
            s.tone_map.operator = ToneMapOperator::parse(v)?;
            Ok(())
        },
        read: |s| s.tone_map.operator.name().into(),
    },
    Knob {
        name: "exposure",
        // Like the operator, the exposure changes what the output shows.
        best: Best::Unchanged,
        values: "auto | a number > 0 (auto: measured from each frame's HDR image)",
        apply: |s, v| {
            s.tone_map.exposure = Exposure::parse(v)?;
            Ok(())
        },
        read: |s| s.tone_map.exposure.name(),
    },
    Knob {
        name: "bloom",
        // Bloom changes what the output shows, not how well.
        best: Best::Unchanged,
        values: "off | on | an intensity in (0, 1] (on: the scene's bloom, or the defaults)",
        apply: |s, v| {
            s.tone_map.bloom = Bloom::parse(v, s.tone_map.bloom)?;
            Ok(())
        },
        read: |s| Bloom::name(s.tone_map.bloom),
    },
    Knob {
        name: "lighting",
        // Both evaluate the same formula; forward does it in full float
        // precision, deferred from a 16-bit G-buffer.
        best: Best::Fixed("forward"),
        values: "forward | deferred",
        apply: |s, v| {
            let lighting = Lighting::parse(v)?;
            if lighting == Lighting::Deferred && s.shadow_light.is_some() {
                return Err(super::SHADOWS_NEED_FORWARD.into());
            }
            s.output.lighting = lighting;
            Ok(())
        },
        read: |s| s.output.lighting.name().into(),
    },
    Knob {
        name: "depth_prepass",
        // The same image either way (up to surfaces at exactly equal
        // depth); only the cost changes.
        best: Best::Unchanged,
        values: "off | on | auto: draw opaque surfaces depth-only first so each visible pixel is shaded once (auto: where the plan estimates it pays)",
        apply: |s, v| {
            s.output.depth_prepass = DepthPrepass::parse(v)?;
            Ok(())
        },
        read: |s| s.output.depth_prepass.name().into(),
    },
    Knob {
        name: "shadow_map",
        best: Best::LastListed,
        values: "N: the shadow map's width and height in texels (512..=8192; list smallest first)",
        apply: |s, v| {
            let n: u32 = v.parse().map_err(|e| format!("{e}"))?;
            s.output.shadow_map = super::shadow_map_side(n)?;
            Ok(())
        },
        read: |s| s.output.shadow_map.to_string(),
    },
    Knob {
        name: "shadow_filter",
        best: Best::Fixed("pcf5"),
        values: "none | pcf3 | pcf5: depth comparisons averaged over 1, 3x3 or 5x5 shadow-map texels",
        apply: |s, v| {
            s.output.shadow_filter = ShadowFilter::parse(v)?;
            Ok(())
        },
        read: |s| s.output.shadow_filter.name().into(),
    },
    Knob {
        name: "shadow_cascades",
        best: Best::LastListed,
        values: "auto | N: shadow maps split along the view's depth (1..=4; list fewest first)",
        apply: |s, v| {
            s.output.shadow_cascades = super::ShadowCascades::parse(v)?;
            Ok(())
        },
        read: |s| s.output.shadow_cascades.name(),
    },
    Knob {
        name: "atmosphere_samples",
        best: Best::LastListed,
        values: "N: ray-march samples per pixel of the atmosphere pass (1..=1024)",
        apply: |s, v| {
            let n: u32 = v.parse().map_err(|e| format!("{e}"))?;
            if !(1..=super::MAX_ATMOSPHERE_SAMPLES).contains(&n) {
                return Err(format!(
                    "must be between 1 and {}",
                    super::MAX_ATMOSPHERE_SAMPLES
                ));
            }
            sky_mut(s)?.samples = n;
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => sky.samples.to_string(),
            None => "-".into(),
        },
    },
    Knob {
        name: "od_table_size",
        best: Best::LastListed,
        values: "WIDTHxHEIGHT: optical-depth table texels, direction x altitude (3..=4096 each)",
        apply: |s, v| {
            let (w, h) = width_x_height(v, "expected WIDTHxHEIGHT")?;
            crate::atmosphere::model::check_table_size(w, h)?;
            sky_mut(s)?.table_size = (w, h);
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => format!("{}x{}", sky.table_size.0, sky.table_size.1),
            None => "-".into(),
        },
    },
    Knob {
        name: "od_table_mapping",
        best: Best::Fixed("horizon"),
        values: "horizon | linear: how altitude and direction map to the optical-depth table",
        apply: |s, v| {
            // "seed" is the old name of "linear": still read, with a warning.
            let mapping = if v == "seed" {
                s.warnings
                    .push(super::sky::seed_renamed("--knob", "od_table_mapping"));
                TableMapping::Linear
            } else {
                TableMapping::parse(v)?
            };
            sky_mut(s)?.table_mapping = mapping;
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => sky.table_mapping.name().into(),
            None => "-".into(),
        },
    },
    Knob {
        name: "sky_view",
        best: Best::Fixed("off"),
        values: "off | WIDTHxHEIGHT: directions of the sky-view table that sky and ground pixels read instead of marching",
        apply: |s, v| {
            let size = if v == "off" {
                None
            } else {
                let (w, h) = width_x_height(v, "expected off or WIDTHxHEIGHT")?;
                crate::atmosphere::model::check_sky_view(w, h)?;
                Some((w, h))
            };
            sky_mut(s)?.sky_view = size;
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => match sky.sky_view {
                Some((w, h)) => format!("{w}x{h}"),
                None => "off".into(),
            },
            None => "-".into(),
        },
    },
    Knob {
        name: "multiple_scattering",
        best: Best::Fixed("on"),
        values: "on | off: every order of scattering and the sky's light on the ground, or single scattering alone",
        apply: |s, v| {
            sky_mut(s)?.multiple_scattering = parse_on_off(v)?;
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => on_off(sky.multiple_scattering).into(),
            None => "-".into(),
        },
    },
    Knob {
        name: "ms_table_size",
        best: Best::LastListed,
        values: "WIDTHxHEIGHT: multiple-scattering table texels, sun angle x altitude (2..=512 each)",
        apply: |s, v| {
            let (w, h) = sun_table_size(v)?;
            sky_mut(s)?.ms_table_size = (w, h);
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => format!("{}x{}", sky.ms_table_size.0, sky.ms_table_size.1),
            None => "-".into(),
        },
    },
    Knob {
        name: "irradiance_table_size",
        best: Best::LastListed,
        values: "WIDTHxHEIGHT: sky-irradiance table texels, sun angle x altitude (2..=512 each)",
        apply: |s, v| {
            let (w, h) = sun_table_size(v)?;
            sky_mut(s)?.irradiance_table_size = (w, h);
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => format!(
                "{}x{}",
                sky.irradiance_table_size.0, sky.irradiance_table_size.1
            ),
            None => "-".into(),
        },
    },
    Knob {
        name: "aerial_perspective",
        best: Best::Fixed("march"),
        values: "march | volume: surfaces march their own ray through the air, or read the aerial-perspective volume",
        apply: |s, v| {
            sky_mut(s)?.aerial_perspective = AerialPerspective::parse(v)?;
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => sky.aerial_perspective.name().into(),
            None => "-".into(),
        },
    },
    Knob {
        name: "aerial_volume",
        best: Best::LastListed,
        values: "WIDTHxHEIGHTxDEPTH: the aerial-perspective volume's columns across and down the screen and slices in distance (2..=256 each; with aerial_perspective=volume)",
        apply: |s, v| {
            sky_mut(s)?.aerial_volume = super::sky::parse_aerial_volume(v)?;
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => {
                let (w, h, d) = sky.aerial_volume;
                format!("{w}x{h}x{d}")
            }
            None => "-".into(),
        },
    },
    Knob {
        name: "od_filter",
        best: Best::Fixed("manual"),
        values: "manual | nearest | hardware: how the atmosphere pass reads the optical-depth table",
        apply: |s, v| {
            sky_mut(s)?.table_filter = TableFilter::parse(v)?;
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => sky.table_filter.name().into(),
            None => "-".into(),
        },
    },
    Knob {
        name: "od_ozone",
        best: Best::Fixed("exact"),
        values: "exact | table: the ozone's integral towards the sun in closed form or from the optical-depth table",
        apply: |s, v| {
            sky_mut(s)?.ozone_depth = OzoneDepth::parse(v)?;
            Ok(())
        },
        read: |s| match &s.sky {
            Some(sky) => sky.ozone_depth.name().into(),
            None => "-".into(),
        },
    },
];

/// The numeric `tessellation` knob: every object's fixed grid times `f`,
/// an auto object's default grid included (it stops being auto, so that
/// the row draws what its label says).
fn scale_tessellation(s: &mut Scene, f: f64) -> Result<(), String> {
    if !(f.is_finite() && f > 0.0) {
        return Err("must be a positive factor".into());
    }
    // Above the maximum is refused rather than clamped: a clamped row would
    // keep a label that does not describe what it drew. Below the minimum
    // still rounds up to it, so coarse factors apply to every scene.
    let max = crate::mesh::MAX_SEGMENTS;
    for (i, o) in s.objects.iter().enumerate() {
        let most = o.tessellation.0.max(o.tessellation.1);
        let scaled = (most as f64 * f).round();
        if scaled > max as f64 {
            return Err(format!(
                "objects[{i}] \"{}\" would get {scaled:e} segments (tessellation \
                 {}x{} times {f}); at most {max} are allowed",
                o.name, o.tessellation.0, o.tessellation.1
            ));
        }
    }
    for o in &mut s.objects {
        let scale = |n: u32| ((n as f64 * f).round() as u32).clamp(super::MIN_SEGMENTS, max);
        o.tessellation = (scale(o.tessellation.0), scale(o.tessellation.1));
        o.auto_tessellation = false;
    }
    Ok(())
}

/// "on" or "off".
fn on_off(on: bool) -> &'static str {
    if on {
        "on"
    } else {
        "off"
    }
}

/// `true` for "on", `false` for "off".
fn parse_on_off(v: &str) -> Result<bool, String> {
    match v {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err("expected on or off".into()),
    }
}

/// A `WIDTHxHEIGHT` value; `expected` says what the knob takes when `v` has
/// no `x`.
fn width_x_height(v: &str, expected: &str) -> Result<(u32, u32), String> {
    let (w, h) = v.split_once('x').ok_or(expected)?;
    let parse = |t: &str| t.trim().parse::<u32>().map_err(|e| format!("'{t}': {e}"));
    Ok((parse(w)?, parse(h)?))
}

/// A multiple-scattering or sky-irradiance table size, `WIDTHxHEIGHT`.
fn sun_table_size(v: &str) -> Result<(u32, u32), String> {
    let (w, h) = width_x_height(v, "expected WIDTHxHEIGHT")?;
    crate::atmosphere::model::check_sun_table_size(w, h)?;
    Ok((w, h))
}

/// A knob whose values are the variants of an enum, by the names the scene
/// file spells them with (each enum's serde `rename_all = "lowercase"`).
trait Named: Copy + PartialEq + 'static {
    /// Every variant and its name.
    const NAMES: &'static [(&'static str, Self)];

    /// The variant called `value`, or "expected a, b or c".
    fn parse(value: &str) -> Result<Self, String> {
        Self::NAMES
            .iter()
            .find(|(name, _)| *name == value)
            .map(|&(_, variant)| variant)
            .ok_or_else(|| {
                let names: Vec<&str> = Self::NAMES.iter().map(|(name, _)| *name).collect();
                let (last, rest) = names.split_last().expect("a named enum has variants");
                if rest.is_empty() {
                    format!("expected {last}")
                } else {
                    format!("expected {} or {last}", rest.join(", "))
                }
            })
    }

    /// This variant's name.
    fn name(self) -> &'static str {
        Self::NAMES
            .iter()
            .find(|(_, variant)| *variant == self)
            .map_or("?", |(name, _)| name)
    }
}

/// `impl Named` for enums: `Type { "name" => Variant, ... }`.
macro_rules! named {
    ($($ty:ident { $($name:literal => $variant:ident),+ $(,)? })+) => {
        $(impl Named for $ty {
            const NAMES: &'static [(&'static str, Self)] = &[$(($name, $ty::$variant)),+];
        })+
    };
}

named! {
    ShadingModel { "phong" => Phong, "gouraud" => Gouraud, "toon" => Toon }
    HdrFormat { "rgba16f" => Rgba16F, "rgba32f" => Rgba32F }
    TextureFilter { "nearest" => Nearest, "bilinear" => Bilinear, "trilinear" => Trilinear }
    ToneMapOperator { "reinhard" => Reinhard, "aces" => Aces, "none" => None }
    Lighting { "forward" => Forward, "deferred" => Deferred }
    DepthPrepass { "off" => Off, "on" => On, "auto" => Auto }
    ShadowFilter { "none" => None, "pcf3" => Pcf3, "pcf5" => Pcf5 }
    TableMapping { "horizon" => Horizon, "linear" => Linear }
    TableFilter { "manual" => Manual, "nearest" => Nearest, "hardware" => Hardware }
    OzoneDepth { "exact" => Exact, "table" => Table }
    AerialPerspective { "march" => March, "volume" => Volume }
}

/// The scene's sky, for the atmosphere knobs.
fn sky_mut(s: &mut Scene) -> Result<&mut super::Sky, String> {
    s.sky
        .as_mut()
        .ok_or_else(|| "the scene has no [atmosphere]".to_string())
}

impl Knob {
    /// The knob called `name`.
    pub fn find(name: &str) -> Result<&'static Knob, KnobError> {
        KNOBS.iter().find(|k| k.name == name).ok_or_else(|| {
            KnobError::Unknown(
                name.to_string(),
                KNOBS.iter().map(|k| k.name).collect::<Vec<_>>().join(", "),
            )
        })
    }

    /// Sets this knob on `scene`, with an error naming knob and value.
    pub fn set(&self, scene: &mut Scene, value: &str) -> Result<(), KnobError> {
        (self.apply)(scene, value).map_err(|reason| KnobError::BadValue {
            knob: self.name.to_string(),
            value: value.to_string(),
            reason,
        })
    }
}

/// Every knob's current setting, in [`KNOBS`] order.
pub fn settings(scene: &Scene) -> Vec<(&'static str, String)> {
    KNOBS.iter().map(|k| (k.name, (k.read)(scene))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names of every `Named` enum are exactly the variants the scene
    /// file accepts (serde's list, from an unknown name's error), each
    /// parsing to the variant it names.
    fn names_match_the_scene_file<T>()
    where
        T: Named + std::fmt::Debug + serde::de::DeserializeOwned,
    {
        use serde::de::{value::StrDeserializer, IntoDeserializer};
        for &(name, variant) in T::NAMES {
            let d: StrDeserializer<'_, serde::de::value::Error> = name.into_deserializer();
            assert_eq!(T::deserialize(d).unwrap(), variant, "{name}");
            assert_eq!(T::parse(name), Ok(variant));
            assert_eq!(variant.name(), name);
        }
        let d: StrDeserializer<'_, serde::de::value::Error> = "no such".into_deserializer();
        let listed = T::deserialize(d).unwrap_err().to_string();
        let serde_names: Vec<&str> = listed.split('`').skip(3).step_by(2).collect();
        let names: Vec<&str> = T::NAMES.iter().map(|(n, _)| *n).collect();
        assert_eq!(serde_names, names, "{listed}");
    }

    #[test]
    fn enum_knobs_name_every_variant_as_the_scene_file_does() {
        names_match_the_scene_file::<ShadingModel>();
        names_match_the_scene_file::<HdrFormat>();
        names_match_the_scene_file::<TextureFilter>();
        names_match_the_scene_file::<ToneMapOperator>();
        names_match_the_scene_file::<Lighting>();
        names_match_the_scene_file::<DepthPrepass>();
        names_match_the_scene_file::<ShadowFilter>();
        names_match_the_scene_file::<TableMapping>();
        names_match_the_scene_file::<TableFilter>();
        names_match_the_scene_file::<OzoneDepth>();
        names_match_the_scene_file::<AerialPerspective>();
        assert_eq!(
            TableFilter::parse("linear"),
            Err("expected manual, nearest or hardware".to_string())
        );
        assert_eq!(
            Lighting::parse("x"),
            Err("expected forward or deferred".to_string())
        );
    }

    #[test]
    fn each_knob_round_trips_a_value() {
        let mut scene = Scene::default_scene();
        for (name, value) in [
            ("size", "320x200"),
            ("shading", "toon"),
            ("lights", "1"),
            ("light_cutoff", "0.01"),
            ("hdr_format", "rgba32f"),
            ("texture_filter", "nearest"),
            ("static_lights", "off"),
            ("depth_prepass", "on"),
            ("depth_prepass", "off"),
            ("depth_prepass", "auto"),
        ] {
            let knob = Knob::find(name).unwrap();
            knob.set(&mut scene, value).unwrap();
            assert_eq!((knob.read)(&scene), value, "knob {name}");
        }
    }

    #[test]
    fn bad_values_name_the_knob() {
        let mut scene = Scene::default_scene();
        for (name, value) in [
            ("size", "0x10"),
            ("shading", "flat"),
            ("lights", "999"),
            ("tessellation", "-1"),
            ("static_lights", "maybe"),
            ("depth_prepass", "yes"),
        ] {
            let e = Knob::find(name)
                .unwrap()
                .set(&mut scene, value)
                .unwrap_err()
                .to_string();
            assert!(e.contains(name) && e.contains(value), "{e}");
        }
        assert!(Knob::find("nope").is_err());
    }

    #[test]
    fn atmosphere_knobs_round_trip_and_name_bad_values() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/earth_noon.toml");
        let mut scene = Scene::load(&path).unwrap();
        for (name, value) in [
            ("sky_view", "off"),
            ("sky_view", "16x128"),
            ("od_filter", "hardware"),
            ("od_ozone", "table"),
            ("od_ozone", "exact"),
            ("od_table_size", "3x3"),
            ("atmosphere_samples", "8"),
            ("aerial_perspective", "volume"),
            ("aerial_perspective", "march"),
            ("aerial_volume", "16x8x64"),
            ("aerial_volume", "2x256x2"),
        ] {
            let knob = Knob::find(name).unwrap();
            knob.set(&mut scene, value).unwrap();
            assert_eq!((knob.read)(&scene), value, "knob {name}");
        }
        for (name, value) in [
            ("sky_view", "16x127"),
            ("sky_view", "on"),
            ("od_filter", "cubic"),
            ("od_ozone", "analytic"),
            ("od_table_size", "256x2"),
            ("aerial_perspective", "froxel"),
            ("aerial_volume", "32x32"),
            ("aerial_volume", "1x32x32"),
            ("aerial_volume", "32x32x257"),
            ("aerial_volume", "32xx32"),
        ] {
            let e = Knob::find(name)
                .unwrap()
                .set(&mut scene, value)
                .unwrap_err()
                .to_string();
            assert!(e.contains(name) && e.contains(value), "{e}");
        }
    }

    #[test]
    fn tessellation_scales_every_object() {
        let mut scene = Scene::default_scene();
        let before: Vec<_> = scene.objects.iter().map(|o| o.tessellation).collect();
        Knob::find("tessellation")
            .unwrap()
            .set(&mut scene, "2")
            .unwrap();
        for (o, b) in scene.objects.iter().zip(before) {
            assert_eq!(o.tessellation, (b.0 * 2, b.1 * 2));
        }
    }
}
