//! The sensitivities, information matrix and its solves by blocks, so that a joint check of
//! many manoeuvres costs time linear in their number.
//!
//! The unknowns are of two kinds: the global ones (biases, scale factors, time shifts, the AHRS
//! lag), which move every manoeuvre's outputs, and each manoeuvre's initial states, which move
//! its own outputs alone. The sensitivity matrix `S` (`N·ny × nβ`) is therefore zero outside a
//! block per manoeuvre of its samples' rows and the columns of the global unknowns and its own
//! initial states, and it is held as those blocks ([`Sensitivities`]): formed densely it took
//! `N·ny·nβ` numbers and `M = Sᵀ W S` cost `N·ny·nβ²`, with `nβ` itself growing by six per
//! manoeuvre, so a flight of 105 manoeuvres (`nβ` ≈ 650) took minutes per iteration. By blocks
//! `M` costs `N·ny·q²`, `q` the global unknowns plus six.
//!
//! `M` itself is kept dense (`nβ²` numbers: small), but it is arrow-shaped: a global block, a
//! band of global × initial blocks, and a block diagonal of each manoeuvre's initial states.
//! Its solves and inverse go through the Schur complement of that block diagonal ([`Schur`]):
//! a Cholesky factor of each manoeuvre's block and one of the global unknowns' complement,
//! linear in the manoeuvres instead of cubic in `nβ`. `M` is positive definite exactly when
//! every manoeuvre's block and the complement are, so a singular `M` is found as before.

use super::{
    Problem, Unknown, manoeuvre_sensitivity, moves_no_state, output_sensitivity, sensitivity,
};
use crate::EstimatorError;
use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

/// Which unknowns are global and which are each manoeuvre's own (indices into the problem's
/// unknowns, increasing).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Partition {
    /// The unknowns that move every manoeuvre: biases, scale factors, time shifts, the lag.
    pub(super) global: Vec<usize>,
    /// Per manoeuvre, its initial states.
    pub(super) own: Vec<Vec<usize>>,
}

impl Partition {
    /// The partition of `unknowns` over `n_man` manoeuvres.
    pub(super) fn of(unknowns: &[Unknown], n_man: usize) -> Self {
        let mut p = Partition { global: Vec::new(), own: vec![Vec::new(); n_man] };
        for (i, u) in unknowns.iter().enumerate() {
            match *u {
                Unknown::Initial { manoeuvre, .. } => p.own[manoeuvre].push(i),
                _ => p.global.push(i),
            }
        }
        p
    }

    /// Per manoeuvre, the unknowns that move its outputs: the global ones, then its own.
    fn columns(&self) -> Vec<Vec<usize>> {
        self.own.iter().map(|own| self.global.iter().chain(own).copied().collect()).collect()
    }
}

/// `S = ∂y/∂β` by manoeuvre blocks (module doc).
#[derive(Debug, Clone)]
pub(super) struct Sensitivities {
    /// Per manoeuvre, the unknowns whose columns its block holds ([`Partition::columns`]).
    pub(super) columns: Vec<Vec<usize>>,
    /// Per manoeuvre, its rows of `S` in those columns, `N_m·ny × q_m` row-major.
    pub(super) blocks: Vec<Vec<f64>>,
    /// Unknowns in all (`nβ`).
    pub(super) n: usize,
}

