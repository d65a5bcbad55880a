//! The `[time]` table of a transient problem: the step, the number of
//! steps (or the end time), θ or the scheme's name, what is saved, and
//! adaptive step control.

use super::Reader;
use crate::frontend::case::expr::closest;
use crate::frontend::case::TimeSpec;
use std::ops::Range;
use toml_edit::TableLike;

pub(super) const TIME_KEYS: &[&str] = &[
    "dt",
    "steps",
    "end",
    "start",
    "scheme",
    "theta",
    "save_every",
    "adaptive",
];
pub(super) const SCHEMES: &[&str] = &["backward-euler", "crank-nicolson"];
/// More steps than this is almost certainly a typo in `dt` or `end`.
pub(super) const MAX_STEPS: i64 = 10_000_000;

impl Reader {
    /// The `[time]` table of a transient problem (heat, growth, transport
    /// in time).
    pub(super) fn time(&mut self, root: &dyn TableLike) -> Option<TimeSpec> {
        let Some((table, entry)) = self.subtable(root, "", "time") else {
            if root.get("time").is_none() {
                let kind = super::kinds::problem_kind(root).to_string();
                self.error(
                    None,
                    "time",
                    format!("no [time] table: a {kind} problem steps in time"),
                    Some("add [time] with `dt = 0.01` and `steps = 100` (or `end = 1.0`)".into()),
                );
            }
            return None;
        };
        let header = entry.span();
        self.check_keys(table, "time", TIME_KEYS);
        let dt = match self.entry(table, "time", "dt") {
            None => {
                self.error(header.clone(), "time.dt", "missing: the time step Δt", None);
                None
            }
            Some(e) => match self.number(&e) {
                Some(v) if v > 0.0 && v.is_finite() => Some(v),
                Some(v) => {
                    self.error(
                        e.span(),
                        "time.dt",
                        format!("the time step must be positive and finite, found {v}"),
                        None,
                    );
                    None
                }
                None => None,
            },
        };
        let start = match self.number_at(table, "time", "start") {
            Some(v) if !v.is_finite() => {
                let span = self.entry(table, "time", "start").and_then(|e| e.span());
                self.error(span, "time.start", format!("not finite: {v}"), None);
                None
            }
            Some(v) => Some(v),
            None => Some(0.0),
        };
        let steps = self.step_count(table, header.clone(), dt, start);
        let theta = self.theta(table);
        let save_every = match self.entry(table, "time", "save_every") {
            None => Some(1),
            Some(e) => match e.item.as_integer() {
                Some(k) if k >= 0 => Some(k as usize),
                Some(k) => {
                    self.error(
                        e.span(),
                        "time.save_every",
                        format!("a step count ≥ 0, found {k}"),
                        Some("0 saves only the first and last levels".into()),
                    );
                    None
                }
                None => {
                    self.type_error(&e, "an integer");
                    None
                }
            },
        };
        let end = self
            .entry(table, "time", "end")
            .and_then(|e| e.item.as_float().or(e.item.as_integer().map(|i| i as f64)));
        let adaptive = self.adaptive(table, theta);
        let time = TimeSpec {
            dt: dt?,
            steps: steps?,
            start: start?,
            theta: theta?,
            save_every: save_every?,
            end,
            adaptive: adaptive?,
        };
        self.time_advances(table, &time).then_some(time)
    }

    /// Whether every saved time t₀ + k·dt is a distinct floating-point
    /// number, as the run computes them; refuses (naming `time.dt` and
    /// `time.start`) a step too small to move t₀, or levels whose times
    /// round to the same number.
    fn time_advances(&mut self, table: &dyn TableLike, time: &TimeSpec) -> bool {
        let span = self.entry(table, "time", "dt").and_then(|e| e.span());
        let (start, dt) = (time.start, time.dt);
        let help = Some(
            "give a larger time.dt, or a time.start nearer 0 (floating-point numbers near t have a spacing of about 2.2e-16 × |t|)"
                .into(),
        );
        if start + dt == start {
            self.error(
                span,
                "time.dt",
                format!(
                    "time.start + time.dt = time.start in floating point (start = {start:e}, dt = {dt:e}): time cannot advance"
                ),
                help,
            );
            return false;
        }
        let saved = (1..=time.steps)
            .filter(|&k| k == time.steps || (time.save_every > 0 && k % time.save_every == 0));
        let mut previous = (0, start);
        for k in saved {
            let t = start + k as f64 * dt;
            if t <= previous.1 {
                self.error(
                    span,
                    "time.dt",
                    format!(
                        "the saved levels after step {} and step {k} both have time {t:e} in floating point (time.start = {start:e}, time.dt = {dt:e}): the steps are too small to tell their times apart",
                        previous.0
                    ),
                    help,
                );
                return false;
            }
            previous = (k, t);
        }
        true
    }

