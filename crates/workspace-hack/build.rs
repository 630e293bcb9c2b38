// Cargo reads a package's build-dependencies only when it has a build script: the host-side
// features of the unified list (proc macros' syn, serde) need one.
fn main() {}
