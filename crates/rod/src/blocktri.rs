//! Block-tridiagonal linear solve with D×D blocks (block Thomas algorithm).
//!
//! A rod couples only neighbouring nodes (3 unknowns each in the plane, 6 in space), so its
//! tangent is block tridiagonal. nalgebra has no banded solver; the block elimination below
//! factors every pivot block once ([`BlockLu`]: partial pivoting, the operations of nalgebra's
//! `LU` in its order, so the same bits, without its generic bookkeeping, which took a fifth of a
//! three-point diagnosis), costs O(n) and is what makes 1,000 load steps on 100 elements cheap.
//! No pivoting between blocks: the rod tangents are block-diagonally dominant enough in practice
//! (clamped/prescribed rows are identity rows); a singular pivot block is reported, not hidden.
//! Does not: store the factorisation beyond one call, handle other sparsity patterns.

use nalgebra::{SMatrix, SVector};

/// LU factors of one D×D block with partial pivoting (row i swapped with `swaps[i]`), computed by
/// exactly the floating-point operations of `nalgebra::linalg::LU::new` and `LU::solve_mut` in
/// their order (tested bit for bit): unit lower factor below the diagonal, upper factor on and
/// above it. A column without a non-zero pivot candidate is skipped, and solves then fail.
struct BlockLu<const D: usize> {
    lu: SMatrix<f64, D, D>,
    swaps: [usize; D],
}

impl<const D: usize> BlockLu<D> {
    #[inline(always)]
    fn new(mut m: SMatrix<f64, D, D>) -> Self {
        let mut swaps = [0; D];
        for i in 0..D {
            swaps[i] = i;
            // Largest |entry| of the column on and below the diagonal, the first one on ties.
            let mut piv = i;
            let mut best = m[(i, i)].abs();
            for r in i + 1..D {
                let v = m[(r, i)].abs();
                if v > best {
                    best = v;
                    piv = r;
                }
            }
            let diag = m[(piv, i)];
            if diag == 0.0 {
                continue;
            }
            if piv != i {
                swaps[i] = piv;
                for c in 0..=i {
                    m.swap((i, c), (piv, c));
                }
            }
            let inv_diag = 1.0 / diag;
            for r in i + 1..D {
                m[(r, i)] *= inv_diag;
            }
            for k in i + 1..D {
                if piv != i {
                    m.swap((i, k), (piv, k));
                }
                let p = m[(i, k)];
                for r in i + 1..D {
                    m[(r, k)] += -p * m[(r, i)];
                }
            }
        }
        BlockLu { lu: m, swaps }
    }

    /// Solve in place; false when the block is singular (a zero on the upper factor's diagonal).
    #[inline(always)]
    fn solve_mut(&self, b: &mut SVector<f64, D>) -> bool {
        for (i, &p) in self.swaps.iter().enumerate() {
            if p != i {
                b.swap_rows(i, p);
            }
        }
        for i in 0..D.saturating_sub(1) {
            let coeff = b[i];
            for r in i + 1..D {
                b[r] += -coeff * self.lu[(r, i)];
            }
        }
        for i in (0..D).rev() {
            let diag = self.lu[(i, i)];
            if diag == 0.0 {
                return false;
            }
            let coeff = b[i] / diag;
            b[i] = coeff;
            for r in 0..i {
                b[r] += -coeff * self.lu[(r, i)];
            }
        }
        true
    }
}

