//! Headless Chromium for the tests of pages (`report.html`, `inspect --html`): found on PATH,
//! run with a fresh profile and no network services.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The Chromium binary on PATH, if any.
pub fn chromium() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    for dir in std::env::split_paths(&path) {
        for name in ["chromium", "chromium-browser", "google-chrome"] {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// The `file://` address of the page at `path`.
pub fn page_url(path: &Path) -> String {
    format!("file://{}", path.display())
}

/// Runs headless Chromium on `url` (a page's [`page_url`], or a server's address) with `extra`
/// arguments and a fresh profile; returns (exit ok, stdout, stderr).
pub fn headless(
    chrome: &Path,
    url: &str,
    profile: &Path,
    extra: &[&str],
) -> (bool, String, String) {
    let o = Command::new(chrome)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--enable-logging=stderr",
            "--v=0",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(url)
        .output()
        .expect("starting chromium");
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Console messages in Chromium's log (`…:CONSOLE(…)` lines and uncaught exceptions).
pub fn console_lines(stderr: &str) -> Vec<&str> {
    stderr.lines().filter(|l| l.contains("CONSOLE") || l.contains("Uncaught")).collect()
}
