//! Measures the thread stack an `aeroident` command needs: bisects, to 16 KiB, the smallest
//! stack on which the command still finishes, run on a spawned thread with rayon's pool and
//! every thread it spawns without a stack size of its own (`RUST_MIN_STACK`) given the same
//! stack. Each try is a child process, since a stack overflow aborts the process.
//!
//! Run from a scratch directory (the command writes its outputs there):
//! `cargo run --release -p aeroident --example stack_need -- run`, or
//! `... --example stack_need -- replay RECORD --model six-axis --estimator oe --out o`.
//! `STACK_NEED_BYTES=N` runs the command once on an `N`-byte stack instead of bisecting.
#![allow(missing_docs)]

use std::process::{Command, ExitCode, Stdio};

const GRANULE: usize = 16 << 10;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match std::env::var("STACK_NEED_BYTES") {
        Ok(bytes) => match bytes.parse() {
            Ok(bytes) => run_on_stack(bytes, args),
            Err(e) => {
                eprintln!("STACK_NEED_BYTES must be a byte count, got {bytes}: {e}");
                ExitCode::FAILURE
            }
        },
        Err(_) => bisect(&args),
    }
}

/// Runs the command on a thread with a `bytes` stack (and rayon's workers on the same).
fn run_on_stack(bytes: usize, args: Vec<String>) -> ExitCode {
    let built = rayon::ThreadPoolBuilder::new().stack_size(bytes).build_global();
    if let Err(e) = built {
        eprintln!("rayon pool: {e}");
        return ExitCode::FAILURE;
    }
    let argv = std::iter::once("aeroident".to_string()).chain(args);
    let cli = aeroident::cli::Cli::try_parse_args(argv).unwrap_or_else(|e| e.exit());
    let worker = std::thread::Builder::new().stack_size(bytes).spawn(move || cli.execute());
    match worker.map(|w| w.join()) {
        Ok(Ok(Ok(()))) => ExitCode::SUCCESS,
        Ok(Ok(Err(e))) => {
            eprintln!("error: {}", aeroident::cli::error_chain(&e));
            ExitCode::from(2)
        }
        _ => ExitCode::from(3),
    }
}

/// Whether the command finishes on a `bytes` stack; `None` when it fails otherwise than by
/// the stack (an error of the command itself: bisecting would be meaningless).
fn fits(bytes: usize, args: &[String]) -> Option<bool> {
    let exe = std::env::current_exe().ok()?;
    let status = Command::new(exe)
        .args(args)
        .env("STACK_NEED_BYTES", bytes.to_string())
        // Threads the command spawns without a stack size get the same stack.
        .env("RUST_MIN_STACK", bytes.to_string())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .ok()?;
    match status.code() {
        Some(0) => Some(true),
        // Killed by a signal (SIGSEGV on the guard page, SIGABRT from the overflow handler).
        None => Some(false),
        Some(_) => None,
    }
}

fn bisect(args: &[String]) -> ExitCode {
    let (mut lo, mut hi) = (GRANULE, 256usize << 20);
    match fits(hi, args) {
        Some(true) => {}
        _ => {
            eprintln!("the command fails on a {hi}-byte stack: run it with STACK_NEED_BYTES={hi}");
            return ExitCode::FAILURE;
        }
    }
    while hi - lo > GRANULE {
        let mid = (lo + hi) / 2 / GRANULE * GRANULE;
        match fits(mid, args) {
            Some(true) => hi = mid,
            Some(false) => lo = mid,
            None => {
                eprintln!("the command failed on a {mid}-byte stack without overflowing it");
                return ExitCode::FAILURE;
            }
        }
    }
    println!("stack need: {hi} bytes ({:.2} MiB)", hi as f64 / (1 << 20) as f64);
    ExitCode::SUCCESS
}
