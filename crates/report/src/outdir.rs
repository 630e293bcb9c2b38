//! Output directories that never mix runs: locked while a run writes, cleared of the previous
//! run's files, every file written atomically, and names from scenario files kept inside.
//!
//! - **Lock**: [`OutputDir::open`] takes an exclusive OS lock on `DIR/.aeroident.lock`
//!   (`File::try_lock`, released when the process ends, so a crash leaves no stale lock); a
//!   second run into the same directory fails at once with an error naming it.
//! - **No stale files**: the files and subdirectories the previous run wrote are listed in
//!   `DIR/.aeroident-manifest`, under the command that wrote them; they are removed before the
//!   new run writes anything, so an old `summary.json` or figure never sits beside a new,
//!   partial run. Files the tool did not write are left alone.
//! - **Never an input, never another command's results**: the directory is refused (nothing
//!   removed) when the previous run was another command (`f16 sim` results are not cleared by a
//!   `replay` into the same directory: they may be its input, and mixing two commands' files in
//!   one directory would make neither's set whole), or when a file to remove or to write is one
//!   of this run's inputs (same file, compared by identity, whatever path names it).
//! - **A failed run leaves no results**: unless the run calls [`OutputDir::finish`], dropping
//!   the directory (an error returned, a panic) removes everything this run wrote, so a
//!   `summary.json` written before a figure that failed never looks like a result.
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
    /// The directory holds another command's results (they are not removed).
    #[error(
        "output directory `{dir}` holds the results of `aeroident {command}` ({files}); they are not removed by `aeroident {this}`: give another --out, or remove them first"
    )]
    OtherCommand {
        /// The directory.
        dir: String,
        /// The command that wrote them.
        command: String,
        /// This run's command.
        this: String,
        /// The first of the files, comma-separated.
        files: String,
    },
    /// A file to remove or to write is an input of this run.
    #[error(
        "`{path}` is an input of this run (given as `{input}`); it is not {action}: give another --out"
    )]
    Input {
        /// The file in the output directory.
        path: String,
        /// The input path as given.
        input: String,
        /// `removed` (a previous run's result) or `overwritten`.
        action: &'static str,
    },
    /// `--out` names something that cannot be an output directory.
    #[error("output directory `{dir}`: {what}")]
    NotADirectory {
        /// The path.
        dir: String,
        /// What it is instead.
        what: String,
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

/// How a file is known whatever path names it: device and inode where the system has them,
/// else the canonical path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Identity {
    #[cfg(unix)]
    Inode(u64, u64),
    #[cfg(not(unix))]
    Canonical(PathBuf),
}

/// The identity of the file at `p` (symbolic links followed), `None` if there is none.
pub(crate) fn identity(p: &Path) -> Option<Identity> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        fs::metadata(p).ok().map(|m| Identity::Inode(m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        fs::canonicalize(p).ok().map(Identity::Canonical)
    }
}

/// The manifest of a run: the command that wrote it and what it wrote. A manifest of an
/// earlier version (bare file names, no command) has `command: None`.
#[derive(Debug, Default)]
struct Manifest {
    command: Option<String>,
    files: Vec<String>,
    dirs: Vec<String>,
}

impl Manifest {
    fn read(dir: &Path) -> Option<Self> {
        let text = fs::read_to_string(dir.join(MANIFEST)).ok()?;
        let mut m = Self::default();
        for line in text.lines() {
            if let Some(c) = line.strip_prefix("command ") {
                m.command = Some(c.to_string());
            } else if let Some(d) = line.strip_prefix("dir ") {
                if safe_relative(d).is_ok() {
                    m.dirs.push(d.to_string());
                }
            } else {
                let name = line.strip_prefix("file ").unwrap_or(line);
                if safe_component(name).is_ok() {
                    m.files.push(name.to_string());
                }
            }
        }
        Some(m)
    }

