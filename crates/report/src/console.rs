//! The console output every face of the command line shares.

/// Writes `text` and a newline to standard output, returning the write error instead of
/// panicking as `println!` does on a closed pipe (`aeroident f16 trim | head -1`); `main`
/// ends quietly on a broken pipe.
///
/// # Errors
/// The I/O error of the write or flush.
pub fn print_stdout(text: &str) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.write_all(b"\n")?;
    out.flush()
}

/// Writes `text` and a newline to standard error, ignoring a write error where `eprintln!`
/// panics: with stderr a closed pipe (`aeroident compat … 2>&1 | head`) a note or a "wrote"
/// line after the results are written ended the run with a panic and exit 101. What stderr
/// carries is for a reader who is there; the results are in the files.
pub fn print_stderr(text: &str) {
    use std::io::Write;
    let mut err = std::io::stderr().lock();
    let _ = err.write_all(text.as_bytes()).and_then(|()| err.write_all(b"\n"));
}

/// `eprintln!` through [`print_stderr`]: the same arguments, no panic on a closed stderr.
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {
        $crate::console::print_stderr(&format!($($arg)*))
    };
}