/// Solve `A x = b` for a block-tridiagonal `A` given by its diagonal blocks `diag[i]`, upper blocks
/// `upper[i] = A(i, i+1)` and lower blocks `lower[i] = A(i+1, i)`. `rhs` is overwritten with the
/// solution. Returns the index of the first singular pivot block as an error.
pub(crate) fn solve_block_tridiagonal<const D: usize>(
    diag: &[SMatrix<f64, D, D>],
    upper: &[SMatrix<f64, D, D>],
    lower: &[SMatrix<f64, D, D>],
    rhs: &mut [SVector<f64, D>],
    work: &mut Vec<SMatrix<f64, D, D>>,
) -> Result<(), usize> {
    let n = diag.len();
    debug_assert_eq!(rhs.len(), n);
    debug_assert!(upper.len() + 1 >= n && lower.len() + 1 >= n);
    if n == 0 {
        return Ok(());
    }
    work.clear();
    // Forward elimination: D'_i = D_i − L_{i−1} X_{i−1}, X_i = D'_i⁻¹ U_i, y_i = D'_i⁻¹ (b_i − L_{i−1} y_{i−1}).
    let mut d = diag[0];
    for i in 0..n {
        if i > 0 {
            d = diag[i] - lower[i - 1] * work[i - 1];
            let corr = lower[i - 1] * rhs[i - 1];
            rhs[i] -= corr;
        }
        let lu = BlockLu::new(d);
        if !lu.solve_mut(&mut rhs[i]) || !rhs[i].iter().all(|v| v.is_finite()) {
            return Err(i);
        }
        push_coupling(&lu, (i, n), upper, work)?;
    }
    // Back substitution: x_i = y_i − X_i x_{i+1}.
    for i in (0..n - 1).rev() {
        let corr = work[i] * rhs[i + 1];
        rhs[i] -= corr;
    }
    Ok(())
}

/// Push X_i = D'_i⁻¹ U_i (pivot block i of n factored in `lu`) onto `work`, unless i is the last.
#[inline(always)]
fn push_coupling<const D: usize>(
    lu: &BlockLu<D>,
    (i, n): (usize, usize),
    upper: &[SMatrix<f64, D, D>],
    work: &mut Vec<SMatrix<f64, D, D>>,
) -> Result<(), usize> {
    if i + 1 >= n {
        return Ok(());
    }
    let mut x = upper[i];
    for mut col in x.column_iter_mut() {
        let mut c: SVector<f64, D> = col.clone_owned();
        if !lu.solve_mut(&mut c) {
            return Err(i);
        }
        col.copy_from(&c);
    }
    work.push(x);
    Ok(())
}

/// [`solve_block_tridiagonal`] for several right-hand sides of one matrix: the blocks are
/// eliminated once, then each of `rhs` (one vector per node each) is substituted through them
/// with the same operations, so each solution has the bits a single solve would give.
pub(crate) fn solve_block_tridiagonal_many<const D: usize>(
    diag: &[SMatrix<f64, D, D>],
    upper: &[SMatrix<f64, D, D>],
    lower: &[SMatrix<f64, D, D>],
    rhs: &mut [Vec<SVector<f64, D>>],
    work: &mut Vec<SMatrix<f64, D, D>>,
) -> Result<(), usize> {
    let n = diag.len();
    if n == 0 {
        return Ok(());
    }
    debug_assert!(rhs.iter().all(|b| b.len() == n));
    work.clear();
    let mut lus = Vec::with_capacity(n);
    let mut d = diag[0];
    for i in 0..n {
        if i > 0 {
            d = diag[i] - lower[i - 1] * work[i - 1];
        }
        let lu = BlockLu::new(d);
        push_coupling(&lu, (i, n), upper, work)?;
        lus.push(lu);
    }
    for b in rhs.iter_mut() {
        for i in 0..n {
            if i > 0 {
                let corr = lower[i - 1] * b[i - 1];
                b[i] -= corr;
            }
            if !lus[i].solve_mut(&mut b[i]) || !b[i].iter().all(|v| v.is_finite()) {
                return Err(i);
            }
        }
        for i in (0..n - 1).rev() {
            let corr = work[i] * b[i + 1];
            b[i] -= corr;
        }
    }
    Ok(())
}

/// Move a prescribed increment `delta` of unknown `d` of node `i` to the right-hand side:
/// `rhs −= A(:, (i, d)) · delta` (the column reaches nodes i − 1, i, i + 1).
pub(crate) fn subtract_column<const D: usize>(
    diag: &[SMatrix<f64, D, D>],
    upper: &[SMatrix<f64, D, D>],
    lower: &[SMatrix<f64, D, D>],
    rhs: &mut [SVector<f64, D>],
    (i, d): (usize, usize),
    delta: f64,
) {
    rhs[i] -= diag[i].column(d) * delta;
    if i > 0 {
        rhs[i - 1] -= upper[i - 1].column(d) * delta;
    }
    if i + 1 < diag.len() {
        rhs[i + 1] -= lower[i].column(d) * delta;
    }
}

