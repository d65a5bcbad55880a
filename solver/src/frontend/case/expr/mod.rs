//! Expressions of case files: coefficients, sources, boundary values and
//! exact solutions written as text in `x`, `y`, `z` and `t`.
//!
//! Parsing and evaluation are exmex's (`+ - * / ^`, `sin cos tan asin acos
//! atan atan2 sinh cosh tanh exp ln log10 log2 sqrt cbrt abs signum floor
//! ceil round trunc fract min max`, the constants `PI`/`π`, `TAU`/`τ`, `E`).
//! hasse adds comparisons (`< <= > >= == !=`, worth 1 or 0), `&&` and `||`
//! (a number holds when it is nonzero), and the conditional
//! `if(condition, value when it holds, value otherwise)`
//! ([`ops`] says how). On top of that a [`Scope`] supplies `pi` (the usual spelling in
//! engineering texts), the case's named constants and its definitions:
//! named expressions that later expressions may use, evaluated point by
//! point in the order the case file gives them.
//!
//! Names are checked when an expression is parsed, so a misspelt variable
//! is reported with a suggestion before anything is solved.
//!
//! ```
//! use hasse_solver::frontend::case::expr::Scope;
//! let mut scope = Scope::new();
//! scope.add_constant("k", 2.0).unwrap();
//! scope.add_definition("r", "sqrt(x^2 + y^2)").unwrap();
//! let e = scope.parse("k * r * sin(pi * t)").unwrap();
//! assert!((e.eval(&[3.0, 4.0], 0.5) - 10.0).abs() < 1e-12);
//! // A conductivity of 20 right of x = 1.2 and 1 elsewhere; a square.
//! let jump = scope.parse("if(x > 1.2, 20, 1)").unwrap();
//! assert_eq!((jump.eval(&[1.0], 0.0), jump.eval(&[1.5], 0.0)), (1.0, 20.0));
//! let square = scope.parse("x > 0 && x < 1 && y > 0 && y < 1").unwrap();
//! assert_eq!((square.eval(&[0.5, 0.5], 0.0), square.eval(&[0.5, 1.5], 0.0)), (1.0, 0.0));
//! ```

mod messages;
pub mod ops;
mod solution;

pub use messages::{quote, QUOTE_WIDTH};
use messages::{syntax_text, unknown_text};

use exmex::prelude::*;
use exmex::MatchLiteral;
use ops::CaseOps;
use std::sync::Arc;

/// Number literals with an optional exponent (`2.5e-3`, `1E6`): exmex's own
/// matcher stops at the `e`, so `1e-3` would parse as `1·e − 3`, and TOML
/// numbers such as `1e-7` (which case files pass on as expression text)
/// could not be read at all.
#[derive(Clone, Debug)]
pub(crate) struct ScientificNumbers;

impl MatchLiteral for ScientificNumbers {
    fn is_literal(text: &str) -> Option<&str> {
        let bytes = text.as_bytes();
        let digits = |from: usize| {
            bytes[from..]
                .iter()
                .take_while(|b| b.is_ascii_digit())
                .count()
        };
        let mut end = digits(0);
        if bytes.get(end) == Some(&b'.') && digits(end + 1) > 0 {
            end += 1 + digits(end + 1);
        }
        if end == 0 {
            return None;
        }
        if matches!(bytes.get(end), Some(b'e' | b'E')) {
            let sign = usize::from(matches!(bytes.get(end + 1), Some(b'+' | b'-')));
            let exponent = digits(end + 1 + sign);
            if exponent > 0 {
                end += 1 + sign + exponent;
            }
        }
        Some(&text[..end])
    }
}

type Flat = FlatEx<f64, CaseOps, ScientificNumbers>;

/// Names every expression may use without declaring them.
pub const COORDINATES: [&str; 4] = ["x", "y", "z", "t"];

