//! A thin binding to PETSc's C API (Debian's `petsc-dev`, 3.18, real
//! double scalars, 32-bit indices): the few calls hasse needs to hand an
//! assembled distributed matrix to KSP and read the solution back.
//!
//! Every `unsafe` call of the distributed path is in this module. The
//! safety argument is the same for all of them, and is stated once here:
//!
//! - PETSc objects (`Mat`, `Vec`, `KSP`, `PC`) are opaque pointers created
//!   by PETSc and owned by exactly one wrapper ([`Matrix`], [`Vector`],
//!   [`Solver`]); the wrapper destroys them once, in `Drop`, and never
//!   hands the raw pointer out.
//! - Slices handed to PETSc are read (or written, for
//!   `VecGetArrayRead`'s view, which is copied out before it is restored)
//!   only during the call, with their lengths passed alongside.
//! - Strings are NUL-terminated `CString`s that live across the call.
//! - PETSc is initialised once ([`Petsc::initialize`]) after MPI and
//!   finalised when the [`Petsc`] guard drops, which its users keep alive
//!   longer than every object they create (objects borrow the guard).
//! - Errors: a hasse error handler replaces PETSc's printing one; it
//!   records PETSc's message, and every call's return code is checked and
//!   turned into [`PetscError`] with that message.

use mpi::ffi::MPI_Comm;
use std::cell::RefCell;
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::marker::PhantomData;

type PetscErrorCode = c_int;
type PetscInt = i32;
type PetscScalar = f64;
type PetscReal = f64;
#[repr(C)]
struct Opaque {
    _private: [u8; 0],
}
type Mat = *mut Opaque;
type Vec_ = *mut Opaque;
type Ksp = *mut Opaque;
type Pc = *mut Opaque;

/// `INSERT_VALUES` and `ADD_VALUES` of PETSc's `InsertMode`.
const INSERT_VALUES: c_int = 1;
const ADD_VALUES: c_int = 2;
/// `MAT_FINAL_ASSEMBLY` of `MatAssemblyType`.
const MAT_FINAL_ASSEMBLY: c_int = 0;
/// `KSP_NORM_UNPRECONDITIONED` of `KSPNormType`.
const KSP_NORM_UNPRECONDITIONED: c_int = 2;
/// `PETSC_DEFAULT` for integer and real arguments.
const PETSC_DEFAULT: PetscInt = -2;

type ErrorHandler = unsafe extern "C" fn(
    MPI_Comm,
    c_int,
    *const c_char,
    *const c_char,
    PetscErrorCode,
    c_int,
    *const c_char,
    *mut c_void,
) -> PetscErrorCode;

