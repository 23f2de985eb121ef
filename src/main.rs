use clap::Parser;

fn main() -> std::process::ExitCode {
    // A closed pipe ends the process quietly, as it does other Unix tools (`prism passes | head`),
    // instead of a panic in println!. Outputs are files committed by rename, so nothing is left
    // half-written.
    // SAFETY: called before any other thread exists; SIG_DFL is a valid disposition.
    unsafe { libc::signal(libc::SIGPIPE, libc::SIG_DFL) };
    let cli = prism::app::Cli::parse();
    match prism::app::output::remove_pending_on_interrupt().and_then(|()| prism::app::run(cli)) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
