//! Tests of the output writers.

use super::levels::{check_name, rfc3339};
use super::*;

#[test]
fn rfc3339_matches_known_dates() {
    assert_eq!(rfc3339(0), "1970-01-01T00:00:00Z");
    // 2000-02-29 is a leap day of a century leap year.
    assert_eq!(rfc3339(951_782_400 + 3661), "2000-02-29T01:01:01Z");
    assert_eq!(rfc3339(1_700_000_000), "2023-11-14T22:13:20Z");
}

#[test]
fn names_that_break_paths_are_rejected() {
    for bad in ["", ".", "a/b", "a:b", "a\nb"] {
        assert!(matches!(
            check_name(bad),
            Err(OutputError::InvalidName { .. })
        ));
    }
    assert!(check_name("u_h (K)").is_ok());
}
