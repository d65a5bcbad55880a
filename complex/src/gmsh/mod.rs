//! Reading Gmsh `.msh` meshes (format 4.1, ASCII or binary) into a
//! [`Complex`], with physical groups as [`Tags`].
//!
//! The file is parsed by the `mshio` crate; this module turns its element
//! blocks into top cells:
//!
//! - The mesh dimension n is the highest dimension of any element in the
//!   file; the top cells are all elements of dimension n, numbered in file
//!   order (element block by element block).
//! - Supported elements: point (Gmsh type 15, only as a member of a
//!   physical group), 2-node line (1), triangle (2), quadrangle (3),
//!   tetrahedron (4), hexahedron (5), prism (6) and pyramid (7). Gmsh's
//!   quadrangle and hexahedron node orders (counter-clockwise faces) are
//!   converted to the tensor order of [`TopCells::cuboids`]; prisms and
//!   pyramids become polyhedra. Any other element type (second-order
//!   elements in particular) is refused with
//!   [`GmshError::UnsupportedElement`].
//! - Nodes not used by any top cell are dropped; the others are renumbered
//!   0, 1, … in the order they appear in the `$Nodes` section.
//! - The embedding dimension is 3 if any kept node has z ≠ 0, otherwise 2
//!   if any has y ≠ 0 or n = 2, otherwise 1, and never less than n.
//! - Every element of dimension q ≤ n in an entity carrying physical tags
//!   adds its q-cell to the tag named in `$PhysicalNames`, or
//!   `physical:<dim>:<tag>` for an unnamed group. For q = n the cell is the
//!   element's top cell; for q < n it is the q-cell with the same vertices,
//!   which must exist ([`GmshError::NotACell`] otherwise). Named groups
//!   without elements become empty tags.
//!
//! ```
//! use hasse_complex::gmsh::read_msh_bytes;
//! let msh = "$MeshFormat\n4.1 0 8\n$EndMeshFormat
//! $Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes
//! $Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n";
//! let k = read_msh_bytes(msh.as_bytes(), "triangle.msh").unwrap();
//! assert_eq!(k.cell_counts(), vec![3, 3, 1]);
//! ```

use crate::cells::{TopCells, Vertices};
use crate::complex::Complex;
use crate::error::ComplexError;
use crate::tags::{CellTag, Tags};
use mshio::ElementType;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

mod sections;
use sections::{
    describe_parse_error, physical_names, read_format, scan_node_tags, section_headers,
};

/// How to obtain a Gmsh 4.1 file, quoted by the error messages.
pub(super) const REEXPORT: &str = "re-export it with Gmsh (File > Export > Gmsh MSH, format \"Version 4 ASCII\" or \"Version 4 Binary\"), or convert it on the command line with `gmsh OLD.msh -save -format msh4 -o NEW.msh`";

/// How to produce a mesh from a geometry, quoted by the error messages.
const MESH_IT: &str = "mesh the geometry before saving it (`gmsh -1`, `gmsh -2` or `gmsh -3 model.geo -o model.msh`, or Mesh > 2D/3D in the GUI)";

/// Why a Gmsh file could not be read. Every message names the file and says
/// how to fix it.
#[derive(Debug, thiserror::Error)]
pub enum GmshError {
    #[error("cannot read Gmsh mesh '{}': {source}; check the path and the file permissions", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("'{}' is not a valid Gmsh .msh 4.1 file: {message}", path.display())]
    Parse { path: PathBuf, message: String },
    #[error("'{}' is a Gmsh .msh file of format version {found}, but only version 4.1 can be read: {REEXPORT}", path.display())]
    UnsupportedVersion { path: PathBuf, found: String },
    #[error("'{}' contains elements of Gmsh type {element_type}, which cannot be read: {hint}", path.display())]
    UnsupportedElement {
        path: PathBuf,
        element_type: i32,
        hint: String,
    },
    #[error("'{}': element {element} refers to node {node}, which is not listed in the $Nodes section; the file is corrupt or was edited by hand: {REEXPORT}", path.display())]
    MissingNode {
        path: PathBuf,
        element: u64,
        node: u64,
    },
    #[error("'{}': element {element} of physical group '{group}' is not a {dim}-cell of the mesh (its nodes are not the vertices of a face of the top-dimensional elements); make the group's elements faces of the mesh, e.g. by meshing the geometry in one go so that boundary and domain elements share nodes", path.display())]
    NotACell {
        path: PathBuf,
        element: u64,
        dim: usize,
        group: String,
    },
    #[error("'{}': element {element} duplicates element {first} (the same nodes, listed twice); remove one of them (Gmsh: Coherence Mesh) or remesh", path.display())]
    DuplicateElement {
        path: PathBuf,
        /// The later element's tag.
        element: u64,
        /// The tag of the element it repeats.
        first: u64,
    },
    #[error("'{}' contains no mesh: {hint}", path.display())]
    Empty { path: PathBuf, hint: String },
    #[error("'{}': the elements do not form a valid cell complex: {source}{hint}", path.display())]
    Complex {
        path: PathBuf,
        #[source]
        source: ComplexError,
        /// Where the offending cell comes from in the file (may be empty).
        hint: String,
    },
}

