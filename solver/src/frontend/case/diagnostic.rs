//! Problems found in a case file, each with the file, line, column and key
//! it concerns, and a hint on how to fix it.

use std::fmt;
use std::ops::Range;

/// One problem in a case file.
///
/// ```
/// use hasse_solver::frontend::case::Case;
/// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n\n[problem]\nmethdo = \"fv\"\n";
/// let errors = Case::from_text("demo.toml", text, &[]).unwrap_err();
/// let first = errors.iter().next().unwrap();
/// assert_eq!((first.line, first.column, first.key.as_str()), (6, 1, "problem.methdo"));
/// assert!(first.help.as_deref().unwrap().contains("method"));
/// assert!(first.to_string().starts_with("demo.toml:6:1: `problem.methdo`: "));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostic {
    /// The case file (as given on the command line).
    pub file: String,
    /// 1-based line, 0 when the problem concerns the file as a whole.
    pub line: usize,
    /// 1-based column (in characters).
    pub column: usize,
    /// The `--set KEY=VALUE` text that gave the key its value, when it
    /// came from the command line: messages then point there instead of
    /// at a line of the file.
    pub set: Option<String>,
    /// The dotted key, e.g. `boundary[1].value`; empty for file-level problems.
    pub key: String,
    /// What is wrong, in the case file's terms.
    pub message: String,
    /// How to fix it.
    pub help: Option<String>,
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(set) = &self.set {
            write!(f, "{}: --set {set}: ", self.file)?;
        } else if self.line > 0 {
            write!(f, "{}:{}:{}: ", self.file, self.line, self.column)?;
        } else {
            write!(f, "{}: ", self.file)?;
        }
        if !self.key.is_empty() {
            write!(f, "`{}`: ", self.key)?;
        }
        write!(f, "{}", self.message)?;
        if let Some(help) = &self.help {
            write!(f, "\n    help: {help}")?;
        }
        Ok(())
    }
}

/// Every problem found in one case file; reading reports all of them at
/// once rather than stopping at the first.
///
/// ```
/// use hasse_solver::frontend::case::Case;
/// // A misspelt method and a source that names an unknown variable.
/// let text = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nmethod = \"fvm\"\nsource = \"sin(w * x)\"\n";
/// let errors = Case::from_text("demo.toml", text, &[]).unwrap_err();
/// let keys: Vec<&str> = errors.iter().map(|d| d.key.as_str()).collect();
/// assert_eq!(keys, ["problem.method", "problem.source"]);
/// // Printed one after the other, each as `error: file:line:col: ...`.
/// assert_eq!(errors.to_string().matches("error: demo.toml:").count(), 2);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diagnostics(
    /// The problems, in the order the reader found them.
    pub Vec<Diagnostic>,
);

impl Diagnostics {
    /// Whether there is no problem.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// How many problems there are.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// The problems, in order.
    pub fn iter(&self) -> impl Iterator<Item = &Diagnostic> {
        self.0.iter()
    }
}

impl fmt::Display for Diagnostics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, d) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "error: {d}")?;
        }
        Ok(())
    }
}

impl std::error::Error for Diagnostics {}

/// Turns byte offsets of the case text into line and column numbers and
/// collects diagnostics.
#[derive(Clone, Debug)]
pub(crate) struct Collector {
    file: String,
    text: String,
    line_starts: Vec<usize>,
    /// Keys set with `--set` (`problem.method`, `boundary[0].value`) and
    /// the assignment as given: a diagnostic about such a key, or a key
    /// under it, names the assignment.
    overrides: Vec<(String, String)>,
    /// The span of every key the reader looked up, by its dotted name
    /// (filled while reading, through a shared reference).
    spans: std::cell::RefCell<std::collections::BTreeMap<String, Range<usize>>>,
    pub diagnostics: Vec<Diagnostic>,
    /// Things that do not stop the case but that the user should know
    /// (a key the overrides made unused).
    pub warnings: Vec<Diagnostic>,
}

