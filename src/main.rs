use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = prism::app::Cli::parse();
    match prism::app::output::remove_pending_on_interrupt().and_then(|()| prism::app::run(cli)) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
