//! Output directories that never mix runs: locked while a run writes, cleared of the previous
//! run's files, every file written atomically, and names from scenario files kept inside.
//!
//! - **Lock**: [`OutputDir::open`] takes an exclusive OS lock on `DIR/.aeroident.lock`
//!   (`File::try_lock`, released when the process ends, so a crash leaves no stale lock); a
//!   second run into the same directory fails at once with an error naming it.
//! - **No stale files**: the files the previous run wrote are listed in
//!   `DIR/.aeroident-manifest`; they are removed before the new run writes anything, so an old
//!   `summary.json` or figure never sits beside a new, partial run. Files the tool did not write
//!   are left alone.
//! - **Atomic files**: [`OutputDir::write`] writes `DIR/.NAME.tmp`, flushes and syncs it, then
//!   renames it to `DIR/NAME`; a failure (disk full, interrupted run) leaves no partial `NAME`
//!   and the error names the file.
//! - **Safe names**: [`safe_component`] refuses names with separators, `..`, control characters
//!   or a leading dot, so a scenario `name = "../../x"` cannot write outside `--out`.

use std::collections::BTreeSet;
use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Errors of an output directory, each naming the path.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Another run holds the directory's lock.
    #[error("output directory `{dir}` is in use by another aeroident run (lock `{lock}`)")]
    Busy {
        /// The directory.
        dir: String,
        /// The lock file.
        lock: String,
    },
    /// A file-system operation failed.
    #[error("{action} `{path}`: {source}")]
    Io {
        /// What was being done (`creating`, `writing`, `renaming` …).
        action: &'static str,
        /// The path concerned.
        path: String,
        /// The cause.
        source: io::Error,
    },
    /// A name cannot be used as a file or directory name inside the output directory.
    #[error("name `{name}` cannot be used inside the output directory: {reason}")]
    UnsafeName {
        /// The name.
        name: String,
        /// Why.
        reason: &'static str,
    },
}

fn io_err(action: &'static str, path: &Path) -> impl FnOnce(io::Error) -> OutputError + use<> {
    let path = path.display().to_string();
    move |source| OutputError::Io { action, path, source }
}

const LOCK: &str = ".aeroident.lock";
const MANIFEST: &str = ".aeroident-manifest";

/// Checks that `name` is a single, ordinary path component (module doc).
///
/// # Errors
/// [`OutputError::UnsafeName`].
pub fn safe_component(name: &str) -> Result<&str, OutputError> {
    let bad = |reason| Err(OutputError::UnsafeName { name: name.to_string(), reason });
    if name.is_empty() {
        return bad("empty");
    }
    if name.contains(['/', '\\']) {
        return bad("contains a path separator");
    }
    if name == "." || name == ".." || name.starts_with('.') {
        return bad("starts with a dot");
    }
    if name.chars().any(char::is_control) {
        return bad("contains a control character");
    }
    if name.len() > 200 {
        return bad("longer than 200 bytes");
    }
    Ok(name)
}

/// A locked output directory (module doc). Dropping it releases the lock.
#[derive(Debug)]
pub struct OutputDir {
    dir: PathBuf,
    _lock: File,
    written: BTreeSet<String>,
}

impl OutputDir {
    /// Creates `dir` if needed, locks it and removes the previous run's files.
    ///
    /// # Errors
    /// [`OutputError::Busy`] if another run holds it; [`OutputError::Io`] for file-system
    /// failures.
    pub fn open(dir: &Path) -> Result<Self, OutputError> {
        fs::create_dir_all(dir).map_err(io_err("creating directory", dir))?;
        let lock_path = dir.join(LOCK);
        let lock = File::options()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&lock_path)
            .map_err(io_err("creating lock", &lock_path))?;
        match lock.try_lock() {
            Ok(()) => {}
            Err(fs::TryLockError::WouldBlock) => {
                return Err(OutputError::Busy {
                    dir: dir.display().to_string(),
                    lock: lock_path.display().to_string(),
                });
            }
            Err(fs::TryLockError::Error(e)) => {
                return Err(io_err("locking", &lock_path)(e));
            }
        }
        let manifest = dir.join(MANIFEST);
        if let Ok(text) = fs::read_to_string(&manifest) {
            for name in text.lines().filter(|l| safe_component(l).is_ok()) {
                let p = dir.join(name);
                match fs::remove_file(&p) {
                    Ok(()) => {}
                    Err(e) if e.kind() == io::ErrorKind::NotFound => {}
                    Err(e) => return Err(io_err("removing stale", &p)(e)),
                }
            }
            fs::remove_file(&manifest).map_err(io_err("removing", &manifest))?;
        }
        Ok(Self { dir: dir.to_path_buf(), _lock: lock, written: BTreeSet::new() })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Writes file `name` atomically with `fill` (module doc) and records it in the manifest.
    ///
    /// # Errors
    /// [`OutputError::UnsafeName`] for a bad name; [`OutputError::Io`] naming the file for any
    /// write, sync or rename failure (the partial temporary file is removed).
    pub fn write<F>(&mut self, name: &str, fill: F) -> Result<PathBuf, OutputError>
    where
        F: FnOnce(&mut dyn Write) -> io::Result<()>,
    {
        let mut f = self.create(name)?;
        if let Err(e) = fill(&mut f) {
            return Err(io_err("writing", &f.target)(e));
        }
        f.commit()
    }

