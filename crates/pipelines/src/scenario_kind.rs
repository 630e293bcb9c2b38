//! The one scenario format: every scenario file starts with a top-level `kind` naming the
//! command that runs it, checked before the rest of the file is read, so a file given to the
//! wrong command gets an error naming the kind expected and the kind found (instead of the
//! first field the other format does not know, e.g. "unknown field `aircraft`").
//!
//! | `kind` | command | shape (module doc) | shipped |
//! |---|---|---|---|
//! | `"run"` | `aeroident run`, `aeroident montecarlo` | [`crate::aircraft::scenario`] | `scenarios/default.toml`, `scenarios/f16/`, `scenarios/montecarlo/` |
//! | `"poc"` | `aeroident poc` | [`crate::poc::scenario`] | `scenarios/poc/` |
//! | `"sim"` | `aeroident f16 sim`, `aeroident sim` | [`crate::sim::scenario`] | `scenarios/sim/` |
//!
//! ```toml
//! kind = "run"      # first key of the file, before any [table]
//! name = "default"
//! ...
//! ```
//! The shipped directories are found from the crate's source directory
//! ([`shipped_dir`]), so `--all` without a directory works from any working directory.

use serde::Deserialize;
use std::path::PathBuf;

/// Which command a scenario file is for (the file's top-level `kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ScenarioKind {
    /// An aircraft estimation experiment: `aeroident run` and `aeroident montecarlo`.
    Run,
    /// A proof-of-concept system of the thesis: `aeroident poc`.
    Poc,
    /// An open-loop simulation: `aeroident f16 sim`, `aeroident sim` (any aircraft).
    Sim,
}

impl ScenarioKind {
    /// Every kind.
    pub const ALL: [ScenarioKind; 3] = [Self::Run, Self::Poc, Self::Sim];

    /// The value of `kind` in the file.
    pub fn name(self) -> &'static str {
        match self {
            Self::Run => "run",
            Self::Poc => "poc",
            Self::Sim => "sim",
        }
    }

    /// The command that runs this kind.
    pub fn command(self) -> &'static str {
        match self {
            Self::Run => "aeroident run FILE (or aeroident montecarlo FILE)",
            Self::Poc => "aeroident poc FILE --out DIR",
            Self::Sim => "aeroident f16 sim FILE --out DIR",
        }
    }

    /// The shipped scenario directory of this kind, under the workspace's `scenarios/`.
    pub fn shipped_subdir(self) -> &'static str {
        match self {
            Self::Run => "f16",
            Self::Poc => "poc",
            Self::Sim => "sim",
        }
    }

    fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// A scenario file whose `kind` is missing, unknown or not the one the command takes.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KindError {
    /// No top-level `kind`.
    #[error(
        "scenario `{file}`: missing top-level `kind`: this command takes `kind = \"{expected}\"` scenarios (write it as the first line){hint}"
    )]
    Missing {
        /// Scenario file.
        file: String,
        /// The kind the command takes.
        expected: &'static str,
        /// Empty, or "; the file looks like a `sim` scenario (…)".
        hint: String,
    },
    /// `kind` is not one of the kinds.
    #[error(
        "scenario `{file}`: line {line}: `kind = {found}` is not a scenario kind (one of \"run\", \"poc\", \"sim\"); this command takes `kind = \"{expected}\"`"
    )]
    Unknown {
        /// Scenario file.
        file: String,
        /// Line of the `kind` key.
        line: usize,
        /// The value found (TOML).
        found: String,
        /// The kind the command takes.
        expected: &'static str,
    },
    /// `kind` names another command's scenario.
    #[error(
        "scenario `{file}`: line {line}: expected kind \"{expected}\", found kind \"{found}\": this is a `{found}` scenario, run it with `{command}`"
    )]
    Wrong {
        /// Scenario file.
        file: String,
        /// Line of the `kind` key.
        line: usize,
        /// The kind the command takes.
        expected: &'static str,
        /// The kind found.
        found: &'static str,
        /// The command that runs the kind found.
        command: &'static str,
    },
}

