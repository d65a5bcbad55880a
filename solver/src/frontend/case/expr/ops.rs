//! The operators of case-file expressions: exmex's float operators, plus
//! comparisons, `&&`, `||` and the conditional `if(condition, a, b)`.
//!
//! exmex has only unary and binary operators, so `if(c, a, b)` is read by
//! rewriting it, before exmex parses the text, into two binary operators:
//! `((c) if_then (a)) if_else (b)`. `if_then` yields `a` when `c` holds and a
//! marker otherwise; `if_else` passes any value but the marker through and
//! replaces the marker by `b`. The marker is a NaN with a payload of its
//! own: exmex hands the value of `if_then` straight to `if_else` (no
//! arithmetic in between), so its bits arrive unchanged, and no arithmetic
//! NaN (whose payload is the default quiet one) can be mistaken for it.

use super::ExprError;
use exmex::{BinOp, FloatOpsFactory, MakeOperators, Operator};

/// `if_then`'s "condition false": a quiet NaN with a payload no arithmetic
/// produces.
const NOT_TAKEN: u64 = 0x7ff8_4861_7373_6500;

/// Truth of a number: nonzero and not NaN (comparisons give 1 or 0).
fn holds(c: f64) -> bool {
    c != 0.0 && !c.is_nan()
}

fn truth(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}

/// The operators of [`super::Expression`]. exmex's own keep their relative
/// priorities; comparisons bind more loosely than `+` and `-` (whose
/// priority is 0 and 1), `&&` more loosely still, and `||` loosest, as in
/// C: `x + 1 > 2 && y < 1 || z == 0` reads `((x + 1 > 2) && (y < 1)) || (z == 0)`.
#[derive(Clone, Debug)]
pub(crate) struct CaseOps;

impl MakeOperators<f64> for CaseOps {
    fn make<'a>() -> Vec<Operator<'a, f64>> {
        let bin = |repr: &'a str, apply: fn(f64, f64) -> f64, prio: i64| {
            Operator::make_bin(
                repr,
                BinOp {
                    apply,
                    prio,
                    is_commutative: false,
                },
            )
        };
        let mut ops = FloatOpsFactory::<f64>::make();
        ops.extend([
            bin("<", |a, b| truth(a < b), -1),
            bin("<=", |a, b| truth(a <= b), -1),
            bin(">", |a, b| truth(a > b), -1),
            bin(">=", |a, b| truth(a >= b), -1),
            bin("==", |a, b| truth(a == b), -1),
            bin("!=", |a, b| truth(a != b), -1),
            bin("&&", |a, b| truth(holds(a) && holds(b)), -2),
            bin("||", |a, b| truth(holds(a) || holds(b)), -3),
            bin(
                "if_then",
                |c, a| {
                    if holds(c) {
                        a
                    } else {
                        f64::from_bits(NOT_TAKEN)
                    }
                },
                0,
            ),
            bin(
                "if_else",
                |v, b| if v.to_bits() == NOT_TAKEN { b } else { v },
                0,
            ),
        ]);
        ops
    }
}

