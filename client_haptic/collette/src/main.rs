//! The `collette` command: see `collette --help` and [`collette::cli`].

fn main() -> anyhow::Result<()> {
    collette::cli::run()
}
