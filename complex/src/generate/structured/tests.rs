//! The direct builder against the general path, exactly, plus invariants
//! and hand-computed matrices.

use super::super::grid::{grid_general, kuhn_general};
use super::super::{graded_axis, grid, kuhn, uniform_axis};
use super::*;

/// Tests return errors instead of unwrapping, so a failure names its cause.
type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn u(n: usize) -> TestResult<Vec<f64>> {
    Ok(uniform_axis(n, 0.0, 1.0)?)
}

/// Axes of every shape the comparison runs on: 1D to 3D, one-cell sides,
/// uneven counts, graded and shifted axes, and a medium 20³ grid.
fn shapes() -> TestResult<Vec<Vec<Vec<f64>>>> {
    let graded = graded_axis(6, 0.0, 3.0, 1.3)?;
    let shifted = uniform_axis(5, -1.0, 2.0)?;
    let fine_end = graded_axis(4, -2.0, 0.5, 0.6)?;
    Ok(vec![
        vec![u(1)?],
        vec![u(3)?],
        vec![graded.clone()],
        vec![u(1)?, u(1)?],
        vec![u(3)?, u(2)?],
        vec![u(1)?, u(4)?],
        vec![u(4)?, u(1)?],
        vec![u(17)?, u(9)?],
        vec![graded.clone(), shifted.clone()],
        vec![u(1)?, u(1)?, u(1)?],
        vec![u(2)?, u(1)?, u(1)?],
        vec![u(1)?, u(3)?, u(2)?],
        vec![u(3)?, u(1)?, u(4)?],
        vec![u(6)?, u(5)?, u(4)?],
        vec![graded, shifted, fine_end],
        vec![u(20)?, u(20)?, u(20)?],
    ])
}

/// Every part of the two complexes, part by part (so that a failure names
/// the part), then as a whole (which also covers anything added later to
/// `Complex`'s equality).
fn assert_same(direct: &Complex, general: &Complex, label: &str) -> TestResult {
    assert_eq!(
        direct.cell_counts(),
        general.cell_counts(),
        "{label}: cell counts"
    );
    assert_eq!(direct.vertices(), general.vertices(), "{label}: vertices");
    for p in 1..=general.dim() {
        let (a, b) = (
            direct.lar().characteristic(p)?,
            general.lar().characteristic(p)?,
        );
        assert_eq!(a.shape(), b.shape(), "{label}: M_{p} shape");
        assert_eq!(
            a.indptr().raw_storage(),
            b.indptr().raw_storage(),
            "{label}: M_{p} indptr"
        );
        assert_eq!(a.indices(), b.indices(), "{label}: M_{p} indices");
        assert_eq!(a.data(), b.data(), "{label}: M_{p} data");
        let (a, b) = (direct.boundary(p), general.boundary(p));
        assert_eq!(a.shape(), b.shape(), "{label}: ∂_{p} shape");
        assert_eq!(
            a.indptr().raw_storage(),
            b.indptr().raw_storage(),
            "{label}: ∂_{p} indptr"
        );
        assert_eq!(a.indices(), b.indices(), "{label}: ∂_{p} indices");
        assert_eq!(a.data(), b.data(), "{label}: ∂_{p} signs");
    }
    assert_eq!(
        direct.top_orientation(),
        general.top_orientation(),
        "{label}: top orientation"
    );
    assert_eq!(direct.tags(), general.tags(), "{label}: tags");
    assert!(direct == general, "{label}: complexes differ");
    Ok(())
}

#[test]
fn cuboidal_grids_equal_the_general_path_exactly() -> TestResult {
    // The general path (facet extraction, filtered LAR products, geometric
    // signs) is the reference: the direct builder must reproduce it bit
    // for bit on every shape.
    for axes in shapes()? {
        let layout = Layout::new(&axes)?;
        let label = format!("grid {:?}", layout.counts);
        let direct = build(&layout, Family::Cuboid)?;
        assert_same(&direct, &grid_general(&layout)?, &label)?;
    }
    Ok(())
}

#[test]
fn kuhn_grids_equal_the_general_path_exactly() -> TestResult {
    for axes in shapes()? {
        let layout = Layout::new(&axes)?;
        let label = format!("kuhn {:?}", layout.counts);
        let direct = build(&layout, Family::Kuhn)?;
        assert_same(&direct, &kuhn_general(&layout)?, &label)?;
    }
    Ok(())
}

/// Cell counts of an n_x × n_y × n_z cuboidal grid by counting cells of
/// each orientation: along axis a a p-cell has n_a positions if it extends
/// along a, n_a + 1 otherwise.
fn cuboid_counts(n: &[usize]) -> Vec<usize> {
    let d = n.len();
    (0..=d)
        .map(|p| {
            (0..1usize << d)
                .filter(|s| s.count_ones() as usize == p)
                .map(|s| {
                    (0..d)
                        .map(|a| if s >> a & 1 == 1 { n[a] } else { n[a] + 1 })
                        .product::<usize>()
                })
                .sum()
        })
        .collect()
}

/// Kuhn cell counts from the cuboidal ones: in 2D each square adds a
/// diagonal and splits in two; in 3D each square face adds a diagonal and
/// splits in two, and each cube adds its main diagonal, the 6 triangles
/// through it and splits into 6 tetrahedra.
fn kuhn_counts(n: &[usize]) -> Vec<usize> {
    let c = cuboid_counts(n);
    match n.len() {
        1 => c,
        2 => vec![c[0], c[1] + c[2], 2 * c[2]],
        _ => vec![c[0], c[1] + c[2] + c[3], 2 * c[2] + 6 * c[3], 6 * c[3]],
    }
}