/// Why an expression or a name was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ExprError {
    /// The text is not an expression; `message` says why in the case
    /// file's terms (never the parser's internals).
    #[error("{}", syntax_text(.text, .message))]
    Syntax {
        /// The text as written.
        text: String,
        /// What is wrong with it.
        message: String,
    },
    /// The expression uses a name that is neither a coordinate, a constant
    /// nor a definition.
    #[error("{}", unknown_text(.text, .name, .suggestion))]
    UnknownVariable {
        /// The expression as written.
        text: String,
        /// The unknown name.
        name: String,
        /// The known name closest to it, if one is close enough to be
        /// the intended one.
        suggestion: Option<String>,
    },
    /// A constant or definition would shadow a coordinate, a built-in or
    /// an earlier name.
    #[error("`{name}` cannot be used as a name: {reason}")]
    ReservedName {
        /// The name.
        name: String,
        /// Why it cannot be one.
        reason: String,
    },
    /// A coefficient of a nonlinear problem whose derivative with respect
    /// to u cannot be formed.
    #[error("cannot differentiate `{text}` with respect to u: {reason}")]
    NotDifferentiable {
        /// The expression as written.
        text: String,
        /// exmex's reason.
        reason: String,
    },
    /// A constant whose value is NaN or infinite.
    #[error("constant `{name}` is not finite ({value})")]
    NonFiniteConstant {
        /// The constant's name.
        name: String,
        /// Its value.
        value: f64,
    },
}

/// Where the value of one exmex variable comes from.
#[derive(Clone, Debug)]
enum Slot {
    Coordinate(usize),
    Time,
    /// The solution u of a nonlinear problem.
    Solution,
    Constant(f64),
    Definition(Arc<Expression>),
}

/// A parsed expression, ready to evaluate at points.
///
/// ```
/// use hasse_solver::frontend::case::expr::Scope;
/// let scope = Scope::new();
/// let e = scope.parse("x^2 + 2.5e-1 * z").unwrap();
/// // Missing coordinates are 0: a point of a 2D mesh has z = 0.
/// assert_eq!(e.eval(&[3.0, 1.0], 0.0), 9.0);
/// assert_eq!(e.eval(&[3.0, 1.0, 4.0], 0.0), 10.0);
/// assert!(!e.is_constant() && !e.uses_time());
/// assert!(scope.parse("2 * pi").unwrap().is_constant());
/// // Division by zero is a value, not an error: callers check values.
/// assert!(scope.parse("1 / x").unwrap().eval(&[0.0], 0.0).is_infinite());
/// ```
#[derive(Clone, Debug)]
pub struct Expression {
    text: String,
    /// Boxed: exmex keeps its nodes in large inline arrays (~20 kB).
    flat: Box<Flat>,
    /// One slot per exmex variable, in exmex's (alphabetical) order.
    slots: Vec<Slot>,
    /// True when the value depends on neither position nor time.
    constant: bool,
    uses_time: bool,
    /// True when the value depends on the solution `u`.
    uses_solution: bool,
    /// Set for a value per region ([`Expression::per_region`]).
    regions: Option<Arc<Regions>>,
}

/// A value per region of top cells, as a case writes it:
/// `conductivity = { steel = 1, copper = "20 + x", default = 5 }`. The
/// names are tags of top cells, checked against the mesh when it is built.
#[derive(Clone, Debug)]
pub struct Regions {
    /// Each region's expression, in the order written.
    pub pieces: Vec<(String, Expression)>,
    /// The expression of cells in no listed region (`default`).
    pub default: Option<Expression>,
}

impl Expression {
    /// The text as written in the case file.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// True when the expression depends on no coordinate and not on t.
    pub fn is_constant(&self) -> bool {
        self.constant
    }

    /// True when the expression depends on t (directly or through a definition).
    pub fn uses_time(&self) -> bool {
        self.uses_time
    }

    /// True when the expression depends on the solution `u` (only a
    /// scope made by [`Scope::with_solution`] lets it).
    pub fn uses_solution(&self) -> bool {
        self.uses_solution
    }

