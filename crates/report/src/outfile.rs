//! Single output files (`export --out FILE`, `inspect --json FILE`, `--html FILE`, a plot's
//! `--out FILE.png`): regular files written atomically, never anything else.
//!
//! - **Never a device, a FIFO, a socket or a directory**: an atomic write renames a temporary
//!   file over its target, which would replace `/dev/null` (or any node the path names) with a
//!   regular file. A path that exists and is not a regular file is refused by name and kind.
//! - **Never an input of the same run**: an output naming the log, the summary or the mapping
//!   the run reads, by whatever path (identity, as [`crate::outdir`] compares it), is refused
//!   before the run does its work, so nothing is read from a file already replaced.
//! - **Never two outputs in one file**: `--json f --html f` would leave only the second.
//! - **Atomic**: the bytes go to a temporary file beside the target (`.NAME.tmp`), are synced,
//!   and the file is renamed into place; a failure leaves no partial file and names it. A
//!   symbolic link is followed, so the file it points to is replaced and the link kept.
//!
//! [`check_outputs`] is the check a run makes before its work, [`write_file`] and
//! [`write_file_with`] the writes after it (which repeat the file-type check, since the path
//! may have changed meanwhile).

use crate::outdir::{Identity, identity};
use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// Why an output file is refused or could not be written; each names the option and path as
/// given.
#[derive(Debug, thiserror::Error)]
pub enum OutputFileError {
    /// The path exists and is not a regular file.
    #[error(
        "{option} `{path}` is {kind}, not a regular file: it is not replaced; give a file path"
    )]
    NotRegular {
        /// The option as typed (`--out`, `--json` …).
        option: String,
        /// The path as given.
        path: String,
        /// What it is (`a character device`, `a FIFO` …).
        kind: &'static str,
    },
    /// The path names a file this run reads.
    #[error(
        "{option} `{path}` is this run's {input_option} `{input}`: it is not overwritten; give another file"
    )]
    Input {
        /// The output option.
        option: String,
        /// The output path as given.
        path: String,
        /// The input's option or role (`--summary`, `the log` …).
        input_option: String,
        /// The input path as given.
        input: String,
    },
    /// Two outputs of the run name one file.
    #[error("{option} `{path}` and {other_option} `{other}` name the same file: give each its own")]
    Same {
        /// The first output's option.
        option: String,
        /// Its path.
        path: String,
        /// The second output's option.
        other_option: String,
        /// Its path.
        other: String,
    },
    /// A file-system operation failed.
    #[error("{action} `{path}`: {source}")]
    Io {
        /// What was being done.
        action: &'static str,
        /// The output path.
        path: String,
        /// The cause.
        source: io::Error,
    },
}

/// What the existing file at `p` is when it is not a regular file (symbolic links followed);
/// `None` for a regular file or no file.
fn irregular_kind(p: &Path) -> Option<&'static str> {
    let t = fs::metadata(p).ok()?.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_char_device() {
            return Some("a character device");
        }
        if t.is_block_device() {
            return Some("a block device");
        }
        if t.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

/// Where `p` would be, for two paths that do not exist yet: its directory's canonical path
/// and its name (`a/../b.json` and `b.json` agree).
fn location(p: &Path) -> Option<PathBuf> {
    let dir = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    Some(fs::canonicalize(dir).ok()?.join(p.file_name()?))
}

/// Whether `a` and `b` name one file: the same identity when both exist, else the same place.
fn same_file(a: &Path, b: &Path) -> bool {
    match (identity(a), identity(b)) {
        (Some(x), Some(y)) => x == y,
        (None, None) => location(a).is_some_and(|l| Some(l) == location(b)),
        _ => false,
    }
}

/// Checks a run's output files before it works: `outputs` and `inputs` are `(option, path)`
/// pairs as the user gave them (an input's option may be a role, `the log`).
///
/// # Errors
/// [`OutputFileError::NotRegular`], [`OutputFileError::Input`] or [`OutputFileError::Same`],
/// for the first output that is refused.
pub fn check_outputs(
    outputs: &[(&str, &Path)],
    inputs: &[(&str, &Path)],
) -> Result<(), OutputFileError> {
    let inputs: Vec<(&str, &Path, Identity)> =
        inputs.iter().filter_map(|(o, p)| Some((*o, *p, identity(p)?))).collect();
    for (k, (option, path)) in outputs.iter().enumerate() {
        check_regular(option, path)?;
        if let Some(id) = identity(path)
            && let Some((input_option, input, _)) = inputs.iter().find(|(_, _, i)| *i == id)
        {
            return Err(OutputFileError::Input {
                option: option.to_string(),
                path: path.display().to_string(),
                input_option: input_option.to_string(),
                input: input.display().to_string(),
            });
        }
        if let Some((other_option, other)) = outputs[..k].iter().find(|(_, o)| same_file(o, path)) {
            return Err(OutputFileError::Same {
                option: other_option.to_string(),
                path: other.display().to_string(),
                other_option: option.to_string(),
                other: path.display().to_string(),
            });
        }
    }
    Ok(())
}

fn check_regular(option: &str, path: &Path) -> Result<(), OutputFileError> {
    match irregular_kind(path) {
        Some(kind) => Err(OutputFileError::NotRegular {
            option: option.to_string(),
            path: path.display().to_string(),
            kind,
        }),
        None => Ok(()),
    }
}

/// Writes `bytes` to the output file `path` given with `option` (module doc).
///
/// # Errors
/// [`OutputFileError::NotRegular`]; [`OutputFileError::Io`] naming the file (no partial file
/// is left).
pub fn write_file(option: &str, path: &Path, bytes: &[u8]) -> Result<(), OutputFileError> {
    write_file_with(option, path, |tmp| {
        let mut f = fs::File::create(tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })
}

/// Writes the output file `path` through code that takes a path (a figure renderer): `fill`
/// writes the temporary path, which keeps the target's extension so that format detection
/// by extension works, and which is then renamed into place (module doc).
///
/// # Errors
/// As [`write_file`]; `fill`'s error is reported as the file's.
pub fn write_file_with<F, E>(option: &str, path: &Path, fill: F) -> Result<(), OutputFileError>
where
    F: FnOnce(&Path) -> Result<(), E>,
    E: std::fmt::Display,
{
    check_regular(option, path)?;
    let io_err = |action| {
        let path = path.display().to_string();
        move |source| OutputFileError::Io { action, path, source }
    };
    // A link is followed: the file it points to is replaced, the link stays.
    let target = if fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        fs::canonicalize(path).map_err(io_err("resolving"))?
    } else {
        path.to_path_buf()
    };
    let name = target.file_name().ok_or_else(|| {
        io_err("writing")(io::Error::new(io::ErrorKind::InvalidInput, "names no file"))
    })?;
    let tmp = target.with_file_name(format!(".{}.tmp", name.to_string_lossy()));
    let tmp = match target.extension() {
        Some(ext) => tmp.with_extension(format!("tmp.{}", ext.to_string_lossy())),
        None => tmp,
    };
    if let Err(e) = fill(&tmp) {
        let _ = fs::remove_file(&tmp);
        return Err(io_err("writing")(io::Error::other(e.to_string())));
    }
    fs::rename(&tmp, &target).map_err(|e| {
        let _ = fs::remove_file(&tmp);
        io_err("renaming into place")(e)
    })
}

#[cfg(test)]
mod tests;
