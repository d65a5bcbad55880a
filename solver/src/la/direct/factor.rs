//! Solving with a numeric factor: one right-hand side or several at once.

use super::{Factor, Factorization, Numeric, SolveError};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::cholesky::{IntranodeLbltRef, LdltRef, LltRef};
use faer::{Conj, Mat, MatMut, MatRef, Par};

impl Factor {
    /// Solve M x = b.
    pub fn solve(&self, rhs: &[f64]) -> Result<Vec<f64>, SolveError> {
        if rhs.len() != self.size {
            return Err(SolveError::RhsSize {
                expected: self.size,
                found: rhs.len(),
            });
        }
        let mut x = Mat::from_fn(self.size, 1, |i, _| rhs[i]);
        self.solve_in_place(x.as_mut())?;
        Ok((0..self.size).map(|i| x[(i, 0)]).collect())
    }

    /// Solve M X = B for every column of B at once (one pass over the
    /// factor per block of columns instead of one per column).
    ///
    /// ```
    /// use faer::sparse::{SparseColMat, Triplet};
    /// use faer::Mat;
    /// use hasse_solver::la::direct::{DirectSolver, Factorization};
    /// // M = [[2, 1], [1, 2]]: M⁻¹ = [[2, −1], [−1, 2]] / 3.
    /// let entries = [Triplet::new(0, 0, 2.0), Triplet::new(1, 0, 1.0),
    ///                Triplet::new(0, 1, 1.0), Triplet::new(1, 1, 2.0)];
    /// let m = SparseColMat::<usize, f64>::try_new_from_triplets(2, 2, &entries).unwrap();
    /// let solver = DirectSolver::analyze(m.as_ref(), Factorization::Llt).unwrap();
    /// let factor = solver.factorize(m.as_ref()).unwrap();
    /// let x = factor.solve_many(Mat::<f64>::identity(2, 2).as_ref()).unwrap();
    /// assert!((x[(0, 0)] - 2.0 / 3.0).abs() < 1e-15 && (x[(1, 0)] + 1.0 / 3.0).abs() < 1e-15);
    /// ```
    pub fn solve_many(&self, rhs: MatRef<'_, f64>) -> Result<Mat<f64>, SolveError> {
        if rhs.nrows() != self.size {
            return Err(SolveError::RhsSize {
                expected: self.size,
                found: rhs.nrows(),
            });
        }
        let mut x = rhs.to_owned();
        self.solve_in_place(x.as_mut())?;
        Ok(x)
    }

    /// Overwrite the columns of `x` (right-hand sides) with the solutions.
    fn solve_in_place(&self, mut x: MatMut<'_, f64>) -> Result<(), SolveError> {
        let columns = x.ncols();
        match &self.inner {
            Numeric::Llt(symbolic, values) => {
                let par = faer::get_global_parallelism();
                let mut buffer =
                    MemBuffer::try_new(symbolic.solve_in_place_scratch::<f64>(columns, par))
                        .map_err(|_| SolveError::OutOfMemory)?;
                LltRef::new(symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    x.as_mut(),
                    par,
                    MemStack::new(&mut buffer),
                );
            }
            Numeric::Lu(f) => f.solve_in_place(x.as_mut()),
            Numeric::Ldlt(symbolic, values) => {
                let par = Par::Seq;
                let mut buffer =
                    MemBuffer::try_new(symbolic.solve_in_place_scratch::<f64>(columns, par))
                        .map_err(|_| SolveError::OutOfMemory)?;
                LdltRef::new(symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    x.as_mut(),
                    par,
                    MemStack::new(&mut buffer),
                );
            }
            Numeric::Lblt(f) => {
                let par = Par::Seq;
                let mut buffer =
                    MemBuffer::try_new(f.symbolic.solve_in_place_scratch::<f64>(columns, par))
                        .map_err(|_| SolveError::OutOfMemory)?;
                // The permutation arrays were written by faer's factorisation
                // as mutual inverses of length n.
                let perm = faer::perm::PermRef::new_checked(&f.forward, &f.inverse, self.size);
                IntranodeLbltRef::new(&f.symbolic, &f.values, &f.subdiag, perm)
                    .solve_in_place_with_conj(
                        Conj::No,
                        x.as_mut(),
                        par,
                        MemStack::new(&mut buffer),
                    );
            }
        }
        let finite = (0..columns).all(|j| (0..self.size).all(|i| x[(i, j)].is_finite()));
        if !finite {
            return Err(SolveError::Singular {
                method: match self.kind {
                    Factorization::Llt => "LLᵀ",
                    Factorization::Ldlt => "LDLᵀ",
                    Factorization::Lblt => "LBLᵀ",
                    Factorization::Lu => "LU",
                },
            });
        }
        Ok(())
    }
}