// Linked by build.rs from `pkg-config PETSc`.
extern "C" {
    fn PetscInitialize(
        argc: *mut c_int,
        args: *mut *mut *mut c_char,
        file: *const c_char,
        help: *const c_char,
    ) -> PetscErrorCode;
    fn PetscFinalize() -> PetscErrorCode;
    fn PetscPushErrorHandler(handler: ErrorHandler, ctx: *mut c_void) -> PetscErrorCode;
    fn PetscOptionsInsertString(options: *mut c_void, text: *const c_char) -> PetscErrorCode;

    fn MatCreate(comm: MPI_Comm, mat: *mut Mat) -> PetscErrorCode;
    fn MatSetSizes(
        mat: Mat,
        m: PetscInt,
        n: PetscInt,
        mm: PetscInt,
        nn: PetscInt,
    ) -> PetscErrorCode;
    fn MatSetType(mat: Mat, kind: *const c_char) -> PetscErrorCode;
    fn MatSeqAIJSetPreallocation(mat: Mat, nz: PetscInt, nnz: *const PetscInt) -> PetscErrorCode;
    fn MatMPIAIJSetPreallocation(
        mat: Mat,
        d_nz: PetscInt,
        d_nnz: *const PetscInt,
        o_nz: PetscInt,
        o_nnz: *const PetscInt,
    ) -> PetscErrorCode;
    fn MatSetValues(
        mat: Mat,
        m: PetscInt,
        rows: *const PetscInt,
        n: PetscInt,
        cols: *const PetscInt,
        values: *const PetscScalar,
        mode: c_int,
    ) -> PetscErrorCode;
    fn MatAssemblyBegin(mat: Mat, kind: c_int) -> PetscErrorCode;
    fn MatAssemblyEnd(mat: Mat, kind: c_int) -> PetscErrorCode;
    fn MatDestroy(mat: *mut Mat) -> PetscErrorCode;

    fn VecCreateMPI(comm: MPI_Comm, n: PetscInt, nn: PetscInt, v: *mut Vec_) -> PetscErrorCode;
    fn VecSetValues(
        v: Vec_,
        n: PetscInt,
        rows: *const PetscInt,
        values: *const PetscScalar,
        mode: c_int,
    ) -> PetscErrorCode;
    fn VecAssemblyBegin(v: Vec_) -> PetscErrorCode;
    fn VecAssemblyEnd(v: Vec_) -> PetscErrorCode;
    fn VecGetArrayRead(v: Vec_, array: *mut *const PetscScalar) -> PetscErrorCode;
    fn VecRestoreArrayRead(v: Vec_, array: *mut *const PetscScalar) -> PetscErrorCode;
    fn VecGetLocalSize(v: Vec_, n: *mut PetscInt) -> PetscErrorCode;
    fn VecDestroy(v: *mut Vec_) -> PetscErrorCode;

    fn KSPCreate(comm: MPI_Comm, ksp: *mut Ksp) -> PetscErrorCode;
    fn KSPSetOperators(ksp: Ksp, a: Mat, p: Mat) -> PetscErrorCode;
    fn KSPSetType(ksp: Ksp, kind: *const c_char) -> PetscErrorCode;
    fn KSPGetPC(ksp: Ksp, pc: *mut Pc) -> PetscErrorCode;
    fn PCSetType(pc: Pc, kind: *const c_char) -> PetscErrorCode;
    fn PCFactorSetMatSolverType(pc: Pc, kind: *const c_char) -> PetscErrorCode;
    fn KSPSetTolerances(
        ksp: Ksp,
        rtol: PetscReal,
        abstol: PetscReal,
        dtol: PetscReal,
        maxits: PetscInt,
    ) -> PetscErrorCode;
    fn KSPSetFromOptions(ksp: Ksp) -> PetscErrorCode;
    fn KSPSetNormType(ksp: Ksp, kind: c_int) -> PetscErrorCode;
    fn KSPSolve(ksp: Ksp, b: Vec_, x: Vec_) -> PetscErrorCode;
    fn KSPGetIterationNumber(ksp: Ksp, its: *mut PetscInt) -> PetscErrorCode;
    fn KSPGetConvergedReason(ksp: Ksp, reason: *mut c_int) -> PetscErrorCode;
    fn KSPGetResidualNorm(ksp: Ksp, norm: *mut PetscReal) -> PetscErrorCode;
    fn KSPGetType(ksp: Ksp, kind: *mut *const c_char) -> PetscErrorCode;
    fn PCGetType(pc: Pc, kind: *mut *const c_char) -> PetscErrorCode;
    fn PCFactorGetMatSolverType(pc: Pc, kind: *mut *const c_char) -> PetscErrorCode;
    fn KSPDestroy(ksp: *mut Ksp) -> PetscErrorCode;
}

/// A failed PETSc call: which one, PETSc's error code and its message.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("PETSc: {call} failed with error {code}: {message}")]
pub struct PetscError {
    /// The C function that failed.
    pub call: &'static str,
    /// PETSc's error code.
    pub code: i32,
    /// The message PETSc gave (empty when it gave none).
    pub message: String,
}

thread_local! {
    /// The first message of the error being raised (PETSc calls the
    /// handler again for each frame of its traceback, with the same code).
    static LAST_MESSAGE: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// PETSc's error handler: remember the message, print nothing, and let the
/// error code travel back to the caller.
unsafe extern "C" fn remember_error(
    _comm: MPI_Comm,
    line: c_int,
    function: *const c_char,
    _file: *const c_char,
    code: PetscErrorCode,
    _kind: c_int,
    message: *const c_char,
    _context: *mut c_void,
) -> PetscErrorCode {
    let text = |p: *const c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: PETSc passes NUL-terminated strings (or null).
            unsafe { CStr::from_ptr(p) }
                .to_string_lossy()
                .trim()
                .to_string()
        }
    };
    let message = text(message);
    let function = text(function);
    LAST_MESSAGE.with(|last| {
        let mut last = last.borrow_mut();
        if last.is_none() && !message.is_empty() {
            *last = Some(format!("{message} (in {function}, line {line})"));
        }
    });
    code
}

fn check(call: &'static str, code: PetscErrorCode) -> Result<(), PetscError> {
    let message = LAST_MESSAGE.with(|last| last.borrow_mut().take());
    if code == 0 {
        return Ok(());
    }
    Err(PetscError {
        call,
        code,
        message: message.unwrap_or_default(),
    })
}

