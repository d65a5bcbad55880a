//! Regions of a case: the tags `[regions]` defines by conditions, and the
//! check that every value given per region fits the mesh's tags, made
//! when the mesh is built so that `hasse check` refuses it before solving.

use super::diagnostic::Collector;
use super::expr::Expression;
use super::Case;
use crate::physics::regions::{top_cell_tags, RegionError, Regional};
use hasse_complex::Complex;

impl Case {
    /// Tag the top cells whose centroid satisfies each `[regions]`
    /// condition (a nonzero value).
    pub(super) fn apply_regions(&self, complex: &mut Complex, collector: &mut Collector) {
        let n = complex.dim();
        let centroids = complex.centroid(n).to_vec();
        let d = complex.embedding_dim();
        for (name, condition) in &self.regions {
            let key = format!("regions.{name}");
            if complex.tag(name).is_some() {
                collector.error(
                    None,
                    &key,
                    format!("the mesh already has a tag `{name}`"),
                    Some("choose another name for the region".into()),
                );
                continue;
            }
            let cells: Vec<usize> = (0..complex.cell_count(n))
                .filter(|&c| {
                    let v = condition.eval(&centroids[c * d..(c + 1) * d], 0.0);
                    v != 0.0 && !v.is_nan()
                })
                .collect();
            if cells.is_empty() {
                collector.error(
                    None,
                    &key,
                    format!("`{}` holds at no top cell's centroid", condition.text()),
                    Some("a region is the set of top cells whose centroid satisfies the condition; check the comparison and the mesh's extent".into()),
                );
                continue;
            }
            if let Err(e) = complex.set_tag(name, n, cells) {
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