impl Collector {
    pub fn new(file: &str, text: &str) -> Self {
        let line_starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Self {
            file: file.to_string(),
            text: text.to_string(),
            line_starts,
            overrides: Vec::new(),
            spans: Default::default(),
            diagnostics: Vec::new(),
            warnings: Vec::new(),
        }
    }

    /// The same collector with the `--set` keys and texts of `overrides`.
    pub(crate) fn with_overrides(mut self, overrides: Vec<(String, String)>) -> Self {
        self.overrides = overrides;
        self
    }

    /// Remember where key `key` is written.
    pub(crate) fn record(&self, key: &str, span: Option<Range<usize>>) {
        if let Some(span) = span {
            self.spans
                .borrow_mut()
                .entry(key.to_string())
                .or_insert(span);
        }
    }

    /// Where key `key` is written, if the reader saw it.
    pub(crate) fn span_of(&self, key: &str) -> Option<Range<usize>> {
        self.spans.borrow().get(key).cloned()
    }

    /// Whether `key` (or a table above it) was given by a `--set`
    /// assignment rather than by the file.
    pub(crate) fn is_set(&self, key: &str) -> bool {
        self.set_text(key).is_some()
    }

    /// The `--set` assignment that gave `key` (or a table above it) its
    /// value.
    fn set_text(&self, key: &str) -> Option<String> {
        self.overrides.iter().find_map(|(set, text)| {
            let under = key == set
                || key
                    .strip_prefix(set.as_str())
                    .is_some_and(|rest| rest.starts_with('.') || rest.starts_with('['));
            under.then(|| text.clone())
        })
    }

    /// A diagnostic about `key` at `span`, or where the reader saw the key
    /// when `span` is `None` (no position when it saw neither), or at the
    /// `--set` text that gave it.
    pub(crate) fn diagnostic(
        &self,
        span: Option<Range<usize>>,
        key: &str,
        message: impl Into<String>,
        help: Option<String>,
    ) -> Diagnostic {
        let set = self.set_text(key);
        let span = span.or_else(|| self.span_of(key));
        let (line, column) = match (&set, span) {
            (None, Some(s)) => self.position(s.start),
            _ => (0, 0),
        };
        Diagnostic {
            file: self.file.clone(),
            line,
            column,
            set,
            key: key.to_string(),
            message: message.into(),
            help,
        }
    }

    /// 1-based (line, column) of a byte offset.
    pub fn position(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let line = self.line_starts.partition_point(|&s| s <= offset);
        let start = self.line_starts[line - 1];
        let column = self.text[start..offset].chars().count() + 1;
        (line, column)
    }

    /// Record a problem at `span` (the start of the span is reported).
    pub fn error(
        &mut self,
        span: Option<Range<usize>>,
        key: &str,
        message: impl Into<String>,
        help: Option<String>,
    ) {
        let diagnostic = self.diagnostic(span, key, message, help);
        self.diagnostics.push(diagnostic);
    }

    /// Record a warning at `span`: printed, but the case still runs.
    pub fn warning(
        &mut self,
        span: Option<Range<usize>>,
        key: &str,
        message: impl Into<String>,
        help: Option<String>,
    ) {
        let diagnostic = self.diagnostic(span, key, message, help);
        self.warnings.push(diagnostic);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_become_lines_and_columns() {
        let c = Collector::new("case.toml", "a = 1\nbé = 2\n\nc = 3");
        assert_eq!(c.position(0), (1, 1));
        assert_eq!(c.position(4), (1, 5));
        assert_eq!(c.position(6), (2, 1));
        // Columns count characters, not bytes: `é` is two bytes.
        assert_eq!(c.position(6 + 3), (2, 3));
        assert_eq!(c.position(14), (3, 1));
        assert_eq!(c.position(15), (4, 1));
    }

    #[test]
    fn display_names_file_line_key_and_help() {
        let mut c = Collector::new("x.toml", "\n[problem]\nmethdo = 1\n");
        c.error(
            Some(11..17),
            "problem.methdo",
            "unknown key",
            Some("did you mean `method`?".into()),
        );
        assert_eq!(
            c.diagnostics[0].to_string(),
            "x.toml:3:1: `problem.methdo`: unknown key\n    help: did you mean `method`?"
        );
    }
}
