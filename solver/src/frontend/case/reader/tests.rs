//! Tests of the reader's own mechanics: `--set` keys, key spans for later
//! diagnostics, and choices read by the enums' names.

use super::overrides::apply_overrides;
use crate::frontend::case::Case;

/// What a test returns: a failed step is its error.
type TestResult = Result<(), Box<dyn std::error::Error>>;

const CASE: &str = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n\n[problem]\nmethod = \"fe\"\nsource = \"x*y\"\n\n[[boundary]]\ntag = \"boundary\"\ntype = \"dirichlet\"\nvalue = 0\n";

#[test]
fn set_keys_are_named_as_diagnostics_name_them() -> TestResult {
    let (text, keys) = apply_overrides(
        "c.toml",
        CASE,
        &["boundary.0.value=2".into(), "mesh.n=[8,8]".into()],
    )?;
    assert_eq!(
        keys,
        [
            (
                "boundary[0].value".to_string(),
                "boundary.0.value=2".to_string()
            ),
            ("mesh.n".to_string(), "mesh.n=[8,8]".to_string()),
        ]
    );
    assert!(
        text.contains("n = [8,8]") && text.contains("value = 2"),
        "{text}"
    );
    // Without overrides the text is unchanged and nothing is overridden.
    assert_eq!(apply_overrides("c.toml", CASE, &[])?, (CASE.into(), vec![]));
    Ok(())
}

#[test]
fn diagnostics_point_at_the_key_or_at_the_set_text() -> TestResult {
    let case = Case::from_text("c.toml", CASE, &[])?;
    // `source = "x*y"` is line 7; its value starts at column 10.
    let d = case.diagnostic("problem.source", "bad", None);
    assert_eq!((d.line, d.column, d.set.as_deref()), (7, 10, None));
    assert_eq!(d.to_string(), "c.toml:7:10: `problem.source`: bad");
    // A key inside an array of tables, and one the file does not write.
    let d = case.diagnostic("boundary[0].value", "bad", None);
    assert_eq!((d.line, d.column), (12, 9));
    let d = case.diagnostic("problem.conductivity", "bad", None);
    assert_eq!(
        (d.line, d.to_string()),
        (0, "c.toml: `problem.conductivity`: bad".into())
    );
    // Given with --set: the assignment, not a line of the file (the
    // override may have been written anywhere in the edited text).
    let case = Case::from_text("c.toml", CASE, &["problem.source=ln(x)".into()])?;
    let d = case.diagnostic("problem.source", "bad", Some("fix it".into()));
    assert_eq!(d.set.as_deref(), Some("problem.source=ln(x)"));
    assert_eq!(
        d.to_string(),
        "c.toml: --set problem.source=ln(x): `problem.source`: bad\n    help: fix it"
    );
    // A key under an overridden table is the override's too.
    let case = Case::from_text("c.toml", CASE, &["boundary.0.value=1".into()])?;
    assert!(case
        .diagnostic("boundary[0].value", "bad", None)
        .set
        .is_some());
    assert!(case
        .diagnostic("boundary[0].tag", "bad", None)
        .set
        .is_none());
    Ok(())
}

#[test]
fn choices_are_read_by_the_enums_own_names() -> TestResult {
    let darcy = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"darcy\"\nmethod = \"mimetc\"\n";
    let errors = Case::from_text("d.toml", darcy, &[])
        .unwrap_err()
        .to_string();
    assert!(
        errors.contains("d.toml:6:10: `problem.method`: unknown flux mass method \"mimetc\""),
        "{errors}"
    );
    assert!(
        errors.contains("did you mean \"mimetic\"? choices: mimetic, dec, dec-barycentric"),
        "{errors}"
    );
    let missing = CASE.replace("method = \"fe\"\n", "");
    let errors = Case::from_text("m.toml", &missing, &[])
        .unwrap_err()
        .to_string();
    assert!(
        errors.contains("one of fd, fe, fv, fv-mimetic, dec, dec-barycentric"),
        "{errors}"
    );
    let plane = "[mesh]\ngenerator = \"rectangle\"\nn = [4, 4]\n[problem]\nkind = \"elasticity\"\nlambda = 1\nmu = 1\nplane = \"stres\"\n";
    let errors = Case::from_text("p.toml", plane, &[])
        .unwrap_err()
        .to_string();
    assert!(
        errors.contains("did you mean \"stress\"? choices: strain, stress"),
        "{errors}"
    );
    Ok(())
}