    /// An expression per region; `text` is how the case wrote it.
    ///
    /// ```
    /// use hasse_solver::frontend::case::expr::{Expression, Regions, Scope};
    /// let scope = Scope::new();
    /// let regions = Regions {
    ///     pieces: vec![("copper".into(), scope.parse("20 + x").unwrap())],
    ///     default: Some(scope.parse("5").unwrap()),
    /// };
    /// let k = Expression::per_region("{ copper = \"20 + x\", default = 5 }", regions);
    /// assert!(!k.is_constant() && k.regions().is_some());
    /// // A point alone does not say which region it is in.
    /// assert!(k.eval(&[0.5], 0.0).is_nan());
    /// ```
    pub fn per_region(text: &str, regions: Regions) -> Expression {
        let uses_time = regions
            .pieces
            .iter()
            .map(|(_, e)| e)
            .chain(&regions.default)
            .any(Expression::uses_time);
        let flat = Flat::parse("0").expect("`0` parses");
        Expression {
            text: text.to_string(),
            flat: Box::new(flat),
            slots: Vec::new(),
            constant: false,
            uses_time,
            uses_solution: regions
                .pieces
                .iter()
                .map(|(_, e)| e)
                .chain(&regions.default)
                .any(Expression::uses_solution),
            regions: Some(Arc::new(regions)),
        }
    }

    /// The expressions per region, if the case gave the value so.
    pub fn regions(&self) -> Option<&Regions> {
        self.regions.as_deref()
    }

    /// The value at `point` (missing coordinates are 0) and time `t`; NaN
    /// for a value per region, which a point alone does not select.
    ///
    /// Division by zero and the like give non-finite values, not errors:
    /// callers check the values they evaluate and say where it happened.
    pub fn eval(&self, point: &[f64], t: f64) -> f64 {
        self.evaluate(point, t, f64::NAN)
    }

    fn evaluate(&self, point: &[f64], t: f64, u: f64) -> f64 {
        if self.regions.is_some() {
            return f64::NAN;
        }
        // Almost every expression has a handful of variables: keep them on
        // the stack; this runs once per cell or quadrature point.
        let mut stack = [0.0; 16];
        let mut heap;
        let values: &mut [f64] = if self.slots.len() <= stack.len() {
            &mut stack[..self.slots.len()]
        } else {
            heap = vec![0.0; self.slots.len()];
            &mut heap
        };
        for (value, slot) in values.iter_mut().zip(&self.slots) {
            *value = match slot {
                Slot::Coordinate(i) => point.get(*i).copied().unwrap_or(0.0),
                Slot::Time => t,
                Slot::Solution => u,
                Slot::Constant(c) => *c,
                Slot::Definition(e) => e.eval(point, t),
            };
        }
        // The slot count equals the variable count by construction, which is
        // the only way exmex's evaluation fails for floats.
        self.flat.eval(values).unwrap_or(f64::NAN)
    }
}

/// Names available to expressions: coordinates, `pi`, constants and
/// definitions.
///
/// ```
/// use hasse_solver::frontend::case::expr::{ExprError, Scope};
/// let mut scope = Scope::new();
/// scope.add_constant("amplitude", 3.0).unwrap();
/// // A definition that uses t makes every expression using it depend on t.
/// scope.add_definition("wave", "amplitude * sin(x - t)").unwrap();
/// assert!(scope.parse("wave^2").unwrap().uses_time());
/// // Names may not shadow coordinates, built-ins or earlier names.
/// assert!(matches!(scope.add_constant("t", 1.0), Err(ExprError::ReservedName { .. })));
/// assert!(matches!(scope.add_constant("sin", 1.0), Err(ExprError::ReservedName { .. })));
/// // Misspelt names come back with the closest known one.
/// let Err(ExprError::UnknownVariable { suggestion, .. }) = scope.parse("amplitud * x") else { panic!() };
/// assert_eq!(suggestion.as_deref(), Some("amplitude"));
/// ```
#[derive(Clone, Debug, Default)]
pub struct Scope {
    constants: Vec<(String, f64)>,
    definitions: Vec<(String, Arc<Expression>)>,
    /// Whether `u` names the solution (coefficients of a nonlinear
    /// problem), unless a constant or definition of the case is called u.
    solution: bool,
}

/// Names exmex already gives a meaning to; a user name equal to one of
/// them would be parsed as the operator or constant instead.
const BUILTINS: [&str; 40] = [
    "abs", "acos", "acosh", "asin", "asinh", "atan", "atan2", "atanh", "cbrt", "ceil", "cos",
    "cosh", "exp", "floor", "fract", "ln", "log", "log10", "log2", "max", "min", "round", "signum",
    "sin", "sinh", "sqrt", "tan", "tanh", "trunc", "PI", "π", "E", "e", "TAU", "τ", "pi", "if",
    "else", "if_then", "if_else",
];