impl Sensitivities {
    /// `S` at `beta` by central differences (as [`sensitivity`]): a global unknown's column from
    /// the whole record (an output's own correction from the states at `beta`, integrated once:
    /// [`output_sensitivity`]), an initial state's from its own manoeuvre alone.
    pub(super) fn of(p: &Problem<'_>, beta: &[f64]) -> Result<Self, EstimatorError> {
        let part = Partition::of(&p.unknowns, p.man.len());
        let columns = part.columns();
        let ny = p.ny();
        let rows: Vec<usize> = p.man.iter().map(|m| m.len() * ny).collect();
        let mut blocks: Vec<Vec<f64>> =
            columns.iter().zip(&rows).map(|(c, r)| vec![0.0; r * c.len()]).collect();
        let sensed = if part.global.iter().any(|&i| moves_no_state(p.unknowns[i])) {
            let c = p.decode(beta);
            (0..p.man.len()).map(|m| p.states(&c, m)).collect::<Result<Vec<_>, _>>()?
        } else {
            Vec::new()
        };
        for (a, &i) in part.global.iter().enumerate() {
            let column = if moves_no_state(p.unknowns[i]) {
                output_sensitivity(p, beta, i, &sensed)
            } else {
                sensitivity(p, beta, i)?
            };
            let mut start = 0;
            for ((block, cols), &r) in blocks.iter_mut().zip(&columns).zip(&rows) {
                let q = cols.len();
                for (row, v) in column[start..start + r].iter().enumerate() {
                    block[row * q + a] = *v;
                }
                start += r;
            }
        }
        let g = part.global.len();
        for (m, own) in part.own.iter().enumerate() {
            let q = columns[m].len();
            for (j, &i) in own.iter().enumerate() {
                let column = manoeuvre_sensitivity(p, beta, i, m)?;
                for (row, v) in column.iter().enumerate() {
                    blocks[m][row * q + g + j] = *v;
                }
            }
        }
        Ok(Self { columns, blocks, n: beta.len() })
    }

    /// `(M, g)`: `M = Sᵀ W S`, `g = Sᵀ W e`, `W = diag(1/r)` per output, `e` the residuals
    /// (`N·ny`, manoeuvres concatenated), summed block by block.
    pub(super) fn information(&self, e: &[f64], r: &[f64]) -> (DMatrix<f64>, DVector<f64>) {
        let (n, ny) = (self.n, r.len());
        let mut m = DMatrix::zeros(n, n);
        let mut g = DVector::zeros(n);
        let mut start = 0;
        for (cols, block) in self.columns.iter().zip(&self.blocks) {
            let q = cols.len();
            if q == 0 {
                continue;
            }
            let rows = block.len() / q;
            let mut local = vec![0.0; q * q];
            let mut local_g = vec![0.0; q];
            for (row, s) in block.chunks_exact(q).enumerate() {
                let (w, er) = (r[row % ny], e[start + row]);
                for a in 0..q {
                    let sw = s[a] / w;
                    local_g[a] += sw * er;
                    for (l, sb) in local[a * q + a..(a + 1) * q].iter_mut().zip(&s[a..]) {
                        *l += sw * sb;
                    }
                }
            }
            for a in 0..q {
                g[cols[a]] += local_g[a];
                for b in a..q {
                    let v = local[a * q + b];
                    m[(cols[a], cols[b])] += v;
                    if a != b {
                        m[(cols[b], cols[a])] += v;
                    }
                }
            }
            start += rows;
        }
        (m, g)
    }

    /// The dense `S` (`N·ny × nβ`).
    pub(super) fn dense(&self) -> DMatrix<f64> {
        let rows: usize =
            self.columns.iter().zip(&self.blocks).map(|(c, b)| b.len() / c.len()).sum();
        let mut s = DMatrix::zeros(rows, self.n);
        let mut start = 0;
        for (cols, block) in self.columns.iter().zip(&self.blocks) {
            let q = cols.len();
            for (row, v) in block.chunks_exact(q).enumerate() {
                for (a, &c) in cols.iter().enumerate() {
                    s[(start + row, c)] = v[a];
                }
            }
            start += block.len() / q;
        }
        s
    }
}

/// The factors of an arrow-shaped `M` (module doc): each manoeuvre's block `D_m` of its initial
/// states, `Y_m = D_m⁻¹ B_mᵀ` (`B_m` the global × own block) and the Cholesky factor of the
/// global unknowns' Schur complement `A − Σ B_m Y_m`.
pub(super) struct Schur {
    part: Partition,
    complement: Cholesky<f64, Dyn>,
    own: Vec<Cholesky<f64, Dyn>>,
    y: Vec<DMatrix<f64>>,
}

impl Schur {
    /// The factors of `m` partitioned by `part`; `None` when `m` is not positive definite.
    pub(super) fn of(m: &DMatrix<f64>, part: &Partition) -> Option<Self> {
        let sub =
            |r: &[usize], c: &[usize]| DMatrix::from_fn(r.len(), c.len(), |i, j| m[(r[i], c[j])]);
        let mut complement = sub(&part.global, &part.global);
        let mut own = Vec::with_capacity(part.own.len());
        let mut y = Vec::with_capacity(part.own.len());
        for o in &part.own {
            let d = sub(o, o).cholesky()?;
            let b = sub(&part.global, o);
            let ym = d.solve(&b.transpose());
            complement -= &b * &ym;
            own.push(d);
            y.push(ym);
        }
        let complement = complement.cholesky()?;
        Some(Self { part: part.clone(), complement, own, y })
    }

