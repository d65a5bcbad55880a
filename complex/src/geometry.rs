//! Geometry of every cell: measures, centroids, normals, circumcentres.
//!
//! Every quantity is computed on first use, in parallel over cells, and
//! cached in the complex. Each cell is computed on its own, with its sums in
//! a fixed order, so the results are bit-for-bit the same whatever the
//! number of threads.
//!
//! # Measures and centroids: the cone decomposition
//!
//! A p-cell c is split into cones from its apex a (the average of its
//! vertices) over its facets, |c| = (1/p) Σ_{f ∈ ∂c} |f| h_f with h_f the
//! distance from a to the affine hull of f, and its centroid is the
//! volume-weighted average of the cone centroids
//! a + p/(p+1) (centroid_f − a). Applied bottom-up this is the
//! decomposition of c into the simplices (apex of c, apex of f, edge) —
//! triangles (a, v₀, v₁) for a polygon, tetrahedra (a_c, a_f, v₀, v₁) for a
//! polyhedron — which is what is computed:
//!
//! - convex polytopes with planar faces (every simplex, polygon, polyhedron,
//!   and every affine image of a square or cube): exact, in any embedding;
//! - non-planar quadrilaterals and polygons embedded in R³ (e.g. the quads
//!   of a torus surface): the area is that of the triangle fan from the
//!   vertex average, Σ_e ½ |e| dist(a, line e);
//! - 3-cells with non-planar faces (e.g. a jittered hexahedral grid): the
//!   volume of the solid bounded by the faces triangulated as fans from
//!   their vertex averages, Σ_f ⅓ (a_f − a_c)·A_f with A_f the vector area
//!   of the fan. Neighbouring cells triangulate their shared face the same
//!   way, so these volumes add up exactly to the volume of their union.

use crate::complex::Complex;
use crate::error::{ComplexError, Result};
use crate::frame::{self, Point};
use crate::lar::Lar;
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use sprs::CsMat;
use std::borrow::Cow;
use std::ops::Range;
use std::sync::{Arc, OnceLock};

/// Highest cell dimension a complex can have (the embedding is at most R³).
const LEVELS: usize = 4;

/// Lazily computed geometric quantities of a complex.
#[derive(Clone, Debug, Default)]
pub(crate) struct GeometryCache {
    /// ∂_p in CSC storage (index p ≥ 1): the facets of each p-cell.
    /// Shared, so that operators built on ∂_p by columns use it in place.
    pub(crate) facets: [OnceLock<Arc<CsMat<i8>>>; LEVELS],
    /// δ^p = ∂_{p+1}ᵀ in CSR storage (index p), shared with the operators
    /// that use it as their A.
    pub(crate) coboundaries: [OnceLock<Arc<CsMat<i8>>>; LEVELS],
    /// Measures and centroids of the p-cells.
    cells: [OnceLock<CellGeometry>; LEVELS],
    /// Unit normals of the (n−1)-cells.
    normals: OnceLock<Vec<f64>>,
    /// Circumcentres of simplicial p-cells.
    circumcentres: [OnceLock<Vec<f64>>; LEVELS],
    /// Largest top-cell diameter.
    mesh_size: OnceLock<f64>,
}

#[derive(Clone, Debug, Default)]
struct CellGeometry {
    measure: Vec<f64>,
    /// Stride d.
    centroid: Vec<f64>,
}

impl Complex {
    /// Measure (length, area, volume) of every p-cell; 1 for vertices and an
    /// empty slice for p > n.
    ///
    /// Exact for convex polytopes; non-planar cells are measured through the
    /// cone decomposition described in the [module documentation](self).
    ///
    /// ```
    /// use hasse_complex::{Complex, TopCells, Vertices};
    /// let v = Vertices::from_points(&[[0.0, 0.0], [2.0, 0.0], [0.0, 1.0], [2.0, 1.0]]).unwrap();
    /// let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
    /// assert_eq!(k.measure(2), &[2.0]);
    /// let mut lengths = k.measure(1).to_vec();
    /// lengths.sort_by(f64::total_cmp);
    /// assert_eq!(lengths, vec![1.0, 1.0, 2.0, 2.0]);
    /// ```
    pub fn measure(&self, p: usize) -> &[f64] {
        self.cell_geometry(p).map_or(&[], |g| &g.measure)
    }

