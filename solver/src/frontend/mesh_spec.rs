//! The `[mesh]` table of a case file: a generator with its parameters, or
//! a mesh file (Gmsh .msh v4, hasse JSON or a LAR file `.lar.json`)
//! relative to the case file.
//!
//! ```toml
//! [mesh]
//! generator = "rectangle"   # interval | rectangle | box | annulus | torus | torus-flat | sphere | hollow-box | voronoi | delaunay
//! n = [32, 32]              # cells per axis
//! x = [0.0, 1.0]            # extent per axis (default [0, 1])
//! y = [0.0, 1.0]
//! cells = "simplex"         # "cuboid" (default) or "simplex" (Kuhn triangles / tetrahedra)
//! perturb = 0.2             # optional: move interior vertices by up to 0.2 × local h
//! seed = 7                  # seed of the perturbation (default 0)
//! ```
//! or a polygonal mesh, the Voronoi diagram of `n` random sites clipped
//! to the rectangle `x × y` (seeded, so the same table gives the same
//! mesh), optionally smoothed by `lloyd` iterations of Lloyd's algorithm:
//! ```toml
//! [mesh]
//! generator = "voronoi"
//! n = [400]                 # number of sites = number of polygons
//! x = [0.0, 1.0]
//! y = [0.0, 1.0]
//! seed = 3                  # site positions (default 0)
//! lloyd = 5                 # optional, default 0
//! ```
//! or a Delaunay triangulation of `n` random points in the rectangle
//! (seeded) and of points along its sides at about their spacing:
//! ```toml
//! [mesh]
//! generator = "delaunay"
//! n = [500]                 # interior points
//! x = [0.0, 1.0]
//! y = [0.0, 1.0]
//! seed = 3                  # point positions (default 0)
//! ```
//! or
//! ```toml
//! [mesh]
//! file = "l-shape.msh"
//! ```
//! or a complex in the LAR paper's representation (`V`, `EV`, `FV`, `CV`;
//! see `hasse_complex::lar_json`):
//! ```toml
//! [mesh]
//! file = "lar-fig2a.lar.json"
//! ```
//!
//! Every mesh with a boundary, generated or read (also a Gmsh file without
//! physical groups), has a `boundary` tag on the (n−1)-cells of its
//! boundary; a physical group named `boundary` takes precedence. Closed
//! surfaces (torus, sphere) have none.

use hasse_complex::{generate, gmsh, json, lar_json, Complex};
use serde::Deserialize;
use std::path::{Path, PathBuf};

pub use super::mesh_defects::{check_mesh, MeshDefect};

