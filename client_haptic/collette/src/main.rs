//! The `collette` command: see `collette --help` and [`collette::cli`].

fn main() -> anyhow::Result<()> {
    // Log lines (none by default) to stderr, chosen with RUST_LOG like every binary of the workspace.
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .try_init();
    collette::cli::run()
}