    /// Centre of mass of every p-cell, row by row with stride
    /// d = [`Complex::embedding_dim`]; an empty slice for p > n.
    ///
    /// ```
    /// use hasse_complex::{Complex, TopCells, Vertices};
    /// // A trapezoid with parallel sides 2 (y = 0) and 1 (y = 1).
    /// let v = Vertices::from_points(&[[0.0, 0.0], [2.0, 0.0], [1.5, 1.0], [0.5, 1.0]]).unwrap();
    /// let k = Complex::build(v, TopCells::polygons([[0, 1, 2, 3]])).unwrap();
    /// let c = k.centroid_of(2, 0);
    /// assert!((c[0] - 1.0).abs() < 1e-15 && (c[1] - 4.0 / 9.0).abs() < 1e-15);
    /// ```
    pub fn centroid(&self, p: usize) -> &[f64] {
        self.cell_geometry(p).map_or(&[], |g| &g.centroid)
    }

    /// Measure and centroid (stride d) of the listed p-cells alone, in
    /// list order, equal to the entries of [`Complex::measure`] and
    /// [`Complex::centroid`]: read from them when they were computed, else
    /// computed for these cells only (a boundary condition on the few
    /// thousand boundary faces of a nodal problem needs their areas, not
    /// those of the million faces inside). A cell id beyond the p-cells is
    /// an error naming it.
    ///
    /// ```
    /// use hasse_complex::generate::rectangle;
    /// let k = rectangle(2, 1, [0.0, 4.0], [0.0, 1.0]).unwrap();
    /// let (measure, centroid) = k.geometry_of(2, &[1]).unwrap();
    /// assert_eq!(measure, vec![2.0]);
    /// assert_eq!(centroid, k.centroid_of(2, 1));
    /// assert!(k.geometry_of(2, &[2]).is_err());
    /// ```
    pub fn geometry_of(&self, p: usize, cells: &[usize]) -> Result<(Vec<f64>, Vec<f64>)> {
        let count = self.cell_count(p);
        if let Some(&i) = cells.iter().find(|&&i| i >= count) {
            return Err(ComplexError::Invalid(format!(
                "{p}-cell {i} does not exist: the complex has {count} {p}-cells (ids start at 0)"
            )));
        }
        let d = self.embedding_dim();
        let mut measure = Vec::with_capacity(cells.len());
        let mut centroid = Vec::with_capacity(cells.len() * d);
        match self.geometry.cells.get(p).and_then(OnceLock::get) {
            Some(all) => {
                for &i in cells {
                    measure.push(all.measure[i]);
                    centroid.extend_from_slice(&all.centroid[i * d..(i + 1) * d]);
                }
            }
            None => {
                let mesh = Mesh::new(self);
                for &i in cells {
                    let (m, c) = mesh.cell(p, i);
                    measure.push(m);
                    centroid.extend_from_slice(&c[..d]);
                }
            }
        }
        Ok((measure, centroid))
    }

    /// Centroid of p-cell `i` (an empty slice when it does not exist).
    pub fn centroid_of(&self, p: usize, i: usize) -> &[f64] {
        let d = self.embedding_dim();
        self.centroid(p).get(i * d..(i + 1) * d).unwrap_or(&[])
    }