/// `text` with every `if(c, a, b)` rewritten for exmex (see the module
/// docs), nested ones included; a conditional without exactly three
/// arguments is a syntax error that says so.
pub(crate) fn rewrite_conditionals(text: &str) -> Result<String, ExprError> {
    let syntax = |message: &str| ExprError::Syntax {
        text: text.to_string(),
        message: message.to_string(),
    };
    let chars: Vec<char> = text.chars().collect();
    let word = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = String::with_capacity(text.len() + 16);
    let mut i = 0;
    while i < chars.len() {
        let starts_if = chars[i] == 'i'
            && chars.get(i + 1) == Some(&'f')
            && (i == 0 || !word(chars[i - 1]))
            && !chars.get(i + 2).copied().is_some_and(word);
        if !starts_if {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let mut j = i + 2;
        while chars.get(j).is_some_and(|c| c.is_whitespace()) {
            j += 1;
        }
        if chars.get(j) != Some(&'(') {
            return Err(syntax(
                "`if` is written if(condition, value when it holds, value otherwise)",
            ));
        }
        // The three arguments: split at commas outside inner brackets.
        let mut depth = 0usize;
        let mut arguments = vec![String::new()];
        let mut k = j + 1;
        loop {
            let Some(&c) = chars.get(k) else {
                return Err(syntax("`if(` is never closed: add the missing `)`"));
            };
            match c {
                '(' => depth += 1,
                ')' if depth == 0 => break,
                ')' => depth -= 1,
                ',' if depth == 0 => {
                    arguments.push(String::new());
                    k += 1;
                    continue;
                }
                _ => {}
            }
            arguments.last_mut().expect("one argument at least").push(c);
            k += 1;
        }
        if arguments.len() != 3 || arguments.iter().any(|a| a.trim().is_empty()) {
            return Err(syntax(&format!(
                "`if` takes three arguments, if(condition, value when it holds, value otherwise); this one has {}",
                arguments.iter().filter(|a| !a.trim().is_empty()).count()
            )));
        }
        let inner: Vec<String> = arguments
            .iter()
            .map(|a| rewrite_conditionals(a))
            .collect::<Result<_, _>>()
            .map_err(|_| syntax("an argument of `if(…)` is not an expression"))?;
        // Infix, fully bracketed: exmex's function syntax `op(a, b)` does
        // not nest binary operators reliably.
        out.push_str(&format!(
            "((({}) if_then ({})) if_else ({}))",
            inner[0], inner[1], inner[2]
        ));
        i = k + 1;
    }
    Ok(out)
}

/// `text` with every unary minus whose operand is raised to a power
/// wrapped around the whole power: `-x^2` becomes `-(x^2)`. exmex binds a
/// unary operator before any binary one, so it would read (−x)², which no
/// mathematical reader means (exp(−x²) would grow). Signs in exponents
/// (`2^-x`), before products (`-x*3`) and binary minus are left alone.
pub(crate) fn rewrite_unary_powers(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len() + 8);
    // The last character that is not white space: a minus after an
    // operator, a bracket or a comma (or first) is unary.
    let mut previous: Option<char> = None;
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let unary = previous.is_none_or(|p| "(,+-*/^<>=&|!".contains(p));
        if c == '-' && unary {
            if let Some(end) = power_end(&chars, i + 1) {
                let inner: String = chars[i + 1..end].iter().collect();
                out.push_str("-(");
                out.push_str(&rewrite_unary_powers(&inner));
                out.push(')');
                previous = Some(')');
                i = end;
                continue;
            }
        }
        out.push(c);
        if !c.is_whitespace() {
            previous = Some(c);
        }
        i += 1;
    }
    out
}

/// Where the power that starts at `start` ends (an operand followed by one
/// or more `^ operand`), or `None` when the operand is not raised to a
/// power.
fn power_end(chars: &[char], start: usize) -> Option<usize> {
    let mut end = operand_end(chars, start)?;
    let mut powered = false;
    loop {
        let mut k = skip_spaces(chars, end);
        if chars.get(k) != Some(&'^') {
            break;
        }
        k = skip_spaces(chars, k + 1);
        while chars.get(k).is_some_and(|&c| c == '-' || c == '+') {
            k = skip_spaces(chars, k + 1);
        }
        end = operand_end(chars, k)?;
        powered = true;
    }
    powered.then_some(end)
}

fn skip_spaces(chars: &[char], mut k: usize) -> usize {
    while chars.get(k).is_some_and(|c| c.is_whitespace()) {
        k += 1;
    }
    k
}

/// The end of the operand at `start` (after white space): a bracketed
/// group, a number, or a name with its call's brackets.
fn operand_end(chars: &[char], start: usize) -> Option<usize> {
    let k = skip_spaces(chars, start);
    let group_end = |open: usize| -> Option<usize> {
        let mut depth = 0usize;
        for (j, &c) in chars.iter().enumerate().skip(open) {
            match c {
                '(' => depth += 1,
                ')' => {
                    depth -= 1;
                    if depth == 0 {
                        return Some(j + 1);
                    }
                }
                _ => {}
            }
        }
        None
    };
    let c = *chars.get(k)?;
    if c == '(' {
        return group_end(k);
    }
    if c.is_ascii_digit() || c == '.' {
        let mut j = k;
        while chars
            .get(j)
            .is_some_and(|c| c.is_ascii_digit() || *c == '.')
        {
            j += 1;
        }
        // An exponent: e, an optional sign, digits.
        if chars.get(j).is_some_and(|c| *c == 'e' || *c == 'E') {
            let mut m = j + 1;
            if chars.get(m).is_some_and(|c| *c == '-' || *c == '+') {
                m += 1;
            }
            if chars.get(m).is_some_and(|c| c.is_ascii_digit()) {
                j = m;
                while chars.get(j).is_some_and(|c| c.is_ascii_digit()) {
                    j += 1;
                }
            }
        }
        return Some(j);
    }
    if c.is_alphabetic() || c == '_' {
        let mut j = k;
        while chars
            .get(j)
            .is_some_and(|c| c.is_alphanumeric() || *c == '_')
        {
            j += 1;
        }
        let call = skip_spaces(chars, j);
        if chars.get(call) == Some(&'(') {
            return group_end(call);
        }
        return Some(j);
    }
    None
}