impl GmshError {
    /// The file (or name) the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Io { path, .. }
            | Self::Parse { path, .. }
            | Self::UnsupportedVersion { path, .. }
            | Self::UnsupportedElement { path, .. }
            | Self::MissingNode { path, .. }
            | Self::NotACell { path, .. }
            | Self::DuplicateElement { path, .. }
            | Self::Empty { path, .. }
            | Self::Complex { path, .. } => path,
        }
    }
}

/// Read a Gmsh `.msh` 4.1 file (ASCII or binary).
pub fn read_msh(path: &Path) -> Result<Complex, GmshError> {
    let bytes = std::fs::read(path).map_err(|source| GmshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    read(&bytes, path)
}

/// Read the contents of a Gmsh `.msh` 4.1 file; `name_for_errors` is the
/// file name quoted by error messages.
pub fn read_msh_bytes(bytes: &[u8], name_for_errors: &str) -> Result<Complex, GmshError> {
    read(bytes, Path::new(name_for_errors))
}

/// The shape of a supported element type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Point,
    Line,
    Triangle,
    Quad,
    Tet,
    Hex,
    Prism,
    Pyramid,
}

impl Kind {
    fn of(t: ElementType) -> Option<Self> {
        Some(match t {
            ElementType::Pnt => Self::Point,
            ElementType::Lin2 => Self::Line,
            ElementType::Tri3 => Self::Triangle,
            ElementType::Qua4 => Self::Quad,
            ElementType::Tet4 => Self::Tet,
            ElementType::Hex8 => Self::Hex,
            ElementType::Pri6 => Self::Prism,
            ElementType::Pyr5 => Self::Pyramid,
            _ => return None,
        })
    }

    fn dim(self) -> usize {
        match self {
            Self::Point => 0,
            Self::Line => 1,
            Self::Triangle | Self::Quad => 2,
            Self::Tet | Self::Hex | Self::Prism | Self::Pyramid => 3,
        }
    }

    fn node_count(self) -> usize {
        match self {
            Self::Point => 1,
            Self::Line => 2,
            Self::Triangle => 3,
            Self::Quad | Self::Tet => 4,
            Self::Pyramid => 5,
            Self::Prism => 6,
            Self::Hex => 8,
        }
    }

    /// Append the element (nodes already renumbered, in Gmsh order) as a top cell.
    fn push(self, v: &[usize], cells: &mut TopCells) {
        match self {
            Self::Point | Self::Line | Self::Triangle | Self::Tet => cells.push_simplex(v),
            // Gmsh: counter-clockwise 0,1,2,3 → tensor order v00, v10, v01, v11.
            Self::Quad => cells.push_cuboid(&[v[0], v[1], v[3], v[2]]),
            // Gmsh: bottom 0,1,2,3 and top 4,5,6,7, both counter-clockwise.
            Self::Hex => cells.push_cuboid(&[v[0], v[1], v[3], v[2], v[4], v[5], v[7], v[6]]),
            // Gmsh: triangles 0,1,2 (bottom) and 3,4,5 (top), i+3 above i.
            Self::Prism => cells.push_polyhedron(&[
                vec![v[0], v[1], v[2]],
                vec![v[3], v[4], v[5]],
                vec![v[0], v[1], v[4], v[3]],
                vec![v[1], v[2], v[5], v[4]],
                vec![v[2], v[0], v[3], v[5]],
            ]),
            // Gmsh: base 0,1,2,3 counter-clockwise, apex 4.
            Self::Pyramid => cells.push_polyhedron(&[
                vec![v[0], v[1], v[2], v[3]],
                vec![v[0], v[1], v[4]],
                vec![v[1], v[2], v[4]],
                vec![v[2], v[3], v[4]],
                vec![v[3], v[0], v[4]],
            ]),
        }
    }
}