/// What went wrong while reading or building a mesh, with where.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The case file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The case file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The case file is not TOML, or has no usable `[mesh]` table.
    #[error("{path}: {message}")]
    Syntax {
        /// The case file.
        path: String,
        /// toml's message, with line and column, or what is missing.
        message: String,
    },
    /// A key of `[mesh]` has a value the generator cannot use, or the
    /// mesh file it names cannot be read or is defective.
    #[error("{path}: key `mesh.{key}`: {message}")]
    Key {
        /// The case file.
        path: String,
        /// The key, without `mesh.`.
        key: &'static str,
        /// What is wrong with its value.
        message: String,
    },
    /// The generator refused its parameters, or the perturbation failed.
    #[error("{path}: {source}")]
    Complex {
        /// The case file.
        path: String,
        /// The complex's error.
        source: hasse_complex::ComplexError,
    },
    /// A Gmsh file could not be read.
    #[error(transparent)]
    Gmsh(#[from] gmsh::GmshError),
    /// A hasse JSON complex could not be read.
    #[error(transparent)]
    Json(#[from] json::JsonError),
    /// A LAR file (`.lar.json`) could not be read.
    #[error(transparent)]
    Lar(#[from] lar_json::LarFileError),
}

/// Read a mesh file by its name: `.msh` (Gmsh v4), `.lar.json` (LAR) or
/// `.json` (hasse complex); `None` for any other name.
pub fn read_mesh_file(path: &Path) -> Option<Result<Complex, MeshError>> {
    if lar_json::is_lar_path(path) {
        return Some(lar_json::read_lar_json(path).map_err(MeshError::from));
    }
    match path.extension().and_then(|e| e.to_str()) {
        Some("msh") => Some(gmsh::read_msh(path).map_err(MeshError::from)),
        Some("json") => Some(json::read_json(path).map_err(MeshError::from)),
        _ => None,
    }
}

/// The `[mesh]` table (its keys are explained in the module
/// documentation and in `cases/README.md`).
///
/// ```
/// use hasse_solver::frontend::mesh_spec::MeshSpec;
/// use std::path::Path;
/// let spec = MeshSpec {
///     generator: Some("rectangle".into()),
///     n: Some(vec![3, 2]),
///     x: Some([0.0, 3.0]),
///     cells: Some("simplex".into()),
///     ..MeshSpec::default()
/// };
/// let k = spec.build(Path::new("demo.toml")).unwrap();
/// // 3 × 2 squares of Kuhn triangles on [0, 3] × [0, 1] (y defaults to [0, 1]).
/// assert_eq!(k.cell_counts(), vec![12, 23, 12]);
/// assert!((k.measure(2).iter().sum::<f64>() - 3.0).abs() < 1e-14);
/// ```
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// Generator name (exclusive with `file`).
    pub generator: Option<String>,
    /// Mesh file, relative to the case file (exclusive with `generator`).
    pub file: Option<PathBuf>,
    /// Cells per axis (or per radial/angular direction).
    pub n: Option<Vec<usize>>,
    /// Extent `[lo, hi]` along x (default `[0, 1]`).
    pub x: Option<[f64; 2]>,
    /// Extent along y (default `[0, 1]`).
    pub y: Option<[f64; 2]>,
    /// Extent along z (default `[0, 1]`).
    pub z: Option<[f64; 2]>,
    /// Geometric grading ratio per axis (spacing multiplies by it cell to cell).
    pub grading: Option<Vec<f64>>,
    /// "cuboid" (default) or "simplex".
    pub cells: Option<String>,
    /// Move interior vertices randomly by up to this fraction of the local
    /// mesh size (default 0).
    pub perturb: Option<f64>,
    /// Seed of the perturbation, or of the Voronoi sites / Delaunay points.
    pub seed: Option<u64>,
    /// Lloyd iterations of the Voronoi generator.
    pub lloyd: Option<usize>,
    /// Sphere radius.
    pub radius: Option<f64>,
    /// Icosphere subdivision levels.
    pub subdivisions: Option<u32>,
    /// Annulus inner radius.
    pub inner_radius: Option<f64>,
    /// Annulus outer radius.
    pub outer_radius: Option<f64>,
    /// Torus radius of the centre circle (larger than `minor_radius`).
    pub major_radius: Option<f64>,
    /// Torus radius of the tube.
    pub minor_radius: Option<f64>,
    /// Cell index range `[first, end)` of the cavity, the same on every
    /// axis (hollow-box; half-open, inside the box).
    pub cavity: Option<[usize; 2]>,
}

/// Only the `[mesh]` table is read here; deserialising it in place (not
/// through a `toml::Value`) keeps toml's line and column in messages.
#[derive(Deserialize)]
struct CaseMeshOnly {
    mesh: Option<MeshSpec>,
}

/// Read the `[mesh]` table of a case file (other tables are left to the
/// case reader).
pub fn read_case_mesh(path: &Path) -> Result<MeshSpec, MeshError> {
    let shown = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| MeshError::Io {
        path: shown.clone(),
        source,
    })?;
    let case: CaseMeshOnly = toml::from_str(&text).map_err(|e| MeshError::Syntax {
        path: shown.clone(),
        message: e.to_string(),
    })?;
    case.mesh.ok_or_else(|| MeshError::Syntax {
        path: shown,
        message: "no [mesh] table: add one with `generator = ...` or `file = ...`".into(),
    })
}