    /// Unit normal of every (n−1)-cell, stride d, consistent with ∂_n: it
    /// points out of every top cell c with ∂_n(f, c) = +1 and into those
    /// with −1.
    ///
    /// For each top cell c on f, ν_{f,c} is the unit normal of f inside the
    /// span of c pointing away from c's centroid; the normal of f is
    /// normalize(Σ_c ∂_n(f, c) ν_{f,c}). In a flat complex (n = d) this is
    /// the normal of f; on an embedded surface it is tangent to the surface
    /// (the average of the two in-plane normals), and for a curve (n = 1)
    /// it is ± the tangent. For a non-planar face of a 3-cell, ν is the
    /// direction of the face's vector area.
    ///
    /// ```
    /// use hasse_complex::{Complex, TopCells, Vertices};
    /// let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
    /// let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
    /// // Edge {0,1} lies on y = 0 and enters ∂ with +1: its normal is (0, −1).
    /// let e = k.find_cell(1, &[0, 1]).unwrap();
    /// assert_eq!(k.boundary(2).get(e, 0), Some(&1));
    /// assert_eq!(&k.normal()[2 * e..2 * e + 2], &[0.0, -1.0]);
    /// ```
    pub fn normal(&self) -> &[f64] {
        self.geometry.normals.get_or_init(|| self.compute_normals())
    }

    /// Circumcentre of every p-cell (stride d), computed in the simplex's
    /// own affine span, so it works for simplices embedded in a higher
    /// dimensional space. Only simplices have one: the error names the
    /// first p-cell that is not a simplex. Empty for p > n.
    ///
    /// ```
    /// use hasse_complex::{Complex, TopCells, Vertices};
    /// let v = Vertices::from_points(&[[0.0, 0.0], [4.0, 0.0], [0.0, 2.0]]).unwrap();
    /// let k = Complex::build(v, TopCells::simplices([[0, 1, 2]])).unwrap();
    /// // Right angle at the origin: the circumcentre is the hypotenuse midpoint.
    /// assert_eq!(k.circumcentre(2).unwrap(), &[2.0, 1.0]);
    /// ```
    pub fn circumcentre(&self, p: usize) -> Result<&[f64]> {
        if p > self.dim() {
            return Ok(&[]);
        }
        let slot = &self.geometry.circumcentres[p];
        if let Some(c) = slot.get() {
            return Ok(c);
        }
        if let Some(i) = (0..self.cell_count(p)).find(|&i| self.cell_vertices(p, i).len() != p + 1)
        {
            let vertices = self.cell_vertices(p, i);
            return Err(ComplexError::Invalid(format!(
                "{p}-cell {i} (vertices {vertices:?}) has {} vertices, not {}: circumcentres exist only for simplices",
                vertices.len(),
                p + 1
            )));
        }
        let centres = self.compute_circumcentres(p)?;
        Ok(slot.get_or_init(|| centres))
    }

    /// The largest diameter (largest distance between two of its vertices)
    /// of a top cell.
    ///
    /// ```
    /// use hasse_complex::{Complex, TopCells, Vertices};
    /// let v = Vertices::from_points(&[[0.0, 0.0], [3.0, 0.0], [0.0, 4.0], [3.0, 4.0]]).unwrap();
    /// let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
    /// assert_eq!(k.mesh_size(), 5.0);
    /// ```
    pub fn mesh_size(&self) -> f64 {
        *self.geometry.mesh_size.get_or_init(|| {
            let n = self.dim();
            let vertices = self.vertices();
            let largest_squared = (0..self.cell_count(n))
                .into_par_iter()
                .map(|c| {
                    let cell = self.cell_vertices(n, c);
                    let mut largest: f64 = 0.0;
                    for (k, &a) in cell.iter().enumerate() {
                        let x = frame::point(vertices, a);
                        for &b in &cell[k + 1..] {
                            let y = vertices.nearest(&frame::point(vertices, b), &x);
                            let r = Vector3::from(y) - Vector3::from(x);
                            largest = largest.max(r.norm_squared());
                        }
                    }
                    largest
                })
                .reduce(|| 0.0, f64::max);
            largest_squared.sqrt()
        })
    }

    fn cell_geometry(&self, p: usize) -> Option<&CellGeometry> {
        (p <= self.dim()).then(|| self.geometry.cells[p].get_or_init(|| self.compute_cells(p)))
    }

