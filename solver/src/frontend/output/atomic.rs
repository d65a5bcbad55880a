//! Every output file is written under a temporary name in its target
//! directory, made durable and renamed into place: readers see the old
//! file or the complete new one, and an interrupted or failed write leaves
//! nothing under a final name. The one module that does this, for the
//! HDF5/XDMF output, the partial output of transient runs and the files of
//! convergence studies.

use super::OutputError;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A tag unique per process and per call, so concurrent writers of the
/// same stem never share a temporary.
pub(crate) fn temporary_tag() -> String {
    static CALLS: AtomicU64 = AtomicU64::new(0);
    format!(
        "{}-{}",
        std::process::id(),
        CALLS.fetch_add(1, Ordering::Relaxed)
    )
}

/// The temporary that becomes `path`: in the same directory, so that the
/// rename is atomic, and hidden, so that listings and globs skip it.
pub(crate) fn temporary(path: &Path, tag: &str) -> PathBuf {
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    // The extension is kept at the end too: writers that pick a format
    // from it (image encoders, HDF5 tools) see the final one.
    match path.extension() {
        Some(extension) => {
            path.with_file_name(format!(".{name}.tmp-{tag}.{}", extension.to_string_lossy()))
        }
        None => path.with_file_name(format!(".{name}.tmp-{tag}")),
    }
}

/// Remove temporaries of `finals` left in `dir` by writers that were
/// killed: those whose tag names a process that no longer runs. Temporaries
/// of running processes (this one included) are kept, since a concurrent
/// writer may still rename them. Best effort: without `/proc` nothing is
/// removed, and a file that cannot be removed is left alone.
pub(crate) fn remove_orphaned_temporaries(dir: &Path, finals: &[PathBuf]) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let prefixes: Vec<String> = finals
        .iter()
        .filter_map(|f| f.file_name())
        .map(|name| format!(".{}.tmp-", name.to_string_lossy()))
        .collect();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(tag) = prefixes.iter().find_map(|p| name.strip_prefix(p.as_str())) else {
            continue;
        };
        let Some(pid) = tag
            .split(['-', '.'])
            .next()
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Whether a file name is one of [`temporary`]'s.
pub(crate) fn is_temporary(name: &str) -> bool {
    name.starts_with('.') && name.contains(".tmp-")
}

/// Write one file under a temporary name with `write`, make it durable
/// and rename it to `path`: readers see the old file or the complete new
/// one, never a part, and an error leaves nothing behind.
pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let mut temps = Temporaries(vec![temporary(path, &temporary_tag())]);
    write(&temps.0[0])?;
    sync(&temps.0[0])?;
    rename(&temps.0[0], path)?;
    temps.0.clear();
    Ok(())
}

pub(crate) fn write_text(path: &Path, text: &str) -> Result<(), OutputError> {
    std::fs::write(path, text).map_err(|source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    })
}

pub(crate) fn create_dir(dir: &Path) -> Result<(), OutputError> {
    std::fs::create_dir_all(dir).map_err(|source| OutputError::Io {
        path: dir.to_path_buf(),
        source,
    })
}

/// Remove a file; whether it was there.
pub(crate) fn remove_if_present(path: &Path) -> Result<bool, OutputError> {
    match std::fs::remove_file(path) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(source) => Err(OutputError::Io {
            path: path.to_path_buf(),
            source,
        }),
    }
}

pub(crate) fn sync(path: &Path) -> Result<(), OutputError> {
    std::fs::File::open(path)
        .and_then(|f| f.sync_all())
        .map_err(|source| OutputError::Io {
            path: path.to_path_buf(),
            source,
        })
}

pub(crate) fn rename(from: &Path, to: &Path) -> Result<(), OutputError> {
    std::fs::rename(from, to).map_err(|source| OutputError::Io {
        path: to.to_path_buf(),
        source,
    })
}

/// Temporary files removed on drop unless taken out of the list.
pub(crate) struct Temporaries(pub(crate) Vec<PathBuf>);

impl Drop for Temporaries {
    fn drop(&mut self) {
        for path in &self.0 {
            // Best effort: the file may not have been created yet.
            let _ = std::fs::remove_file(path);
        }
    }
}

/// Write `bytes` to the file `path` (a temporary name of
/// [`write_atomically`]).
pub(crate) fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    std::fs::write(path, bytes).map_err(|source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    })
}