    /// `M⁻¹ b`.
    pub(super) fn solve(&self, b: &DVector<f64>) -> DVector<f64> {
        let pick = |idx: &[usize]| DVector::from_fn(idx.len(), |i, _| b[idx[i]]);
        let z: Vec<DVector<f64>> =
            self.own.iter().zip(&self.part.own).map(|(d, o)| d.solve(&pick(o))).collect();
        let mut rhs = pick(&self.part.global);
        for (ym, o) in self.y.iter().zip(&self.part.own) {
            // B_m D_m⁻¹ b_m = Y_mᵀ b_m.
            rhs -= ym.transpose() * pick(o);
        }
        let xg = self.complement.solve(&rhs);
        let mut x = DVector::zeros(b.len());
        for (a, &i) in self.part.global.iter().enumerate() {
            x[i] = xg[a];
        }
        for (zm, (ym, o)) in z.iter().zip(self.y.iter().zip(&self.part.own)) {
            let xm = zm - ym * &xg;
            for (a, &i) in o.iter().enumerate() {
                x[i] = xm[a];
            }
        }
        x
    }

    /// The diagonal of `M⁻¹`: `(A − Σ B Y)⁻¹` for the global unknowns, `D_m⁻¹ + Y_m (A − Σ B
    /// Y)⁻¹ Y_mᵀ` for a manoeuvre's.
    pub(super) fn inverse_diagonal(&self) -> Vec<f64> {
        let sinv = self.complement.inverse();
        let n = self.part.global.len() + self.part.own.iter().map(Vec::len).sum::<usize>();
        let mut diag = vec![0.0; n];
        for (a, &i) in self.part.global.iter().enumerate() {
            diag[i] = sinv[(a, a)];
        }
        for ((d, ym), o) in self.own.iter().zip(&self.y).zip(&self.part.own) {
            let dinv = d.inverse();
            let ys = ym * &sinv;
            for (a, &i) in o.iter().enumerate() {
                diag[i] = dinv[(a, a)] + ys.row(a).dot(&ym.row(a));
            }
        }
        diag
    }

    /// `M⁻¹`, dense: `[S⁻¹, −S⁻¹ Yᵀ; −Y S⁻¹, D⁻¹ + Y S⁻¹ Yᵀ]` with `S = A − Σ B Y` and `Y` the
    /// manoeuvres' `Y_m` stacked.
    pub(super) fn inverse(&self) -> DMatrix<f64> {
        let sinv = self.complement.inverse();
        let g = &self.part.global;
        let own: Vec<usize> = self.part.own.iter().flatten().copied().collect();
        let n = g.len() + own.len();
        let mut y = DMatrix::zeros(own.len(), g.len());
        let mut row = 0;
        for ym in &self.y {
            y.rows_mut(row, ym.nrows()).copy_from(ym);
            row += ym.nrows();
        }
        let ys = &y * &sinv;
        let yy = &ys * y.transpose();
        let mut inv = DMatrix::zeros(n, n);
        for (a, &i) in g.iter().enumerate() {
            for (b, &j) in g.iter().enumerate() {
                inv[(i, j)] = sinv[(a, b)];
            }
            for (b, &j) in own.iter().enumerate() {
                inv[(i, j)] = -ys[(b, a)];
                inv[(j, i)] = -ys[(b, a)];
            }
        }
        for (a, &i) in own.iter().enumerate() {
            for (b, &j) in own.iter().enumerate() {
                inv[(i, j)] = yy[(a, b)];
            }
        }
        for (d, o) in self.own.iter().zip(&self.part.own) {
            let dinv = d.inverse();
            for (a, &i) in o.iter().enumerate() {
                for (b, &j) in o.iter().enumerate() {
                    inv[(i, j)] += dinv[(a, b)];
                }
            }
        }
        inv
    }
}