fn c_string(call: &'static str, text: &str) -> Result<CString, PetscError> {
    CString::new(text).map_err(|_| PetscError {
        call,
        code: -1,
        message: format!("the text {text:?} contains a NUL byte"),
    })
}

/// PETSc, initialised on an MPI communicator that is already running.
/// Dropping it finalises PETSc (not MPI, which it did not start).
pub struct Petsc {
    comm: MPI_Comm,
}

impl Petsc {
    /// Initialise PETSc (reading `PETSC_OPTIONS` from the environment) and
    /// add `options` (e.g. `"-ksp_type cg -pc_type gamg"`) to its options
    /// database. Call once per process, after MPI is initialised.
    pub fn initialize(comm: MPI_Comm, options: &str) -> Result<Self, PetscError> {
        // SAFETY: see the module documentation; null argc/args/file/help are
        // allowed by PetscInitialize.
        unsafe {
            check(
                "PetscInitialize",
                PetscInitialize(
                    std::ptr::null_mut(),
                    std::ptr::null_mut(),
                    std::ptr::null(),
                    std::ptr::null(),
                ),
            )?;
            check(
                "PetscPushErrorHandler",
                PetscPushErrorHandler(remember_error, std::ptr::null_mut()),
            )?;
        }
        let petsc = Petsc { comm };
        if !options.trim().is_empty() {
            let text = c_string("PetscOptionsInsertString", options)?;
            // SAFETY: a null options database is PETSc's global one.
            unsafe {
                check(
                    "PetscOptionsInsertString",
                    PetscOptionsInsertString(std::ptr::null_mut(), text.as_ptr()),
                )?;
            }
        }
        Ok(petsc)
    }
}

impl Drop for Petsc {
    fn drop(&mut self) {
        // SAFETY: every object borrows the guard and is gone by now.
        unsafe {
            PetscFinalize();
        }
    }
}

/// A distributed sparse matrix (MPIAIJ on several ranks, SeqAIJ on one)
/// whose rows `first..first + rows` live on this rank.
pub struct Matrix<'p> {
    mat: Mat,
    _petsc: PhantomData<&'p Petsc>,
}

impl<'p> Matrix<'p> {
    /// An `rows`-row block of a `global`×`global` matrix, preallocated
    /// exactly: `diagonal[i]` entries of local row i in this rank's column
    /// block, `off_diagonal[i]` in the others'.
    pub fn new(
        petsc: &'p Petsc,
        rows: usize,
        global: usize,
        diagonal: &[i32],
        off_diagonal: &[i32],
    ) -> Result<Self, PetscError> {
        let mut mat: Mat = std::ptr::null_mut();
        let aij = c_string("MatSetType", "aij")?;
        // SAFETY: see the module documentation; the preallocation arrays
        // have one entry per local row.
        unsafe {
            check("MatCreate", MatCreate(petsc.comm, &mut mat))?;
            let matrix = Matrix {
                mat,
                _petsc: PhantomData,
            };
            check(
                "MatSetSizes",
                MatSetSizes(
                    mat,
                    rows as PetscInt,
                    rows as PetscInt,
                    global as PetscInt,
                    global as PetscInt,
                ),
            )?;
            check("MatSetType", MatSetType(mat, aij.as_ptr()))?;
            // One of the two applies (SeqAIJ on one rank, MPIAIJ on more);
            // PETSc ignores the other.
            check(
                "MatSeqAIJSetPreallocation",
                MatSeqAIJSetPreallocation(mat, 0, diagonal.as_ptr()),
            )?;
            check(
                "MatMPIAIJSetPreallocation",
                MatMPIAIJSetPreallocation(mat, 0, diagonal.as_ptr(), 0, off_diagonal.as_ptr()),
            )?;
            Ok(matrix)
        }
    }

    /// Set the entries of one (owned) row.
    pub fn set_row(&mut self, row: i32, columns: &[i32], values: &[f64]) -> Result<(), PetscError> {
        debug_assert_eq!(columns.len(), values.len());
        // SAFETY: one row index, and `columns`/`values` of equal length.
        unsafe {
            check(
                "MatSetValues",
                MatSetValues(
                    self.mat,
                    1,
                    &row,
                    columns.len() as PetscInt,
                    columns.as_ptr(),
                    values.as_ptr(),
                    INSERT_VALUES,
                ),
            )
        }
    }

    /// Finish the assembly (collective).
    pub fn assemble(&mut self) -> Result<(), PetscError> {
        // SAFETY: see the module documentation.
        unsafe {
            check(
                "MatAssemblyBegin",
                MatAssemblyBegin(self.mat, MAT_FINAL_ASSEMBLY),
            )?;
            check(
                "MatAssemblyEnd",
                MatAssemblyEnd(self.mat, MAT_FINAL_ASSEMBLY),
            )
        }
    }
}