impl Scope {
    /// A scope with the coordinates and `pi` only.
    pub fn new() -> Self {
        Self::default()
    }

    /// The same scope in which `u` names the solution (the conductivity
    /// and reaction of a diffusion problem), unless the case defines a
    /// constant or definition `u` itself.
    pub fn with_solution(&self) -> Scope {
        Scope {
            solution: true,
            ..self.clone()
        }
    }

    /// Every name an expression may use, for suggestions and messages.
    pub fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = COORDINATES.iter().map(|s| s.to_string()).collect();
        if self.solution {
            names.push("u".into());
        }
        names.push("pi".into());
        names.extend(self.constants.iter().map(|(n, _)| n.clone()));
        names.extend(self.definitions.iter().map(|(n, _)| n.clone()));
        names
    }

    fn check_new_name(&self, name: &str) -> Result<(), ExprError> {
        let reserved = |reason: &str| ExprError::ReservedName {
            name: name.to_string(),
            reason: reason.to_string(),
        };
        let mut chars = name.chars();
        let valid = chars.next().is_some_and(|c| c.is_alphabetic() || c == '_')
            && chars.all(|c| c.is_alphanumeric() || c == '_');
        if !valid {
            return Err(reserved(
                "names start with a letter or `_` and continue with letters, digits or `_`",
            ));
        }
        if COORDINATES.contains(&name) {
            return Err(reserved("it is a coordinate (x, y, z) or the time (t)"));
        }
        if BUILTINS.contains(&name) {
            return Err(reserved("it is a built-in function or constant"));
        }
        if self.constants.iter().any(|(n, _)| n == name)
            || self.definitions.iter().any(|(n, _)| n == name)
        {
            return Err(reserved("it is already defined"));
        }
        Ok(())
    }

    /// Add a named constant.
    pub fn add_constant(&mut self, name: &str, value: f64) -> Result<(), ExprError> {
        self.check_new_name(name)?;
        if !value.is_finite() {
            return Err(ExprError::NonFiniteConstant {
                name: name.to_string(),
                value,
            });
        }
        self.constants.push((name.to_string(), value));
        Ok(())
    }

    /// Add a named expression; it may use the coordinates, constants and
    /// earlier definitions.
    pub fn add_definition(&mut self, name: &str, text: &str) -> Result<(), ExprError> {
        self.check_new_name(name)?;
        let expression = self.parse(text)?;
        self.definitions
            .push((name.to_string(), Arc::new(expression)));
        Ok(())
    }

    /// Parse `text` against this scope.
    pub fn parse(&self, text: &str) -> Result<Expression, ExprError> {
        let rewritten = ops::rewrite_unary_powers(&ops::rewrite_conditionals(text)?);
        let flat = Flat::parse(&rewritten).map_err(|_| ExprError::Syntax {
            text: text.to_string(),
            message: syntax_problem(text, &self.names()),
        })?;
        let mut slots = Vec::with_capacity(flat.var_names().len());
        let mut constant = true;
        let mut uses_time = false;
        let mut uses_solution = false;
        let defined = |name: &str| {
            self.constants.iter().any(|(n, _)| n == name)
                || self.definitions.iter().any(|(n, _)| n == name)
        };
        for name in flat.var_names() {
            let slot = if let Some(i) = ["x", "y", "z"].iter().position(|c| c == name) {
                constant = false;
                Slot::Coordinate(i)
            } else if name == "t" {
                constant = false;
                uses_time = true;
                Slot::Time
            } else if name == "pi" {
                Slot::Constant(std::f64::consts::PI)
            } else if name == "u" && self.solution && !defined(name) {
                constant = false;
                uses_solution = true;
                Slot::Solution
            } else if let Some((_, v)) = self.constants.iter().find(|(n, _)| n == name) {
                Slot::Constant(*v)
            } else if let Some((_, e)) = self.definitions.iter().find(|(n, _)| n == name) {
                constant &= e.constant;
                uses_time |= e.uses_time;
                Slot::Definition(e.clone())
            } else {
                return Err(ExprError::UnknownVariable {
                    text: text.to_string(),
                    name: name.clone(),
                    suggestion: closest(name, &self.names()),
                });
            };
            slots.push(slot);
        }
        Ok(Expression {
            text: text.to_string(),
            flat: Box::new(flat),
            slots,
            constant,
            uses_time,
            uses_solution,
            regions: None,
        })
    }
}

