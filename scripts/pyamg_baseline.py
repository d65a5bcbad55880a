"""pyamg smoothed-aggregation CG on a Matrix Market system, the baseline of
scripts/bench: prints one line `RESULT case pyamg key=value ...` with the
setup and solve seconds, iterations to relative residual 1e-8, and the
process's peak memory (reading the file excluded from the timings, not
from the memory).

usage: python pyamg_baseline.py CASE MATRIX.mtx RHS.mtx
"""
import resource
import sys
import time

import numpy as np
import pyamg
import scipy.io

case, matrix_path, rhs_path = sys.argv[1:4]
A = scipy.io.mmread(matrix_path).tocsr()
b = np.asarray(scipy.io.mmread(rhs_path)).ravel()
t = time.perf_counter()
ml = pyamg.smoothed_aggregation_solver(A, symmetry="symmetric")
setup = time.perf_counter() - t
residuals = []
t = time.perf_counter()
x = ml.solve(b, tol=1e-8, accel="cg", residuals=residuals, maxiter=500)
solve = time.perf_counter() - t
relative = np.linalg.norm(b - A @ x) / np.linalg.norm(b)
# ru_maxrss is in KiB on Linux.
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2
print(
    f"RESULT {case} pyamg unknowns={A.shape[0]} setup={setup:.3f} solve={solve:.3f} "
    f"iterations={len(residuals) - 1} residual={relative:.2e} peak_gib={peak:.3f}"
)
