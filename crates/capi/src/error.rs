//! Errors across the C boundary: a result code per call ([`AeroidentResult`]) and the last
//! failure's message, per thread, in a fixed buffer ([`aeroident_last_error_message`]).
//!
//! The message is written into a thread-local array with `core::fmt`, never into a `String`,
//! so a refused sample costs no heap allocation either: the allocation-free `update` holds on
//! its error path too.

use core::cell::RefCell;
use core::ffi::c_char;
use core::fmt::Write;

/// What a call did. Every function that can fail returns one; on anything but
/// `AEROIDENT_RESULT_OK`, [`aeroident_last_error_message`] says why.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AeroidentResult {
    /// Success.
    Ok = 0,
    /// A required pointer argument was NULL (the message names it).
    NullPointer = 1,
    /// An argument is not valid: a string that is not UTF-8, an unknown estimator kind, a
    /// presence bit that is not defined.
    InvalidArgument = 2,
    /// The model text is neither a preset name nor a valid model file (the message names the
    /// line and key).
    Model = 3,
    /// The options text is not TOML, or names an option the kind does not take, or a value
    /// out of its domain.
    Option = 4,
    /// The estimator could not be built over the model with the options (e.g. a batch method,
    /// a prior out of range, a structure the EKF cannot integrate).
    Build = 5,
    /// The estimator refused the sample (a channel the model needs is absent, a value is not
    /// finite or not plausible, time did not increase); its state is unchanged.
    SampleRefused = 6,
    /// The estimator diverged; its numbers are no longer a result (reset it).
    Diverged = 7,
    /// A caller buffer is shorter than the number of parameters.
    BufferTooSmall = 8,
    /// An internal error (a bug) was caught at the boundary; a handle it happened in is
    /// unusable from then on (free it).
    Panic = 9,
}

/// Capacity of the message buffer, bytes with the terminating NUL; a longer message is cut at
/// a character boundary and ends in `…`.
pub const AEROIDENT_MESSAGE_CAPACITY: usize = 2048;

/// A message in a fixed buffer, always NUL-terminated.
struct Message {
    buf: [u8; AEROIDENT_MESSAGE_CAPACITY],
    len: usize,
    truncated: bool,
}

impl Message {
    const fn new() -> Self {
        Self { buf: [0; AEROIDENT_MESSAGE_CAPACITY], len: 0, truncated: false }
    }

    fn clear(&mut self) {
        self.len = 0;
        self.truncated = false;
        self.buf[0] = 0;
    }
}

/// Room for the `…` (3 bytes) and the NUL.
const RESERVE: usize = 4;

impl Write for Message {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        if self.truncated {
            return Ok(());
        }
        let room = AEROIDENT_MESSAGE_CAPACITY - RESERVE - self.len;
        let take = if s.len() <= room {
            s.len()
        } else {
            self.truncated = true;
            (0..=room).rev().find(|&k| s.is_char_boundary(k)).unwrap_or(0)
        };
        self.buf[self.len..self.len + take].copy_from_slice(&s.as_bytes()[..take]);
        self.len += take;
        if self.truncated {
            self.buf[self.len..self.len + 3].copy_from_slice("…".as_bytes());
            self.len += 3;
        }
        self.buf[self.len] = 0;
        Ok(())
    }
}

thread_local! {
    // Const-initialised and without a destructor: no allocation on first use.
    static LAST_ERROR: RefCell<Message> = const { RefCell::new(Message::new()) };
}

/// Clears this thread's message (a call starts).
pub(crate) fn clear() {
    LAST_ERROR.with(|m| m.borrow_mut().clear());
}

/// Sets this thread's message to `args` and returns `code`.
pub(crate) fn fail(code: AeroidentResult, args: core::fmt::Arguments<'_>) -> AeroidentResult {
    LAST_ERROR.with(|m| {
        let mut m = m.borrow_mut();
        m.clear();
        // Writing into the fixed buffer cannot fail (it truncates).
        let _ = m.write_fmt(args);
    });
    code
}

/// The message of the last call on this thread that did not return `AEROIDENT_RESULT_OK`:
/// what was wrong, naming the argument, option, model line or sample field. Empty (`""`) after
/// a call that succeeded. Never NULL; UTF-8, NUL-terminated, at most 2047 bytes. The pointer
/// stays valid for the life of the thread, the text until the next `aeroident_*` call on this
/// thread: copy it to keep it.
#[unsafe(no_mangle)]
pub extern "C" fn aeroident_last_error_message() -> *const c_char {
    LAST_ERROR.with(|m| m.borrow().buf.as_ptr().cast())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text() -> String {
        LAST_ERROR.with(|m| {
            let m = m.borrow();
            assert_eq!(m.buf[m.len], 0, "NUL-terminated");
            String::from_utf8(m.buf[..m.len].to_vec()).unwrap()
        })
    }

    /// A message longer than the buffer is cut at a character boundary (never inside the
    /// multi-byte `σ`), ends in `…` and stays NUL-terminated; a short one is kept whole.
    #[test]
    fn long_messages_are_cut_at_a_character_boundary() {
        fail(AeroidentResult::Model, format_args!("short: {}", 42));
        assert_eq!(text(), "short: 42");
        let long = "σ".repeat(AEROIDENT_MESSAGE_CAPACITY);
        fail(AeroidentResult::Model, format_args!("x{long}"));
        let t = text();
        assert!(t.ends_with('…') && t.starts_with("xσσ"), "{t}");
        assert!(
            t.len() < AEROIDENT_MESSAGE_CAPACITY && t.len() > AEROIDENT_MESSAGE_CAPACITY - 8,
            "{}",
            t.len()
        );
        assert_eq!(t.chars().filter(|c| *c == 'σ').count(), (t.len() - 1 - 3) / 2);
        clear();
        assert_eq!(text(), "");
    }
}
