//! The atmosphere as the renderer and the reference take it: the planet
//! and its air ([`Atmosphere`]), the sun ([`Sun`]), how the tables are
//! built and read ([`Sky`]), and their bounds. `scene::sky` reads these
//! from a scene file's `[sun]` and `[atmosphere]` tables.

use glam::DVec3;
use serde::Deserialize;

/// Default ray-march sample count of the atmosphere pass.
pub const DEFAULT_ATMOSPHERE_SAMPLES: u32 = 32;
/// Largest accepted `atmosphere.samples`.
pub const MAX_ATMOSPHERE_SAMPLES: u32 = 1024;
/// Largest accepted atmosphere radius (m): the same bound as lengths.
pub const MAX_RADIUS: f64 = 1e9;

/// Default optical-depth table size (direction × altitude texels).
pub const DEFAULT_TABLE_SIZE: (u32, u32) = (256, 64);
/// Largest accepted table side: 4096² texels of four f32 are 256 MiB.
pub const MAX_TABLE_SIDE: u32 = 4096;
/// Smallest accepted table side: the horizon mapping needs two rows of
/// upward directions and the horizontal row.
pub const MIN_TABLE_SIDE: u32 = 3;

/// Checks an optical-depth table size (the scene field and the knob).
pub fn check_table_size(w: u32, h: u32) -> Result<(), String> {
    if [w, h]
        .iter()
        .all(|n| (MIN_TABLE_SIDE..=MAX_TABLE_SIDE).contains(n))
    {
        Ok(())
    } else {
        Err(format!(
            "each side must be between {MIN_TABLE_SIDE} and {MAX_TABLE_SIDE}, got [{w}, {h}]"
        ))
    }
}

/// Default multiple-scattering table size (sun angle × altitude texels):
/// Hillaire's 32 × 32.
pub const DEFAULT_MS_TABLE_SIZE: (u32, u32) = (32, 32);
/// Default sky-irradiance table size (sun angle × altitude texels):
/// Bruneton's 64 × 16.
pub const DEFAULT_IRRADIANCE_TABLE_SIZE: (u32, u32) = (64, 16);
/// Largest accepted side of either table: both are baked on the device
/// once per atmosphere, marching dozens of directions per texel.
pub const MAX_SUN_TABLE_SIDE: u32 = 512;

/// Checks a multiple-scattering or sky-irradiance table size (the scene
/// fields and the knobs): 2 to [`MAX_SUN_TABLE_SIDE`] texels a side, so
/// every lookup interpolates between two texels on both axes.
pub fn check_sun_table_size(w: u32, h: u32) -> Result<(), String> {
    if [w, h].iter().all(|n| (2..=MAX_SUN_TABLE_SIDE).contains(n)) {
        Ok(())
    } else {
        Err(format!(
            "each side must be between 2 and {MAX_SUN_TABLE_SIDE}, got [{w}, {h}]"
        ))
    }
}

/// Default sky-view table size (azimuth × nadir-angle directions).
pub const DEFAULT_SKY_VIEW: Option<(u32, u32)> = Some((128, 256));
/// Largest accepted sky-view table side.
pub const MAX_SKY_VIEW_SIDE: u32 = 2048;

/// Checks a sky-view table size: at least two columns, and an even number
/// of at least four rows (two per half, so each half interpolates).
pub fn check_sky_view(w: u32, h: u32) -> Result<(), String> {
    if !(2..=MAX_SKY_VIEW_SIDE).contains(&w)
        || !(4..=MAX_SKY_VIEW_SIDE).contains(&h)
        || !h.is_multiple_of(2)
    {
        return Err(format!(
            "width must be 2..={MAX_SKY_VIEW_SIDE} and height an even 4..={MAX_SKY_VIEW_SIDE}, got [{w}, {h}]"
        ));
    }
    Ok(())
}

/// Default size of the aerial-perspective volume (columns across ×
/// columns down × slices in distance): Hillaire's 32³.
pub const DEFAULT_AERIAL_VOLUME: (u32, u32, u32) = (32, 32, 32);
/// Smallest accepted side of the volume: two texels to interpolate between.
pub const MIN_AERIAL_VOLUME_SIDE: u32 = 2;
/// Largest accepted side of the volume.
pub const MAX_AERIAL_VOLUME_SIDE: u32 = 256;

/// Checks an aerial-perspective volume size (the scene field and the knob).
pub fn check_aerial_volume(size: (u32, u32, u32)) -> Result<(), String> {
    let (w, h, d) = size;
    if [w, h, d]
        .iter()
        .all(|n| (MIN_AERIAL_VOLUME_SIDE..=MAX_AERIAL_VOLUME_SIDE).contains(n))
    {
        Ok(())
    } else {
        Err(format!(
            "each side must be between {MIN_AERIAL_VOLUME_SIDE} and {MAX_AERIAL_VOLUME_SIDE}, \
             got {w}x{h}x{d}"
        ))
    }
}

/// How the atmosphere in front of a surface is found
/// (`atmosphere.aerial_perspective`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AerialPerspective {
    /// Every pixel with a surface marches its own ray to it.
    March,
    /// Pixels read a camera-frustum volume marched once per frame
    /// (Hillaire 2020's aerial-perspective volume).
    Volume,
}