    /// Files and directories to remove to clear this manifest's run from `dir`, subdirectories'
    /// own manifests included (directories deepest first).
    fn plan(&self, dir: &Path, files: &mut Vec<PathBuf>, dirs: &mut Vec<PathBuf>) {
        files.extend(self.files.iter().map(|n| dir.join(n)));
        for rel in &self.dirs {
            let sub = dir.join(rel);
            if let Some(m) = Self::read(&sub) {
                m.plan(&sub, files, dirs);
            }
            files.extend([sub.join(MANIFEST), sub.join(LOCK)]);
            let mut p = Path::new(rel);
            while !p.as_os_str().is_empty() {
                dirs.push(dir.join(p));
                p = p.parent().unwrap_or(Path::new(""));
            }
        }
        dirs.sort_by_key(|d| std::cmp::Reverse(d.components().count()));
        dirs.dedup();
    }
}

/// Checks a relative path of safe components (`a/b`), for subdirectories.
fn safe_relative(rel: &str) -> Result<&str, OutputError> {
    for c in rel.split('/') {
        safe_component(c)?;
    }
    Ok(rel)
}

/// Refuses an output path that is, or lies below, something other than a directory: a
/// dangling symbolic link, a link loop, a file (rather than the file system's "File exists").
fn check_out_path(dir: &Path) -> Result<(), OutputError> {
    let Some(existing) = dir.ancestors().find(|a| fs::symlink_metadata(a).is_ok()) else {
        return Ok(());
    };
    let name = if existing == dir {
        String::new()
    } else {
        format!(" (its parent `{}`)", existing.display())
    };
    let bad = |what: String| {
        Err(OutputError::NotADirectory {
            dir: dir.display().to_string(),
            what: format!("{what}{name}"),
        })
    };
    let link = fs::symlink_metadata(existing).is_ok_and(|m| m.file_type().is_symlink());
    let target = fs::read_link(existing).map(|t| t.display().to_string()).unwrap_or_default();
    match fs::metadata(existing) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) if link => bad(format!("a symbolic link to `{target}`, which is not a directory")),
        Ok(_) => bad("exists and is not a directory".into()),
        Err(e) if link && e.kind() == io::ErrorKind::NotFound => {
            bad(format!("a dangling symbolic link (to `{target}`, which does not exist)"))
        }
        Err(e) if link => {
            bad(format!("a symbolic link that cannot be followed (to `{target}`; a loop?): {e}"))
        }
        Err(e) => bad(format!("cannot be read: {e}")),
    }
}

/// A locked output directory (module doc). Dropping it releases the lock, and removes what
/// this run wrote unless [`OutputDir::finish`] was called.
#[derive(Debug)]
pub struct OutputDir {
    dir: PathBuf,
    _lock: File,
    command: String,
    inputs: Vec<(String, Identity)>,
    written: BTreeSet<String>,
    subdirs: BTreeSet<String>,
    finished: bool,
}

impl OutputDir {
    /// Creates `dir` if needed, locks it and removes the previous run of `command`'s files
    /// (module doc). `command` is the subcommand (`replay`, `f16 sim` …); `inputs` are the
    /// files this run reads (paths that name no file, such as `-`, are ignored).
    ///
    /// # Errors
    /// [`OutputError::NotADirectory`] for a path that cannot be a directory;
    /// [`OutputError::Busy`] if another run holds it; [`OutputError::OtherCommand`] if another
    /// command's results are there; [`OutputError::Input`] if a file to remove is an input;
    /// [`OutputError::Io`] for file-system failures.
    pub fn open(dir: &Path, command: &str, inputs: &[&Path]) -> Result<Self, OutputError> {
        check_out_path(dir)?;
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
        let inputs = inputs
            .iter()
            .filter_map(|p| identity(p).map(|id| (p.display().to_string(), id)))
            .collect();
        let mut out = Self {
            dir: dir.to_path_buf(),
            _lock: lock,
            command: command.to_string(),
            inputs,
            written: BTreeSet::new(),
            subdirs: BTreeSet::new(),
            // Nothing of this run to remove until it writes.
            finished: true,
        };
        out.clear_previous()?;
        out.finished = false;
        Ok(out)
    }