/// The field names of a struct as serde reads them: the names it passes
/// to `deserialize_struct`, caught by a deserializer that reads nothing
/// else. So the list of `[mesh]` keys is `MeshSpec`'s fields, not a copy.
fn struct_fields<T: for<'de> Deserialize<'de>>() -> &'static [&'static str] {
    struct Fields(Option<&'static [&'static str]>);
    #[derive(Debug)]
    struct Stop;
    impl std::fmt::Display for Stop {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("field names read")
        }
    }
    impl std::error::Error for Stop {}
    impl serde::de::Error for Stop {
        fn custom<M: std::fmt::Display>(_: M) -> Self {
            Stop
        }
    }
    impl<'de> serde::Deserializer<'de> for &mut Fields {
        type Error = Stop;
        fn deserialize_any<V: serde::de::Visitor<'de>>(self, _: V) -> Result<V::Value, Stop> {
            Err(Stop)
        }
        fn deserialize_struct<V: serde::de::Visitor<'de>>(
            self,
            _name: &'static str,
            fields: &'static [&'static str],
            _visitor: V,
        ) -> Result<V::Value, Stop> {
            self.0 = Some(fields);
            Err(Stop)
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
            bytes byte_buf option unit unit_struct newtype_struct seq tuple
            tuple_struct map enum identifier ignored_any
        }
    }
    let mut fields = Fields(None);
    let _ = T::deserialize(&mut fields);
    fields.0.unwrap_or(&[])
}