fn unsupported(path: &Path, t: ElementType) -> GmshError {
    let name = format!("{t:?}");
    let higher_order = ["Lin", "Tri", "Qua", "Tet", "Hex", "Pri", "Pyr"]
        .iter()
        .any(|p| name.starts_with(p))
        && t.nodes().is_ok_and(|k| k > 1);
    let hint = if higher_order {
        format!("{name} is a higher-order element; mesh with first-order elements (`gmsh -order 1`, or `Mesh.ElementOrder = 1;` in the .geo file)")
    } else {
        format!("{name} elements are not supported, only first-order points, lines, triangles, quadrangles, tetrahedra, hexahedra, prisms and pyramids; remesh with those element types")
    };
    GmshError::UnsupportedElement {
        path: path.to_path_buf(),
        element_type: t as i32,
        hint,
    }
}

pub(super) fn parse_error(path: &Path, message: impl Into<String>) -> GmshError {
    GmshError::Parse {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

fn empty(path: &Path, what: &str) -> GmshError {
    GmshError::Empty {
        path: path.to_path_buf(),
        hint: format!("{what}; {MESH_IT}"),
    }
}

fn read(bytes: &[u8], path: &Path) -> Result<Complex, GmshError> {
    let format = read_format(bytes, path)?;

    // mshio subtracts 1 from the node and element counts, which overflows on
    // empty sections, and computes max − min of the tag ranges, which
    // overflows when a range is inverted (panics in checked builds): report
    // those before handing the file over. Every line that opens such a
    // section is checked, since a damaged file may have several.
    for (section, what) in [("$Nodes", "node"), ("$Elements", "element")] {
        for [_, count, min, max] in section_headers(bytes, format, section) {
            if count == 0 {
                return Err(empty(
                    path,
                    &format!("the {section} section lists no {what}s"),
                ));
            }
            if max < min {
                return Err(parse_error(
                    path,
                    format!("the {section} header gives the {what} tags as {min}..{max}: the largest is below the smallest; {REEXPORT}"),
                ));
            }
        }
    }

    let parsed = std::panic::catch_unwind(|| {
        mshio::parse_msh_bytes(bytes).map_err(|e| describe_parse_error(bytes, &e))
    });
    let msh = match parsed {
        Ok(Ok(msh)) => msh,
        Ok(Err(message)) => return Err(parse_error(path, message)),
        Err(_) => {
            return Err(parse_error(
                path,
                format!("the Gmsh parser (mshio) gave up on malformed content; {REEXPORT}"),
            ))
        }
    };
    let names = physical_names(bytes, path)?;

    let Some(nodes) = msh.data.nodes.as_ref() else {
        return Err(empty(path, "the file has no $Nodes section"));
    };
    let Some(elements) = msh.data.elements.as_ref() else {
        return Err(empty(path, "the file has no $Elements section"));
    };

    // Node coordinates in file order and tag → position.
    let mut coords: Vec<[f64; 3]> = Vec::new();
    for block in &nodes.node_blocks {
        coords.extend(block.nodes.iter().map(|n| [n.x, n.y, n.z]));
    }
    let tags = match scan_node_tags(bytes, format) {
        Some(tags) if tags.len() == coords.len() => tags,
        _ => mshio_node_tags(nodes),
    };
    let mut position: HashMap<u64, usize> = HashMap::with_capacity(tags.len());
    for (i, &t) in tags.iter().enumerate() {
        if position.insert(t, i).is_some() {
            return Err(parse_error(
                path,
                format!("node tag {t} is listed twice in the $Nodes section; {REEXPORT}"),
            ));
        }
    }

    // Element kinds, node lookups and the mesh dimension.
    let mut kinds = Vec::with_capacity(elements.element_blocks.len());
    let mut n = 0;
    for block in &elements.element_blocks {
        let kind =
            Kind::of(block.element_type).ok_or_else(|| unsupported(path, block.element_type))?;
        for e in &block.elements {
            if e.nodes.len() != kind.node_count() {
                return Err(parse_error(
                    path,
                    format!(
                        "element {} lists {} nodes, a {:?} has {}",
                        e.element_tag,
                        e.nodes.len(),
                        block.element_type,
                        kind.node_count()
                    ),
                ));
            }
            if let Some(&node) = e.nodes.iter().find(|t| !position.contains_key(t)) {
                return Err(GmshError::MissingNode {
                    path: path.to_path_buf(),
                    element: e.element_tag,
                    node,
                });
            }
        }
        if !block.elements.is_empty() {
            n = n.max(kind.dim());
        }
        kinds.push(kind);
    }
    if n == 0 {
        return Err(empty(
            path,
            "it has no line, surface or volume elements (only points)",
        ));
    }

    // Keep the nodes of top elements, renumbered in file order.
    let mut used = vec![false; coords.len()];
    for (block, kind) in elements.element_blocks.iter().zip(&kinds) {
        if kind.dim() == n {
            for e in &block.elements {
                for t in &e.nodes {
                    if let Some(&i) = position.get(t) {
                        used[i] = true;
                    }
                }
            }
        }
    }
    let mut new_id = vec![usize::MAX; coords.len()];
    let mut kept = Vec::new();
    let mut kept_tags = Vec::new();
    for (i, &u) in used.iter().enumerate() {
        if u {
            new_id[i] = kept.len();
            kept.push(coords[i]);
            kept_tags.push(tags[i]);
        }
    }
    let renumber = |nodes: &[u64]| -> Option<Vec<usize>> {
        nodes
            .iter()
            .map(|t| Some(new_id[*position.get(t)?]).filter(|&v| v != usize::MAX))
            .collect()
    };

    let mut cells = TopCells::default();
    let mut top_tags = Vec::new();
    // A top element listed twice would otherwise be reported as two
    // overlapping cells.
    let mut seen: HashMap<Vec<u64>, u64> = HashMap::new();
    for (block, kind) in elements.element_blocks.iter().zip(&kinds) {
        if kind.dim() == n {
            for e in &block.elements {
                let mut key = e.nodes.clone();
                key.sort_unstable();
                if let Some(&first) = seen.get(&key) {
                    return Err(GmshError::DuplicateElement {
                        path: path.to_path_buf(),
                        element: e.element_tag,
                        first,
                    });
                }
                seen.insert(key, e.element_tag);
                // Every node of a top element exists (checked above) and is kept.
                let v = renumber(&e.nodes).ok_or_else(|| {
                    parse_error(
                        path,
                        format!("internal: element {} lost a node", e.element_tag),
                    )
                })?;
                kind.push(&v, &mut cells);
                top_tags.push(e.element_tag);
            }
        }
    }

    let z = kept.iter().any(|p| p[2] != 0.0);
    let y = kept.iter().any(|p| p[1] != 0.0);
    let d = if z {
        3
    } else if y || n == 2 {
        2
    } else {
        1
    }
    .max(n);
    let flat: Vec<f64> = kept.iter().flat_map(|p| p[..d].to_vec()).collect();
    let complex_error = |source: ComplexError| {
        let hint = complex_error_hint(&source, n, &top_tags, &kept_tags);
        GmshError::Complex {
            path: path.to_path_buf(),
            source,
            hint,
        }
    };
    let vertices = Vertices::new(d, flat).map_err(complex_error)?;
    let mut complex = Complex::build(vertices, cells).map_err(complex_error)?;

    // Physical groups.
    let mut physical: HashMap<(i32, i32), &[i32]> = HashMap::new();
    if let Some(entities) = msh.data.entities.as_ref() {
        for e in &entities.points {
            physical.insert((0, e.tag), &e.physical_tags);
        }
        for e in &entities.curves {
            physical.insert((1, e.tag), &e.physical_tags);
        }
        for e in &entities.surfaces {
            physical.insert((2, e.tag), &e.physical_tags);
        }
        for e in &entities.volumes {
            physical.insert((3, e.tag), &e.physical_tags);
        }
    }
    let group_name = |dim: usize, tag: i32| {
        names
            .get(&(dim as i32, tag))
            .cloned()
            .unwrap_or_else(|| format!("physical:{dim}:{tag}"))
    };
    let mut groups: BTreeMap<(usize, i32), Vec<usize>> = BTreeMap::new();
    for (&(dim, tag), _) in names.iter() {
        if let Ok(dim) = usize::try_from(dim) {
            if dim <= n {
                groups.entry((dim, tag)).or_default();
            }
        }
    }
    let mut top_index = 0;
    for (block, kind) in elements.element_blocks.iter().zip(&kinds) {
        let q = kind.dim();
        let phys = physical
            .get(&(block.entity_dim, block.entity_tag))
            .copied()
            .unwrap_or(&[]);
        for e in &block.elements {
            let cell = if q == n {
                top_index += 1;
                Some(top_index - 1)
            } else {
                None
            };
            if phys.is_empty() {
                continue;
            }
            let cell = match cell {
                Some(c) => c,
                None => renumber(&e.nodes)
                    .and_then(|v| complex.find_cell(q, &v))
                    .ok_or_else(|| GmshError::NotACell {
                        path: path.to_path_buf(),
                        element: e.element_tag,
                        dim: q,
                        group: group_name(q, phys[0]),
                    })?,
            };
            for &p in phys {
                groups.entry((q, p)).or_default().push(cell);
            }
        }
    }
    let mut tags = Tags::default();
    let mut dims: HashMap<String, usize> = HashMap::new();
    for ((dim, tag), cells) in groups {
        let name = group_name(dim, tag);
        let mut all = cells;
        if let Some(&other) = dims.get(&name) {
            if other != dim {
                return Err(parse_error(
                    path,
                    format!("physical groups of dimension {other} and {dim} are both named '{name}'; give them distinct names"),
                ));
            }
            if let Some(existing) = tags.get(&name) {
                all.extend_from_slice(&existing.cells);
            }
        }
        dims.insert(name.clone(), dim);
        tags.insert(&name, CellTag::new(dim, all));
    }
    complex.replace_tags(tags);
    Ok(complex)
}

/// Points a complex-building error at the Gmsh element it came from.
fn complex_error_hint(
    error: &ComplexError,
    n: usize,
    top_tags: &[u64],
    node_tags: &[u64],
) -> String {
    // A bad coordinate is the node's, not an element's: no hint about
    // cells.
    if let ComplexError::NonFiniteCoordinate { vertex, .. } = error {
        return match node_tags.get(*vertex) {
            Some(t) => format!(" (vertex {vertex} is Gmsh node {t})"),
            None => String::new(),
        };
    }
    let cell = match error {
        ComplexError::VertexOutOfRange { cell, .. }
        | ComplexError::RepeatedVertex { cell, .. }
        | ComplexError::WrongVertexCount { cell, .. }
        | ComplexError::MixedDimension { cell, .. }
        | ComplexError::NonOrientable { cell, .. } => Some(*cell),
        ComplexError::DegenerateCell { dim, cell, .. } if *dim == n => Some(*cell),
        _ => None,
    };
    match cell.and_then(|c| top_tags.get(c).map(|t| (c, t))) {
        Some((c, t)) => {
            format!(" (top cell {c} is Gmsh element {t}; check that element's nodes, or remesh)")
        }
        None => " (check for inverted, overlapping or flat elements, or remesh)".to_string(),
    }
}

/// Node tags in file order as far as mshio keeps them: an explicit map for
/// sparse tags, otherwise consecutive tags from the minimum.
fn mshio_node_tags(nodes: &mshio::Nodes<u64, i32, f64>) -> Vec<u64> {
    let mut tags = Vec::new();
    let mut next = nodes.min_node_tag;
    for block in &nodes.node_blocks {
        match &block.node_tags {
            Some(map) => {
                let mut local = vec![0; block.nodes.len()];
                for (&t, &i) in map {
                    if let Some(slot) = local.get_mut(i) {
                        *slot = t;
                    }
                }
                tags.extend(local);
            }
            None => {
                tags.extend((0..block.nodes.len() as u64).map(|i| next + i));
                next += block.nodes.len() as u64;
            }
        }
    }
    tags
}
