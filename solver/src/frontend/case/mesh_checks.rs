//! What a case asks of its mesh, checked when the mesh is built so that
//! `hasse check` refuses it before solving: the tags `[regions]` defines,
//! values per region, quantities of interest and probes.

use super::diagnostic::Collector;
use super::expr::Expression;
use super::Case;
use crate::physics::regions::{top_cell_tags, RegionError, Regional};
use hasse_complex::Complex;

impl Case {
    /// A DEC kind's degree must be at most the mesh's dimension (cohomology
    /// generators, absolute and relative, and Hodge decompositions are
    /// computed for every degree), and the
    /// circumcentric and Whitney stars need simplices. Only these kinds
    /// measure a periodic mesh unwrapped.
    pub(super) fn check_hodge(&self, complex: &Complex, collector: &mut Collector) {
        use super::Problem;
        let (method, method_span, degree) = match &self.problem {
            Problem::Hodge(spec) => (
                spec.method,
                &spec.method_span,
                Some((spec.degree, &spec.degree_span)),
            ),
            Problem::Cohomology(spec) => (
                spec.method,
                &spec.method_span,
                Some((spec.degree, &spec.degree_span)),
            ),
            Problem::Decomposition(spec) => (
                spec.method,
                &spec.method_span,
                Some((spec.degree, &spec.degree_span)),
            ),
            Problem::FormDiffusion(spec) => (
                spec.method,
                &spec.method_span,
                Some((spec.degree, &spec.degree_span)),
            ),
            _ => {
                // Only the stars and Whitney forms read a cell's geometry from
                // its unwrapped points; every other kind's metrics, loads and
                // error norms read vertex coordinates directly, and would see
                // the cells that wrap around stretched across the domain.
                if complex.vertices().period().is_some() {
                    collector.error(
                        self.mesh_spans.get("generator").cloned(),
                        "mesh.generator",
                        format!(
                            "a periodic mesh (the flat torus) is measured unwrapped only by the DEC kinds (hodge-laplacian, cohomology, hodge-decomposition, diffusion of k-forms); kind = \"{}\" would read the wrapped cells' coordinates directly",
                            self.problem.kind()
                        ),
                        Some("use kind = \"hodge-laplacian\" on generator = \"torus-flat\"".into()),
                    );
                }
                return;
            }
        };
        let n = complex.dim();
        if let Some((degree, span)) = degree {
            if degree > n {
                collector.error(
                    span.clone(),
                    "problem.degree",
                    format!(
                        "degree {degree} is out of range: the mesh is {n}-dimensional, so 0 ≤ degree ≤ {n}"
                    ),
                    Some(format!(
                        "k-forms live on k-cells; choose a degree from 0 to {n}"
                    )),
                );
            }
        }
        if !matches!(
            method,
            super::HodgeMethod::DecBarycentric | super::HodgeMethod::Supplied
        ) {
            if let Some(c) =
                (0..complex.cell_count(n)).find(|&c| complex.cell_vertices(n, c).len() != n + 1)
            {
                collector.error(
                    method_span.clone(),
                    "problem.method",
                    format!(
                        "method \"{}\" needs a simplicial mesh; top cell {c} has {} vertices",
                        method.name(),
                        complex.cell_vertices(n, c).len()
                    ),
                    Some("use method = \"dec-barycentric\" on cells that are not simplices".into()),
                );
            }
        }
    }

    /// Tag the top cells whose centroid satisfies each `[regions]`
    /// condition (a nonzero value).
    pub(super) fn apply_regions(&self, complex: &mut Complex, collector: &mut Collector) {
        let d = complex.embedding_dim();
        for region in &self.regions {
            let name = &region.name;
            let key = format!("regions.{name}");
            let dim = complex.dim() - usize::from(region.faces);
            if complex.tag(name).is_some() {
                collector.error(
                    None,
                    &key,
                    format!("the mesh already has a tag `{name}`"),
                    Some("choose another name for the region".into()),
                );
                continue;
            }
            let centroids = complex.centroid(dim);
            let cells: Vec<usize> = (0..complex.cell_count(dim))
                .filter(|&c| {
                    let v = region.condition.eval(&centroids[c * d..(c + 1) * d], 0.0);
                    v != 0.0 && !v.is_nan()
                })
                .collect();
            if cells.is_empty() {
                collector.error(
                    None,
                    &key,
                    format!(
                        "`{}` holds at no {}'s centroid",
                        region.condition.text(),
                        if region.faces { "(n−1)-cell" } else { "top cell" }
                    ),
                    Some("a region is the set of cells whose centroid satisfies the condition; check the comparison and the mesh's extent (compare coordinates of faces with a tolerance, e.g. abs(x - 1) < 1e-9)".into()),
                );
                continue;
            }
            if let Err(e) = complex.set_tag(name, dim, cells) {
                collector.error(None, &key, e.to_string(), None);
            }
        }
    }

