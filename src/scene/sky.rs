//! The `[sun]` and `[atmosphere]` tables of a scene file: their syntax
//! (serde mirror types) and the rules only they have (a shell above the
//! ground, coefficients from the gas or the turbidity, table sizes), which
//! turn them into a [`Sky`]. Numbers, vectors and directions are checked
//! by the shared checks in `checks.rs`, with the same words as in the rest
//! of the file.
//!
//! Every number is kept in f64: the CPU reference integrator and the
//! optical-depth table baker work in double precision, and planet-scale
//! radii (6.36e6 m) with kilometre-scale heights above them lose metres in
//! f32. The GPU gets f32 values derived from these (camera-relative).

use glam::DVec3;
use serde::Deserialize;

use super::value_checks::{Check, Result};
use crate::atmosphere::coefficients;
use crate::atmosphere::model::*;

/// The warning for `"seed"`, the old name of the linear table mapping,
/// given in `file` (or on the command line) at `field`.
pub(super) fn seed_renamed(file: &str, field: &str) -> super::SceneWarning {
    super::SceneWarning {
        file: file.to_owned(),
        field: field.to_owned(),
        warning: super::AssetWarning {
            problem: format!("{file}: {field}: \"seed\" is the old name of \"linear\""),
            fallback: "read as \"linear\"; write \"linear\"".into(),
        },
    }
}

/// `atmosphere.od_table_mapping` as written: the old name `"seed"` is
/// read as `"linear"`, with a warning.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
enum TableMappingField {
    Horizon,
    Linear,
    Seed,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SunFile {
    direction: [f64; 3],
    #[serde(default = "ones")]
    irradiance: [f64; 3],
    #[serde(default = "default_angular_radius")]
    angular_radius: f64,
    #[serde(default = "yes")]
    disc: bool,
    /// The sun casts shadows (`Scene::shadow_light`).
    #[serde(default)]
    pub(super) shadows: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct AtmosphereFile {
    center: Option<[f64; 3]>,
    bottom_radius: Option<f64>,
    top_radius: Option<f64>,
    rayleigh_scattering: Option<[f64; 3]>,
    rayleigh_scale_height: Option<f64>,
    mie_scattering: Option<[f64; 3]>,
    mie_extinction: Option<[f64; 3]>,
    mie_scale_height: Option<f64>,
    mie_g: Option<f64>,
    ozone_absorption: Option<[f64; 3]>,
    ozone_layer: Option<[f64; 3]>,
    ground_albedo: Option<[f64; 3]>,
    rayleigh_from: Option<RayleighFromFile>,
    mie_from: Option<MieFromFile>,
    wavelengths: Option<[f64; 3]>,
    samples: Option<u32>,
    od_table_size: Option<[u32; 2]>,
    od_table_mapping: Option<TableMappingField>,
    od_filter: Option<TableFilter>,
    od_ozone: Option<OzoneDepth>,
    sky_view: Option<SkyViewField>,
    multiple_scattering: Option<bool>,
    ms_table_size: Option<[u32; 2]>,
    irradiance_table_size: Option<[u32; 2]>,
    aerial_perspective: Option<AerialPerspective>,
    aerial_volume: Option<String>,
}

/// `atmosphere.sky_view`: `[width, height]` or `"off"`.
#[derive(Deserialize)]
#[serde(untagged)]
enum SkyViewField {
    Size([u32; 2]),
    Word(String),
}

/// `atmosphere.rayleigh_from`: Rayleigh scattering from the gas (the
/// seed's constants by default), instead of `rayleigh_scattering`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RayleighFromFile {
    refractive_index: Option<f64>,
    number_density: Option<f64>,
    depolarization: Option<f64>,
}

/// `atmosphere.mie_from`: Mie scattering from the turbidity (Preetham's
/// formula), instead of `mie_scattering` and `mie_extinction`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct MieFromFile {
    turbidity: f64,
    k: Option<[f64; 3]>,
    albedo: Option<f64>,
}

