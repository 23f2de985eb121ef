use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = prism::app::Cli::parse();
    match prism::app::run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
