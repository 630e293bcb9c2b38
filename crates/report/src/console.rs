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
