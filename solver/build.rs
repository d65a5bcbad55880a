//! With the feature `mpi`, link PETSc as `pkg-config PETSc` describes it
//! (Debian's petsc-dev installs PETSc.pc); without it, nothing to do.

use std::process::Command;

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-env-changed=PKG_CONFIG_PATH");
    if std::env::var_os("CARGO_FEATURE_MPI").is_none() {
        return;
    }
    let output = Command::new("pkg-config")
        .args(["--libs", "PETSc"])
        .output();
    let libs = match output {
        Ok(out) if out.status.success() => String::from_utf8_lossy(&out.stdout).into_owned(),
        _ => {
            println!(
                "cargo::error=the feature `mpi` needs PETSc's development files (pkg-config PETSc failed): run scripts/setup --mpi, or apt-get install petsc-dev libopenmpi-dev libclang-dev"
            );
            return;
        }
    };
    for flag in libs.split_whitespace() {
        if let Some(dir) = flag.strip_prefix("-L") {
            println!("cargo::rustc-link-search=native={dir}");
        } else if let Some(lib) = flag.strip_prefix("-l") {
            println!("cargo::rustc-link-lib={lib}");
        }
    }
}
