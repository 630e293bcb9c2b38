//! SI at the Python boundary. The F-16 of Stevens, Lewis & Johnson computes in the textbook's
//! units (ft, ft/s, lbf, psf) and the library keeps them, so that its numbers stay the book's;
//! Python gets SI by default and the textbook units only where a name asks for them
//! (`*_textbook`, `vt_fps`, `alt_ft`). A quantity's unit is read from its name's suffix, the
//! convention of every state, column and key in aeroident, so one table converts them all.

use aeroident_physics::units::{M_PER_FT, N_PER_LBF, PA_PER_PSF};

/// Textbook suffix, SI suffix, SI units per textbook unit.
const SUFFIXES: [(&str, &str, f64); 5] = [
    ("_fps2", "_mps2", M_PER_FT),
    ("_fps", "_mps", M_PER_FT),
    ("_ft", "_m", M_PER_FT),
    ("_psf", "_pa", PA_PER_PSF),
    ("_lbf", "_n", N_PER_LBF),
];

/// The SI name of a quantity named `name` and the factor taking its value there (1 for a name
/// already in SI or without a unit).
pub fn si_name(name: &str) -> (String, f64) {
    for (textbook, si, factor) in SUFFIXES {
        if let Some(stem) = name.strip_suffix(textbook) {
            return (format!("{stem}{si}"), factor);
        }
    }
    (name.to_string(), 1.0)
}

/// The units of a state vector: its names as the library gives them (the textbook's for the
/// F-16), their SI names and the factors between the two.
pub struct StateUnits {
    /// The library's names (with their units).
    pub textbook: Vec<String>,
    /// The SI names, in the same order.
    pub si: Vec<String>,
    /// SI units per library unit, per state.
    factors: Vec<f64>,
}

impl StateUnits {
    /// The units of the states named `names`.
    pub fn of<S: AsRef<str>>(names: &[S]) -> Self {
        let textbook: Vec<String> = names.iter().map(|n| n.as_ref().to_string()).collect();
        let (si, factors) = textbook.iter().map(|n| si_name(n)).unzip();
        Self { textbook, si, factors }
    }

    /// A state (or its time derivative) in the library's units as SI; a vector longer than the
    /// names keeps its extra entries as they are.
    pub fn to_si(&self, x: &[f64]) -> Vec<f64> {
        x.iter().enumerate().map(|(i, v)| v * self.factor(i)).collect()
    }

    /// An SI state in the library's units (the inverse of [`Self::to_si`]).
    pub fn to_library(&self, x: &[f64]) -> Vec<f64> {
        x.iter().enumerate().map(|(i, v)| v / self.factor(i)).collect()
    }

    /// A state matrix `A` (ẋ = A x) of the library's units in SI: `D A D⁻¹`, `D` the factors.
    pub fn a_to_si(&self, a: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let row = |(i, r): (usize, &Vec<f64>)| {
            r.iter().enumerate().map(|(j, v)| self.factor(i) * v / self.factor(j)).collect()
        };
        a.iter().enumerate().map(row).collect()
    }

    /// An input matrix `B` (ẋ = B u, inputs already SI) of the library's units in SI: `D B`.
    pub fn b_to_si(&self, b: &[Vec<f64>]) -> Vec<Vec<f64>> {
        b.iter().enumerate().map(|(i, r)| r.iter().map(|v| self.factor(i) * v).collect()).collect()
    }

    fn factor(&self, i: usize) -> f64 {
        self.factors.get(i).copied().unwrap_or(1.0)
    }
}