impl Drop for Matrix<'_> {
    fn drop(&mut self) {
        // SAFETY: the wrapper owns `mat` and destroys it once.
        unsafe {
            MatDestroy(&mut self.mat);
        }
    }
}

/// A distributed vector with `rows` entries on this rank.
pub struct Vector<'p> {
    vec: Vec_,
    _petsc: PhantomData<&'p Petsc>,
}

impl<'p> Vector<'p> {
    /// Zeros, `rows` of them here, `global` in all.
    pub fn new(petsc: &'p Petsc, rows: usize, global: usize) -> Result<Self, PetscError> {
        let mut vec: Vec_ = std::ptr::null_mut();
        // SAFETY: see the module documentation.
        unsafe {
            check(
                "VecCreateMPI",
                VecCreateMPI(petsc.comm, rows as PetscInt, global as PetscInt, &mut vec),
            )?;
        }
        Ok(Vector {
            vec,
            _petsc: PhantomData,
        })
    }

    /// Add `values` at the global `rows` (collective assembly follows).
    pub fn add(&mut self, rows: &[i32], values: &[f64]) -> Result<(), PetscError> {
        debug_assert_eq!(rows.len(), values.len());
        // SAFETY: `rows` and `values` have equal lengths.
        unsafe {
            check(
                "VecSetValues",
                VecSetValues(
                    self.vec,
                    rows.len() as PetscInt,
                    rows.as_ptr(),
                    values.as_ptr(),
                    ADD_VALUES,
                ),
            )?;
            check("VecAssemblyBegin", VecAssemblyBegin(self.vec))?;
            check("VecAssemblyEnd", VecAssemblyEnd(self.vec))
        }
    }

    /// This rank's entries.
    pub fn local_values(&self) -> Result<Vec<f64>, PetscError> {
        let mut n: PetscInt = 0;
        let mut array: *const PetscScalar = std::ptr::null();
        // SAFETY: PETSc returns a view of `n` local entries, copied out
        // before the view is restored.
        unsafe {
            check("VecGetLocalSize", VecGetLocalSize(self.vec, &mut n))?;
            check("VecGetArrayRead", VecGetArrayRead(self.vec, &mut array))?;
            let values = if n > 0 && !array.is_null() {
                std::slice::from_raw_parts(array, n as usize).to_vec()
            } else {
                Vec::new()
            };
            check(
                "VecRestoreArrayRead",
                VecRestoreArrayRead(self.vec, &mut array),
            )?;
            Ok(values)
        }
    }
}

impl Drop for Vector<'_> {
    fn drop(&mut self) {
        // SAFETY: the wrapper owns `vec` and destroys it once.
        unsafe {
            VecDestroy(&mut self.vec);
        }
    }
}

/// How a KSP solve ended.
#[derive(Clone, Debug, PartialEq)]
pub struct KspReport {
    /// PETSc's Krylov method (`KSPGetType`).
    pub ksp: String,
    /// Its preconditioner (`PCGetType`), with the factorisation package
    /// in brackets for factor preconditioners (`cholesky (mumps)`).
    pub pc: String,
    /// Iterations taken.
    pub iterations: usize,
    /// `KSPConvergedReason`: positive converged, negative diverged.
    pub reason: i32,
    /// The last residual norm KSP measured.
    pub residual_norm: f64,
}

/// The default solver for a system: CG + GAMG, or a direct solve by MUMPS
/// (`preonly` + LU or Cholesky), before the user's options apply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Defaults {
    /// Conjugate gradients with algebraic multigrid, to a relative tolerance.
    Iterative {
        /// Relative residual tolerance.
        tolerance: f64,
    },
    /// A distributed direct factorisation by MUMPS.
    Direct {
        /// Cholesky (symmetric) instead of LU.
        cholesky: bool,
    },
}

