//! The `handeye` command-line tool.
fn main() {}
