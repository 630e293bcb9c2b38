//! Fixed-size lookup tables with an explicit out-of-range policy.
//!
//! Source of the interpolation rule: SLJ §3.5 / Appendix A (Fortran functions CX, CM, CL, …, DAMP,
//! THRUST): piecewise-linear in 1-D, bilinear in 2-D, and **linear extrapolation from the end
//! segment** outside the grid (the textbook does not clamp). See
//! `shared/data/f16-stevens-lewis/README.md` §4.
//!
//! The tables are plain arrays after loading, so a lookup allocates nothing and hashes nothing.

/// What a lookup does outside the breakpoints.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Extrapolation {
    /// Continue the end segment linearly (the textbook's Fortran index arithmetic, SLJ App. A).
    Linear,
    /// Hold the end value (what JSBSim and AeroBench do below 0 ft).
    Clamp,
}

/// A located point on an axis: segment index and fractional position (see [`segment`]).
pub type Segment = (usize, f64);

/// Segment index `i` (so that the point lies on `[x[i], x[i+1]]` or beyond an end) and the
/// fractional position `t` in that segment (`t` < 0 or > 1 only when extrapolating linearly).
#[inline]
pub fn segment<const N: usize>(x: &[f64; N], v: f64, policy: Extrapolation) -> (usize, f64) {
    // N is small (≤ 12): a linear scan is faster than bisection here.
    let mut i = 0;
    while i + 2 < N && v >= x[i + 1] {
        i += 1;
    }
    let t = (v - x[i]) / (x[i + 1] - x[i]);
    let t = match policy {
        Extrapolation::Linear => t,
        Extrapolation::Clamp => t.clamp(0.0, 1.0),
    };
    (i, t)
}

/// Checks that breakpoints are finite and strictly increasing; returns a reason otherwise.
pub(crate) fn check_breakpoints(x: &[f64]) -> Result<(), &'static str> {
    if x.len() < 2 {
        return Err("needs at least two breakpoints");
    }
    if x.iter().any(|v| !v.is_finite()) {
        return Err("breakpoints must be finite");
    }
    if x.windows(2).any(|w| w[1] <= w[0]) {
        return Err("breakpoints must be strictly increasing");
    }
    Ok(())
}

/// A 1-D table `y(x)` on `N` strictly increasing breakpoints.
#[derive(Debug, Clone, PartialEq)]
pub struct Table1<const N: usize> {
    /// Breakpoints (strictly increasing).
    pub x: [f64; N],
    /// Values at the breakpoints.
    pub y: [f64; N],
}

impl<const N: usize> Table1<N> {
    /// Piecewise-linear value at `v` with the given out-of-range `policy`.
    #[inline]
    pub fn lookup(&self, v: f64, policy: Extrapolation) -> f64 {
        self.at(segment(&self.x, v, policy))
    }

    /// Value at a point already located on this table's axis with [`segment`] (lets tables that
    /// share an axis locate the point once).
    #[inline]
    pub fn at(&self, (i, t): Segment) -> f64 {
        self.y[i] + t * (self.y[i + 1] - self.y[i])
    }
}

/// A 2-D table `z(r, c)` with `R` row breakpoints and `C` column breakpoints;
/// `z[i][j] = z(r[i], c[j])` (row-major, as `values[i][j]` in the data file).
#[derive(Debug, Clone, PartialEq)]
pub struct Table2<const R: usize, const C: usize> {
    /// Row breakpoints (strictly increasing).
    pub r: [f64; R],
    /// Column breakpoints (strictly increasing).
    pub c: [f64; C],
    /// Values, `z[row][column]`.
    pub z: [[f64; C]; R],
}

impl<const R: usize, const C: usize> Table2<R, C> {
    /// Bilinear value at `(rv, cv)`, the same `policy` on both axes.
    #[inline]
    pub fn lookup(&self, rv: f64, cv: f64, policy: Extrapolation) -> f64 {
        self.at(segment(&self.r, rv, policy), segment(&self.c, cv, policy))
    }

    /// Value at points already located on the row and column axes with [`segment`].
    #[inline]
    pub fn at(&self, (i, s): Segment, (j, t): Segment) -> f64 {
        let a = self.z[i][j] + t * (self.z[i][j + 1] - self.z[i][j]);
        let b = self.z[i + 1][j] + t * (self.z[i + 1][j + 1] - self.z[i + 1][j]);
        a + s * (b - a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn t1() -> Table1<3> {
        Table1 { x: [0.0, 1.0, 3.0], y: [1.0, 3.0, 2.0] }
    }

    #[test]
    fn analytic_piecewise_linear_inside_and_outside() {
        let t = t1();
        assert_eq!(t.lookup(0.5, Extrapolation::Linear), 2.0);
        assert_eq!(t.lookup(2.0, Extrapolation::Linear), 2.5);
        // End-segment extrapolation: slope 2 below 0, slope −0.5 above 3.
        assert_eq!(t.lookup(-1.0, Extrapolation::Linear), -1.0);
        assert_eq!(t.lookup(5.0, Extrapolation::Linear), 1.0);
        assert_eq!(t.lookup(-1.0, Extrapolation::Clamp), 1.0);
        assert_eq!(t.lookup(5.0, Extrapolation::Clamp), 2.0);
    }

    #[test]
    fn analytic_bilinear_reproduces_a_bilinear_function() {
        // z = 1 + 2 r + 3 c + 4 r c is reproduced exactly by bilinear interpolation, also outside.
        let f = |r: f64, c: f64| 1.0 + 2.0 * r + 3.0 * c + 4.0 * r * c;
        let r = [-1.0, 0.5, 2.0];
        let c = [0.0, 1.0];
        let mut z = [[0.0; 2]; 3];
        for i in 0..3 {
            for j in 0..2 {
                z[i][j] = f(r[i], c[j]);
            }
        }
        let t = Table2 { r, c, z };
        for &(a, b) in &[(0.0, 0.5), (1.7, 0.2), (-3.0, 2.5), (5.0, -1.0)] {
            assert!((t.lookup(a, b, Extrapolation::Linear) - f(a, b)).abs() < 1e-12);
        }
    }

    proptest! {
        #[test]
        fn prop_clamped_lookup_stays_in_hull(v in -100.0f64..100.0) {
            let y = t1().lookup(v, Extrapolation::Clamp);
            prop_assert!((1.0..=3.0).contains(&y));
        }
    }

    #[test]
    fn analytic_breakpoint_checks() {
        assert!(check_breakpoints(&[0.0, 1.0]).is_ok());
        assert!(check_breakpoints(&[0.0]).is_err());
        assert!(check_breakpoints(&[0.0, 0.0]).is_err());
        assert!(check_breakpoints(&[0.0, f64::NAN]).is_err());
    }
}
