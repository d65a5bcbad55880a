"""hypre BoomerAMG-CG through petsc4py on one MPI rank, on a Matrix Market
system: the hypre baseline of scripts/bench, next to pyamg_baseline.py.
Prints one line `RESULT case hypre key=value ...`:

- setup: seconds of KSPSetUp (with PCHYPRE this builds the BoomerAMG
  hierarchy: PCSetUp runs inside KSPSetUp), the matrix already assembled;
- solve: seconds of KSPSolve from x = 0;
- iterations: CG iterations to ‖b − A x‖₂ ≤ 1e-8 ‖b‖₂, the unpreconditioned
  relative residual that hasse's CG and pyamg stop on
  (`-ksp_norm_type unpreconditioned`, rtol 1e-8, atol 0, x₀ = 0, so
  PETSc's reference norm is ‖b‖₂); residual: that ratio recomputed
  afterwards from A, x and b;
- peak_gib: the process's peak resident memory (VmHWM), as pyamg's line,
  reading the file included; matrix_gib: the bytes of the assembled matrix
  alone in CSR (8-byte values, PETSc's column and row-start indices, both
  triangles; MatGetInfo's `memory` reads 0 without PETSc's memory
  logging, so the size is computed from the entries), the yardstick of
  "peak memory ≤ 1.5× the matrix's own".

BoomerAMG runs with the options PETSc sets when none are given (PETSc
3.18's PCHYPRE defaults, printed by `-ksp_view`): one V-cycle per
application, Falgout coarsening (coarsen type 6), classical interpolation
(type 0) without truncation (P_max 0, truncation factor 0), strong
threshold 0.25, max row sum 0.9, no aggressive coarsening (agg_nl 0),
relaxation symmetric-SOR/Jacobi (hypre's hybrid Gauss-Seidel, relax type
6) down and up, one sweep, Gaussian elimination on the coarsest level, at
most 25 levels. Pass extra PETSc options after the file names (e.g.
`-pc_hypre_boomeramg_coarsen_type HMIS`) to try others; the line then
carries them in `options=`.

Reading the Matrix Market file uses numpy alone (Debian's python3 has
numpy with petsc4py; scipy is not needed). The export is the lower
triangle of a symmetric matrix; both triangles are assembled.

usage: python3 hypre_baseline.py CASE MATRIX.mtx RHS.mtx [PETSc options]
"""
import resource
import sys
import time

import numpy as np
import petsc4py

case, matrix_path, rhs_path = sys.argv[1:4]
extra = sys.argv[4:]
petsc4py.init([sys.argv[0]] + extra)
from petsc4py import PETSc  # noqa: E402  (after init, which reads the options)


def read_coordinate(path):
    """(n, rows, cols, values) of a `coordinate real symmetric` file, both
    triangles, indices from 0."""
    with open(path) as f:
        header = f.readline().lower()
        if "coordinate" not in header:
            sys.exit(f"{path}: not a Matrix Market coordinate file")
        symmetric = "symmetric" in header
        line = f.readline()
        while line.startswith("%"):
            line = f.readline()
        n, m, nnz = (int(t) for t in line.split())
        data = np.fromfile(f, sep=" ")
    if n != m or data.size != 3 * nnz:
        sys.exit(f"{path}: expected a square matrix with {nnz} entries")
    data = data.reshape(nnz, 3)
    i = data[:, 0].astype(np.int64) - 1
    j = data[:, 1].astype(np.int64) - 1
    v = data[:, 2].copy()
    if symmetric:
        off = i != j
        i, j, v = np.concatenate([i, j[off]]), np.concatenate([j, i[off]]), np.concatenate([v, v[off]])
    return n, i, j, v


def read_array(path):
    with open(path) as f:
        header = f.readline().lower()
        if "array" not in header:
            sys.exit(f"{path}: not a Matrix Market array file")
        line = f.readline()
        while line.startswith("%"):
            line = f.readline()
        return np.fromfile(f, sep=" ")


n, rows, cols, values = read_coordinate(matrix_path)
order = np.lexsort((cols, rows))
rows, cols, values = rows[order], cols[order], values[order]
indptr = np.zeros(n + 1, dtype=PETSc.IntType)
np.cumsum(np.bincount(rows, minlength=n), out=indptr[1:])
indices = cols.astype(PETSc.IntType)
del rows, cols, order
b_array = read_array(rhs_path)

A = PETSc.Mat().createAIJ(size=(n, n), csr=(indptr, indices, values), comm=PETSc.COMM_SELF)
A.setOption(PETSc.Mat.Option.SPD, True)
A.assemble()
del indptr, indices, values
index_bytes = np.dtype(PETSc.IntType).itemsize
matrix_bytes = int(A.getInfo()["nz_used"]) * (8 + index_bytes) + (n + 1) * index_bytes
b = A.createVecLeft()
b.setArray(b_array)
x = A.createVecRight()
x.set(0.0)

ksp = PETSc.KSP().create(comm=PETSc.COMM_SELF)
ksp.setOperators(A)
ksp.setType(PETSc.KSP.Type.CG)
ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
ksp.setTolerances(rtol=1e-8, atol=0.0, max_it=500)
ksp.setInitialGuessNonzero(False)
pc = ksp.getPC()
pc.setType(PETSc.PC.Type.HYPRE)
pc.setHYPREType("boomeramg")
ksp.setFromOptions()

t = time.perf_counter()
ksp.setUp()
setup = time.perf_counter() - t
t = time.perf_counter()
ksp.solve(b, x)
solve = time.perf_counter() - t

r = b.duplicate()
A.mult(x, r)
r.aypx(-1.0, b)
relative = r.norm() / b.norm()
reason = ksp.getConvergedReason()
# ru_maxrss is in KiB on Linux.
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2
options = f" options={','.join(extra)}" if extra else ""
status = "" if reason > 0 else f" diverged={reason}"
print(
    f"RESULT {case} hypre unknowns={n} setup={setup:.3f} solve={solve:.3f} "
    f"iterations={ksp.getIterationNumber()} residual={relative:.2e} "
    f"peak_gib={peak:.3f} matrix_gib={matrix_bytes / 1024**3:.3f}{options}{status}"
)
