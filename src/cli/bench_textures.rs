//! placeholder, replaced below
#[derive(clap::Args, Debug)]
pub struct BenchTexturesArgs {}
pub fn run(_a: &BenchTexturesArgs) -> Result<(), String> { Ok(()) }