    fn compute_cells(&self, p: usize) -> CellGeometry {
        let d = self.embedding_dim();
        let count = self.cell_count(p);
        let mut measure = vec![0.0; count];
        let mut centroid = vec![0.0; count * d];
        let mesh = Mesh::new(self);
        let write = |(i, (m, c)): (usize, (&mut f64, &mut [f64]))| {
            let (mi, ci) = mesh.cell(p, i);
            *m = mi;
            c.copy_from_slice(&ci[..d]);
        };
        measure
            .par_iter_mut()
            .zip(centroid.par_chunks_mut(d))
            .enumerate()
            .for_each(write);
        CellGeometry { measure, centroid }
    }

    /// The points of p-cell `i`'s vertices (in the order of
    /// [`Complex::cell_vertices`]), padded to three coordinates; on a flat
    /// torus each is the image nearest the first vertex, so the cell is
    /// seen unwrapped. Per-cell metrics (Whitney stars, elements) read
    /// their geometry here.
    ///
    /// ```
    /// use hasse_complex::generate::torus_flat;
    /// let k = torus_flat(3, 3, [0.0, 3.0], [0.0, 3.0], false).unwrap();
    /// // Every square is unit, also those that wrap around.
    /// assert!(k.measure(2).iter().all(|a| (a - 1.0).abs() < 1e-14));
    /// for c in 0..k.cell_count(2) {
    ///     let p = k.cell_points(2, c);
    ///     assert!(p.iter().all(|x| (x[0] - p[0][0]).abs() <= 1.0 && (x[1] - p[0][1]).abs() <= 1.0));
    /// }
    /// ```
    pub fn cell_points(&self, p: usize, i: usize) -> Vec<[f64; 3]> {
        let mut points: Vec<Point> = self
            .cell_vertices(p, i)
            .iter()
            .map(|&v| self.point3(v))
            .collect();
        frame::unwrap_cell(self.vertices(), &mut points);
        points
    }

    /// Vertex `i` padded to three coordinates.
    pub(crate) fn point3(&self, i: usize) -> Point {
        frame::point(self.vertices(), i)
    }

    fn compute_normals(&self) -> Vec<f64> {
        let n = self.dim();
        let d = self.embedding_dim();
        if n == 0 {
            return Vec::new();
        }
        let mesh = Mesh::new(self);
        let top = self.boundary(n);
        let top_centres = self.centroid(n);
        let face_centres = self.centroid(n - 1);
        let mut normals = vec![0.0; self.cell_count(n - 1) * d];
        normals.par_chunks_mut(d).enumerate().for_each(|(f, out)| {
            let xf = Vector3::from(padded(&face_centres[f * d..(f + 1) * d]));
            // Directions spanned by the face itself.
            let face_direction = match n {
                1 => Vector3::zeros(),
                2 => {
                    let (a, b) = mesh.ends(f);
                    unit(&(b - a))
                }
                _ => unit(&mesh.vector_area(f)),
            };
            let (cells, signs) = row(top, f);
            let mut sum = Vector3::zeros();
            for (&c, &s) in cells.iter().zip(signs) {
                let centre = padded(&top_centres[c * d..(c + 1) * d]);
                let centre = self.vertices().nearest(&centre, &xf.into());
                let away = xf - Vector3::from(centre);
                let nu = match n {
                    1 => away,
                    2 => away - face_direction * away.dot(&face_direction),
                    _ => {
                        if away.dot(&face_direction) >= 0.0 {
                            face_direction
                        } else {
                            -face_direction
                        }
                    }
                };
                sum += unit(&nu) * f64::from(s);
            }
            out.copy_from_slice(&unit(&sum).as_slice()[..d]);
        });
        normals
    }

