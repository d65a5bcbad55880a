//! The `[mesh]` table of a case file: a generator with its parameters, or
//! a mesh file (Gmsh .msh v4 or hasse JSON) relative to the case file.
//!
//! ```toml
//! [mesh]
//! generator = "rectangle"   # interval | rectangle | box | annulus | torus | sphere | hollow-box | voronoi
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
//! or
//! ```toml
//! [mesh]
//! file = "l-shape.msh"
//! ```

use hasse_complex::{generate, gmsh, json, Complex};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// What went wrong while reading or building a mesh, with where.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Syntax { path: String, message: String },
    #[error("{path}: key `mesh.{key}`: {message}")]
    Key {
        path: String,
        key: &'static str,
        message: String,
    },
    #[error("{path}: {source}")]
    Complex {
        path: String,
        source: hasse_complex::ComplexError,
    },
    #[error(transparent)]
    Gmsh(#[from] gmsh::GmshError),
    #[error(transparent)]
    Json(#[from] json::JsonError),
}

/// The `[mesh]` table.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// Generator name (exclusive with `file`).
    pub generator: Option<String>,
    /// Mesh file, relative to the case file (exclusive with `generator`).
    pub file: Option<PathBuf>,
    /// Cells per axis (or per radial/angular direction).
    pub n: Option<Vec<usize>>,
    pub x: Option<[f64; 2]>,
    pub y: Option<[f64; 2]>,
    pub z: Option<[f64; 2]>,
    /// Geometric grading ratio per axis (spacing multiplies by it cell to cell).
    pub grading: Option<Vec<f64>>,
    /// "cuboid" (default) or "simplex".
    pub cells: Option<String>,
    pub perturb: Option<f64>,
    /// Seed of the perturbation, or of the Voronoi sites.
    pub seed: Option<u64>,
    /// Lloyd iterations of the Voronoi generator.
    pub lloyd: Option<usize>,
    /// Sphere radius.
    pub radius: Option<f64>,
    /// Icosphere subdivision levels.
    pub subdivisions: Option<u32>,
    pub inner_radius: Option<f64>,
    pub outer_radius: Option<f64>,
    pub major_radius: Option<f64>,
    pub minor_radius: Option<f64>,
    /// Cell index range [first, last] of the cavity (hollow-box).
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

impl MeshSpec {
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
                match full.extension().and_then(|e| e.to_str()) {
                    Some("msh") => gmsh::read_msh(&full).map_err(|e| key("file", e.to_string()))?,
                    Some("json") => json::read_json(&full).map_err(|e| key("file", e.to_string()))?,
                    _ => {
                        return Err(key(
                            "file",
                            format!(
                                "{}: unknown mesh format; use a Gmsh .msh (v4) or a hasse .json file",
                                full.display()
                            ),
                        ))
                    }
                }
            }
            (Some(name), None) => self.generate(name, &key).map_err(|e| match e {
                Generated::Key(k) => k,
                Generated::Complex(c) => complex_err(c),
            })?,
        };
        match self.perturb {
            Some(amplitude) if amplitude != 0.0 => {
                generate::perturb(&complex, amplitude, self.seed.unwrap_or(0)).map_err(complex_err)
            }
            _ => Ok(complex),
        }
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
                let n = self.counts(2, key).map_err(Generated::Key)?;
                generate::annulus(
                    need(self.inner_radius, "inner_radius")?,
                    need(self.outer_radius, "outer_radius")?,
                    n[0],
                    n[1],
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
            "voronoi" => {
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
                generate::voronoi(
                    n[0],
                    extent(self.x, "x")?,
                    extent(self.y, "y")?,
                    self.seed.unwrap_or(0),
                    self.lloyd.unwrap_or(0),
                )
                .map_err(Generated::Complex)
            }
            other => Err(Generated::Key(key(
                "generator",
                format!(
                    "unknown generator \"{other}\"; known: interval, rectangle, box, annulus, torus, sphere, hollow-box, voronoi"
                ),
            ))),
        }
    }
}

enum Generated {
    Key(MeshError),
    Complex(hasse_complex::ComplexError),
}