/// What is wrong with `text`, which the parser refused, in the terms of a
/// case file: the parser's own messages describe its internals ("we have
/// 1 ops and 4 node"), so the text is examined here instead. `names` are
/// the variables the expression could use.
fn syntax_problem(text: &str, names: &[String]) -> String {
    let trimmed = text.trim();
    if trimmed.is_empty() {
        return "the expression is empty".into();
    }
    // Brackets first: an unclosed one confuses every other reading.
    let mut depth = 0i32;
    for c in trimmed.chars() {
        match c {
            '(' => depth += 1,
            ')' if depth == 0 => return "a `)` closes no `(`".into(),
            ')' => depth -= 1,
            _ => {}
        }
    }
    if depth > 0 {
        return format!(
            "{depth} `(` never closed: add the missing `)`{}",
            if depth > 1 { "s" } else { "" }
        );
    }
    // A number followed by a word: a unit (`5 W/m`), or a product written
    // without `*` (`2x`).
    let number_end = trimmed
        .char_indices()
        .find(|&(i, c)| {
            !(c.is_ascii_digit()
                || c == '.'
                || (i == 0 && (c == '-' || c == '+'))
                || ((c == 'e' || c == 'E')
                    && trimmed[i + c.len_utf8()..]
                        .chars()
                        .next()
                        .is_some_and(|d| d.is_ascii_digit() || d == '-' || d == '+')))
        })
        .map_or(trimmed.len(), |(i, _)| i);
    let number = &trimmed[..number_end];
    let rest = trimmed[number_end..].trim();
    if number.parse::<f64>().is_ok() && !rest.is_empty() {
        let word: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if !word.is_empty() && names.contains(&word) {
            return format!("`{number}{word}` is a product without `*`: write `{number}*{word}`");
        }
        if rest.starts_with(|c: char| c.is_alphabetic() || "µ°%Ω".contains(c)) {
            return format!(
                "`{trimmed}` looks like a number with a unit, but hasse has no units: write the number alone ({number}) in the units used throughout the case"
            );
        }
    }
    if let Some(c) = trimmed.chars().find(|c| "²³·×÷−".contains(*c)) {
        let instead = match c {
            '²' => "^2",
            '³' => "^3",
            '·' | '×' => "*",
            '÷' => "/",
            _ => "-",
        };
        return format!("`{c}` is not an operator here: write `{instead}`");
    }
    if trimmed.contains("**") {
        return "`**` is not an operator here: write powers as x^2".into();
    }
    if trimmed.ends_with(['+', '-', '*', '/', '^', ',']) {
        return "it ends with an operator: something is missing after it".into();
    }
    if trimmed.starts_with(['*', '/', '^', ',']) {
        return "it starts with an operator: something is missing before it".into();
    }
    // Two operands side by side: `2 3`, `x y`, `x (y)`.
    let tokens: Vec<&str> = trimmed.split_whitespace().collect();
    let operand = |t: &str| {
        t.chars()
            .all(|c| c.is_alphanumeric() || c == '.' || c == '_')
    };
    if tokens.windows(2).any(|w| operand(w[0]) && operand(w[1])) {
        return "two values stand side by side without an operator between them (products need `*`)".into();
    }
    "it is not a valid expression".into()
}