    /// Opens file `name` for streaming: the data go to a temporary file in the directory that
    /// [`AtomicFile::commit`] renames into place; dropping it uncommitted removes it. Write
    /// errors name the file.
    ///
    /// # Errors
    /// [`OutputError::UnsafeName`]; [`OutputError::Io`] if the temporary file or the manifest
    /// cannot be created.
    pub fn create(&mut self, name: &str) -> Result<AtomicFile, OutputError> {
        let name = safe_component(name)?.to_string();
        let target = self.dir.join(&name);
        let tmp = self.dir.join(format!(".{name}.tmp"));
        // Record first, so a crash after the rename still lets the next run clear it.
        self.written.insert(name);
        self.save_manifest()?;
        let f = File::create(&tmp).map_err(io_err("creating", &target))?;
        Ok(AtomicFile { tmp, target, w: Some(BufWriter::new(f)) })
    }

    /// Writes file `name` atomically through code that takes a path (e.g. a figure renderer):
    /// `fill` writes the temporary path `DIR/.tmp-NAME` (same extension, so format detection by
    /// extension works), which is then renamed to `DIR/NAME`.
    ///
    /// # Errors
    /// [`OutputError::UnsafeName`]; [`OutputError::Io`] naming the file when `fill` or the
    /// rename fails (the temporary file is removed).
    pub fn write_path<F, E>(&mut self, name: &str, fill: F) -> Result<PathBuf, OutputError>
    where
        F: FnOnce(&Path) -> Result<(), E>,
        E: std::fmt::Display,
    {
        let name = safe_component(name)?.to_string();
        let target = self.dir.join(&name);
        let tmp = self.dir.join(format!(".tmp-{name}"));
        self.written.insert(name);
        self.save_manifest()?;
        if let Err(e) = fill(&tmp) {
            let _ = fs::remove_file(&tmp);
            return Err(io_err("writing", &target)(io::Error::other(e.to_string())));
        }
        fs::rename(&tmp, &target).map_err(io_err("renaming into place", &target))?;
        Ok(target)
    }

    /// Writes `bytes` to file `name` atomically.
    ///
    /// # Errors
    /// As [`OutputDir::write`].
    pub fn write_bytes(&mut self, name: &str, bytes: &[u8]) -> Result<PathBuf, OutputError> {
        self.write(name, |w| w.write_all(bytes))
    }

    /// Registers a file that is written by other code (e.g. a figure library that takes a
    /// path), so the next run clears it; returns its path.
    ///
    /// # Errors
    /// [`OutputError::UnsafeName`], or [`OutputError::Io`] if the manifest cannot be written.
    pub fn register(&mut self, name: &str) -> Result<PathBuf, OutputError> {
        let name = safe_component(name)?.to_string();
        self.written.insert(name.clone());
        self.save_manifest()?;
        Ok(self.dir.join(name))
    }

    fn save_manifest(&self) -> Result<(), OutputError> {
        let manifest = self.dir.join(MANIFEST);
        let text: String = self.written.iter().map(|n| format!("{n}\n")).collect();
        fs::write(&manifest, text).map_err(io_err("writing", &manifest))
    }
}

/// A file being written into an [`OutputDir`] (see [`OutputDir::create`]).
#[derive(Debug)]
pub struct AtomicFile {
    tmp: PathBuf,
    target: PathBuf,
    w: Option<BufWriter<File>>,
}

impl AtomicFile {
    /// The final path of the file.
    pub fn path(&self) -> &Path {
        &self.target
    }

    fn named(&self, e: io::Error) -> io::Error {
        io::Error::new(e.kind(), format!("writing `{}`: {e}", self.target.display()))
    }