/// Turn unknown `d` of node `i` into a prescribed one: its row and column become those of the
/// identity (the caller sets its right-hand side to the prescribed increment).
pub(crate) fn constrain<const D: usize>(
    diag: &mut [SMatrix<f64, D, D>],
    upper: &mut [SMatrix<f64, D, D>],
    lower: &mut [SMatrix<f64, D, D>],
    (i, d): (usize, usize),
) {
    diag[i].row_mut(d).fill(0.0);
    diag[i].column_mut(d).fill(0.0);
    diag[i][(d, d)] = 1.0;
    if i + 1 < diag.len() {
        upper[i].row_mut(d).fill(0.0);
        lower[i].column_mut(d).fill(0.0);
    }
    if i > 0 {
        lower[i - 1].row_mut(d).fill(0.0);
        upper[i - 1].column_mut(d).fill(0.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, Matrix3, Vector3};

    /// Numbers in [−0.5, 0.5) from a 64-bit linear congruential generator (deterministic).
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64) / (1u64 << 53) as f64 - 0.5
        }
    }

    /// The block LU gives nalgebra's LU solve bit for bit: random 3×3 and 6×6 blocks whose
    /// entries span ten orders of magnitude (a rod's forces against its moments), permuted so
    /// that every pivot order occurs, plus singular and NaN blocks.
    #[test]
    fn block_lu_is_nalgebras_lu_bit_for_bit() {
        let mut rnd = uniform(7);
        fn check<const D: usize>(m: SMatrix<f64, D, D>, b: SVector<f64, D>)
        where
            nalgebra::Const<D>: nalgebra::ToTypenum
                + nalgebra::DimMin<nalgebra::Const<D>, Output = nalgebra::Const<D>>,
        {
            let reference = m.lu().solve(&b);
            let mut mine = b;
            let ok = BlockLu::new(m).solve_mut(&mut mine);
            match reference {
                Some(x) => {
                    assert!(ok, "{m}");
                    for (a, c) in x.iter().zip(mine.iter()) {
                        assert!(
                            a.to_bits() == c.to_bits() || (a.is_nan() && c.is_nan()),
                            "{m}: {x} vs {mine}"
                        );
                    }
                }
                None => assert!(!ok, "{m}"),
            }
        }
        for case in 0..400 {
            let scale = 10f64.powi(case % 11 - 5);
            let m3 = Matrix3::from_fn(|i, _| rnd() * if i == 2 { scale } else { 1.0 });
            check(m3, Vector3::new(rnd(), rnd(), rnd()));
            let m6 = SMatrix::<f64, 6, 6>::from_fn(|i, j| {
                rnd() * if (i + j) % 3 == 0 { scale } else { 1.0 }
            });
            check(m6, SVector::<f64, 6>::from_fn(|_, _| rnd()));
        }
        check(
            Matrix3::new(0.0, 1.0, 2.0, 0.0, 3.0, 4.0, 0.0, 5.0, 6.0),
            Vector3::new(1.0, 2.0, 3.0),
        );
        check(
            Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 1.0, 1.0, 1.0),
            Vector3::new(1.0, 0.0, 0.0),
        );
        check(
            Matrix3::new(0.0, 2.0, 0.0, 3.0, 0.0, 0.0, 0.0, 0.0, 5.0),
            Vector3::new(1.0, 2.0, 3.0),
        );
        check(
            Matrix3::new(f64::NAN, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 1.0),
            Vector3::new(1.0, 2.0, 3.0),
        );
    }

    /// The block solve agrees with a dense LU solve of the same (non-symmetric) system.
    #[test]
    fn matches_dense_lu() {
        let n = 6;
        let mut diag = Vec::new();
        let mut upper = Vec::new();
        let mut lower = Vec::new();
        let mut rhs = Vec::new();
        let mut rnd = uniform(1);
        for i in 0..n {
            let mut d = Matrix3::from_fn(|_, _| rnd());
            d += Matrix3::identity() * 4.0;
            diag.push(d);
            rhs.push(Vector3::new(rnd(), rnd(), rnd()));
            if i + 1 < n {
                upper.push(Matrix3::from_fn(|_, _| rnd()));
                lower.push(Matrix3::from_fn(|_, _| rnd()));
            }
        }
        let mut a = DMatrix::<f64>::zeros(3 * n, 3 * n);
        let mut b = nalgebra::DVector::<f64>::zeros(3 * n);
        for i in 0..n {
            a.view_mut((3 * i, 3 * i), (3, 3)).copy_from(&diag[i]);
            b.rows_mut(3 * i, 3).copy_from(&rhs[i]);
            if i + 1 < n {
                a.view_mut((3 * i, 3 * i + 3), (3, 3)).copy_from(&upper[i]);
                a.view_mut((3 * i + 3, 3 * i), (3, 3)).copy_from(&lower[i]);
            }
        }
        let x_dense = a.lu().solve(&b).unwrap();
        let mut work = Vec::new();
        solve_block_tridiagonal(&diag, &upper, &lower, &mut rhs, &mut work).unwrap();
        for i in 0..n {
            for d in 0..3 {
                assert!((rhs[i][d] - x_dense[3 * i + d]).abs() < 1e-12);
            }
        }
    }

    /// A singular pivot is reported with its block index.
    /// Several right-hand sides through one elimination give each single solve's bits, and a
    /// singular pivot is reported at the same block.
    #[test]
    fn many_right_hand_sides_are_single_solves_bit_for_bit() {
        let mut rnd = uniform(11);
        let n = 9;
        let diag: Vec<Matrix3<f64>> = (0..n)
            .map(|_| Matrix3::from_fn(|i, j| rnd() + if i == j { 4.0 } else { 0.0 }))
            .collect();
        let upper: Vec<Matrix3<f64>> = (0..n - 1).map(|_| Matrix3::from_fn(|_, _| rnd())).collect();
        let lower: Vec<Matrix3<f64>> = (0..n - 1).map(|_| Matrix3::from_fn(|_, _| rnd())).collect();
        let mut many: Vec<Vec<Vector3<f64>>> = (0..4)
            .map(|_| (0..n).map(|_| Vector3::new(rnd(), rnd(), rnd())).collect())
            .collect();
        let mut work = Vec::new();
        let singles: Vec<Vec<Vector3<f64>>> = many
            .iter()
            .map(|b| {
                let mut x = b.clone();
                solve_block_tridiagonal(&diag, &upper, &lower, &mut x, &mut work).unwrap();
                x
            })
            .collect();
        solve_block_tridiagonal_many(&diag, &upper, &lower, &mut many, &mut work).unwrap();
        for (a, b) in many.iter().flatten().zip(singles.iter().flatten()) {
            assert!(a
                .iter()
                .zip(b.iter())
                .all(|(x, y)| x.to_bits() == y.to_bits()));
        }
        let mut bad = diag.clone();
        bad[0] = Matrix3::zeros();
        let mut one = vec![many[0].clone()];
        let single = solve_block_tridiagonal(&bad, &upper, &lower, &mut many[1], &mut work);
        let multi = solve_block_tridiagonal_many(&bad, &upper, &lower, &mut one, &mut work);
        assert_eq!(single.unwrap_err(), multi.unwrap_err());
    }

    #[test]
    fn singular_block_is_reported() {
        let diag = vec![Matrix3::identity(), Matrix3::zeros()];
        let upper = vec![Matrix3::zeros()];
        let lower = vec![Matrix3::zeros()];
        let mut rhs = vec![Vector3::new(1.0, 2.0, 3.0), Vector3::new(1.0, 0.0, 0.0)];
        let mut work = Vec::new();
        assert_eq!(
            solve_block_tridiagonal(&diag, &upper, &lower, &mut rhs, &mut work),
            Err(1)
        );
    }
}