/// The candidate closest to `word`, if it is close enough to be a likely
/// typo (Jaro–Winkler similarity above 0.8).
pub fn closest(word: &str, candidates: &[String]) -> Option<String> {
    candidates
        .iter()
        .map(|c| (strsim::jaro_winkler(word, c), c))
        .filter(|(score, _)| *score > 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, c)| c.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_time_and_constants() {
        let scope = Scope::new();
        let e = scope.parse("2*x + 3*y - z + t").unwrap();
        assert_eq!(
            e.eval(&[1.0, 10.0, 100.0], 1000.0),
            2.0 + 30.0 - 100.0 + 1000.0
        );
        // Missing coordinates are zero: a 2D point has z = 0.
        assert_eq!(e.eval(&[1.0, 10.0], 0.0), 32.0);
        assert!(!e.is_constant());
        assert!(e.uses_time());
        let c = scope.parse("pi * 2").unwrap();
        assert!(c.is_constant());
        assert_eq!(c.eval(&[], 0.0), 2.0 * std::f64::consts::PI);
    }

    #[test]
    fn comparisons_logic_and_conditionals() {
        let scope = Scope::new();
        let at = |text: &str, x: f64, y: f64| scope.parse(text).unwrap().eval(&[x, y], 0.0);
        // Comparisons bind more loosely than arithmetic: 2 + 1 > 2.5.
        assert_eq!(at("x + 1 > 2.5", 2.0, 0.0), 1.0);
        assert_eq!(at("x + 1 > 2.5", 1.0, 0.0), 0.0);
        assert_eq!(at("x <= 1", 1.0, 0.0), 1.0);
        assert_eq!(at("x >= 1", 0.5, 0.0), 0.0);
        assert_eq!(at("x == y", 2.0, 2.0), 1.0);
        assert_eq!(at("x != y", 2.0, 2.0), 0.0);
        // && before ||, as in C: 0 || (1 && 0) is 0, (0 || 1) && 0 would be 0
        // too, so tell them apart with 1 || (0 && 0) = 1 against
        // (1 || 0) && 0 = 0.
        assert_eq!(at("x > 0 || y > 0 && y < 0", 1.0, 1.0), 1.0);
        assert_eq!(at("x < 0 && y > 0", -1.0, 1.0), 1.0);
        // The conditional takes either branch, whatever the other's value:
        // ln(x) is NaN for x < 0 but is not chosen there.
        assert_eq!(at("if(x > 0, ln(x), -1)", -2.0, 0.0), -1.0);
        assert_eq!(at("if(x > 0, ln(x), -1)", 1.0, 0.0), 0.0);
        // Nested, inside arithmetic, and with a NaN of its own chosen.
        assert_eq!(at("2 * if(x < 1, if(y < 1, 1, 2), 3) + 1", 0.0, 5.0), 5.0);
        assert_eq!(at("2 * if(x < 1, if(y < 1, 1, 2), 3) + 1", 4.0, 0.0), 7.0);
        assert!(at("if(x > 0, sqrt(-1), 1)", 1.0, 0.0).is_nan());
        // Wrongly written conditionals are syntax errors that say how.
        for (text, words) in [
            ("if(x > 0, 1)", "three arguments"),
            (
                "if x > 0",
                "if(condition, value when it holds, value otherwise)",
            ),
            ("if(x > 0, 1, 2", "never closed"),
        ] {
            match scope.parse(text) {
                Err(ExprError::Syntax { message, .. }) => {
                    assert!(message.contains(words), "{text}: {message}")
                }
                other => panic!("{text}: expected a syntax error, got {other:?}"),
            }
        }
        // A name that merely starts with `if` is a variable like any other.
        let mut scope = Scope::new();
        scope.add_constant("iff", 3.0).unwrap();
        assert_eq!(scope.parse("iff + 1").unwrap().eval(&[], 0.0), 4.0);
    }

    #[test]
    fn definitions_chain_in_order() {
        let mut scope = Scope::new();
        scope.add_constant("l", 50.0).unwrap();
        scope.add_definition("xi", "l * x").unwrap();
        scope.add_definition("xi2", "xi * xi").unwrap();
        let e = scope.parse("xi2 + 1").unwrap();
        assert_eq!(e.eval(&[0.1], 0.0), 26.0);
        // A definition may not use a later one.
        let mut scope = Scope::new();
        assert!(matches!(
            scope.add_definition("a", "b + 1"),
            Err(ExprError::UnknownVariable { .. })
        ));
    }

    #[test]
    fn unknown_names_come_with_a_suggestion() {
        let mut scope = Scope::new();
        scope.add_constant("alpha", 1.0).unwrap();
        match scope.parse("alpah * x") {
            Err(ExprError::UnknownVariable {
                name, suggestion, ..
            }) => {
                assert_eq!(name, "alpah");
                assert_eq!(suggestion.as_deref(), Some("alpha"));
            }
            other => panic!("expected an unknown variable, got {other:?}"),
        }
        assert!(matches!(
            scope.parse("sin(x"),
            Err(ExprError::Syntax { .. })
        ));
    }

    #[test]
    fn syntax_errors_are_told_in_the_case_files_terms() {
        // Each malformed text and the words its message must contain; the
        // parser's own wording ("ops", "node") must never reach the user.
        let scope = Scope::new();
        let cases = [
            ("sin(pi*x", "`(` never closed"),
            ("x)", "a `)` closes no `(`"),
            ("5 W/m", "hasse has no units: write the number alone (5)"),
            ("20 degC", "hasse has no units"),
            ("1.5e3 Pa", "write the number alone (1.5e3)"),
            ("2x", "write `2*x`"),
            ("x²", "write `^2`"),
            ("x ** 2", "write powers as x^2"),
            ("x +", "ends with an operator"),
            ("2 3", "side by side"),
            ("   ", "empty"),
        ];
        for (text, says) in cases {
            let Err(error) = scope.parse(text) else {
                panic!("`{text}` parsed");
            };
            let message = error.to_string();
            assert!(message.contains(says), "`{text}`: {message}");
            assert!(
                !message.contains(" ops ") && !message.contains("node"),
                "`{text}`: {message}"
            );
        }
    }

    #[test]
    fn reserved_names_are_refused() {
        let mut scope = Scope::new();
        for name in ["x", "t", "sin", "pi", "E", "2a", ""] {
            assert!(
                matches!(
                    scope.add_constant(name, 1.0),
                    Err(ExprError::ReservedName { .. })
                ),
                "{name}"
            );
        }
        scope.add_constant("k", 1.0).unwrap();
        assert!(scope.add_constant("k", 2.0).is_err());
        assert!(scope.add_constant("inf", f64::INFINITY).is_err());
    }

    #[test]
    fn numbers_in_scientific_notation() {
        let scope = Scope::new();
        let e = scope.parse("1e-320").unwrap();
        assert_eq!(e.eval(&[], 0.0), 1e-320);
        let e = scope.parse("2.5E+3*x + .5e1 - 3e2").unwrap();
        assert_eq!(e.eval(&[2.0], 0.0), 5000.0 + 5.0 - 300.0);
        // `e` alone is still Euler's number, and `2*e` its double.
        let e = scope.parse("2*e").unwrap();
        assert_eq!(e.eval(&[], 0.0), 2.0 * std::f64::consts::E);
    }

    #[test]
    fn division_by_zero_gives_a_non_finite_value() {
        let e = Scope::new().parse("1 / x").unwrap();
        assert!(!e.eval(&[0.0], 0.0).is_finite());
    }

    /// A unary minus applies to the whole power, as in mathematics (and
    /// Python, Fortran, MATLAB): −x² is −(x²), so exp(−x²) decays. exmex
    /// alone binds the sign first, (−x)².
    #[test]
    fn unary_minus_binds_looser_than_powers() {
        let scope = Scope::new();
        let at_two = |text: &str| scope.parse(text).unwrap().eval(&[2.0], 0.0);
        assert_eq!(at_two("-2^2"), -4.0);
        assert_eq!(at_two("-x^2"), -4.0);
        assert_eq!(at_two("exp(-x^2)"), (-4.0f64).exp());
        assert_eq!(at_two("2*-x^2"), -8.0);
        assert_eq!(at_two("-(x)^2"), -4.0);
        assert_eq!(at_two("-sin(x)^2"), -(2.0f64.sin().powi(2)));
        assert_eq!(at_two("-2^-2"), -0.25);
        assert_eq!(at_two("(-x)^2"), 4.0);
        // Unchanged: signs in exponents, products, binary minus.
        assert_eq!(at_two("2^-x"), 0.25);
        assert_eq!(at_two("-x*3"), -6.0);
        assert_eq!(at_two("3 - x^2"), -1.0);
        assert_eq!(at_two("-1e-1^2"), -(0.1f64.powi(2)));
        assert_eq!(at_two("if(x > 1, -x^2, 0)"), -4.0);
    }
}