    fn compute_circumcentres(&self, p: usize) -> Result<Vec<f64>> {
        let d = self.embedding_dim();
        let centres: Vec<Option<Point>> = (0..self.cell_count(p))
            .into_par_iter()
            .map(|i| circumcentre_of(self, self.cell_vertices(p, i)))
            .collect();
        let mut out = Vec::with_capacity(centres.len() * d);
        for (i, c) in centres.into_iter().enumerate() {
            let c = c.ok_or_else(|| ComplexError::DegenerateCell {
                dim: p,
                cell: i,
                vertices: self.cell_vertices(p, i).to_vec(),
            })?;
            out.extend_from_slice(&c[..d]);
        }
        Ok(out)
    }
}

/// Allocation-free access to coordinates, edge ends and facet columns
/// for the per-cell kernels.
struct Mesh<'a> {
    coords: &'a [f64],
    d: usize,
    /// The vertices when they are periodic (a flat torus), for unwrapping.
    periodic: Option<&'a crate::cells::Vertices>,
    /// The vertex pairs of the edges, flat (row i of M₁ is entries 2i, 2i+1).
    edges: Cow<'a, [usize]>,
    /// ∂₂ and ∂₃ by columns: the complex's shared copies when it has them,
    /// else built here for this computation and dropped with it, so that
    /// measuring cells does not keep a second copy of each matrix in the
    /// complex (on a 10⁶-hexahedron box the two are 0.2 GB).
    facets: [OnceLock<Cow<'a, CsMat<i8>>>; 2],
    complex: &'a Complex,
}

/// Polygons with at most this many edges keep their edge end points on the
/// stack between the two passes of [`Mesh::polygon`].
const SMALL_POLYGON: usize = 8;

impl<'a> Mesh<'a> {
    fn new(complex: &'a Complex) -> Self {
        Self {
            coords: complex.vertices().as_slice(),
            d: complex.embedding_dim(),
            periodic: complex.vertices().period().map(|_| complex.vertices()),
            edges: edge_pairs(complex.lar()),
            facets: [OnceLock::new(), OnceLock::new()],
            complex,
        }
    }

    /// ∂_p by columns (p = 2 or 3): the complex's cached copy, or one of
    /// this computation's own.
    fn facets(&self, p: usize) -> &CsMat<i8> {
        self.facets[p - 2].get_or_init(|| match self.complex.geometry.facets[p].get() {
            Some(shared) => Cow::Borrowed(&**shared),
            None => Cow::Owned(self.complex.boundary(p).to_csc()),
        })
    }

    #[inline(always)]
    fn point(&self, i: usize) -> Vector3<f64> {
        let x = &self.coords[i * self.d..(i + 1) * self.d];
        match *x {
            [a] => Vector3::new(a, 0.0, 0.0),
            [a, b] => Vector3::new(a, b, 0.0),
            [a, b, c, ..] => Vector3::new(a, b, c),
            [] => Vector3::zeros(),
        }
    }

    /// Measure and centroid of p-cell `i`.
    #[inline(always)]
    fn cell(&self, p: usize, i: usize) -> (f64, Point) {
        let (measure, centroid) = match p {
            0 => (1.0, self.point(i)),
            1 => self.segment(i),
            2 => self.polygon(i),
            _ => self.polyhedron(i),
        };
        (measure, centroid.into())
    }

    /// The two end points of edge `e` (tail = lower vertex id, head = higher);
    /// on a flat torus the head is the image nearest the tail.
    #[inline(always)]
    fn ends(&self, e: usize) -> (Vector3<f64>, Vector3<f64>) {
        let tail = self.point(self.edges[2 * e]);
        let head = self.point(self.edges[2 * e + 1]);
        (tail, self.near(head, &tail))
    }

    /// The image of `x` nearest `reference` (x itself off a flat torus).
    #[inline(always)]
    fn near(&self, x: Vector3<f64>, reference: &Vector3<f64>) -> Vector3<f64> {
        match self.periodic {
            Some(vertices) => Vector3::from(vertices.nearest(&x.into(), &(*reference).into())),
            None => x,
        }
    }