    /// Removes the previous run's files, after checking they are this command's and no input.
    fn clear_previous(&self) -> Result<(), OutputError> {
        let Some(previous) = Manifest::read(&self.dir) else { return Ok(()) };
        if let Some(c) = previous.command.as_deref().filter(|c| *c != self.command) {
            let mut names: Vec<String> = previous.files.iter().take(4).cloned().collect();
            names
                .extend(previous.dirs.iter().take(4 - names.len().min(4)).map(|d| format!("{d}/")));
            if previous.files.len() + previous.dirs.len() > names.len() {
                names.push("…".into());
            }
            return Err(OutputError::OtherCommand {
                dir: self.dir.display().to_string(),
                command: c.to_string(),
                this: self.command.clone(),
                files: names.join(", "),
            });
        }
        let (mut files, mut dirs) = (Vec::new(), Vec::new());
        previous.plan(&self.dir, &mut files, &mut dirs);
        for f in &files {
            self.check_not_input(f, "removed")?;
        }
        remove_all(&files, &dirs)?;
        let manifest = self.dir.join(MANIFEST);
        fs::remove_file(&manifest).map_err(io_err("removing", &manifest))
    }

    /// [`OutputError::Input`] if `path` is one of this run's inputs.
    fn check_not_input(&self, path: &Path, action: &'static str) -> Result<(), OutputError> {
        let Some(id) = identity(path) else { return Ok(()) };
        match self.inputs.iter().find(|(_, i)| *i == id) {
            Some((input, _)) => Err(OutputError::Input {
                path: path.display().to_string(),
                input: input.clone(),
                action,
            }),
            None => Ok(()),
        }
    }

