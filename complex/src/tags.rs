//! Named sets of cells: boundary regions and material regions, from
//! generators, Gmsh physical groups or geometric predicates.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A named set of p-cells (sorted, without repeats).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CellTag {
    /// Dimension p of the tagged cells.
    pub dim: usize,
    /// Sorted ids of the tagged p-cells.
    pub cells: Vec<usize>,
}

impl CellTag {
    /// A tag of p-cells; ids are sorted and repeats dropped.
    pub fn new(dim: usize, mut cells: Vec<usize>) -> Self {
        cells.sort_unstable();
        cells.dedup();
        Self { dim, cells }
    }

    /// True when p-cell `i` carries this tag.
    pub fn contains(&self, i: usize) -> bool {
        self.cells.binary_search(&i).is_ok()
    }
}

/// All tags of a complex, by name (iteration in name order).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tags {
    by_name: BTreeMap<String, CellTag>,
}

impl Tags {
    /// The tag called `name`.
    pub fn get(&self, name: &str) -> Option<&CellTag> {
        self.by_name.get(name)
    }

    /// Add or replace a tag.
    pub fn insert(&mut self, name: &str, tag: CellTag) {
        self.by_name.insert(name.to_string(), tag);
    }

    /// Tag names in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.by_name.keys().map(String::as_str)
    }

    /// (name, tag) pairs in name order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &CellTag)> {
        self.by_name.iter().map(|(k, v)| (k.as_str(), v))
    }

    /// Number of tags.
    pub fn len(&self) -> usize {
        self.by_name.len()
    }

    /// True when there is no tag.
    pub fn is_empty(&self) -> bool {
        self.by_name.is_empty()
    }
}