impl MeshSpec {
    /// The keys of the `[mesh]` table: `MeshSpec`'s fields.
    ///
    /// ```
    /// use hasse_solver::frontend::mesh_spec::MeshSpec;
    /// let mut keys = MeshSpec::keys().to_vec();
    /// keys.sort_unstable();
    /// assert_eq!(keys, [
    ///     "cavity", "cells", "file", "generator", "grading", "inner_radius", "lloyd",
    ///     "major_radius", "minor_radius", "n", "outer_radius", "perturb", "radius", "seed",
    ///     "subdivisions", "x", "y", "z",
    /// ]);
    /// ```
    pub fn keys() -> &'static [&'static str] {
        struct_fields::<MeshSpec>()
    }

    /// Build the complex; `case_path` names the case file in messages and
    /// anchors relative mesh paths.
    pub fn build(&self, case_path: &Path) -> Result<Complex, MeshError> {
        let shown = case_path.display().to_string();
        let key = |key: &'static str, message: String| MeshError::Key {
            path: shown.clone(),
            key,
            message,
        };
        let complex_err = |source| MeshError::Complex {
            path: shown.clone(),
            source,
        };
        let complex = match (&self.generator, &self.file) {
            (Some(_), Some(_)) => {
                return Err(key(
                    "file",
                    "give either `generator` or `file`, not both".into(),
                ))
            }
            (None, None) => {
                return Err(key(
                    "generator",
                    "missing: set `generator = \"rectangle\"` (or another generator) or `file = \"mesh.msh\"`".into(),
                ))
            }
            (None, Some(file)) => {
                let base = case_path.parent().unwrap_or(Path::new("."));
                let full = base.join(file);
                let read = match read_mesh_file(&full) {
                    Some(read) => read.map_err(|e| key("file", e.to_string()))?,
                    None => {
                        return Err(key(
                            "file",
                            format!(
                                "{}: unknown mesh format; use a Gmsh .msh (v4), a LAR .lar.json or a hasse .json file",
                                full.display()
                            ),
                        ))
                    }
                };
                check_mesh(&read).map_err(|e| key("file", format!("{}: {e}", full.display())))?;
                read
            }
            (Some(name), None) => {
                if let Some(estimate) = self.estimate(name) {
                    estimate.check().map_err(|message| key(estimate.key, message))?;
                }
                self.generate(name, &key).map_err(|e| match e {
                Generated::Key(k) => k,
                Generated::Complex(c) => complex_err(c),
            })?
            }
        };
        let mut complex = match self.perturb {
            Some(amplitude) if amplitude != 0.0 => {
                generate::perturb(&complex, amplitude, self.seed.unwrap_or(0))
                    .map_err(complex_err)?
            }
            _ => complex,
        };
        tag_boundary(&mut complex);
        Ok(complex)
    }

    /// A lower bound on what a generated mesh costs, from its parameters
    /// alone (nothing is built), or `None` when the parameters are invalid
    /// (generation reports them).
    pub fn estimate(&self, generator: &str) -> Option<MemoryEstimate> {
        let n: Vec<f64> = self.n.as_deref()?.iter().map(|&k| k as f64).collect();
        let simplex = self.cells.as_deref() == Some("simplex");
        // Top cells, cells of every dimension per top cell, dimension.
        let (top, per_top, dim, key) = match (generator, n.as_slice()) {
            ("interval", [a]) => (*a, 2.0, 1, "n"),
            // Kuhn: 2 triangles per square (6 cells of all dimensions per
            // square: 1 vertex, 3 edges, 2 triangles), 6 tetrahedra per cube
            // (1 + 7 + 12 + 6 = 26 cells).
            ("rectangle", [a, b]) if simplex => (2.0 * a * b, 3.0, 2, "n"),
            ("torus-flat", [a, b]) if simplex => (2.0 * a * b, 3.0, 2, "n"),
            ("rectangle" | "annulus" | "torus" | "torus-flat", [a, b]) => (a * b, 4.0, 2, "n"),
            ("box" | "torus-flat", [a, b, c]) if simplex => (6.0 * a * b * c, 26.0 / 6.0, 3, "n"),
            ("box" | "torus-flat", [a, b, c]) => (a * b * c, 8.0, 3, "n"),
            ("voronoi", [a]) => (*a, 6.0, 2, "n"),
            // About 2 triangles per point, 1 + 3 + 2 cells per point.
            ("delaunay", [a]) => (2.0 * a, 3.0, 2, "n"),
            ("sphere", _) => (
                20.0 * 4f64.powi(self.subdivisions.unwrap_or(2).min(64) as i32),
                3.0,
                2,
                "subdivisions",
            ),
            _ => return None,
        };
        let cells = top * per_top;
        // The sparsest system any method builds: a two-point stencil, 2n + 1
        // entries per top cell.
        let nonzeros = top * (2 * dim + 1) as f64;
        Some(MemoryEstimate {
            key,
            top_cells: top,
            cells,
            nonzeros,
            bytes: BYTES_PER_CELL * cells + BYTES_PER_NONZERO * nonzeros,
        })
    }

    fn counts(
        &self,
        wanted: usize,
        key: &dyn Fn(&'static str, String) -> MeshError,
    ) -> Result<Vec<usize>, MeshError> {
        let n = self.n.clone().ok_or_else(|| {
            key(
                "n",
                format!(
                    "missing: give {wanted} cell count(s), e.g. n = {:?}",
                    vec![8; wanted]
                ),
            )
        })?;
        if n.len() != wanted {
            return Err(key(
                "n",
                format!("expected {wanted} cell count(s), found {}", n.len()),
            ));
        }
        if n.contains(&0) {
            return Err(key("n", "cell counts must be at least 1".into()));
        }
        Ok(n)
    }

    fn axes(
        &self,
        counts: &[usize],
        key: &dyn Fn(&'static str, String) -> MeshError,
    ) -> Result<Vec<Vec<f64>>, Generated> {
        let extents = [self.x, self.y, self.z];
        let names = ["x", "y", "z"];
        let mut axes = Vec::new();
        for (a, &n) in counts.iter().enumerate() {
            let [lo, hi] = extents[a].unwrap_or([0.0, 1.0]);
            if lo.is_nan() || hi.is_nan() || lo >= hi {
                return Err(Generated::Key(key(
                    names[a],
                    format!("extent [{lo}, {hi}] must be increasing"),
                )));
            }
            let axis = match self.grading.as_ref().and_then(|g| g.get(a)) {
                Some(&ratio) => generate::graded_axis(n, lo, hi, ratio),
                None => generate::uniform_axis(n, lo, hi),
            };
            axes.push(axis.map_err(Generated::Complex)?);
        }
        Ok(axes)
    }

    fn generate(
        &self,
        name: &str,
        key: &dyn Fn(&'static str, String) -> MeshError,
    ) -> Result<Complex, Generated> {
        let need = |v: Option<f64>, k: &'static str| {
            v.ok_or_else(|| Generated::Key(key(k, "missing: this generator needs it".into())))
        };
        let simplicial = match self.cells.as_deref() {
            None | Some("cuboid") => false,
            Some("simplex") => true,
            Some(other) => {
                return Err(Generated::Key(key(
                    "cells",
                    format!("unknown cell kind \"{other}\": use \"cuboid\" or \"simplex\""),
                )))
            }
        };
        let grid = |dim: usize| -> Result<Complex, Generated> {
            let counts = self.counts(dim, key).map_err(Generated::Key)?;
            let axes = self.axes(&counts, key)?;
            if simplicial {
                generate::kuhn(&axes).map_err(Generated::Complex)
            } else {
                generate::grid(&axes).map_err(Generated::Complex)
            }
        };
        match name {
            "interval" => grid(1),
            "rectangle" => grid(2),
            "box" => grid(3),
            "annulus" => {
                // n = [angular, radial] (cases/README.md); the generator
                // takes the radial count first.
                let n = self.counts(2, key).map_err(Generated::Key)?;
                generate::annulus(
                    need(self.inner_radius, "inner_radius")?,
                    need(self.outer_radius, "outer_radius")?,
                    n[1],
                    n[0],
                )
                .map_err(Generated::Complex)
            }
            "torus" => {
                let n = self.counts(2, key).map_err(Generated::Key)?;
                generate::torus(
                    need(self.major_radius, "major_radius")?,
                    need(self.minor_radius, "minor_radius")?,
                    n[0],
                    n[1],
                )
                .map_err(Generated::Complex)
            }
            "torus-flat" => {
                // The rectangle x × y with opposite sides identified; the
                // flat metric comes from each cell's unwrapped points.
                // n = [nx, ny] or [nx, ny, nz] (the periodic box).
                let wanted = match self.n.as_deref() {
                    Some([_, _, _]) => 3,
                    _ => 2,
                };
                let n = self.counts(wanted, key).map_err(Generated::Key)?;
                let extent = |e: Option<[f64; 2]>| e.unwrap_or([0.0, 1.0]);
                let built = match *n.as_slice() {
                    [nx, ny, nz] => generate::torus_flat_box(
                        [nx, ny, nz],
                        [extent(self.x), extent(self.y), extent(self.z)],
                        simplicial,
                    ),
                    _ => generate::torus_flat(n[0], n[1], extent(self.x), extent(self.y), simplicial),
                };
                built.map_err(|e| Generated::Key(key("n", e.to_string())))
            }
            "sphere" => generate::sphere(
                self.radius.unwrap_or(1.0),
                self.subdivisions.unwrap_or(2),
            )
            .map_err(Generated::Complex),
            "hollow-box" => {
                let n = self.counts(1, key).map_err(Generated::Key)?;
                let cavity = self.cavity.ok_or_else(|| {
                    Generated::Key(key(
                        "cavity",
                        "missing: give the cavity's cell index range, e.g. cavity = [2, 3]".into(),
                    ))
                })?;
                generate::hollow_box(n[0], cavity).map_err(Generated::Complex)
            }
            "voronoi" | "delaunay" => {
                let n = self.counts(1, key).map_err(Generated::Key)?;
                let extent = |e: Option<[f64; 2]>, k: &'static str| {
                    let [lo, hi] = e.unwrap_or([0.0, 1.0]);
                    if lo.is_nan() || hi.is_nan() || lo >= hi {
                        return Err(Generated::Key(key(
                            k,
                            format!("extent [{lo}, {hi}] must be increasing"),
                        )));
                    }
                    Ok([lo, hi])
                };
                let (x, y) = (extent(self.x, "x")?, extent(self.y, "y")?);
                let seed = self.seed.unwrap_or(0);
                if name == "voronoi" {
                    generate::voronoi(n[0], x, y, seed, self.lloyd.unwrap_or(0))
                } else if self.lloyd.is_some() {
                    return Err(Generated::Key(key(
                        "lloyd",
                        "Lloyd smoothing is for generator = \"voronoi\"; remove it".into(),
                    )));
                } else {
                    generate::delaunay_rectangle(n[0], x, y, seed)
                }
                .map_err(Generated::Complex)
            }
            other => Err(Generated::Key(key(
                "generator",
                format!(
                    "unknown generator \"{other}\"; known: interval, rectangle, box, annulus, torus, torus-flat, sphere, hollow-box, voronoi, delaunay"
                ),
            ))),
        }
    }
}

