//! The reader orders of cells rebuilt from ∂, checked against geometry
//! (areas, volumes, axis-aligned edges) computed here independently.

use super::*;
use hasse_complex::{generate, TopCells, Vertices};

/// Tests return errors instead of unwrapping, so a failure names its cause.
type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn shoelace(complex: &Complex, cycle: &[usize]) -> f64 {
    (0..cycle.len())
        .map(|k| {
            let a = point3(complex, cycle[k]);
            let b = point3(complex, cycle[(k + 1) % cycle.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        / 2.0
}

#[test]
fn unit_quad_is_cyclic_with_positive_area() -> TestResult {
    let k = generate::rectangle(1, 1, [0.0, 1.0], [0.0, 1.0])?;
    let grid = grid_topology(&k, 2, Polygons::Keep)?;
    assert_eq!(grid.uniform, Some(("Quadrilateral", 4)));
    let quad: Vec<usize> = grid.connectivity.iter().map(|&v| v as usize).collect();
    // Tensor order 0,1,2,3 = (0,0),(1,0),(0,1),(1,1); cyclic means the
    // diagonal pairs {0,3} and {1,2} sit at distance two in the cycle.
    let at = |v: usize| {
        quad.iter()
            .position(|&x| x == v)
            .map(|i| i as i64)
            .ok_or(format!("vertex {v} is not in the quad {quad:?}"))
    };
    assert_eq!((at(0)? - at(3)?).abs(), 2);
    assert_eq!((at(1)? - at(2)?).abs(), 2);
    assert!((shoelace(&k, &quad) - 1.0).abs() < 1e-12);
    Ok(())
}

/// Volume of a VTK-ordered hexahedron split into the five tetrahedra of
/// the corner decomposition, each in VTK orientation.
fn vtk_hex_volume(p: &[[f64; 3]; 8]) -> f64 {
    let tets = [
        [0, 1, 3, 4],
        [1, 2, 3, 6],
        [1, 4, 5, 6],
        [3, 6, 7, 4],
        [1, 3, 4, 6],
    ];
    tets.iter()
        .map(|t| tet_volume6(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) / 6.0)
        .sum()
}

#[test]
fn unit_hex_has_positive_vtk_volume() -> TestResult {
    let k = generate::box3(1, 1, 1, [0.0, 1.0], [0.0, 2.0], [0.0, 3.0])?;
    let grid = grid_topology(&k, 3, Polygons::Keep)?;
    assert_eq!(grid.uniform, Some(("Hexahedron", 8)));
    let hex: Vec<usize> = grid.connectivity.iter().map(|&v| v as usize).collect();
    let p: [[f64; 3]; 8] = std::array::from_fn(|i| point3(&k, hex[i]));
    assert!((vtk_hex_volume(&p) - 6.0).abs() < 1e-12);
    // Each top vertex sits straight above its bottom vertex along one axis.
    for i in 0..4 {
        let d = Vector3::from(p[i + 4]) - Vector3::from(p[i]);
        assert_eq!(d.iter().filter(|x| x.abs() > 0.0).count(), 1);
    }
    // Bottom face is a cycle: consecutive vertices differ along one axis.
    for i in 0..4 {
        let d = Vector3::from(p[(i + 1) % 4]) - Vector3::from(p[i]);
        assert_eq!(d.iter().filter(|x| x.abs() > 0.0).count(), 1);
    }
    Ok(())
}

#[test]
fn mixed_polygons_use_polygon_codes() -> TestResult {
    // A pentagon and a triangle sharing the edge (1, 2).
    let v = Vertices::from_points(&[
        [0.0, 0.0],
        [2.0, 0.0],
        [2.0, 1.0],
        [1.0, 2.0],
        [0.0, 1.0],
        [3.0, 0.5],
    ])?;
    let k = Complex::build(v, TopCells::polygons([vec![0, 1, 2, 3, 4], vec![1, 5, 2]]))?;
    let grid = grid_topology(&k, 2, Polygons::Keep)?;
    assert_eq!(grid.uniform, None);
    assert_eq!(grid.connectivity.len(), (2 + 5) + (1 + 3));
    let pentagon: Vec<usize> = grid.connectivity[2..7]
        .iter()
        .map(|&x| x as usize)
        .collect();
    assert_eq!(&grid.connectivity[..2], &[code::POLYGON, 5]);
    assert_eq!(grid.connectivity[7], code::TRIANGLE);
    assert!((shoelace(&k, &pentagon) - 3.0).abs() < 1e-12);
    Ok(())
}

#[test]
fn general_polyhedron_becomes_positive_tetrahedra() -> TestResult {
    // A triangular prism: 2 triangles, 3 quads.
    let v = Vertices::from_points(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
    ])?;
    let prism = vec![
        vec![0, 2, 1],
        vec![3, 4, 5],
        vec![0, 1, 4, 3],
        vec![1, 2, 5, 4],
        vec![2, 0, 3, 5],
    ];
    let k = Complex::build(v, TopCells::polyhedra([prism]))?;
    let grid = grid_topology(&k, 3, Polygons::Keep)?;
    assert_eq!(grid.uniform, Some(("Tetrahedron", 4)));
    let ids = grid
        .cell_ids
        .clone()
        .ok_or("no cell ids for a split polyhedron")?;
    assert!(ids.iter().all(|&c| c == 0));
    let volume: f64 = grid
        .connectivity
        .chunks(4)
        .map(|t| {
            let [a, b, c, d] = [0, 1, 2, 3].map(|i| point3(&k, t[i] as usize));
            let v6 = tet_volume6(a, b, c, d);
            assert!(v6 > 0.0);
            v6 / 6.0
        })
        .sum();
    assert!((volume - 0.5).abs() < 1e-12);
    Ok(())
}

#[test]
fn hanging_vertices_are_triangulated_without_flat_triangles() -> TestResult {
    // The unit square with a hanging vertex in the middle of its bottom
    // and of its right side (a neighbour on each was cut): a hexagon
    // whose fan from the corner (0, 0) would hold two flat triangles.
    let v = Vertices::from_points(&[
        [0.0, 0.0],
        [0.5, 0.0],
        [1.0, 0.0],
        [1.0, 0.5],
        [1.0, 1.0],
        [0.0, 1.0],
        [2.0, 0.0],
    ])?;
    let k = Complex::build(
        v,
        TopCells::polygons([vec![0, 1, 2, 3, 4, 5], vec![2, 6, 3]]),
    )?;
    let kept = grid_topology(&k, 2, Polygons::Keep)?;
    assert_eq!(&kept.connectivity[..2], &[code::POLYGON, 6]);
    assert_eq!(kept.cell_ids, None);

    let grid = grid_topology(&k, 2, Polygons::Triangulate)?;
    assert_eq!(grid.uniform, Some(("Triangle", 3)));
    let ids = grid
        .cell_ids
        .clone()
        .ok_or("no cell ids for triangulated polygons")?;
    // Four triangles for the hexagon (k − 2), one for the triangle.
    assert_eq!(ids, [0, 0, 0, 0, 1]);
    let mut used = Vec::new();
    let area: f64 = grid.connectivity[..12]
        .chunks(3)
        .map(|t| {
            let t: Vec<usize> = t.iter().map(|&v| v as usize).collect();
            let a = shoelace(&k, &t);
            assert!(a > 1e-3, "flat or clockwise triangle {t:?}: {a}");
            used.extend(t);
            a
        })
        .sum();
    assert!((area - 1.0).abs() < 1e-12);
    used.sort_unstable();
    used.dedup();
    assert_eq!(
        used,
        [0, 1, 2, 3, 4, 5],
        "every vertex of the hexagon is used"
    );
    Ok(())
}

/// The sorted vertex ids of each element of a `Mixed` array, with its code.
fn mixed_elements(connectivity: &[i64]) -> Vec<(i64, Vec<usize>)> {
    let mut elements = Vec::new();
    let mut at = 0;
    while at < connectivity.len() {
        let code = connectivity[at];
        let (skip, nodes) = match code {
            code::TRIANGLE => (1, 3),
            code::QUADRILATERAL => (1, 4),
            other => panic!("unexpected code {other}"),
        };
        let mut v: Vec<usize> = connectivity[at + skip..at + skip + nodes]
            .iter()
            .map(|&x| x as usize)
            .collect();
        v.sort_unstable();
        elements.push((code, v));
        at += skip + nodes;
    }
    elements
}

#[test]
fn a_grid_of_several_tasks_stays_uniform_and_in_cell_order() -> TestResult {
    // 60 × 40 squares of side 0.05: more cells than one task builds, so
    // the grid is joined from runs. Each element must be the cell of its
    // index (same vertex set as row i of M_2) with area 0.05² > 0.
    let k = generate::rectangle(60, 40, [0.0, 3.0], [0.0, 2.0])?;
    assert!(k.cell_count(2) > TASK_CELLS);
    let grid = grid_topology(&k, 2, Polygons::Keep)?;
    assert_eq!(grid.uniform, Some(("Quadrilateral", 4)));
    assert_eq!(grid.element_count, 2400);
    assert_eq!(grid.cell_ids, None);
    assert_eq!(grid.connectivity.len(), 4 * 2400);
    for (i, quad) in grid.connectivity.chunks(4).enumerate() {
        let quad: Vec<usize> = quad.iter().map(|&v| v as usize).collect();
        let mut sorted = quad.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, k.cell_vertices(2, i), "element {i}");
        assert!((shoelace(&k, &quad) - 0.0025).abs() < 1e-12, "element {i}");
    }
    Ok(())
}

#[test]
fn a_kind_met_in_a_later_task_makes_the_whole_grid_mixed() -> TestResult {
    // A strip of n unit squares (more than one task's cells) closed by one
    // triangle: every element, the earlier tasks' quads too, must carry
    // its code, n times 5 (quadrilateral) and once 4 (triangle).
    let n = TASK_CELLS + 5;
    let mut points: Vec<[f64; 2]> = (0..=n).map(|i| [i as f64, 0.0]).collect();
    points.extend((0..=n).map(|i| [i as f64, 1.0]));
    points.push([n as f64 + 1.0, 0.5]);
    let top = |i: usize| n + 1 + i;
    let mut cells: Vec<Vec<usize>> = (0..n).map(|i| vec![i, i + 1, top(i + 1), top(i)]).collect();
    cells.push(vec![n, 2 * n + 2, top(n)]);
    let k = Complex::build(Vertices::from_points(&points)?, TopCells::polygons(cells))?;
    let grid = grid_topology(&k, 2, Polygons::Keep)?;
    assert_eq!(grid.uniform, None);
    assert_eq!(grid.element_count, n + 1);
    assert_eq!(grid.connectivity.len(), 5 * n + 4);
    let elements = mixed_elements(&grid.connectivity);
    assert_eq!(elements.len(), n + 1);
    let count = |c: i64| elements.iter().filter(|(code, _)| *code == c).count();
    assert_eq!(count(code::QUADRILATERAL), n);
    assert_eq!(count(code::TRIANGLE), 1);
    for (i, (_, vertices)) in elements.iter().enumerate() {
        assert_eq!(vertices, k.cell_vertices(2, i), "element {i}");
    }
    Ok(())
}