    /// Refuse every value per region whose regions are not tags of top
    /// cells, that leaves a cell without a value, or that gives a cell
    /// two.
    pub(super) fn check_regional_data(&self, complex: &Complex, collector: &mut Collector) {
        for (key, expression) in self.problem.regional_data() {
            let Some(regions) = expression.regions() else {
                continue;
            };
            let regional: Regional<&Expression> = Regional::new(
                regions.pieces.iter().map(|(n, e)| (n.clone(), e)).collect(),
                regions.default.as_ref(),
            );
            if let Err(e) = regional.piece_per_cell(complex) {
                let help = match e {
                    _ if top_cell_tags(complex).is_empty() => "the mesh has no tags of top cells: define regions under [regions] (`name = \"x < 0.5\"`) or use Gmsh physical groups of the mesh's dimension",
                    RegionError::Uncovered { .. } => "add `default = …` for the cells in no listed region",
                    RegionError::Overlap { .. } => "a top cell may be in one listed region only: give the overlap a region of its own, or tighten the [regions] conditions",
                    RegionError::UnknownTag { .. } | RegionError::NotTopCells { .. } => "regions are tags of top cells: Gmsh physical groups of the mesh's dimension, or conditions under [regions]",
                };
                collector.error(None, &key, e.to_string(), Some(help.to_string()));
            }
        }
    }
}

impl Case {
    /// Refuse quantities whose tag or region the mesh does not have and
    /// quantities of problems that do not compute them.
    pub(super) fn check_quantities(&self, complex: &Complex, collector: &mut Collector) {
        use super::Problem;
        let n = complex.dim();
        for q in &self.output.quantities {
            match (&self.problem, q.kind) {
                (Problem::Diffusion(_) | Problem::Heat(_), _) => {}
                _ => {
                    collector.error(
                        None,
                        &q.key,
                        "quantities are computed for diffusion and heat problems",
                        Some("remove the [[output.quantity]] tables of this case".into()),
                    );
                    continue;
                }
            }
            let (name, dim, what) = match (&q.tag, &q.region) {
                (Some(tag), _) => (tag, n - 1, "tag"),
                (None, Some(region)) => (region, n, "region"),
                (None, None) => continue,
            };
            let key = format!("{}.{what}", q.key);
            let candidates: Vec<String> = complex
                .tags()
                .iter()
                .filter(|(_, t)| t.dim == dim)
                .map(|(n, _)| n.to_string())
                .collect();
            let Some(tag) = complex.tag(name) else {
                collector.error(
                    None,
                    &key,
                    format!("no tag `{name}` in the mesh"),
                    Some(format!(
                        "its tags of {dim}-cells: {}",
                        candidates.join(", ")
                    )),
                );
                continue;
            };
            if tag.dim != dim {
                collector.error(
                    None,
                    &key,
                    format!(
                        "tag `{name}` names {}-cells; a {} needs {dim}-cells",
                        tag.dim,
                        q.kind.name()
                    ),
                    Some(format!(
                        "its tags of {dim}-cells: {}",
                        candidates.join(", ")
                    )),
                );
                continue;
            }
        }
    }
}

impl Case {
    /// Refuse probes outside the mesh (with the point) and probes on a
    /// mesh whose cells do not fill their space.
    pub(super) fn check_probes(&self, complex: &Complex, collector: &mut Collector) {
        if self.output.probes.is_empty() {
            return;
        }
        let form_degree = crate::frontend::run::probes::form_degree(&self.problem);
        if form_degree.is_none()
            && !matches!(
                self.problem,
                super::Problem::Diffusion(_) | super::Problem::Heat(_)
            )
        {
            collector.error(
                None,
                &self.output.probes[0].key,
                "probes are evaluated for diffusion and heat problems, and for the forms of maxwell, hodge-laplacian, cohomology and hodge-decomposition",
                Some("remove the [[output.probe]] tables of this case".into()),
            );
            return;
        }
        // A form is probed through its proxy: a function, a vector field
        // or a density (not, e.g., a 2-form on a 4-complex).
        if let Some(Err(e)) = form_degree
            .filter(|&k| k <= complex.dim())
            .map(|k| crate::physics::forms::whitney_map::ProxyKind::of(complex, k))
        {
            collector.error(None, &self.output.probes[0].key, e.to_string(), None);
            return;
        }
        let locator = match crate::physics::probe::PointLocator::new(complex) {
            Ok(locator) => locator,
            Err(e) => {
                collector.error(None, &self.output.probes[0].key, e.to_string(), None);
                return;
            }
        };
        let d = complex.embedding_dim();
        for probe in &self.output.probes {
            if let Some(p) = probe.points.iter().find(|p| p.len() != d) {
                collector.error(
                    None,
                    &probe.key,
                    format!(
                        "the point {p:?} has {} coordinates; the mesh lives in R^{d}",
                        p.len()
                    ),
                    None,
                );
                continue;
            }
            if let Some((i, p)) = probe
                .points
                .iter()
                .enumerate()
                .find(|(_, p)| locator.locate(p).is_none())
            {
                let which = if probe.points.len() == 1 {
                    String::new()
                } else {
                    format!(" (point {i} of the line)")
                };
                collector.error(
                    None,
                    &probe.key,
                    format!("the probe point {p:?}{which} is outside the mesh"),
                    Some(
                        "`hasse info` prints the mesh's extent; a point on the boundary is inside"
                            .into(),
                    ),
                );
            }
        }
    }
}
