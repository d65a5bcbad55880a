//! One flux convention for every method (issue 29, item 4): the `flux`
//! field is −K∇u·n through each (n−1)-cell along its orientation,
//! `outflow` the flux leaving the domain through each boundary cell, and
//! the conductivity is written per cell.
//!
//! On `cases/two-materials.toml` (K = 1 on x < 1, 20 on x > 1, u = 0 at
//! x = 0 and 1 at x = 2) the exact flux density is −K u′ x̂ = −(20/21) x̂ in
//! both materials (derived in the case file), so a face with unit normal
//! n_F and measure |F| carries −(20/21)(n_F · x̂)|F|, whatever the method.
//! The normals and the orientation come from the library's own generator
//! (the same grid the case builds), not from the output code.

use crate::scratch::Scratch;
use hasse_complex::generate::rectangle;
use std::process::Command;

#[test]
fn every_method_writes_the_physical_flux_through_oriented_faces() {
    let dir = Scratch::new("flux_convention");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mesh = rectangle(8, 4, [0.0, 2.0], [0.0, 1.0]).unwrap();
    let (n, d) = (2, 2);
    let normal = mesh.normal();
    let measure = mesh.measure(n - 1);
    let centroid = mesh.centroid(n - 1);
    let q = 20.0 / 21.0;
    for method in ["fe", "fv", "fv-mimetic", "fd"] {
        let stem = dir.join(method);
        let set = format!("problem.method=\"{method}\"");
        let out = Command::new(env!("CARGO_BIN_EXE_hasse"))
            .args(["run", "cases/two-materials.toml", "-q", "--set", &set, "-o"])
            .arg(&stem)
            .current_dir(&root)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let file = hdf5::File::open(stem.with_extension("h5")).unwrap();
        let read = |path: &str| file.dataset(path).unwrap().read_raw::<f64>().unwrap();
        let flux = read("steps/0/flux");
        let outflow = read("steps/0/outflow");
        assert_eq!(flux.len(), mesh.cell_count(1), "{method}");
        for f in 0..mesh.cell_count(1) {
            let expected = -q * normal[f * d] * measure[f];
            // Rounding of a solve with K jumping 20×: 1e-12 of q.
            assert!(
                (flux[f] - expected).abs() < 1e-12,
                "{method}: face {f} at {:?}: flux {:e}, expected {expected:e}",
                &centroid[f * d..f * d + d],
                flux[f]
            );
        }
        // `outflow`: the flux leaving through each boundary cell; over a
        // tag it sums to the flux out through it (OUTPUT.md's example).
        let tag = |name: &str| -> f64 {
            mesh.tag(name)
                .unwrap()
                .cells
                .iter()
                .map(|&f| outflow[f])
                .sum()
        };
        assert!((tag("xmin") - q).abs() < 1e-12, "{method}: {}", tag("xmin"));
        assert!((tag("xmax") + q).abs() < 1e-12, "{method}: {}", tag("xmax"));
        assert!(
            tag("ymin").abs() < 1e-12 && tag("ymax").abs() < 1e-12,
            "{method}"
        );
        // The conductivity of each cell, by its centroid's side of x = 1.
        let k = read("steps/0/conductivity");
        let centres = mesh.centroid(n);
        for (c, &kc) in k.iter().enumerate() {
            let expected = if centres[c * d] < 1.0 { 1.0 } else { 20.0 };
            assert_eq!(kc, expected, "{method}: cell {c}");
        }
    }
}
