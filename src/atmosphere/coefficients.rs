//! Scattering coefficients from physical quantities, the seed's optional
//! derivation (scene fields `atmosphere.rayleigh_from`, `mie_from` and
//! `wavelengths`):
//!
//! - Rayleigh, from the refractive index n of air, its molecular number
//!   density N and depolarization factor p_n:
//!   β_R(λ) = 8π³(n² − 1)² / (3Nλ⁴) · (6 + 3p_n)/(6 − 7p_n).
//! - Mie, from the turbidity T (Preetham et al. 1999, appendix):
//!   β_M(λ) = 0.434·c·π·(2π/λ)^(v−2)·K with Junge exponent v = 4,
//!   concentration c = (0.6544·T − 0.6510)·10⁻¹⁶ and K ≈ 0.67.
//!
//! The Rayleigh formula with the seed's constants reproduces the measured
//! Earth coefficients the renderer defaults to. The Mie formula's absolute
//! scale is not physical (T = 2 gives 7.8·10⁻³ m⁻¹ at 550 nm, two thousand
//! times Earth's measured aerosol scattering; the formula's concentration
//! reaches that measured value near T = 1, a sky without aerosols by the
//! definition of turbidity): it is here as the seed gives it, tested to
//! reproduce the published numbers, not as a default.

use std::f64::consts::PI;

/// The seed's constants for air: refractive index, molecules per m³,
/// depolarization factor.
pub const AIR_REFRACTIVE_INDEX: f64 = 1.0003;
pub const AIR_NUMBER_DENSITY: f64 = 2.545e25;
pub const AIR_DEPOLARIZATION: f64 = 0.035;
/// The seed's wavelength factor K of the Mie formula.
pub const MIE_K: f64 = 0.67;
/// The wavelengths of the red, green and blue channels (nm), as the
/// default coefficients (Bruneton 2017's 680, 550 and 440 nm).
pub const WAVELENGTHS_NM: [f64; 3] = [680.0, 550.0, 440.0];

/// Rayleigh scattering coefficient (1/m) at `wavelength` (m).
pub fn rayleigh_scattering(
    refractive_index: f64,
    number_density: f64,
    depolarization: f64,
    wavelength: f64,
) -> f64 {
    // n² − 1 as (n − 1)(n + 1): n − 1 is 3e-4, and n² rounds away digits.
    let n2_minus_1 = (refractive_index - 1.0) * (refractive_index + 1.0);
    let king = (6.0 + 3.0 * depolarization) / (6.0 - 7.0 * depolarization);
    8.0 * PI.powi(3) * n2_minus_1 * n2_minus_1 / (3.0 * number_density * wavelength.powi(4)) * king
}

/// The aerosol concentration factor c(T) of Preetham's Mie formula.
pub fn mie_concentration(turbidity: f64) -> f64 {
    (0.6544 * turbidity - 0.6510) * 1e-16
}

/// The smallest turbidity whose concentration is positive.
pub const MIN_TURBIDITY: f64 = 0.6510 / 0.6544;

/// Mie scattering coefficient (1/m) at `wavelength` (m) for `turbidity`
/// and the factor `k`.
pub fn mie_scattering(turbidity: f64, k: f64, wavelength: f64) -> f64 {
    0.434 * mie_concentration(turbidity) * PI * (2.0 * PI / wavelength).powi(2) * k
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(got: f64, want: f64, rel: f64) -> bool {
        ((got - want) / want).abs() <= rel
    }

    /// three.js's Preetham sky (`examples/jsm/objects/Sky.js`) publishes
    /// both formulas evaluated at 680, 550 and 450 nm with the seed's n, N
    /// and p_n (`totalRayleigh`), and π(2π/λ)^(v−2)·K for
    /// K = (0.686, 0.678, 0.666) (`MieConst`): an independent evaluation
    /// to 16 digits.
    #[test]
    fn the_formulas_reproduce_published_values() {
        let lambdas = [680e-9, 550e-9, 450e-9];
        let total_rayleigh = [
            5.804542996261093e-6,
            1.3562911419845635e-5,
            3.0265902468824876e-5,
        ];
        let k = [0.686, 0.678, 0.666];
        let mie_const = [
            1.8399918514433978e14,
            2.7798023919660528e14,
            4.0790479543861094e14,
        ];
        for i in 0..3 {
            let r = rayleigh_scattering(
                AIR_REFRACTIVE_INDEX,
                AIR_NUMBER_DENSITY,
                AIR_DEPOLARIZATION,
                lambdas[i],
            );
            // The published value computed n² − 1 directly, which loses
            // about 1e-12 relative of (n² − 1)² in doubles.
            assert!(
                close(r, total_rayleigh[i], 1e-9),
                "{r} against {}",
                total_rayleigh[i]
            );
            // β_M = 0.434·c·MieConst, so β_M / (0.434 c) is MieConst.
            let t = 2.0;
            let m = mie_scattering(t, k[i], lambdas[i]) / (0.434 * mie_concentration(t));
            assert!(
                close(m, mie_const[i], 1e-12),
                "{m} against {}",
                mie_const[i]
            );
        }
    }

    /// The seed says ≈ 5.8e-6 1/m at 680 nm; Bruneton 2017 measures Earth
    /// as (5.802, 13.558, 33.1)e-6 1/m at 680, 550 and 440 nm (given to 4
    /// significant digits, so compared to 1e-3).
    #[test]
    fn rayleigh_from_the_seeds_air_is_earths_measured_coefficient() {
        let earth = [5.802e-6, 13.558e-6, 33.1e-6];
        for (nm, want) in WAVELENGTHS_NM.iter().zip(earth) {
            let got = rayleigh_scattering(
                AIR_REFRACTIVE_INDEX,
                AIR_NUMBER_DENSITY,
                AIR_DEPOLARIZATION,
                nm * 1e-9,
            );
            assert!(close(got, want, 1e-3), "{nm} nm: {got:e} against {want:e}");
        }
    }

    /// The seed's Mie at T = 2, 550 nm, K = 0.67, by hand: c = 0.6578e-16,
    /// (2π/550 nm)² = 1.30507e14 m⁻², so β_M = 0.434 · 0.6578e-16 · π ·
    /// 1.30507e14 · 0.67 = 7.843e-3 1/m; it falls as 1/λ² and grows
    /// linearly with T.
    #[test]
    fn mie_from_turbidity_follows_the_seed() {
        let got = mie_scattering(2.0, MIE_K, 550e-9);
        assert!(close(got, 7.843e-3, 1e-3), "{got:e}");
        let ratio = mie_scattering(2.0, MIE_K, 440e-9) / got;
        assert!(close(ratio, (550.0f64 / 440.0).powi(2), 1e-12), "{ratio}");
        let slope = mie_scattering(3.0, MIE_K, 550e-9) - got;
        assert!(close(
            slope,
            0.434 * 0.6544e-16 * PI * (2.0 * PI / 550e-9).powi(2) * MIE_K,
            1e-9
        ));
        assert!(mie_concentration(MIN_TURBIDITY).abs() < 1e-30);
    }
}