    /// Both ends of edge `e` as images near `reference`.
    #[inline(always)]
    fn ends_near(&self, e: usize, reference: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let (a, b) = self.ends(e);
        if self.periodic.is_none() {
            return (a, b);
        }
        let a2 = self.near(a, reference);
        (a2, b + (a2 - a))
    }

    fn segment(&self, e: usize) -> (f64, Vector3<f64>) {
        let (a, b) = self.ends(e);
        ((b - a).norm(), (a + b) * 0.5)
    }

    /// Fan of triangles (apex, v₀, v₁) over the edges of a 2-cell, apex the
    /// vertex average (every vertex of the cycle ends two edges).
    fn polygon(&self, f: usize) -> (f64, Vector3<f64>) {
        let (edges, signs) = column(self.facets(2), f);
        let Some(&first) = edges.first() else {
            return (0.0, Vector3::zeros());
        };
        let origin = self.ends(first).0;
        let small = edges.len() <= SMALL_POLYGON;
        let mut ends = [(Vector3::zeros(), Vector3::zeros()); SMALL_POLYGON];
        let mut sum = Vector3::zeros();
        for (k, &e) in edges.iter().enumerate() {
            let (a, b) = self.ends_near(e, &origin);
            if small {
                ends[k] = (a, b);
            }
            sum += (a - origin) + (b - origin);
        }
        let apex = origin + sum * (0.5 / edges.len() as f64);
        let mut area = 0.0;
        let mut moment = Vector3::zeros();
        // The fan's triangles with the cell's signs: their sum is twice
        // the vector area; kept for the convexity check below.
        let mut turned = [Vector3::zeros(); SMALL_POLYGON];
        let mut oriented = Vector3::zeros();
        for (k, &e) in edges.iter().enumerate() {
            let (a, b) = if small {
                ends[k]
            } else {
                self.ends_near(e, &origin)
            };
            let a = a - apex;
            let b = b - apex;
            let c = a.cross(&b);
            let t = 0.5 * c.norm();
            if small {
                turned[k] = c * f64::from(signs[k]);
            }
            oriented += c * f64::from(signs[k]);
            area += t;
            // Triangle centroid relative to the apex: (a + b) / 3.
            moment += (a + b) * (t / 3.0);
        }
        // A triangle of the fan turned against the cell: the apex is
        // outside the kernel of a non-convex polygon (never a triangle).
        if edges.len() > 3 {
            let normal = unit(&oriented);
            let against = |c: &Vector3<f64>| c.dot(&normal) < -1e-12 * c.norm();
            let reflex = if small {
                turned[..edges.len()].iter().any(against)
            } else {
                edges.iter().zip(signs).any(|(&e, &r)| {
                    let (a, b) = self.ends(e);
                    against(&((a - apex).cross(&(b - apex)) * f64::from(r)))
                })
            };
            if reflex {
                return self.signed_polygon(f, &apex, &normal);
            }
        }
        (area, centred(&apex, &moment, area))
    }

    /// The fan of [`Self::polygon`] with signed triangles (by the cell's
    /// orientation), exact for any simple polygon, convex or not.
    fn signed_polygon(
        &self,
        f: usize,
        apex: &Vector3<f64>,
        normal: &Vector3<f64>,
    ) -> (f64, Vector3<f64>) {
        let (edges, signs) = column(self.facets(2), f);
        let mut area = 0.0;
        let mut moment = Vector3::zeros();
        for (&e, &r) in edges.iter().zip(signs) {
            let (a, b) = self.ends(e);
            let (a, b) = (a - apex, b - apex);
            let t = 0.5 * f64::from(r) * a.cross(&b).dot(normal);
            area += t;
            moment += (a + b) * (t / 3.0);
        }
        (area, centred(apex, &moment, area))
    }

