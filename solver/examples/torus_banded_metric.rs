//! Writes the thesis's banded face-to-face metric Ω = (1/5)[[L, S], [0, 0]]
//! (chapter 6.3) for the torus mesh of `hasse_complex::generate::torus`, as
//! the `row column value` file read by a case's
//! `metric = { type = "file", file = ... }`.
//!
//! The thesis numbers the long edges first (they separate cells that are
//! neighbours along ξ), then the short ones (neighbours along η), each
//! family as k = i + n_ξ j for the edge starting at vertex (i, j). L and S
//! are circulant in k: row k is row 0 rotated right by k, with first rows
//!
//!   L: (1, 0.5, 0.1, 0.01, 0, …, 0, −0.01, −0.1, −0.5)
//!   S: (0.05, 0.01, 0.001, 0, …, 0, 0.001, 0.01, 0.05)
//!
//! Ω acts on the jumps of f along +ξ (long edges) and +η (short edges);
//! hasse's faces carry their own orientation, so each entry is multiplied
//! by the signs s_F s_G that turn a face's jump into the +ξ/+η jump.
//!
//! ξ runs along the generator's major circle (`major`) or around the tube
//! (`minor`): a ring torus needs R > r, so with ℓ = 50 < m = 250 the long
//! direction η goes around the major circle and ξ around the tube.
//!
//! Usage: cargo run -p hasse-solver --example torus_banded_metric -- 50 50 minor cases/torus-banded-omega.txt

// ci-args: 10 4 minor {tmp}/banded.txt

use std::io::Write;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 5 || !["major", "minor"].contains(&args[3].as_str()) {
        eprintln!("usage: torus_banded_metric N_XI N_ETA major|minor OUTPUT");
        std::process::exit(2);
    }
    let n_xi: usize = args[1].parse()?;
    let n_eta: usize = args[2].parse()?;
    let xi_major = args[3] == "major";
    let (n_major, n_minor) = if xi_major {
        (n_xi, n_eta)
    } else {
        (n_eta, n_xi)
    };
    // Radii do not matter: Ω is topological plus the thesis's weights.
    let complex = hasse_complex::generate::torus(2.0, 1.0, n_major, n_minor)?;
    // Vertex v of the generator is (v mod n_major, v / n_major); in (ξ, η):
    let xi_eta = |v: usize| {
        let (a, b) = (v % n_major, v / n_major);
        if xi_major {
            (a, b)
        } else {
            (b, a)
        }
    };
    let cells = n_xi * n_eta;
    // Cell (a, b) of the generator has index a + n_major b, like its first vertex.
    let cell = |i: usize, j: usize| {
        let (i, j) = (i % n_xi, j % n_eta);
        if xi_major {
            i + n_major * j
        } else {
            j + n_major * i
        }
    };
    let boundary = complex.boundary(2);
    // (family, k, sign): family 0 = long (between cells (i−1, j) and (i, j)),
    // 1 = short (between cells (i, j−1) and (i, j)).
    let mut long = vec![(0usize, 0i8); cells];
    let mut short = vec![(0usize, 0i8); cells];
    for face in 0..complex.cell_count(1) {
        let v = complex.cell_vertices(1, face);
        let (a, b) = (v[0], v[1]);
        let ((ia, ja), (ib, jb)) = (xi_eta(a), xi_eta(b));
        let sign_from = |from: usize| -> i8 {
            boundary
                .outer_view(face)
                .and_then(|row| row.get(from).copied())
                .unwrap_or(0)
        };
        if ia == ib {
            // Along η: the edge starting at (i, min) in cyclic order.
            let j = if (ja + 1) % n_eta == jb { ja } else { jb };
            let k = ia + n_xi * j;
            // +ξ jump: ∂(F, left cell) = +1 means F points from left to right.
            let left = cell(ia + n_xi - 1, j);
            long[k] = (face, sign_from(left));
        } else {
            let i = if (ia + 1) % n_xi == ib { ia } else { ib };
            let k = i + n_xi * ja;
            let below = cell(i, ja + n_eta - 1);
            short[k] = (face, sign_from(below));
        }
    }
    if long.iter().chain(&short).any(|&(_, s)| s == 0) {
        return Err("a face was not classified; is this the torus generator's mesh?".into());
    }
    let l_row = [
        (0i64, 1.0),
        (1, 0.5),
        (2, 0.1),
        (3, 0.01),
        (-3, -0.01),
        (-2, -0.1),
        (-1, -0.5),
    ];
    let s_row = [
        (0i64, 0.05),
        (1, 0.01),
        (2, 0.001),
        (-3, 0.001),
        (-2, 0.01),
        (-1, 0.05),
    ];
    let mut out = std::io::BufWriter::new(std::fs::File::create(&args[4])?);
    writeln!(
        out,
        "# Thesis ch. 6.3 banded metric (L | S) for a {n_xi} x {n_eta} torus; scale 1/5 in the case file"
    )?;
    writeln!(out, "# row column value (hasse face ids, signs folded in)")?;
    let n = cells as i64;
    for k in 0..cells {
        let (row_face, row_sign) = long[k];
        for (family, weights) in [(&long, &l_row[..]), (&short, &s_row[..])] {
            for &(offset, w) in weights {
                let col = ((k as i64 + offset).rem_euclid(n)) as usize;
                let (col_face, col_sign) = family[col];
                let value = w * f64::from(row_sign * col_sign);
                writeln!(out, "{row_face} {col_face} {value}")?;
            }
        }
    }
    out.flush()?;
    Ok(())
}