/// The sun and the atmosphere around a planet.
#[derive(Clone, Debug, PartialEq)]
pub struct Sky {
    pub sun: Sun,
    pub atmosphere: Atmosphere,
    /// Ray-march samples per pixel in the atmosphere pass.
    pub samples: u32,
    /// Optical-depth table texels, direction × altitude.
    pub table_size: (u32, u32),
    pub table_mapping: TableMapping,
    pub table_filter: TableFilter,
    pub ozone_depth: OzoneDepth,
    /// Directions of the sky-view table (azimuth × nadir angle) that
    /// pixels showing sky or ground read instead of marching; `None`
    /// marches every pixel.
    pub sky_view: Option<(u32, u32)>,
    /// Whether light scattered more than once (and the sky's light on the
    /// ground) is drawn, from Hillaire's multiple-scattering table; off
    /// draws single scattering alone.
    pub multiple_scattering: bool,
    /// The multiple-scattering table's texels, sun angle × altitude.
    pub ms_table_size: (u32, u32),
    /// The sky-irradiance table's texels, sun angle × altitude.
    pub irradiance_table_size: (u32, u32),
    /// How pixels with a surface get the air in front of it.
    pub aerial_perspective: AerialPerspective,
    /// The aerial-perspective volume's size with `AerialPerspective::Volume`:
    /// columns across and down the screen, and slices in distance.
    pub aerial_volume: (u32, u32, u32),
}

impl Sky {
    /// Panels of the sky-view table, side by side: the Rayleigh and Mie
    /// sums and the transmittance, and the higher orders' sums with
    /// multiple scattering.
    pub fn sky_view_panels(&self) -> u32 {
        if self.multiple_scattering {
            4
        } else {
            3
        }
    }
}

/// How (altitude, direction) maps to the optical-depth table
/// (`atmosphere.od_table_mapping`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TableMapping {
    /// Bruneton-style: distance to the top; upward directions in 2D and
    /// the horizontal ray in a row of its own (downward ones from both).
    Horizon,
    /// Linear altitude, linear cosine of the zenith angle (the mapping of
    /// the original brief; `"seed"` is its old name, still read with a
    /// warning).
    Linear,
}

/// How the atmosphere pass reads the table (`atmosphere.od_filter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TableFilter {
    /// Bilinear from four texel fetches, by hand (the seed's method).
    Manual,
    /// The nearest texel.
    Nearest,
    /// The sampler's linear filter (needs SAMPLED_IMAGE_FILTER_LINEAR for
    /// RGBA32F; its weights' precision is the device's).
    Hardware,
}

/// Where the ozone's integral towards the sun comes from
/// (`atmosphere.od_ozone`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OzoneDepth {
    /// In closed form along the ray (`atmosphere::ozone`): exact to 1e-6.
    Exact,
    /// The table's third channel: one lookup less work, but the tent's
    /// kinks cost up to 2.6e-3 in transmittance at 256 × 64.
    Table,
}

/// The sun: parallel light from `direction`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sun {
    /// Unit vector towards the sun.
    pub direction: DVec3,
    /// Irradiance at the top of the atmosphere, per channel (>= 0).
    pub irradiance: DVec3,
    /// Angular radius of the disc in radians, in (0, pi/2).
    pub angular_radius: f64,
    /// Whether the disc is drawn.
    pub disc: bool,
}

/// A spherical planet with a Rayleigh + Mie + ozone atmosphere. Lengths in
/// metres, coefficients in 1/m per channel (red, green, blue).
#[derive(Clone, Debug, PartialEq)]
pub struct Atmosphere {
    pub center: DVec3,
    pub bottom_radius: f64,
    pub top_radius: f64,
    pub rayleigh_scattering: DVec3,
    pub rayleigh_scale_height: f64,
    pub mie_scattering: DVec3,
    pub mie_extinction: DVec3,
    pub mie_scale_height: f64,
    /// Cornette–Shanks asymmetry, in (-1, 1).
    pub mie_g: f64,
    pub ozone_absorption: DVec3,
    /// Tent profile: altitudes where it starts, peaks and ends.
    pub ozone_layer: [f64; 3],
    pub ground_albedo: DVec3,
}

impl Atmosphere {
    /// Earth, from measured constants as in Bruneton's 2017 model (680, 550
    /// and 440 nm).
    pub fn earth() -> Atmosphere {
        Atmosphere {
            center: DVec3::new(0.0, -6_360_000.0, 0.0),
            bottom_radius: 6_360_000.0,
            top_radius: 6_420_000.0,
            rayleigh_scattering: DVec3::new(5.802e-6, 13.558e-6, 33.1e-6),
            rayleigh_scale_height: 8000.0,
            mie_scattering: DVec3::splat(3.996e-6),
            mie_extinction: DVec3::splat(4.44e-6),
            mie_scale_height: 1200.0,
            mie_g: 0.8,
            ozone_absorption: DVec3::new(0.650e-6, 1.881e-6, 0.085e-6),
            ozone_layer: [10_000.0, 25_000.0, 40_000.0],
            ground_albedo: DVec3::splat(0.3),
        }
    }
}