/// An aerial-perspective volume size, `WIDTHxHEIGHTxDEPTH` (the scene
/// field and the knob), each side within the bounds.
pub(super) fn parse_aerial_volume(v: &str) -> std::result::Result<(u32, u32, u32), String> {
    let sides: Vec<&str> = v.split('x').collect();
    let [w, h, d] = sides[..] else {
        return Err(format!(
            "expected WIDTHxHEIGHTxDEPTH (e.g. \"32x32x32\"), got \"{v}\""
        ));
    };
    let parse = |t: &str| {
        t.trim()
            .parse::<u32>()
            .map_err(|e| format!("'{t}' in \"{v}\": {e}"))
    };
    let size = (parse(w)?, parse(h)?, parse(d)?);
    check_aerial_volume(size)?;
    Ok(size)
}

fn ones() -> [f64; 3] {
    [1.0; 3]
}
pub(super) fn yes() -> bool {
    true
}
fn default_angular_radius() -> f64 {
    0.004675
}

/// Rayleigh scattering, Mie scattering and Mie extinction as the file
/// gives them: written out, derived (`rayleigh_from`, `mie_from`) or left
/// out (`None`, Earth's).
struct GivenCoefficients {
    rayleigh_scattering: Option<[f64; 3]>,
    mie_scattering: Option<[f64; 3]>,
    mie_extinction: Option<[f64; 3]>,
}

/// The sizes and sample counts of the sky's tables and march, checked.
struct SkyTables {
    samples: u32,
    table_size: (u32, u32),
    sky_view: Option<(u32, u32)>,
    ms_table_size: (u32, u32),
    irradiance_table_size: (u32, u32),
    aerial_volume: (u32, u32, u32),
}

