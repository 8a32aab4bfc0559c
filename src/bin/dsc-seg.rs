//! The `dsc-seg` command line.
fn main() {}
