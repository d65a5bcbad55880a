//! How messages quote an expression and point at the fault in it.

/// Expressions longer than this many characters are quoted in messages
/// by an excerpt of this width around the fault, not whole.
pub const QUOTE_WIDTH: usize = 80;

/// An expression as messages quote it: whole and in backquotes when it is
/// short; otherwise by its length, and (the second part, for the end of
/// the message) at most [`QUOTE_WIDTH`] characters around character `at`
/// (the start when the fault has no one place) on a line of their own with
/// a caret under that character on the next.
///
/// ```
/// use hasse_solver::frontend::case::expr::quote;
/// assert_eq!(quote("sin(x", Some(3)), ("`sin(x`".to_string(), String::new()));
/// let long = format!("{}(", "x + ".repeat(50_000));
/// let (head, tail) = quote(&long, Some(200_000));
/// assert_eq!(head, "the expression of 200001 characters");
/// let lines: Vec<&str> = tail.lines().collect();
/// assert_eq!(lines[0], ", at character 200001:");
/// // `…` and 80 characters, the last of them the fault, and the caret
/// // under it.
/// assert_eq!(lines[1], format!("    …{}(", &"x + ".repeat(20)[1..]));
/// assert_eq!(lines[2], format!("    {}^", " ".repeat(80)));
/// ```
pub fn quote(text: &str, at: Option<usize>) -> (String, String) {
    let chars: Vec<char> = text.chars().collect();
    if chars.len() <= QUOTE_WIDTH {
        return (format!("`{text}`"), String::new());
    }
    let at = at.unwrap_or(0).min(chars.len() - 1);
    let start = at
        .saturating_sub(QUOTE_WIDTH / 2)
        .min(chars.len() - QUOTE_WIDTH);
    let end = start + QUOTE_WIDTH;
    let before = if start > 0 { "…" } else { "" };
    let after = if end < chars.len() { "…" } else { "" };
    let excerpt: String = chars[start..end].iter().collect();
    let caret = before.chars().count() + (at - start);
    (
        format!("the expression of {} characters", chars.len()),
        format!(
            ", at character {}:\n    {before}{excerpt}{after}\n    {}^",
            at + 1,
            " ".repeat(caret)
        ),
    )
}

/// The message of a syntax error: what is wrong, then where.
pub(super) fn syntax_text(text: &str, message: &str) -> String {
    let (head, tail) = quote(text, syntax_position(text));
    format!("cannot parse {head}: {message}{tail}")
}

/// The message of an unknown name: which, with the closest known one,
/// then where.
pub(super) fn unknown_text(text: &str, name: &str, suggestion: &Option<String>) -> String {
    let (head, tail) = quote(text, word_position(text, name));
    format!(
        "unknown variable `{name}` in {head}{}{tail}",
        suggestion_text(suggestion)
    )
}

/// Where (in characters) a syntax error shows first: a `)` that closes
/// nothing, the first `(` never closed, or a character that is not part
/// of an expression; `None` when the fault is not one place.
fn syntax_position(text: &str) -> Option<usize> {
    let mut open = Vec::new();
    for (i, c) in text.chars().enumerate() {
        match c {
            '(' => open.push(i),
            ')' if open.is_empty() => return Some(i),
            ')' => {
                open.pop();
            }
            _ => {}
        }
    }
    if let Some(&first) = open.first() {
        return Some(first);
    }
    text.chars()
        .position(|c| !(c.is_alphanumeric() || c.is_whitespace() || "+-*/^(),._<>=!&|".contains(c)))
}

/// Where (in characters) `name` first stands as a whole word in `text`.
fn word_position(text: &str, name: &str) -> Option<usize> {
    let word = |c: char| c.is_alphanumeric() || c == '_';
    text.match_indices(name)
        .find(|&(i, _)| {
            !text[..i].chars().next_back().is_some_and(word)
                && !text[i + name.len()..].chars().next().is_some_and(word)
        })
        .map(|(i, _)| text[..i].chars().count())
}

fn suggestion_text(suggestion: &Option<String>) -> String {
    match suggestion {
        Some(s) => format!(" (did you mean `{s}`?)"),
        None => String::new(),
    }
}