    /// Marks the run complete: its files stay when the directory is dropped.
    pub fn finish(&mut self) {
        self.finished = true;
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// The names of the files this run has written (or registered) so far.
    pub fn written(&self) -> impl Iterator<Item = &str> {
        self.written.iter().map(String::as_str)
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
        self.check_not_input(&target, "overwritten")?;
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
        self.check_not_input(&target, "overwritten")?;
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

    /// Registers a subdirectory `rel` (components separated by `/`) that other code writes
    /// as an output directory of its own (e.g. one per scenario of `run --all`), so the next run
    /// (or this one's failure) clears it as well; returns its path.
    ///
    /// # Errors
    /// [`OutputError::UnsafeName`] for an unsafe component; [`OutputError::Io`] if the manifest
    /// cannot be written.
    pub fn register_dir(&mut self, rel: &str) -> Result<PathBuf, OutputError> {
        let rel = safe_relative(rel)?.to_string();
        self.subdirs.insert(rel.clone());
        self.save_manifest()?;
        Ok(self.dir.join(rel))
    }

    fn save_manifest(&self) -> Result<(), OutputError> {
        let manifest = self.dir.join(MANIFEST);
        let mut text = format!("command {}\n", self.command);
        text.extend(self.written.iter().map(|n| format!("file {n}\n")));
        text.extend(self.subdirs.iter().map(|d| format!("dir {d}\n")));
        fs::write(&manifest, text).map_err(io_err("writing", &manifest))
    }
}

/// Removes `files` (those already gone are fine), then `dirs` where empty (a directory that
/// still holds files the tool did not write is kept).
fn remove_all(files: &[PathBuf], dirs: &[PathBuf]) -> Result<(), OutputError> {
    for p in files {
        match fs::remove_file(p) {
            Ok(()) => {}
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(io_err("removing stale", p)(e)),
        }
    }
    for d in dirs {
        let _ = fs::remove_dir(d);
    }
    Ok(())
}

impl Drop for OutputDir {
    /// A run that did not [`finish`](OutputDir::finish) leaves none of its files (module doc).
    fn drop(&mut self) {
        if self.finished {
            return;
        }
        let this = Manifest {
            command: None,
            files: self.written.iter().cloned().collect(),
            dirs: self.subdirs.iter().cloned().collect(),
        };
        let (mut files, mut dirs) = (Vec::new(), Vec::new());
        this.plan(&self.dir, &mut files, &mut dirs);
        files.retain(|f| self.check_not_input(f, "removed").is_ok());
        files.push(self.dir.join(MANIFEST));
        let _ = remove_all(&files, &dirs);
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
        let first = OutputDir::open(&d, "t", &[]).unwrap();
        let err = OutputDir::open(&d, "t", &[]).unwrap_err();
        assert!(matches!(err, OutputError::Busy { .. }), "{err}");
        assert!(err.to_string().contains(&d.display().to_string()));
        drop(first);
        OutputDir::open(&d, "t", &[]).unwrap();
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn previous_runs_files_are_removed_and_foreign_files_kept() {
        let d = scratch("stale");
        {
            let mut o = OutputDir::open(&d, "t", &[]).unwrap();
            o.write_bytes("summary.json", b"{}").unwrap();
            o.write_bytes("old.png", b"x").unwrap();
            o.finish();
        }
        fs::write(d.join("notes.txt"), "mine").unwrap();
        {
            let mut o = OutputDir::open(&d, "t", &[]).unwrap();
            assert!(!d.join("summary.json").exists() && !d.join("old.png").exists());
            o.write_bytes("summary.json", b"{\"new\":1}").unwrap();
            o.finish();
        }
        assert_eq!(fs::read_to_string(d.join("summary.json")).unwrap(), "{\"new\":1}");
        assert_eq!(fs::read_to_string(d.join("notes.txt")).unwrap(), "mine");
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn failed_write_leaves_no_partial_file_and_names_it() {
        let d = scratch("fail");
        let mut o = OutputDir::open(&d, "t", &[]).unwrap();
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
        let mut o = OutputDir::open(&d, "t", &[]).unwrap();
        assert!(o.write_bytes("../escape.json", b"x").is_err());
        assert!(!d.parent().unwrap().join("escape.json").exists());
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn uncommitted_stream_leaves_nothing_and_path_writer_renames() {
        let d = scratch("stream");
        let mut o = OutputDir::open(&d, "t", &[]).unwrap();
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

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| !n.starts_with(".aeroident"))
            .collect();
        v.sort();
        v
    }

    #[test]
    fn another_commands_results_are_refused_and_kept() {
        let d = scratch("other");
        let mut o = OutputDir::open(&d, "f16 sim", &[]).unwrap();
        o.write_bytes("timeseries.csv", b"t_s\n0\n").unwrap();
        o.finish();
        drop(o);
        let err = OutputDir::open(&d, "replay", &[]).unwrap_err();
        let msg = err.to_string();
        assert!(matches!(err, OutputError::OtherCommand { .. }), "{msg}");
        assert!(msg.contains("f16 sim") && msg.contains("timeseries.csv"), "{msg}");
        assert_eq!(fs::read_to_string(d.join("timeseries.csv")).unwrap(), "t_s\n0\n");
        // The same command clears them as before.
        drop(OutputDir::open(&d, "f16 sim", &[]).unwrap());
        assert!(!d.join("timeseries.csv").exists());
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn an_input_is_never_removed_nor_overwritten() {
        let d = scratch("input");
        let mut o = OutputDir::open(&d, "replay", &[]).unwrap();
        o.write_bytes("estimates.csv", b"t_s\n").unwrap();
        o.finish();
        drop(o);
        // Named through another path (a symbolic link elsewhere): the same file.
        let other = scratch("input-link");
        fs::create_dir_all(&other).unwrap();
        let link = other.join("data.csv");
        #[cfg(unix)]
        std::os::unix::fs::symlink(d.join("estimates.csv"), &link).unwrap();
        #[cfg(not(unix))]
        let link = d.join("estimates.csv");
        let err = OutputDir::open(&d, "replay", &[link.as_path()]).unwrap_err();
        assert!(matches!(err, OutputError::Input { action: "removed", .. }), "{err}");
        assert!(err.to_string().contains(&link.display().to_string()), "{err}");
        assert!(d.join("estimates.csv").exists());
        // A file the tool did not write, read as input, is not overwritten either.
        fs::write(d.join("summary.json"), "mine").unwrap();
        fs::remove_file(d.join(MANIFEST)).unwrap();
        let input = d.join("summary.json");
        let mut o = OutputDir::open(&d, "replay", &[input.as_path()]).unwrap();
        let err = o.write_bytes("summary.json", b"{}").unwrap_err();
        assert!(matches!(err, OutputError::Input { action: "overwritten", .. }), "{err}");
        assert_eq!(fs::read_to_string(&input).unwrap(), "mine");
        let _ = fs::remove_dir_all(&d);
        let _ = fs::remove_dir_all(&other);
    }

    #[test]
    fn an_unfinished_run_leaves_none_of_its_files() {
        let d = scratch("unfinished");
        fs::create_dir_all(&d).unwrap();
        fs::write(d.join("notes.txt"), "mine").unwrap();
        {
            let mut o = OutputDir::open(&d, "replay", &[]).unwrap();
            o.write_bytes("summary.json", b"{}").unwrap();
            o.write_bytes("estimates.csv", b"t_s\n").unwrap();
            // A figure that fails: the run returns its error without finishing.
            assert!(o.write_path("fit.png", |_: &Path| Err("No space left on device")).is_err());
        }
        assert_eq!(names(&d), ["notes.txt"]);
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn subdirectories_are_cleared_with_their_parent() {
        let d = scratch("subdirs");
        {
            let mut top = OutputDir::open(&d, "run", &[]).unwrap();
            for rel in ["a", "b/corrected"] {
                let sub = top.register_dir(rel).unwrap();
                let mut o = OutputDir::open(&sub, "run", &[]).unwrap();
                o.write_bytes("summary.json", b"{}").unwrap();
                o.finish();
            }
            top.write_bytes("report.md", b"#").unwrap();
            top.finish();
        }
        fs::write(d.join("a").join("mine.txt"), "mine").unwrap();
        let o = OutputDir::open(&d, "run", &[]).unwrap();
        // `a` keeps the file the tool did not write; `b/corrected` and `b` are gone.
        assert_eq!(names(&d), ["a"]);
        assert_eq!(names(&d.join("a")), ["mine.txt"]);
        drop(o);
        let _ = fs::remove_dir_all(&d);
    }

    #[cfg(unix)]
    #[test]
    fn dangling_links_and_loops_are_named() {
        let d = scratch("links");
        fs::create_dir_all(&d).unwrap();
        let dangling = d.join("dangling");
        std::os::unix::fs::symlink(d.join("nowhere"), &dangling).unwrap();
        let looped = d.join("loop");
        std::os::unix::fs::symlink(&looped, &looped).unwrap();
        let file = d.join("file");
        fs::write(&file, "x").unwrap();
        for (out, what) in [
            (dangling.clone(), "dangling symbolic link"),
            (dangling.join("sub"), "dangling symbolic link"),
            (looped.clone(), "cannot be followed"),
            (file.clone(), "not a directory"),
        ] {
            let err = OutputDir::open(&out, "t", &[]).unwrap_err();
            let msg = err.to_string();
            assert!(msg.contains(&out.display().to_string()) && msg.contains(what), "{msg}");
            assert!(!msg.contains("File exists"), "{msg}");
        }
        let _ = fs::remove_dir_all(&d);
    }
}