    /// Signed tetrahedra (o, a_f, v₀, v₁) over the oriented fan of every
    /// face f, a_f its vertex average. The faces close up, so the result
    /// does not depend on the apex o (taken at a vertex of the cell): it is
    /// the cone decomposition from the vertex average, computed with fewer
    /// loads. Per face, with primes relative to o and C = r (v₀′ × v₁′):
    /// 6 vol = s a_f′·ΣC and 24 moment = s [a_f′ (a_f′·ΣC) + Σ (v₀′ + v₁′)(C·a_f′)].
    fn polyhedron(&self, c: usize) -> (f64, Vector3<f64>) {
        let (faces, face_signs) = column(self.facets(3), c);
        let edge_csc = self.facets(2);
        let Some(&first_face) = faces.first() else {
            return (0.0, Vector3::zeros());
        };
        let origin = match column(edge_csc, first_face).0.first() {
            Some(&e) => self.ends(e).0,
            None => return (0.0, Vector3::zeros()),
        };
        let mut volume6 = 0.0;
        let mut moment24 = Vector3::zeros();
        for (&f, &s) in faces.iter().zip(face_signs) {
            let (edges, edge_signs) = column(edge_csc, f);
            let mut sum = Vector3::zeros();
            let mut normal = Vector3::zeros();
            let mut tensor = [Vector3::zeros(); 3];
            for (&e, &r) in edges.iter().zip(edge_signs) {
                let (a, b) = self.ends_near(e, &origin);
                let a = a - origin;
                let b = b - origin;
                let ab = a + b;
                let c = a.cross(&b) * f64::from(r);
                sum += ab;
                normal += c;
                for (row, x) in tensor.iter_mut().zip(ab.iter()) {
                    *row += c * *x;
                }
            }
            let apex = sum * (0.5 / edges.len().max(1) as f64);
            let s = f64::from(s);
            let height = s * apex.dot(&normal);
            volume6 += height;
            let spread = Vector3::from(tensor.map(|row| row.dot(&apex)));
            moment24 += apex * height + spread * s;
        }
        // The sign follows the orientation convention; the centroid does not.
        let centroid = if volume6 == 0.0 {
            origin
        } else {
            origin + moment24 * (0.25 / volume6)
        };
        ((volume6 / 6.0).abs(), centroid)
    }

    /// Vector area of 2-cell `f` in its own orientation: ½ Σ r (v₀ − o) × (v₁ − o)
    /// over its edges with their ∂₂ signs, for any o.
    fn vector_area(&self, f: usize) -> Vector3<f64> {
        let (edges, signs) = column(self.facets(2), f);
        let Some(&first) = edges.first() else {
            return Vector3::zeros();
        };
        let origin = self.ends(first).0;
        let mut area = Vector3::zeros();
        for (&e, &r) in edges.iter().zip(signs) {
            let (a, b) = self.ends_near(e, &origin);
            let a = a - origin;
            let b = b - origin;
            area += a.cross(&b) * (0.5 * f64::from(r));
        }
        area
    }
}

/// The vertex pairs of the edges as one flat slice: M₁'s own column
/// indices when every row holds two entries (always, for a valid complex),
/// otherwise each row's first two (or its one vertex twice).
fn edge_pairs(lar: &Lar) -> Cow<'_, [usize]> {
    if let Some(pairs) = lar.edge_vertex_pairs() {
        return Cow::Borrowed(pairs);
    }
    let Ok(m) = lar.characteristic(1) else {
        return Cow::Borrowed(&[][..]);
    };
    let indptr = m.indptr();
    Cow::Owned(
        (0..m.rows())
            .flat_map(|i| {
                let row = &m.indices()[indptr.outer_inds_sz(i)];
                let first = row.first().copied().unwrap_or(0);
                [first, row.get(1).copied().unwrap_or(first)]
            })
            .collect(),
    )
}