impl Check<'_> {
    /// Validates the two tables. `[atmosphere]` needs `[sun]` and the other
    /// way round: the sun only exists in this renderer as light through the
    /// atmosphere.
    pub(super) fn sky(
        &self,
        sun: Option<SunFile>,
        atmosphere: Option<AtmosphereFile>,
        warnings: &mut Vec<super::SceneWarning>,
    ) -> Result<Option<Sky>> {
        let (sun, atmosphere) = match (sun, atmosphere) {
            (None, None) => return Ok(None),
            (Some(_), None) => {
                return Err(self.invalid(
                    "sun",
                    "a sun needs an [atmosphere] table (it is drawn by the atmosphere pass)",
                ))
            }
            (None, Some(_)) => {
                return Err(self.invalid(
                    "atmosphere",
                    "an atmosphere needs a [sun] table with a direction",
                ))
            }
            (Some(s), Some(a)) => (s, a),
        };
        let sun = self.sun(&sun)?;
        let shell = self.atmosphere(&atmosphere)?;
        let tables = self.sky_tables(&atmosphere)?;
        Ok(Some(Sky {
            sky_view: tables.sky_view,
            aerial_perspective: atmosphere
                .aerial_perspective
                .unwrap_or(AerialPerspective::March),
            aerial_volume: tables.aerial_volume,
            multiple_scattering: atmosphere.multiple_scattering.unwrap_or(true),
            ms_table_size: tables.ms_table_size,
            irradiance_table_size: tables.irradiance_table_size,
            table_size: tables.table_size,
            table_mapping: match atmosphere.od_table_mapping {
                None | Some(TableMappingField::Horizon) => TableMapping::Horizon,
                Some(TableMappingField::Linear) => TableMapping::Linear,
                Some(TableMappingField::Seed) => {
                    warnings.push(seed_renamed(self.file, "atmosphere.od_table_mapping"));
                    TableMapping::Linear
                }
            },
            table_filter: atmosphere.od_filter.unwrap_or(TableFilter::Manual),
            ozone_depth: atmosphere.od_ozone.unwrap_or(OzoneDepth::Exact),
            sun,
            atmosphere: shell,
            samples: tables.samples,
        }))
    }

    /// `[sun]`, checked.
    fn sun(&self, sun: &SunFile) -> Result<Sun> {
        let direction = self.direction("sun.direction", sun.direction, "direction")?;
        let irradiance = self.components_up_to("sun.irradiance", sun.irradiance, 1e6)?;
        let angular_radius = self.within(
            "sun.angular_radius",
            sun.angular_radius,
            &|x| x > 0.0 && x < std::f64::consts::FRAC_PI_2,
            "between 0 and pi/2 radians (exclusive)",
        )?;
        Ok(Sun {
            direction,
            irradiance,
            angular_radius,
            disc: sun.disc,
        })
    }

    /// Radii and scale heights, kept in f64: above 0 and at most
    /// MAX_RADIUS (the scene's length bound, without its lower end).
    fn planet_length(&self, field: &str, x: f64) -> Result<f64> {
        self.within(
            field,
            x,
            &|x| x > 0.0 && x <= MAX_RADIUS,
            &format!("greater than 0 and at most {MAX_RADIUS:e}"),
        )
    }

    /// The physical atmosphere of `[atmosphere]`, checked field by field in
    /// the order the errors are reported; Earth's values where one is left
    /// out.
    fn atmosphere(&self, atmosphere: &AtmosphereFile) -> Result<Atmosphere> {
        let earth = Atmosphere::earth();
        let (center, bottom_radius, top_radius) = self.shell(atmosphere, &earth)?;
        let coefficient = |name: &str, v: Option<[f64; 3]>, default: DVec3| {
            self.components_up_to(
                &format!("atmosphere.{name}"),
                v.unwrap_or(default.to_array()),
                1.0,
            )
        };
        let given = self.given_coefficients(atmosphere)?;
        let rayleigh_scattering = coefficient(
            "rayleigh_scattering",
            given.rayleigh_scattering,
            earth.rayleigh_scattering,
        )?;
        let mie_scattering =
            coefficient("mie_scattering", given.mie_scattering, earth.mie_scattering)?;
        let mie_extinction =
            coefficient("mie_extinction", given.mie_extinction, earth.mie_extinction)?;
        for i in 0..3 {
            if mie_extinction[i] < mie_scattering[i] {
                return Err(self.invalid(
                    "atmosphere.mie_extinction",
                    format!(
                        "component {i} ({:e}) must be at least mie_scattering ({:e}): \
                         extinction is scattering plus absorption",
                        mie_extinction[i], mie_scattering[i]
                    ),
                ));
            }
        }
        let ozone_absorption = coefficient(
            "ozone_absorption",
            atmosphere.ozone_absorption,
            earth.ozone_absorption,
        )?;
        let ground_albedo = self.components_up_to(
            "atmosphere.ground_albedo",
            atmosphere
                .ground_albedo
                .unwrap_or(earth.ground_albedo.to_array()),
            1.0,
        )?;
        let rayleigh_scale_height = self.scale_height(
            "rayleigh_scale_height",
            atmosphere.rayleigh_scale_height,
            earth.rayleigh_scale_height,
        )?;
        let mie_scale_height = self.scale_height(
            "mie_scale_height",
            atmosphere.mie_scale_height,
            earth.mie_scale_height,
        )?;
        // |g| -> 1 makes the phase function a delta; 0.999 already peaks at 1e8.
        let mie_g = self.within(
            "atmosphere.mie_g",
            atmosphere.mie_g.unwrap_or(earth.mie_g),
            &|g| g.abs() <= 0.999,
            "between -0.999 and 0.999",
        )?;
        let ozone_layer = self.ozone_layer(atmosphere.ozone_layer.unwrap_or(earth.ozone_layer))?;
        Ok(Atmosphere {
            center,
            bottom_radius,
            top_radius,
            rayleigh_scattering,
            rayleigh_scale_height,
            mie_scattering,
            mie_extinction,
            mie_scale_height,
            mie_g,
            ozone_absorption,
            ozone_layer,
            ground_albedo,
        })
    }

    /// The planet's centre and the shell's bottom and top radii.
    fn shell(&self, atmosphere: &AtmosphereFile, earth: &Atmosphere) -> Result<(DVec3, f64, f64)> {
        let bottom_radius = self.planet_length(
            "atmosphere.bottom_radius",
            atmosphere.bottom_radius.unwrap_or(earth.bottom_radius),
        )?;
        let top_radius = self.planet_length(
            "atmosphere.top_radius",
            atmosphere.top_radius.unwrap_or(earth.top_radius),
        )?;
        // A shell thinner than a millionth of the radius cannot be resolved by
        // f32 altitudes on the GPU.
        if top_radius <= bottom_radius * (1.0 + 1e-6) {
            return Err(self.invalid(
                "atmosphere.top_radius",
                format!(
                    "must be above bottom_radius ({bottom_radius:e}) by more than a millionth of it, \
                     got {top_radius:e}"
                ),
            ));
        }
        let center = match atmosphere.center {
            Some(c) => self.vector("atmosphere.center", c)?,
            None => DVec3::new(0.0, -bottom_radius, 0.0),
        };
        if let Some(i) = center.to_array().iter().position(|x| x.abs() > MAX_RADIUS) {
            return Err(self.invalid(
                "atmosphere.center",
                format!(
                    "component {i} must be between -{MAX_RADIUS:e} and {MAX_RADIUS:e}, got {:e}",
                    center[i]
                ),
            ));
        }
        Ok((center, bottom_radius, top_radius))
    }

    /// The coefficients as given, derived ones computed and checked.
    fn given_coefficients(&self, atmosphere: &AtmosphereFile) -> Result<GivenCoefficients> {
        // The derived coefficients (the seed's formulas) replace the explicit
        // ones; giving both is refused rather than one silently winning.
        if atmosphere.rayleigh_from.is_some() && atmosphere.rayleigh_scattering.is_some() {
            return Err(self.invalid(
                "atmosphere.rayleigh_from",
                "give either rayleigh_scattering or rayleigh_from, not both",
            ));
        }
        if atmosphere.mie_from.is_some()
            && (atmosphere.mie_scattering.is_some() || atmosphere.mie_extinction.is_some())
        {
            return Err(self.invalid(
                "atmosphere.mie_from",
                "give either mie_scattering and mie_extinction or mie_from, not both",
            ));
        }
        let wavelengths = self.wavelengths(atmosphere)?;
        let rayleigh_given = match &atmosphere.rayleigh_from {
            None => atmosphere.rayleigh_scattering,
            Some(from) => Some(self.rayleigh_from(from, wavelengths)?),
        };
        let (mie_scattering_given, mie_extinction_given) = match &atmosphere.mie_from {
            None => (atmosphere.mie_scattering, atmosphere.mie_extinction),
            Some(from) => {
                let (scattering, extinction) = self.mie_from(from, wavelengths)?;
                (Some(scattering), Some(extinction))
            }
        };
        Ok(GivenCoefficients {
            rayleigh_scattering: rayleigh_given,
            mie_scattering: mie_scattering_given,
            mie_extinction: mie_extinction_given,
        })
    }

    /// The wavelengths (nm) the derived coefficients are computed at.
    fn wavelengths(&self, atmosphere: &AtmosphereFile) -> Result<DVec3> {
        Ok(match atmosphere.wavelengths {
            Some(_) if atmosphere.rayleigh_from.is_none() && atmosphere.mie_from.is_none() => {
                return Err(self.invalid(
                    "atmosphere.wavelengths",
                    "only used by rayleigh_from and mie_from; give one of them",
                ))
            }
            Some(w) => {
                let w = self.vector("atmosphere.wavelengths", w)?;
                if let Some(i) = (0..3).find(|&i| !(100.0..=100_000.0).contains(&w[i])) {
                    return Err(self.invalid(
                        "atmosphere.wavelengths",
                        format!(
                            "component {i} must be between 100 and 100000 nm, got {}",
                            w[i]
                        ),
                    ));
                }
                w
            }
            None => DVec3::from(coefficients::WAVELENGTHS_NM),
        })
    }

    /// A derived coefficient, refused where a channel is not finite or
    /// above 1 per metre.
    fn derived(&self, field: &str, v: DVec3) -> Result<[f64; 3]> {
        if let Some(i) = (0..3).find(|&i| !(v[i].is_finite() && v[i] <= 1.0)) {
            return Err(self.invalid(
                field,
                format!(
                    "gives a coefficient of {:e} 1/m in channel {i}; at most 1 is accepted",
                    v[i]
                ),
            ));
        }
        Ok(v.to_array())
    }

    /// Rayleigh scattering from the gas, `atmosphere.rayleigh_from`.
    fn rayleigh_from(&self, from: &RayleighFromFile, wavelengths: DVec3) -> Result<[f64; 3]> {
        let n = self.within(
            "atmosphere.rayleigh_from.refractive_index",
            from.refractive_index
                .unwrap_or(coefficients::AIR_REFRACTIVE_INDEX),
            &|n| n > 1.0 && n <= 2.0,
            "above 1 and at most 2",
        )?;
        let number_density = self.within(
            "atmosphere.rayleigh_from.number_density",
            from.number_density
                .unwrap_or(coefficients::AIR_NUMBER_DENSITY),
            &|x| (1e10..=1e35).contains(&x),
            "between 1e10 and 1e35 per m^3",
        )?;
        // (6 + 3p)/(6 - 7p): physical factors are 0..0.5.
        let p = self.within(
            "atmosphere.rayleigh_from.depolarization",
            from.depolarization
                .unwrap_or(coefficients::AIR_DEPOLARIZATION),
            &|p| (0.0..=0.5).contains(&p),
            "between 0 and 0.5",
        )?;
        let beta = DVec3::from_array(std::array::from_fn(|i| {
            coefficients::rayleigh_scattering(n, number_density, p, wavelengths[i] * 1e-9)
        }));
        self.derived("atmosphere.rayleigh_from", beta)
    }

    /// Mie scattering and extinction from the turbidity,
    /// `atmosphere.mie_from`.
    fn mie_from(&self, from: &MieFromFile, wavelengths: DVec3) -> Result<([f64; 3], [f64; 3])> {
        let t = self.within(
            "atmosphere.mie_from.turbidity",
            from.turbidity,
            &|t| t > coefficients::MIN_TURBIDITY && t <= 1000.0,
            &format!(
                "above {:.4} (where the formula's aerosol concentration \
                 0.6544 T - 0.6510 turns positive) and at most 1000",
                coefficients::MIN_TURBIDITY
            ),
        )?;
        let k = self.components_up_to(
            "atmosphere.mie_from.k",
            from.k.unwrap_or([coefficients::MIE_K; 3]),
            10.0,
        )?;
        let albedo = self.within(
            "atmosphere.mie_from.albedo",
            from.albedo.unwrap_or(0.9),
            &|a| a > 0.0 && a <= 1.0,
            "above 0 and at most 1",
        )?;
        let beta = DVec3::from_array(std::array::from_fn(|i| {
            coefficients::mie_scattering(t, k[i], wavelengths[i] * 1e-9)
        }));
        let scattering = self.derived("atmosphere.mie_from.turbidity", beta)?;
        let extinction = self.derived("atmosphere.mie_from", beta / albedo)?;
        Ok((scattering, extinction))
    }

    /// Scale heights below a metre make the density a step the table and
    /// the march cannot resolve; above 1e9 they are meaningless.
    fn scale_height(&self, name: &str, x: Option<f64>, default: f64) -> Result<f64> {
        let field = format!("atmosphere.{name}");
        let x = self.planet_length(&field, x.unwrap_or(default))?;
        if x < 1.0 {
            return Err(self.invalid(&field, format!("must be at least 1 m, got {x:e}")));
        }
        Ok(x)
    }

    /// The ozone layer's increasing altitudes `[start, peak, end]`.
    fn ozone_layer(&self, ozone_layer: [f64; 3]) -> Result<[f64; 3]> {
        for (i, x) in ozone_layer.iter().enumerate() {
            if !x.is_finite() || *x < 0.0 || *x > MAX_RADIUS {
                return Err(self.invalid(
                    "atmosphere.ozone_layer",
                    format!("component {i} must be between 0 and {MAX_RADIUS:e}, got {x:e}"),
                ));
            }
        }
        if !(ozone_layer[0] < ozone_layer[1] && ozone_layer[1] < ozone_layer[2]) {
            return Err(self.invalid(
                "atmosphere.ozone_layer",
                format!(
                    "must be increasing altitudes [start, peak, end], got {:?}",
                    ozone_layer
                ),
            ));
        }
        Ok(ozone_layer)
    }

    /// The sample count and the tables' sizes.
    fn sky_tables(&self, atmosphere: &AtmosphereFile) -> Result<SkyTables> {
        let samples = atmosphere.samples.unwrap_or(DEFAULT_ATMOSPHERE_SAMPLES);
        if !(1..=MAX_ATMOSPHERE_SAMPLES).contains(&samples) {
            return Err(self.invalid(
                "atmosphere.samples",
                format!("must be between 1 and {MAX_ATMOSPHERE_SAMPLES}, got {samples}"),
            ));
        }
        let table_size = atmosphere
            .od_table_size
            .map_or(DEFAULT_TABLE_SIZE, |[w, h]| (w, h));
        check_table_size(table_size.0, table_size.1)
            .map_err(|e| self.invalid("atmosphere.od_table_size", e))?;
        let sky_view = match &atmosphere.sky_view {
            None => DEFAULT_SKY_VIEW,
            Some(SkyViewField::Word(w)) if w == "off" => None,
            Some(SkyViewField::Word(w)) => {
                return Err(self.invalid(
                    "atmosphere.sky_view",
                    format!("expected [width, height] or \"off\", got \"{w}\""),
                ))
            }
            Some(SkyViewField::Size([w, h])) => {
                check_sky_view(*w, *h).map_err(|e| self.invalid("atmosphere.sky_view", e))?;
                Some((*w, *h))
            }
        };
        let sun_table = |field: &str, size: Option<[u32; 2]>, default: (u32, u32)| {
            let size = size.map_or(default, |[w, h]| (w, h));
            check_sun_table_size(size.0, size.1)
                .map(|()| size)
                .map_err(|e| self.invalid(field, e))
        };
        let ms_table_size = sun_table(
            "atmosphere.ms_table_size",
            atmosphere.ms_table_size,
            DEFAULT_MS_TABLE_SIZE,
        )?;
        let irradiance_table_size = sun_table(
            "atmosphere.irradiance_table_size",
            atmosphere.irradiance_table_size,
            DEFAULT_IRRADIANCE_TABLE_SIZE,
        )?;
        let aerial_volume = match &atmosphere.aerial_volume {
            None => DEFAULT_AERIAL_VOLUME,
            Some(v) => {
                parse_aerial_volume(v).map_err(|e| self.invalid("atmosphere.aerial_volume", e))?
            }
        };
        Ok(SkyTables {
            samples,
            table_size,
            sky_view,
            ms_table_size,
            irradiance_table_size,
            aerial_volume,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::{Atmosphere, Scene, SceneError};
    use std::path::Path;

    const CAMERA: &str = "[camera]\neye = [0.0, 2.0, 0.0]\nlook_at = [0.0, 2.0, -1.0]\n";

    fn parse(extra: &str) -> Result<Scene, SceneError> {
        Scene::from_toml(&format!("{CAMERA}{extra}"), "sky.toml", Path::new("."))
    }

    fn field_of(extra: &str) -> String {
        match parse(extra) {
            Err(e) => {
                let message = e.to_string();
                assert!(message.starts_with("sky.toml: "), "{message}");
                e.field().unwrap_or("").to_owned()
            }
            Ok(_) => panic!("accepted: {extra}"),
        }
    }

    #[test]
    fn a_sky_only_scene_gets_earth_defaults() {
        let scene = parse("[sun]\ndirection = [0.0, 2.0, 0.0]\n[atmosphere]\n").unwrap();
        assert!(scene.objects.is_empty());
        let sky = scene.sky.unwrap();
        assert_eq!(sky.atmosphere, Atmosphere::earth());
        assert_eq!(sky.sun.direction, glam::DVec3::Y);
        assert_eq!(sky.sun.irradiance, glam::DVec3::ONE);
        assert_eq!(sky.sun.angular_radius, 0.004675);
        assert!(sky.sun.disc);
        assert_eq!(sky.samples, super::DEFAULT_ATMOSPHERE_SAMPLES);
        assert_eq!(
            sky.aerial_perspective,
            crate::scene::AerialPerspective::March
        );
        assert_eq!(sky.aerial_volume, (32, 32, 32));
        // The centre defaults to [0, -bottom_radius, 0] for any radius.
        let scene = parse("[sun]\ndirection = [0.0, 1.0, 0.0]\n[atmosphere]\nbottom_radius = 1000.0\ntop_radius = 1100.0\n").unwrap();
        assert_eq!(
            scene.sky.unwrap().atmosphere.center,
            glam::DVec3::new(0.0, -1000.0, 0.0)
        );
        assert!(parse("").unwrap().sky.is_none());
    }

    #[test]
    fn bad_sun_and_atmosphere_values_name_their_field() {
        let sun = "[sun]\ndirection = [0.0, 1.0, 0.0]\n";
        for (extra, field) in [
            ("[sun]\ndirection = [0.0, 1.0, 0.0]\n", "sun"),
            // Leading newline: not given a sun below.
            ("\n[atmosphere]\n", "atmosphere"),
            (
                "[sun]\ndirection = [0.0, 0.0, 0.0]\n[atmosphere]\n",
                "sun.direction",
            ),
            (
                "[sun]\ndirection = [0.0, nan, 0.0]\n[atmosphere]\n",
                "sun.direction",
            ),
            (
                "[sun]\ndirection = [0.0, 1.0, 0.0]\nirradiance = [1.0, -1.0, 1.0]\n[atmosphere]\n",
                "sun.irradiance",
            ),
            (
                "[sun]\ndirection = [0.0, 1.0, 0.0]\nangular_radius = 0.0\n[atmosphere]\n",
                "sun.angular_radius",
            ),
            (
                "[atmosphere]\ntop_radius = 6000000.0\n",
                "atmosphere.top_radius",
            ),
            (
                "[atmosphere]\nbottom_radius = 0.0\n",
                "atmosphere.bottom_radius",
            ),
            (
                "[atmosphere]\nbottom_radius = inf\n",
                "atmosphere.bottom_radius",
            ),
            ("[atmosphere]\nmie_g = 1.0\n", "atmosphere.mie_g"),
            ("[atmosphere]\nmie_g = -1.5\n", "atmosphere.mie_g"),
            (
                "[atmosphere]\nrayleigh_scattering = [1e-6, -1e-6, 1e-6]\n",
                "atmosphere.rayleigh_scattering",
            ),
            (
                "[atmosphere]\nmie_extinction = [1e-6, 1e-6, 1e-6]\n",
                "atmosphere.mie_extinction",
            ),
            (
                "[atmosphere]\nmie_scale_height = 0.5\n",
                "atmosphere.mie_scale_height",
            ),
            (
                "[atmosphere]\nrayleigh_scale_height = nan\n",
                "atmosphere.rayleigh_scale_height",
            ),
            (
                "[atmosphere]\nozone_layer = [25000.0, 10000.0, 40000.0]\n",
                "atmosphere.ozone_layer",
            ),
            (
                "[atmosphere]\ncenter = [0.0, -2e9, 0.0]\n",
                "atmosphere.center",
            ),
            (
                "[atmosphere]\nground_albedo = [2.0, 0.3, 0.3]\n",
                "atmosphere.ground_albedo",
            ),
            ("[atmosphere]\nsamples = 0\n", "atmosphere.samples"),
            (
                "[atmosphere]\nod_table_size = [1, 64]\n",
                "atmosphere.od_table_size",
            ),
            (
                "[atmosphere]\nod_table_size = [256, 5000]\n",
                "atmosphere.od_table_size",
            ),
            (
                "[atmosphere]\nod_table_size = [256, 2]\n",
                "atmosphere.od_table_size",
            ),
            (
                "[atmosphere]\nsky_view = [128, 255]\n",
                "atmosphere.sky_view",
            ),
            ("[atmosphere]\nsky_view = [1, 256]\n", "atmosphere.sky_view"),
            ("[atmosphere]\nsky_view = [128, 2]\n", "atmosphere.sky_view"),
            ("[atmosphere]\nsky_view = \"on\"\n", "atmosphere.sky_view"),
            (
                "[atmosphere]\naerial_volume = \"32x32\"\n",
                "atmosphere.aerial_volume",
            ),
            (
                "[atmosphere]\naerial_volume = \"32x1x32\"\n",
                "atmosphere.aerial_volume",
            ),
            (
                "[atmosphere]\naerial_volume = \"32x32x300\"\n",
                "atmosphere.aerial_volume",
            ),
        ] {
            let text = if extra.starts_with("[atmosphere]") {
                format!("{sun}{extra}")
            } else {
                extra.to_owned()
            };
            assert_eq!(field_of(&text), field, "{text}");
        }
        // Named values outside their set are refused by the parser.
        for bad in [
            "od_table_mapping = \"log\"",
            "od_filter = \"cubic\"",
            "od_ozone = \"analytic\"",
            "aerial_perspective = \"froxels\"",
        ] {
            let text = format!("[sun]\ndirection = [0.0, 1.0, 0.0]\n[atmosphere]\n{bad}\n");
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.contains(bad.split(' ').next().unwrap()), "{e}");
        }
        // Unknown keys are refused by the parser with a line number.
        let e = parse("[sun]\ndirection = [0.0, 1.0, 0.0]\n[atmosphere]\nrayleigh = 1.0\n")
            .unwrap_err();
        assert!(e.to_string().contains("rayleigh"), "{e}");
    }

    #[test]
    fn rayleigh_and_mie_can_come_from_the_seeds_formulas() {
        use crate::atmosphere::coefficients as k;
        let sun = "[sun]\ndirection = [0.0, 1.0, 0.0]\n";
        let sky = |extra: &str| {
            parse(&format!("{sun}[atmosphere]\n{extra}"))
                .unwrap_or_else(|e| panic!("{e}"))
                .sky
                .unwrap()
                .atmosphere
        };
        // The seed's air at the default wavelengths is Earth's default.
        let a = sky("rayleigh_from = {}\n");
        let earth = Atmosphere::earth();
        for c in 0..3 {
            let rel = (a.rayleigh_scattering[c] / earth.rayleigh_scattering[c] - 1.0).abs();
            assert!(rel < 1e-3, "channel {c}: {}", a.rayleigh_scattering);
        }
        assert_eq!(a.mie_scattering, earth.mie_scattering);
        // Other air and wavelengths go through the formula.
        let a = sky(
            "rayleigh_from = { refractive_index = 1.0006, number_density = 5e25, depolarization = 0.0 }\n\
             wavelengths = [700.0, 500.0, 400.0]\n",
        );
        // (Wavelengths are given in nm: 400 * 1e-9 is not 400e-9 to the last bit.)
        let close = |a: f64, b: f64| ((a - b) / b).abs() < 1e-12;
        assert!(close(
            a.rayleigh_scattering.z,
            k::rayleigh_scattering(1.0006, 5e25, 0.0, 400e-9)
        ));
        // Turbidity: extinction is scattering over the albedo (0.9 unless given).
        let a = sky("mie_from = { turbidity = 1.0 }\n");
        assert!(close(
            a.mie_scattering.y,
            k::mie_scattering(1.0, k::MIE_K, 550e-9)
        ));
        assert!((a.mie_extinction.y - a.mie_scattering.y / 0.9).abs() < 1e-20);
        let a = sky("mie_from = { turbidity = 1.0, k = [0.686, 0.678, 0.666], albedo = 1.0 }\n");
        assert_eq!(a.mie_extinction, a.mie_scattering);
        assert!(close(
            a.mie_scattering.x,
            k::mie_scattering(1.0, 0.686, 680e-9)
        ));

        for (extra, field) in [
            (
                "rayleigh_from = {}\nrayleigh_scattering = [1e-6, 1e-6, 1e-6]\n",
                "atmosphere.rayleigh_from",
            ),
            (
                "mie_from = { turbidity = 2.0 }\nmie_extinction = [1e-6, 1e-6, 1e-6]\n",
                "atmosphere.mie_from",
            ),
            (
                "wavelengths = [680.0, 550.0, 440.0]\n",
                "atmosphere.wavelengths",
            ),
            (
                "rayleigh_from = {}\nwavelengths = [680.0, 0.0, 440.0]\n",
                "atmosphere.wavelengths",
            ),
            (
                "rayleigh_from = { refractive_index = 0.9 }\n",
                "atmosphere.rayleigh_from.refractive_index",
            ),
            (
                "rayleigh_from = { number_density = -1.0 }\n",
                "atmosphere.rayleigh_from.number_density",
            ),
            (
                "rayleigh_from = { depolarization = 0.9 }\n",
                "atmosphere.rayleigh_from.depolarization",
            ),
            // Below 0.9948 the formula's concentration is negative.
            (
                "mie_from = { turbidity = 0.9 }\n",
                "atmosphere.mie_from.turbidity",
            ),
            (
                "mie_from = { turbidity = nan }\n",
                "atmosphere.mie_from.turbidity",
            ),
            // T = 500 gives 2 1/m at 440 nm: past the coefficient bound.
            (
                "mie_from = { turbidity = 500.0 }\n",
                "atmosphere.mie_from.turbidity",
            ),
            (
                "mie_from = { turbidity = 2.0, albedo = 0.0 }\n",
                "atmosphere.mie_from.albedo",
            ),
            (
                "mie_from = { turbidity = 2.0, k = [0.6, -0.6, 0.6] }\n",
                "atmosphere.mie_from.k",
            ),
        ] {
            assert_eq!(
                field_of(&format!("{sun}[atmosphere]\n{extra}")),
                field,
                "{extra}"
            );
        }
        // The turbidity is required, and unknown keys are refused.
        for bad in ["mie_from = {}", "rayleigh_from = { n = 1.0003 }"] {
            let e = parse(&format!("{sun}[atmosphere]\n{bad}\n"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("sky.toml"), "{e}");
        }
    }
}