/// Give `complex` the tag `boundary` (the (n−1)-cells on exactly one top
/// cell, the top cells of its boundary subcomplex) when it has none and
/// its boundary is not empty, so that boundary conditions on `boundary`
/// work on every mesh: a Gmsh file without physical groups has no tags at
/// all. An existing `boundary` tag (a physical group of that name) is
/// kept.
///
/// ```
/// use hasse_complex::{Complex, TopCells, Vertices};
/// use hasse_solver::frontend::mesh_spec::tag_boundary;
/// // Two triangles of the unit square, built without tags: the four sides
/// // are the boundary, the diagonal is not.
/// let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]).unwrap();
/// let mut k = Complex::build(v, TopCells::simplices([[0, 1, 2], [0, 2, 3]])).unwrap();
/// assert!(k.tag("boundary").is_none());
/// tag_boundary(&mut k);
/// let tag = k.tag("boundary").unwrap();
/// assert_eq!((tag.dim, tag.cells.len()), (1, 4));
/// ```
pub fn tag_boundary(complex: &mut Complex) {
    let n = complex.dim();
    if n == 0 || complex.tag("boundary").is_some() {
        return;
    }
    let facets: Vec<usize> = complex
        .boundary(n)
        .outer_iterator()
        .enumerate()
        .filter(|(_, row)| row.nnz() == 1)
        .map(|(i, _)| i)
        .collect();
    if !facets.is_empty() {
        // The dimension is in range and the facets are rows of ∂_n.
        let _ = complex.set_tag("boundary", n - 1, facets);
    }
}

