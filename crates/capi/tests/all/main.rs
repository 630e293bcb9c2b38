//! The C ABI's integration tests: one test binary, each file of this directory a module of it
//! (a file of its own under `tests/` would be a binary of its own, compiled and linked
//! separately). A new test file is added here with `mod <name>;`. `no_alloc`'s counting global
//! allocator is the whole binary's; it counts only on the thread that turns counting on.

mod common;

mod api;
mod c_replay_hfb320;
mod header;
mod no_alloc;
