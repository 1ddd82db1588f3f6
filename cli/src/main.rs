//! `qrm` — the command line of qrm.
//!
//! Arguments are parsed in two stages: clap turns the command line into raw flags
//! ([`args`]), then each subcommand validates them into a config before any work starts, so
//! a bad flag never leaves half a result behind. The binary stays thin: every algorithm
//! lives in the library crates; this crate formats, writes files and reports errors (each
//! error once, at the top, with its chain).

/// `println!` that returns the write error instead of panicking. A closed pipe (`qrm … | head`)
/// is not an error: the command goes on, writes its files and exits 0; any other error is
/// reported.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        match writeln!(std::io::stdout().lock(), $($arg)*) {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
            other => other,
        }
    }};
}

mod args;
mod binary_cmd;
mod calculus_cmd;
mod calculus_text;
mod convert_cmd;
mod demo_cmd;
mod field_cmd;
mod flags;
mod output;
mod pqrm_cmd;
mod progress;
mod qlink_cmd;
mod reason_cmd;
mod serge_cmd;
mod sim_cmd;
mod study_cmd;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = args::Cli::parse();
    output::install_interrupt_handler();
    let result = match cli.command {
        args::Command::Calculus(cmd) => calculus_cmd::run(cmd),
        args::Command::Pqrm(cmd) => pqrm_cmd::run(cmd),
        args::Command::Map(a) => pqrm_cmd::map(a),
        args::Command::Sim(a) => sim_cmd::run(a),
        args::Command::Convert(a) => convert_cmd::run(a),
        args::Command::Serge(cmd) => serge_cmd::run(cmd),
        args::Command::Qlink(cmd) => qlink_cmd::run(cmd),
        args::Command::Demo(a) => demo_cmd::run(a),
        args::Command::Reason(cmd) => reason_cmd::run(cmd),
        args::Command::Study(cmd) => study_cmd::run(cmd),
        args::Command::NumericFlags => args::numeric_flags()
            .into_iter()
            .try_for_each(|(cmd, flag, kind)| outln!("{cmd}\t{flag}\t{kind}").map_err(Into::into)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader went away (`qrm ... | head`): what it wanted was written; not an error.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