/// Bytes per cell (any dimension) of a built complex with its geometry:
/// about 130 measured on a 500 × 500 rectangle (`hasse info --timing`);
/// rounded down, as the estimate is a lower bound.
const BYTES_PER_CELL: f64 = 100.0;
/// A value and a row index of a sparse matrix.
const BYTES_PER_NONZERO: f64 = 16.0;

/// What a generated mesh will at least cost, before it is built.
///
/// ```
/// use hasse_solver::frontend::mesh_spec::MeshSpec;
/// let spec = MeshSpec { generator: Some("rectangle".into()), n: Some(vec![100, 100]), ..MeshSpec::default() };
/// let estimate = spec.estimate("rectangle").unwrap();
/// // 10⁴ squares, ≈ 4 cells of all dimensions and 5 nonzeros each.
/// assert_eq!((estimate.top_cells, estimate.cells, estimate.nonzeros), (1e4, 4e4, 5e4));
/// assert_eq!(estimate.bytes, 100.0 * 4e4 + 16.0 * 5e4);
/// // Under a 1 MB limit the mesh is refused before it is built.
/// std::env::set_var("HASSE_MEMORY_LIMIT", "1000000");
/// assert!(estimate.check().unwrap_err().contains("use a smaller mesh.n"));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryEstimate {
    /// The `[mesh]` key that sets the size.
    pub key: &'static str,
    /// Top cells the mesh will have.
    pub top_cells: f64,
    /// Cells of every dimension.
    pub cells: f64,
    /// Nonzeros of the sparsest system a method assembles on it.
    pub nonzeros: f64,
    /// Lower bound on the memory needed to build and solve.
    pub bytes: f64,
}