/// Solve M x = b by KSP with the given defaults, overridden by the options
/// database (`[solver.petsc] options`, `PETSC_OPTIONS`). Returns this
/// rank's entries of x.
pub fn solve(
    petsc: &Petsc,
    matrix: &Matrix<'_>,
    rhs: &Vector<'_>,
    defaults: Defaults,
) -> Result<(Vec<f64>, KspReport), PetscError> {
    let mut ksp: Ksp = std::ptr::null_mut();
    // The solution vector has the rhs's layout.
    let mut local: PetscInt = 0;
    // SAFETY: see the module documentation.
    unsafe {
        check("VecGetLocalSize", VecGetLocalSize(rhs.vec, &mut local))?;
    }
    let x = {
        let mut vec: Vec_ = std::ptr::null_mut();
        // SAFETY: PETSC_DETERMINE (-1) lets PETSc sum the global size.
        unsafe {
            check(
                "VecCreateMPI",
                VecCreateMPI(petsc.comm, local, -1, &mut vec),
            )?;
        }
        Vector {
            vec,
            _petsc: PhantomData::<&Petsc>,
        }
    };
    // SAFETY: see the module documentation; `ksp` is destroyed below on
    // every path (the guard).
    unsafe {
        check("KSPCreate", KSPCreate(petsc.comm, &mut ksp))?;
    }
    let guard = KspGuard(ksp);
    let mut pc: Pc = std::ptr::null_mut();
    let (ksp_type, pc_type, solver_type) = match defaults {
        Defaults::Iterative { .. } => ("cg", "gamg", None),
        Defaults::Direct { cholesky } => (
            "preonly",
            if cholesky { "cholesky" } else { "lu" },
            Some("mumps"),
        ),
    };
    let ksp_type = c_string("KSPSetType", ksp_type)?;
    let pc_type = c_string("PCSetType", pc_type)?;
    let solver_type = solver_type
        .map(|s| c_string("PCFactorSetMatSolverType", s))
        .transpose()?;
    // SAFETY: see the module documentation.
    unsafe {
        check(
            "KSPSetOperators",
            KSPSetOperators(guard.0, matrix.mat, matrix.mat),
        )?;
        check("KSPSetType", KSPSetType(guard.0, ksp_type.as_ptr()))?;
        check("KSPGetPC", KSPGetPC(guard.0, &mut pc))?;
        check("PCSetType", PCSetType(pc, pc_type.as_ptr()))?;
        if let Some(s) = &solver_type {
            check(
                "PCFactorSetMatSolverType",
                PCFactorSetMatSolverType(pc, s.as_ptr()),
            )?;
        }
        if let Defaults::Iterative { tolerance } = defaults {
            check(
                "KSPSetTolerances",
                KSPSetTolerances(guard.0, tolerance, 0.0, PETSC_DEFAULT as f64, 10_000),
            )?;
            // The tolerance bounds ‖b − Mx‖ / ‖b‖, as hasse's own CG does,
            // not the preconditioned residual PETSc's CG measures by
            // default.
            check(
                "KSPSetNormType",
                KSPSetNormType(guard.0, KSP_NORM_UNPRECONDITIONED),
            )?;
        }
        check("KSPSetFromOptions", KSPSetFromOptions(guard.0))?;
        check("KSPSolve", KSPSolve(guard.0, rhs.vec, x.vec))?;
        let mut its: PetscInt = 0;
        let mut reason: c_int = 0;
        let mut norm: PetscReal = 0.0;
        let mut ksp_name: *const c_char = std::ptr::null();
        let mut pc_name: *const c_char = std::ptr::null();
        check(
            "KSPGetIterationNumber",
            KSPGetIterationNumber(guard.0, &mut its),
        )?;
        check(
            "KSPGetConvergedReason",
            KSPGetConvergedReason(guard.0, &mut reason),
        )?;
        check("KSPGetResidualNorm", KSPGetResidualNorm(guard.0, &mut norm))?;
        check("KSPGetType", KSPGetType(guard.0, &mut ksp_name))?;
        check("KSPGetPC", KSPGetPC(guard.0, &mut pc))?;
        check("PCGetType", PCGetType(pc, &mut pc_name))?;
        // Only factor preconditioners answer (PETSc's "try method"); the
        // others leave the name null.
        let mut package: *const c_char = std::ptr::null();
        check(
            "PCFactorGetMatSolverType",
            PCFactorGetMatSolverType(pc, &mut package),
        )?;
        let name = |p: *const c_char| {
            if p.is_null() {
                String::from("?")
            } else {
                CStr::from_ptr(p).to_string_lossy().into_owned()
            }
        };
        let report = KspReport {
            ksp: name(ksp_name),
            pc: if package.is_null() {
                name(pc_name)
            } else {
                format!("{} ({})", name(pc_name), name(package))
            },
            iterations: its.max(0) as usize,
            reason,
            residual_norm: norm,
        };
        Ok((x.local_values()?, report))
    }
}

/// Destroys a KSP on every path out of [`solve`].
struct KspGuard(Ksp);

impl Drop for KspGuard {
    fn drop(&mut self) {
        // SAFETY: the guard owns the KSP and destroys it once.
        unsafe {
            KSPDestroy(&mut self.0);
        }
    }
}