    /// `steps`, or `end` turned into a whole number of steps of `dt`.
    pub(super) fn step_count(
        &mut self,
        table: &dyn TableLike,
        header: Option<Range<usize>>,
        dt: Option<f64>,
        start: Option<f64>,
    ) -> Option<usize> {
        let steps = self.entry(table, "time", "steps");
        let end = self.entry(table, "time", "end");
        match (steps, end) {
            (Some(_), Some(e)) => {
                self.error(
                    e.key_span.clone(),
                    "time.end",
                    "give either steps or end, not both",
                    None,
                );
                None
            }
            (None, None) => {
                self.error(
                    header,
                    "time.steps",
                    "missing: how long to run",
                    Some("give `steps = 100` or `end = 1.0`".into()),
                );
                None
            }
            (Some(e), None) => match e.item.as_integer() {
                Some(n) if (1..=MAX_STEPS).contains(&n) => Some(n as usize),
                Some(n) => {
                    self.error(
                        e.span(),
                        "time.steps",
                        format!("between 1 and {MAX_STEPS} steps, found {n}"),
                        None,
                    );
                    None
                }
                None => {
                    self.type_error(&e, "an integer");
                    None
                }
            },
            (None, Some(e)) => {
                let end = self.number(&e)?;
                let (dt, start) = (dt?, start?);
                let span = e.span();
                if !(end.is_finite() && end > start) {
                    self.error(
                        span,
                        "time.end",
                        format!(
                            "the end time must be finite and after the start {start}, found {end}"
                        ),
                        None,
                    );
                    return None;
                }
                let exact = (end - start) / dt;
                let steps = exact.round();
                // Steps must tile [t₀, end] exactly, or the last level would
                // not be at `end` and errors there would be misleading.
                if (exact - steps).abs() > 1e-9 * exact.max(1.0) || steps < 1.0 {
                    self.error(
                        span,
                        "time.end",
                        format!("end − start = {} is not a whole number of steps dt = {dt} ({exact:.6} steps)", end - start),
                        Some("change dt or end, or give `steps` instead".into()),
                    );
                    return None;
                }
                if steps > MAX_STEPS as f64 {
                    self.error(
                        span,
                        "time.end",
                        format!("{steps} steps of dt = {dt}: more than {MAX_STEPS}"),
                        Some("check dt and end".into()),
                    );
                    return None;
                }
                Some(steps as usize)
            }
        }
    }

    /// θ from `scheme` or `theta` (default backward Euler, θ = 1).
    pub(super) fn theta(&mut self, table: &dyn TableLike) -> Option<f64> {
        let scheme = self.entry(table, "time", "scheme");
        let theta = self.entry(table, "time", "theta");
        if let (Some(_), Some(t)) = (&scheme, &theta) {
            self.error(
                t.key_span.clone(),
                "time.theta",
                "give either scheme or theta, not both",
                None,
            );
            return None;
        }
        if let Some(t) = theta {
            let v = self.number(&t)?;
            if !(0.0..=1.0).contains(&v) {
                self.error(
                    t.span(),
                    "time.theta",
                    format!("θ must lie in [0, 1], found {v}"),
                    Some("1 is backward Euler, 0.5 Crank–Nicolson".into()),
                );
                return None;
            }
            return Some(v);
        }
        let Some(s) = scheme else {
            return Some(1.0);
        };
        match s.item.as_str() {
            Some("backward-euler") => Some(1.0),
            Some("crank-nicolson") => Some(0.5),
            Some(other) => {
                let owned: Vec<String> = SCHEMES.iter().map(|s| s.to_string()).collect();
                let help = closest(other, &owned).map_or_else(
                    || format!("schemes: {} (or theta = …)", SCHEMES.join(", ")),
                    |s| format!("did you mean \"{s}\"?"),
                );
                self.error(
                    s.span(),
                    "time.scheme",
                    format!("unknown time scheme \"{other}\""),
                    Some(help),
                );
                None
            }
            None => {
                self.type_error(&s, "a string");
                None
            }
        }
    }

    /// `adaptive = { tolerance = 1e-4 }`: adaptive step sizes with this
    /// relative local error per step; `Some(None)` when absent. Needs θ in
    /// [½, 1], where the step-size control knows the scheme's error.
    fn adaptive(&mut self, table: &dyn TableLike, theta: Option<f64>) -> Option<Option<f64>> {
        let Some((adaptive, entry)) = self.subtable(table, "time", "adaptive") else {
            return Some(None);
        };
        self.check_keys(adaptive, "time.adaptive", &["tolerance"]);
        let Some(e) = self.entry(adaptive, "time.adaptive", "tolerance") else {
            self.error(
                entry.span(),
                "time.adaptive.tolerance",
                "missing: the relative local error allowed per step",
                Some("e.g. adaptive = { tolerance = 1e-4 }".into()),
            );
            return None;
        };
        let tolerance = self.number(&e)?;
        if !(tolerance > 0.0 && tolerance < 1.0) {
            self.error(
                e.span(),
                "time.adaptive.tolerance",
                format!("a relative error in (0, 1), found {tolerance}"),
                Some("e.g. 1e-4".into()),
            );
            return None;
        }
        if let Some(theta) = theta.filter(|&t| t < 0.5) {
            self.error(
                entry.span(),
                "time.adaptive",
                format!("adaptive steps need θ in [0.5, 1] (backward Euler to Crank–Nicolson), this scheme has θ = {theta}"),
                Some("set time.theta ≥ 0.5, or remove time.adaptive".into()),
            );
            return None;
        }
        Some(Some(tolerance))
    }
}