#[test]
fn direct_grids_are_chain_complexes_of_a_ball() -> TestResult {
    // ∂_{p−1} ∂_p = 0 exactly, χ = 1 (a ball), and the cell counts of the
    // closed-form counting above.
    for axes in shapes()? {
        let layout = Layout::new(&axes)?;
        let n: Vec<usize> = layout.counts.iter().map(|c| c - 1).collect();
        for (family, expected) in [
            (Family::Cuboid, cuboid_counts(&n)),
            (Family::Kuhn, kuhn_counts(&n)),
        ] {
            let k = build(&layout, family)?;
            let label = format!("{family:?} {n:?}");
            assert_eq!(k.cell_counts(), expected, "{label}");
            assert_eq!(k.euler_characteristic(), 1, "{label}");
            for p in 2..=k.dim() {
                let product = &k.boundary(p - 1).map(|&x| i32::from(x))
                    * &k.boundary(p).map(|&x| i32::from(x));
                assert!(
                    product.data().iter().all(|&x| x == 0),
                    "{label}: ∂{}∂{p}",
                    p - 1
                );
            }
        }
    }
    Ok(())
}

fn dense(m: &CsMat<i8>) -> Vec<Vec<i8>> {
    m.to_dense()
        .rows()
        .into_iter()
        .map(|r| r.to_vec())
        .collect()
}

#[test]
fn unit_square_matrices_by_hand() -> TestResult {
    let axes = [u(1)?, u(1)?];
    let layout = Layout::new(&axes)?;
    // Vertices 0 (0,0), 1 (1,0), 2 (0,1), 3 (1,1). Edges by vertex list:
    // e0 {0,1} bottom, e1 {0,2} left, e2 {1,3} right, e3 {2,3} top, each
    // from its lower to its higher vertex.
    let quad = build(&layout, Family::Cuboid)?;
    assert_eq!(
        dense(quad.boundary(1)),
        vec![
            vec![-1, -1, 0, 0],
            vec![1, 0, -1, 0],
            vec![0, 1, 0, -1],
            vec![0, 0, 1, 1]
        ]
    );
    // Counter-clockwise: 0 → 1 → 3 → 2 → 0 = e0 + e2 − e3 − e1.
    assert_eq!(
        dense(quad.boundary(2)),
        vec![vec![1], vec![-1], vec![1], vec![-1]]
    );
    assert_eq!(quad.top_orientation(), &[1]);
    // Kuhn: edges e0 {0,1}, e1 {0,2}, e2 {0,3} (the diagonal), e3 {1,3},
    // e4 {2,3}; triangles t0 [0,1,3] (counter-clockwise as listed) and
    // t1 [0,2,3] (clockwise as listed, so flagged −1). Counter-clockwise
    // boundaries: t0 = 0→1→3→0 = e0 + e3 − e2, t1 = 0→3→2→0 = e2 − e4 − e1.
    let tris = build(&layout, Family::Kuhn)?;
    assert_eq!(tris.top_orientation(), &[1, -1]);
    assert_eq!(
        dense(tris.boundary(2)),
        vec![
            vec![1, 0],
            vec![0, -1],
            vec![-1, 1],
            vec![1, 0],
            vec![0, -1]
        ]
    );
    assert_eq!(tris.tag("xmin").ok_or("no xmin tag")?.cells, vec![1]);
    assert_eq!(
        tris.tag("boundary").ok_or("no boundary tag")?.cells,
        vec![0, 1, 3, 4]
    );
    Ok(())
}

#[test]
fn unit_cube_top_boundary_by_hand() -> TestResult {
    // Faces by vertex list: f0 {0,1,2,3} (z = 0), f1 {0,1,4,5} (y = 0),
    // f2 {0,2,4,6} (x = 0), f3 {1,3,5,7} (x = 1), f4 {2,3,6,7} (y = 1),
    // f5 {4,5,6,7} (z = 1). Each face's frame follows its axes in
    // increasing order (xy, xz, yz), so its sign is that of the outward
    // normal against n_xy = +z, n_xz = −y, n_yz = +x: z = 0 has outward −z
    // (−1), y = 0 has outward −y (+1), x = 0 has −x (−1), and the far
    // sides the opposite.
    let axes = [u(1)?, u(1)?, u(1)?];
    let layout = Layout::new(&axes)?;
    let cube = build(&layout, Family::Cuboid)?;
    assert_eq!(
        dense(cube.boundary(3)),
        vec![vec![-1], vec![1], vec![-1], vec![1], vec![-1], vec![1]]
    );
    // The six Kuhn tetrahedra are flagged with the signs of the axis
    // permutations (012, 021, 102, 120, 201, 210).
    let tets = build(&layout, Family::Kuhn)?;
    assert_eq!(tets.top_orientation(), &[1, -1, -1, 1, 1, -1]);
    Ok(())
}

#[test]
fn thin_cells_go_through_the_general_path() -> TestResult {
    // A spacing of 1e-9 against a unit diagonal is below THINNEST (1e-6):
    // the public generators must hand such grids to the general path,
    // whose own checks decide on them.
    let thin = vec![vec![0.0, 1e-9, 1.0], u(1)?];
    let layout = Layout::new(&thin)?;
    assert!(!well_shaped(&layout));
    assert_eq!(grid(&thin)?, grid_general(&layout)?);
    assert_eq!(kuhn(&thin)?, kuhn_general(&layout)?);
    let layout_ok = [u(3)?, u(2)?];
    assert!(well_shaped(&Layout::new(&layout_ok)?));
    Ok(())
}
