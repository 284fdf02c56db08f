pub fn run(_s: Option<std::path::PathBuf>, _a: crate::cli::AppArgs) -> anyhow::Result<()> { anyhow::bail!("todo") }