    /// Flushes, syncs and renames the file into place; returns its path.
    ///
    /// # Errors
    /// [`OutputError::Io`] naming the file (the temporary file is removed).
    pub fn commit(mut self) -> Result<PathBuf, OutputError> {
        let Some(w) = self.w.take() else {
            return Err(io_err("writing", &self.target)(io::Error::other("already closed")));
        };
        let result =
            w.into_inner().map_err(io::IntoInnerError::into_error).and_then(|f| f.sync_all());
        if let Err(e) = result {
            let _ = fs::remove_file(&self.tmp);
            return Err(io_err("writing", &self.target)(e));
        }
        fs::rename(&self.tmp, &self.target).map_err(io_err("renaming into place", &self.target))?;
        Ok(self.target.clone())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let r = match self.w.as_mut() {
            Some(w) => w.write(buf),
            None => Err(io::Error::other("already closed")),
        };
        r.map_err(|e| self.named(e))
    }

    fn flush(&mut self) -> io::Result<()> {
        let r = match self.w.as_mut() {
            Some(w) => w.flush(),
            None => Ok(()),
        };
        r.map_err(|e| self.named(e))
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.w.take().is_some() {
            let _ = fs::remove_file(&self.tmp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("aeroident-outdir-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn second_run_into_a_locked_directory_is_refused() {
        let d = scratch("lock");
        let first = OutputDir::open(&d).unwrap();
        let err = OutputDir::open(&d).unwrap_err();
        assert!(matches!(err, OutputError::Busy { .. }), "{err}");
        assert!(err.to_string().contains(&d.display().to_string()));
        drop(first);
        OutputDir::open(&d).unwrap();
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn previous_runs_files_are_removed_and_foreign_files_kept() {
        let d = scratch("stale");
        {
            let mut o = OutputDir::open(&d).unwrap();
            o.write_bytes("summary.json", b"{}").unwrap();
            o.write_bytes("old.png", b"x").unwrap();
        }
        fs::write(d.join("notes.txt"), "mine").unwrap();
        {
            let mut o = OutputDir::open(&d).unwrap();
            assert!(!d.join("summary.json").exists() && !d.join("old.png").exists());
            o.write_bytes("summary.json", b"{\"new\":1}").unwrap();
        }
        assert_eq!(fs::read_to_string(d.join("summary.json")).unwrap(), "{\"new\":1}");
        assert_eq!(fs::read_to_string(d.join("notes.txt")).unwrap(), "mine");
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn failed_write_leaves_no_partial_file_and_names_it() {
        let d = scratch("fail");
        let mut o = OutputDir::open(&d).unwrap();
        let err = o
            .write("summary.json", |w| {
                w.write_all(b"{\"half")?;
                Err(io::Error::other("No space left on device"))
            })
            .unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("summary.json") && msg.contains("No space left"), "{msg}");
        assert!(!d.join("summary.json").exists() && !d.join(".summary.json.tmp").exists());
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn unsafe_names_are_refused() {
        for n in ["../../x", "a/b", "..", ".hidden", "", "a\\b", "x\ny"] {
            assert!(safe_component(n).is_err(), "{n:?}");
        }
        assert_eq!(safe_component("t4_7_case4").unwrap(), "t4_7_case4");
        let d = scratch("names");
        let mut o = OutputDir::open(&d).unwrap();
        assert!(o.write_bytes("../escape.json", b"x").is_err());
        assert!(!d.parent().unwrap().join("escape.json").exists());
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn uncommitted_stream_leaves_nothing_and_path_writer_renames() {
        let d = scratch("stream");
        let mut o = OutputDir::open(&d).unwrap();
        {
            let mut f = o.create("estimates.csv").unwrap();
            f.write_all(b"t_s\n1\n").unwrap();
        }
        assert!(!d.join("estimates.csv").exists() && !d.join(".estimates.csv.tmp").exists());
        let mut f = o.create("estimates.csv").unwrap();
        f.write_all(b"t_s\n").unwrap();
        assert!(!d.join("estimates.csv").exists(), "visible before commit");
        f.commit().unwrap();
        assert_eq!(fs::read_to_string(d.join("estimates.csv")).unwrap(), "t_s\n");
        let seen = std::cell::RefCell::new(PathBuf::new());
        o.write_path("fig.png", |p: &Path| {
            *seen.borrow_mut() = p.to_path_buf();
            fs::write(p, b"png")
        })
        .unwrap();
        assert!(seen.borrow().to_string_lossy().ends_with(".png"));
        assert_eq!(fs::read(d.join("fig.png")).unwrap(), b"png");
        let err = o.write_path("bad.png", |_: &Path| Err("No space left on device")).unwrap_err();
        assert!(err.to_string().contains("bad.png") && err.to_string().contains("No space"));
        assert!(!d.join("bad.png").exists());
        let _ = fs::remove_dir_all(&d);
    }
}
