//! Closed sets of named choices (estimator kinds, surfaces, derivative sources): one list of
//! names that the command line, scenario files and Python all parse with, instead of a
//! command-line derive in the library.

/// A closed set of choices, each with one lower-case name.
pub trait Named: Sized + Copy + 'static {
    /// Every choice, in the order they are listed to a user.
    const ALL: &'static [Self];

    /// The choice's name (command line, scenario files, `summary.json`).
    fn name(self) -> &'static str;

    /// The choice named `text`, if any (exact, case-sensitive).
    fn from_name(text: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|c| c.name() == text)
    }

    /// Every name, in [`ALL`](Self::ALL)'s order.
    fn names() -> Vec<&'static str> {
        Self::ALL.iter().map(|c| c.name()).collect()
    }
}