/// Checks that `text` (the scenario file `file`) declares `kind = "<expected>"`.
///
/// Text that is not valid TOML passes: the command's own parser then reports the syntax error
/// with its line and column.
///
/// # Errors
/// [`KindError`] naming the file, the line of `kind`, the kind expected and the kind found.
pub fn check(text: &str, file: &str, expected: ScenarioKind) -> Result<(), KindError> {
    let Ok(table) = toml::from_str::<toml::Table>(text) else {
        return Ok(());
    };
    let Some(value) = table.get("kind") else {
        // Guess the kind from the tables only that format has.
        let looks = if table.contains_key("case") && table.contains_key("system") {
            Some(ScenarioKind::Poc)
        } else if table.contains_key("aircraft") && table.contains_key("run") {
            Some(ScenarioKind::Sim)
        } else if table.contains_key("name") && table.contains_key("duration_s") {
            Some(ScenarioKind::Run)
        } else {
            None
        };
        let hint = match looks {
            Some(k) if k != expected => format!(
                "; the file looks like a `{}` scenario (kind = \"{}\", run with `{}`)",
                k.name(),
                k.name(),
                k.command()
            ),
            _ => String::new(),
        };
        return Err(KindError::Missing { file: file.into(), expected: expected.name(), hint });
    };
    let line = line_of_key(text);
    match value.as_str().and_then(ScenarioKind::parse) {
        Some(k) if k == expected => Ok(()),
        Some(k) => Err(KindError::Wrong {
            file: file.into(),
            line,
            expected: expected.name(),
            found: k.name(),
            command: k.command(),
        }),
        None => Err(KindError::Unknown {
            file: file.into(),
            line,
            found: value.to_string(),
            expected: expected.name(),
        }),
    }
}

/// 1-based line of the top-level `kind` key (the first line that starts with `kind`, before
/// any table header; 1 if not found).
fn line_of_key(text: &str) -> usize {
    for (i, l) in text.lines().enumerate() {
        let l = l.trim_start();
        if l.starts_with('[') {
            break;
        }
        if let Some(rest) = l.strip_prefix("kind") {
            let rest = rest.trim_start();
            if rest.starts_with('=') {
                return i + 1;
            }
        }
    }
    1
}

/// The shipped scenario directory of `kind` (`<workspace>/scenarios/<subdir>`), found from this
/// crate's source directory at build time, so it does not depend on the working directory.
pub fn shipped_dir(kind: ScenarioKind) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(kind.shipped_subdir())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_wrong_kind_names_expected_found_and_line() {
        let text = "# a sim\n\nkind = \"sim\"\n[aircraft]\nxcg = 0.3\n";
        let e = check(text, "s.toml", ScenarioKind::Run).unwrap_err().to_string();
        assert!(
            e.starts_with("scenario `s.toml`: line 3: expected kind \"run\", found kind \"sim\""),
            "{e}"
        );
        assert!(e.contains("aeroident f16 sim"), "{e}");
        assert_eq!(check(text, "s.toml", ScenarioKind::Sim), Ok(()));
    }

    #[test]
    fn errors_missing_kind_guesses_the_format() {
        let text = "[case]\nname = \"x\"\n[system]\nkind = \"first_order\"\n";
        let e = check(text, "p.toml", ScenarioKind::Run).unwrap_err().to_string();
        assert!(e.contains("p.toml") && e.contains("missing top-level `kind`"), "{e}");
        assert!(e.contains("kind = \"run\"") && e.contains("looks like a `poc` scenario"), "{e}");
        // The nested [system] kind is not the file's kind.
        let e = check(text, "p.toml", ScenarioKind::Poc).unwrap_err().to_string();
        assert!(e.contains("missing top-level `kind`") && !e.contains("looks like"), "{e}");
    }

    #[test]
    fn errors_unknown_kind_is_quoted() {
        for (v, shown) in [("\"simulation\"", "\"simulation\""), ("3", "3")] {
            let text = format!("kind = {v}\nname = \"x\"\n");
            let e = check(&text, "u.toml", ScenarioKind::Poc).unwrap_err().to_string();
            assert!(e.contains(&format!("line 1: `kind = {shown}` is not a scenario kind")), "{e}");
        }
    }

    #[test]
    fn invalid_toml_is_left_to_the_parser() {
        assert_eq!(check("kind = \"sim\n", "x.toml", ScenarioKind::Run), Ok(()));
    }

    #[test]
    fn shipped_dirs_exist() {
        for k in ScenarioKind::ALL {
            assert!(shipped_dir(k).is_dir(), "{}", shipped_dir(k).display());
        }
    }
}
