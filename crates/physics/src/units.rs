//! Physical constants and unit conversions, each defined once.
//!
//! Every factor converts *to* SI by multiplication (`x_m = x_ft * M_PER_FT`). The base
//! definitions are exact by law; the derived factors are computed from them in `f64`, in the
//! order written, so every crate that converts gets the same bits.
//!
//! Sources: NIST Special Publication 811 (2008), *Guide for the Use of the International System
//! of Units*, appendix B (conversion factors; exact values marked there in bold); NIST SP 330
//! (2019) for standard gravity; the 1959 international yard and pound agreement for the foot and
//! the pound.

/// Standard acceleration of gravity g₀, m/s² (exact; 3rd CGPM 1901, NIST SP 330 §5 / SP 811
/// B.8). The unit `g` of accelerometers and the gravity of the estimators' flat-earth model.
pub const G0_MPS2: f64 = 9.80665;

/// Metres per international foot (exact; 1959 agreement, NIST SP 811 B.8: 1 ft = 0.3048 m).
pub const M_PER_FT: f64 = 0.3048;

/// International feet per metre, `1 / M_PER_FT`.
pub const FT_PER_M: f64 = 1.0 / M_PER_FT;

/// Metres per inch (exact; NIST SP 811 B.8: 1 in = 0.0254 m).
pub const M_PER_IN: f64 = 0.0254;

/// Square metres per square foot, `M_PER_FT²`.
pub const M2_PER_FT2: f64 = M_PER_FT * M_PER_FT;

/// Kilograms per avoirdupois pound (exact; 1959 agreement, NIST SP 811 B.8:
/// 1 lb = 0.453 592 37 kg).
pub const KG_PER_LB: f64 = 0.453_592_37;

/// Newtons per pound-force: `KG_PER_LB · G0_MPS2` (the weight of one pound under standard
/// gravity; 4.448 221 615 260 5 N exactly, NIST SP 811 B.8, which this product rounds to).
pub const N_PER_LBF: f64 = KG_PER_LB * G0_MPS2;

/// Kilograms per slug (1 slug = 1 lbf·s²/ft = 0.453 592 37 · 9.806 65 / 0.3048 kg
/// = 14.593 902 937 206 364 8… kg; NIST SP 811 B.8 prints 14.593 90). Written as the
/// correctly rounded value: the `f64` quotient `N_PER_LBF / M_PER_FT` is one unit in the last
/// place below it.
pub const KG_PER_SLUG: f64 = 14.593_902_937_206_364;

/// Pascals per pound-force per square foot (psf), `N_PER_LBF / M_PER_FT²` (NIST SP 811 B.8:
/// 47.880 26 Pa).
pub const PA_PER_PSF: f64 = N_PER_LBF / (M_PER_FT * M_PER_FT);

/// Pascals per pound-force per square inch (psi), `N_PER_LBF / M_PER_IN²` (NIST SP 811 B.8:
/// 6 894.757 Pa).
pub const PA_PER_PSI: f64 = N_PER_LBF / (M_PER_IN * M_PER_IN);

/// Newton-metres per pound-force-foot, `N_PER_LBF · M_PER_FT` (NIST SP 811 B.8: 1.355 818 N·m).
pub const NM_PER_LBFFT: f64 = N_PER_LBF * M_PER_FT;

/// kg·m² per slug·ft², `KG_PER_SLUG · M_PER_FT · M_PER_FT` (NIST SP 811 B.8: 1.355 818 kg·m²).
pub const KGM2_PER_SLUGFT2: f64 = KG_PER_SLUG * M_PER_FT * M_PER_FT;

/// kg/m³ per slug/ft³, `KG_PER_SLUG / M_PER_FT³` (NIST SP 811 B.8: 515.3788 kg/m³).
pub const KGPM3_PER_SLUGPFT3: f64 = KG_PER_SLUG / (M_PER_FT * M_PER_FT * M_PER_FT);

/// Metres per second per international knot (exact: 1 kt = 1 nautical mile per hour
/// = 1852 m / 3600 s; NIST SP 811 B.8: 0.514 444 m/s).
pub const MPS_PER_KT: f64 = 1852.0 / 3600.0;

/// Feet per second per knot, `MPS_PER_KT / M_PER_FT` (1.687 81 ft/s).
pub const FPS_PER_KT: f64 = MPS_PER_KT / M_PER_FT;

#[cfg(test)]
mod tests {
    use super::*;

    fn close(got: f64, want: f64, rtol: f64) -> bool {
        (got - want).abs() <= rtol * want.abs()
    }

    /// The derived factors against the values NIST SP 811 appendix B prints (7 digits).
    #[test]
    fn val_nist_sp811_appendix_b() {
        for (name, got, want) in [
            ("lbf", N_PER_LBF, 4.448_222),
            ("slug", KG_PER_SLUG, 14.593_90),
            ("psf", PA_PER_PSF, 47.880_26),
            ("psi", PA_PER_PSI, 6_894.757),
            ("lbf*ft", NM_PER_LBFFT, 1.355_818),
            ("slug*ft2", KGM2_PER_SLUGFT2, 1.355_818),
            ("slug/ft3", KGPM3_PER_SLUGPFT3, 515.378_8),
            ("ft2", M2_PER_FT2, 0.092_903_04),
            ("kt", MPS_PER_KT, 0.514_444),
            ("kt in ft/s", FPS_PER_KT, 1.687_810),
        ] {
            assert!(close(got, want, 1e-6), "{name}: {got} vs {want}");
        }
        // Standard gravity in English units is the familiar 32.174 ft/s².
        assert!(close(G0_MPS2 / M_PER_FT, 32.174_05, 1e-6));
    }

    /// The slug is written as the correctly rounded value of its definition
    /// (0.453 592 37 · 9.806 65 / 0.3048 = 14.593 902 937 206 364 829 396 3… exactly), one ulp
    /// above the f64 quotient.
    #[test]
    fn analytic_slug_is_one_lbf_s2_per_ft() {
        let exact: f64 = "14.5939029372063648293963254593".parse().unwrap();
        assert_eq!(KG_PER_SLUG, exact);
        let quotient = N_PER_LBF / M_PER_FT;
        assert_eq!(KG_PER_SLUG, f64::from_bits(quotient.to_bits() + 1));
        // 1 lbf = 4.448 221 615 260 5 N exactly; the f64 product rounds to that decimal's float.
        assert_eq!(N_PER_LBF, 4.448_221_615_260_5);
        assert!((FT_PER_M * M_PER_FT - 1.0).abs() <= f64::EPSILON);
    }
}
