//! Text mutation for the parser fuzz tests: shared by this crate's `fuzz_parsers.rs` and the
//! application's `crates/aeroident/tests/all/fuzz_scenarios.rs` (included there with `#[path]`).

/// Applies `edits` to `seed` in order; each `(at, op, s)` acts at character `at` modulo the
/// text's length + 1: `op % 4` = 0 inserts `s`, 1 deletes `s.len()` characters, 2 replaces
/// one character with the first of `s` (`=` if empty), 3 duplicates the line containing it
/// (repeated keys and tables).
pub fn mutate(seed: &str, edits: &[(usize, u8, String)]) -> String {
    let mut c: Vec<char> = seed.chars().collect();
    for (at, op, s) in edits {
        let i = if c.is_empty() { 0 } else { at % (c.len() + 1) };
        match op % 4 {
            0 => c.splice(i..i, s.chars()).for_each(drop),
            1 => {
                let end = (i + s.len()).min(c.len());
                c.drain(i..end).for_each(drop);
            }
            2 => {
                // Replace one character.
                if i < c.len() {
                    c[i] = s.chars().next().unwrap_or('=');
                }
            }
            _ => {
                // Duplicate the line containing `i` (repeated keys and tables).
                let start = c[..i].iter().rposition(|&x| x == '\n').map_or(0, |p| p + 1);
                let end = c[i..].iter().position(|&x| x == '\n').map_or(c.len(), |p| i + p + 1);
                let line: Vec<char> = c[start..end].to_vec();
                c.splice(end..end, line).for_each(drop);
            }
        }
    }
    c.into_iter().collect()
}