/// Circumcentre of the simplex with these vertices: x₀ + B y with
/// (2BᵀB) y = (|x_i − x₀|²)_i, B = [x₁ − x₀, …, x_p − x₀]; `None` when
/// the simplex is degenerate.
fn circumcentre_of(complex: &Complex, cell: &[usize]) -> Option<Point> {
    let origin = Vector3::from(complex.point3(*cell.first()?));
    let mut edges = [Vector3::zeros(); 3];
    let p = cell.len() - 1;
    for (k, &v) in cell[1..].iter().enumerate() {
        let x = complex
            .vertices()
            .nearest(&complex.point3(v), &origin.into());
        edges[k] = Vector3::from(x) - origin;
    }
    // Unused rows/columns are padded with the identity and a zero right-hand side.
    let mut gram = Matrix3::<f64>::identity();
    let mut rhs = Vector3::<f64>::zeros();
    for i in 0..p {
        for j in 0..p {
            gram[(i, j)] = 2.0 * edges[i].dot(&edges[j]);
        }
        rhs[i] = edges[i].dot(&edges[i]);
    }
    let y = gram.lu().solve(&rhs)?;
    let mut centre = origin;
    for (k, edge) in edges.iter().take(p).enumerate() {
        centre += edge * y[k];
    }
    centre
        .iter()
        .all(|x| x.is_finite())
        .then_some(centre.into())
}

/// Entries (row or column indices, values) of outer slice `j` of a
/// compressed matrix: a column of a CSC matrix.
pub(crate) fn column(m: &CsMat<i8>, j: usize) -> (&[usize], &[i8]) {
    let range: Range<usize> = m.indptr().outer_inds_sz(j);
    (&m.indices()[range.clone()], &m.data()[range])
}

/// A row of a CSR matrix (same storage access as [`column`]).
pub(crate) fn row(m: &CsMat<i8>, i: usize) -> (&[usize], &[i8]) {
    column(m, i)
}

/// A stored point (1 to 3 coordinates) padded to three.
pub(crate) fn padded(x: &[f64]) -> Point {
    let mut out = [0.0; 3];
    out[..x.len()].copy_from_slice(x);
    out
}

/// `a / |a|`, or zero when |a| is not positive. Scaled by the reciprocal
/// of the length rather than divided by it as nalgebra's `normalize`
/// does, so that the normals keep their last bits.
fn unit(a: &Vector3<f64>) -> Vector3<f64> {
    let len = a.norm();
    if len > 0.0 {
        a * (1.0 / len)
    } else {
        Vector3::zeros()
    }
}

/// apex + moment / mass, or the apex for a zero mass.
fn centred(apex: &Vector3<f64>, moment: &Vector3<f64>, mass: f64) -> Vector3<f64> {
    if mass == 0.0 {
        *apex
    } else {
        apex + moment * (1.0 / mass)
    }
}

#[cfg(test)]
mod tests {
    use crate::{Complex, TopCells, Vertices};

    #[test]
    fn unit_tetrahedron_volume_and_centroid() {
        let v = Vertices::from_points(&[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ])
        .unwrap();
        let k = Complex::build(v, TopCells::simplices([[0, 1, 2, 3]])).unwrap();
        assert!((k.measure(3)[0] - 1.0 / 6.0).abs() < 1e-16);
        for x in k.centroid(3) {
            assert!((x - 0.25).abs() < 1e-16);
        }
        // Faces: three right triangles of area 1/2 and one equilateral of side √2.
        let mut areas = k.measure(2).to_vec();
        areas.sort_by(f64::total_cmp);
        for a in &areas[..3] {
            assert!((a - 0.5).abs() < 1e-15);
        }
        assert!((areas[3] - 3f64.sqrt() / 2.0).abs() < 1e-15);
        assert_eq!(k.measure(0), &[1.0; 4]);
        assert!(k.measure(4).is_empty());
        assert!(k.centroid_of(3, 1).is_empty());
    }

    #[test]
    fn circumcentre_rejects_non_simplices() {
        let v = Vertices::from_points(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]).unwrap();
        let k = Complex::build(v, TopCells::cuboids([[0, 1, 2, 3]])).unwrap();
        let err = k.circumcentre(2).unwrap_err().to_string();
        assert!(err.contains("2-cell 0"), "{err}");
        // Edges are simplices.
        assert_eq!(k.circumcentre(1).unwrap().len(), 8);
    }
}
