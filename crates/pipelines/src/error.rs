//! The error of the pipelines that have no error type of their own (simulation, design,
//! export, trim): a message, or a message in front of the error that caused it, so that a face
//! printing the [`source`](std::error::Error::source) chain shows `context: cause: …`.

use std::error::Error as StdError;
use std::fmt::Display;

/// A result whose error is a [`PipelineError`].
pub type Result<T, E = PipelineError> = std::result::Result<T, E>;

/// A pipeline error: a message, optionally over the error that caused it.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// A message alone.
    #[error("{0}")]
    Message(String),
    /// An error of a crate below, shown as it is.
    #[error(transparent)]
    Source(Box<dyn StdError + Send + Sync + 'static>),
    /// What was being done, over the error that stopped it.
    #[error("{context}")]
    Context {
        /// What was being done (a file, a table key, a condition).
        context: String,
        /// The cause.
        #[source]
        source: Box<dyn StdError + Send + Sync + 'static>,
    },
}

/// The error types of the crates below whose messages pass through as they are.
macro_rules! transparent_from {
    ($($t:ty),* $(,)?) => {$(
        impl From<$t> for PipelineError {
            fn from(e: $t) -> Self {
                PipelineError::Source(Box::new(e))
            }
        }
    )*};
}

transparent_from!(
    aeroident_models::ModelError,
    aeroident_signals::SignalError,
    aeroident_estimators::EstimatorError,
    crate::scenario_kind::KindError,
    std::io::Error,
);

impl PipelineError {
    /// An error of one message.
    pub fn msg(text: impl Display) -> Self {
        PipelineError::Message(text.to_string())
    }
}

/// Adds what was being done to an error (`result.context("[trim]")?`).
pub trait Context<T> {
    /// Wraps the error under `context`.
    ///
    /// # Errors
    /// The original error under `context`.
    fn context(self, context: impl Display) -> Result<T, PipelineError>;

    /// Wraps the error under the context `f` gives (evaluated on error only).
    ///
    /// # Errors
    /// The original error under `f()`.
    fn with_context<D: Display>(self, f: impl FnOnce() -> D) -> Result<T, PipelineError>;
}

impl<T, E: StdError + Send + Sync + 'static> Context<T> for Result<T, E> {
    fn context(self, context: impl Display) -> Result<T, PipelineError> {
        self.map_err(|e| PipelineError::Context {
            context: context.to_string(),
            source: Box::new(e),
        })
    }

    fn with_context<D: Display>(self, f: impl FnOnce() -> D) -> Result<T, PipelineError> {
        self.map_err(|e| PipelineError::Context { context: f().to_string(), source: Box::new(e) })
    }
}

/// Returns early with a [`PipelineError::Message`] formatted as `format!` does.
#[macro_export]
macro_rules! bail {
    ($($arg:tt)*) => {
        return Err($crate::error::PipelineError::msg(format!($($arg)*)))
    };
}

/// A [`PipelineError::Message`] formatted as `format!` does.
#[macro_export]
macro_rules! err {
    ($($arg:tt)*) => {
        $crate::error::PipelineError::msg(format!($($arg)*))
    };
}

/// An error and its causes on one line ("file:line: field: reason"): each cause is appended
/// after `: ` unless the text so far already contains it (some error types print their source
/// in their own message and some do not). The faces print and raise this.
pub fn error_chain(e: &(dyn StdError + 'static)) -> String {
    chain_message(std::iter::successors(Some(e), |&e| e.source()))
}

/// [`error_chain`] over an explicit chain, outermost first (a face's own error type walks its
/// chain and passes it here).
pub fn chain_message<'a>(errors: impl IntoIterator<Item = &'a (dyn StdError + 'static)>) -> String {
    let mut msg = String::new();
    for cause in errors {
        let c = cause.to_string();
        if msg.is_empty() {
            msg = c;
        } else if !msg.contains(&c) {
            msg.push_str(": ");
            msg.push_str(&c);
        }
    }
    msg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn context_keeps_the_cause_as_source() {
        let r: Result<(), std::io::Error> = Err(std::io::Error::other("disk full"));
        let e = r.context("writing `a.csv`").unwrap_err();
        assert_eq!(e.to_string(), "writing `a.csv`");
        assert_eq!(e.source().map(|s| s.to_string()).as_deref(), Some("disk full"));
        assert_eq!(error_chain(&e), "writing `a.csv`: disk full");
    }

    /// A cause already in the message is not repeated.
    #[test]
    fn chain_skips_a_cause_already_said() {
        let inner = std::io::Error::other("bad row 3");
        let outer = PipelineError::Context {
            context: "reading `x.csv`: bad row 3".into(),
            source: Box::new(inner),
        };
        assert_eq!(error_chain(&outer), "reading `x.csv`: bad row 3");
    }
}