impl MemoryEstimate {
    /// Refuse, with the numbers, an estimate above the memory available:
    /// `HASSE_MEMORY_LIMIT` (bytes) if set, else MemAvailable of
    /// /proc/meminfo; no check where neither is known.
    pub fn check(&self) -> Result<(), String> {
        let Some((available, source)) = available_memory() else {
            return Ok(());
        };
        if self.bytes <= available as f64 {
            return Ok(());
        }
        Err(format!(
            "this mesh would have {:.3e} top cells ({:.3e} cells of all dimensions, at least {:.3e} nonzeros in the system): at least {} of memory, but {} is available ({source}); use a smaller mesh.{}",
            self.top_cells,
            self.cells,
            self.nonzeros,
            human_bytes(self.bytes),
            human_bytes(available as f64),
            self.key,
        ))
    }
}

/// Memory the process may still use, and where the number comes from.
pub(crate) fn available_memory() -> Option<(u64, &'static str)> {
    if let Some(limit) = std::env::var("HASSE_MEMORY_LIMIT")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
    {
        return Some((limit, "HASSE_MEMORY_LIMIT"));
    }
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = meminfo.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some((kib.saturating_mul(1024), "MemAvailable in /proc/meminfo"))
}

pub(crate) fn human_bytes(bytes: f64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut value = bytes;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < units.len() {
        value /= 1024.0;
        unit += 1;
    }
    format!("{value:.1} {}", units[unit])
}

enum Generated {
    Key(MeshError),
    Complex(hasse_complex::ComplexError),
}

#[cfg(test)]
mod tests {
    use super::*;

    fn annulus(n: [usize; 2]) -> Result<Complex, MeshError> {
        MeshSpec {
            generator: Some("annulus".into()),
            n: Some(n.to_vec()),
            inner_radius: Some(0.5),
            outer_radius: Some(1.0),
            ..MeshSpec::default()
        }
        .build(Path::new("annulus.toml"))
    }

    /// `n = [angular, radial]` as cases/README.md documents it. By hand,
    /// for a sectors and r rings of quads: a(r + 1) vertices on r + 1
    /// circles, a·r radial edges plus a(r + 1) circular edges, a·r quads.
    #[test]
    fn annulus_reads_n_as_angular_then_radial() {
        let k = annulus([16, 4]).unwrap();
        assert_eq!(k.cell_counts(), vec![16 * 5, 16 * 4 + 16 * 5, 16 * 4]);
        assert_eq!(k.cell_counts(), vec![80, 144, 64]);
        // Each of the two boundary circles has one edge per sector.
        assert_eq!(k.tag("inner").unwrap().cells.len(), 16);
        assert_eq!(k.tag("outer").unwrap().cells.len(), 16);
        // Two rings are a valid annulus (two sectors would not be).
        assert_eq!(annulus([16, 2]).unwrap().cell_counts(), vec![48, 80, 32]);
        assert!(annulus([2, 16]).is_err());
    }
}
