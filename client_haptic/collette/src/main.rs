//! The `collette` command: see `collette --help` and [`collette::cli`].

/// Errors end the program on one line (`error: what: why`), never with a backtrace, even with
/// `RUST_BACKTRACE` set.
fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> anyhow::Result<()> {
    // Log lines (none by default) to stderr, chosen with RUST_LOG like every binary of the workspace.
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .try_init();
    collette::cli::run()
}
