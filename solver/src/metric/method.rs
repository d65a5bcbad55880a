//! The discretisation methods, by the name case files and reports use,
//! and where each puts its unknowns.

use hasse_complex::DualKind;
use std::fmt;
use std::str::FromStr;

/// The discretisation: which Ω (and A) a scalar diffusion problem uses.
///
/// The name is what case files, `--methods` and reports write; `parse` and
/// `Display` are the one mapping between names and methods.
///
/// ```
/// use hasse_solver::metric::Method;
/// let m: Method = "fv-mimetic".parse().unwrap();
/// assert_eq!(m, Method::FvMimetic);
/// assert_eq!(m.to_string(), "fv-mimetic");
/// let wrong = "fvm".parse::<Method>().unwrap_err();
/// assert!(wrong.to_string().contains("fd, fe, fv, fv-mimetic, dec, dec-barycentric"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Five/seven-point finite differences on cell centres of an axis-aligned grid.
    Fd,
    /// Nodal finite elements: P1 on simplices, Q1 on quads/hexes, lowest-order
    /// virtual elements on other polytopes.
    Fe,
    /// Cell-centred finite volumes with the two-point flux.
    Fv,
    /// Hybrid mimetic finite differences (cell and face unknowns).
    FvMimetic,
    /// Discrete exterior calculus on vertices with the given dual.
    Dec(DualKind),
}

impl Method {
    /// Every method, in the order help texts list them.
    pub const ALL: [Method; 6] = [
        Method::Fd,
        Method::Fe,
        Method::Fv,
        Method::FvMimetic,
        Method::Dec(DualKind::Circumcentric),
        Method::Dec(DualKind::Barycentric),
    ];

    /// The name used in case files and reports.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Fd => "fd",
            Method::Fe => "fe",
            Method::Fv => "fv",
            Method::FvMimetic => "fv-mimetic",
            Method::Dec(DualKind::Circumcentric) => "dec",
            Method::Dec(DualKind::Barycentric) => "dec-barycentric",
        }
    }

    /// Every method's name, in the order of [`Method::ALL`].
    pub fn names() -> Vec<&'static str> {
        Self::ALL.iter().map(Method::name).collect()
    }

    /// Where this method's unknowns live.
    pub fn location(&self) -> Location {
        match self {
            Method::Fe | Method::Dec(_) => Location::Nodal,
            Method::Fd | Method::Fv => Location::CellCentred,
            Method::FvMimetic => Location::Hybrid,
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A method name that names no method.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown method \"{name}\"; the methods are {}", Method::names().join(", "))]
pub struct UnknownMethod {
    /// The name as given.
    pub name: String,
}

impl FromStr for Method {
    type Err = UnknownMethod;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        let name = name.trim();
        Self::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| UnknownMethod {
                name: name.to_string(),
            })
    }
}

/// Where the unknowns of a method live.
///
/// ```
/// use hasse_complex::generate::rectangle;
/// use hasse_solver::metric::mass::lumped;
/// use hasse_solver::metric::Location;
/// // A 2×1 grid of unit squares: 6 vertices, 2 cells of area 1.
/// let k = rectangle(2, 1, [0.0, 2.0], [0.0, 1.0]).unwrap();
/// assert_eq!(lumped(&k, Location::Nodal).unwrap().len(), 6);
/// assert_eq!(lumped(&k, Location::CellCentred), Some(vec![1.0, 1.0]));
/// // Face unknowns stand for no volume.
/// assert_eq!(lumped(&k, Location::Hybrid), None);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// On vertices (0-cells).
    Nodal,
    /// On top cells.
    CellCentred,
    /// On top cells, then on (n−1)-cells.
    Hybrid,
}
