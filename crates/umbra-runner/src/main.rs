//! The `umbra` binary: `umbra render` for one case at a desk, `umbra conformance` for CI, and
//! the tools around them. The command line is parsed in [`umbra_runner::cli`]; each command is
//! a library function of [`umbra_runner::commands`] (the worker, of the harness).

use std::process::ExitCode;

use umbra_runner::cli::{self, Command};
use umbra_runner::commands::{
    backends, bisect, card, conformance, deqp, drivers, merge, reduce, render, repro, selftest,
    soak, sweep, tier, timing,
};
use umbra_runner::exit::{self, Error, Exit};
use umbra_runner::harness;

fn main() -> ExitCode {
    quiet_on_closed_pipe();
    match umbra_case::fault::Fault::check_env() {
        Err(e) => return ExitCode::from(Error::new(e.to_string()).report().code()),
        Ok(Some(warning)) => eprintln!("warning: {warning}"),
        Ok(None) => {}
    }
    if let Err(e) = harness::memory_limit::check_env() {
        return ExitCode::from(Error::new(e).report().code());
    }
    let argv: Vec<String> = std::env::args().collect();
    // dEQP's protocol (deqp-runner): its `--deqp-*=V` flags are not umbra's to parse.
    if argv.get(1).is_some_and(|a| a == "deqp") {
        return ExitCode::from(exit::code(deqp::main(&argv[2..])));
    }
    let command = match cli::parse(&argv) {
        Ok(c) => c,
        Err(e) => {
            let usage_error = e.use_stderr();
            let _ = e.print();
            let exit = if usage_error {
                Exit::CouldNotRun
            } else {
                Exit::Pass
            };
            return ExitCode::from(exit.code());
        }
    };
    // An interrupt is 130 for every command; conformance and soak then install their own
    // orderly stop over this. A worker is stopped by its parent, and keeps the default.
    if !matches!(command, Command::Worker(_)) {
        harness::interrupt::exit_on_signal();
    }
    // A panic is umbra's own bug: the hook has printed it; the process exits 125 (could
    // not run), never Rust's 101, which `git bisect run` would read as a bad commit.
    let dispatched = std::panic::catch_unwind(|| dispatch(&command));
    let outcome = dispatched.unwrap_or_else(|_| {
        Err(Error::new(
            "umbra stopped on an internal error (the panic above is a bug in umbra; please report it with the command line)",
        ))
    });
    ExitCode::from(exit::code(outcome))
}

/// Runs one parsed command.
fn dispatch(command: &Command) -> exit::Outcome {
    match command {
        Command::Render(a) => render::main(a),
        Command::Conformance(a) => conformance::main(a),
        Command::Merge(a) => merge::main(a),
        Command::Selftest(a) => selftest::main(a),
        Command::Soak(a) => soak::main(a),
        Command::Sweep(a) => sweep::main(a),
        Command::Drivers(a) => drivers::main(a),
        Command::Bisect(a) => bisect::main(a),
        Command::Reduce(a) => reduce::main(a),
        Command::Tier(a) => tier::main(a),
        Command::Timing(a) => timing::main(a),
        Command::Repro(a) => repro::main(a),
        Command::Card(a) => card::main(a),
        Command::Backends(a) => backends::main(a),
        Command::Worker(a) => harness::worker::main(&a.backend),
        Command::BisectStep(a) => bisect::step(a),
        Command::Completions(a) => cli::completions(a),
    }
}

/// `umbra render CASE | head -1`: when the reader of stdout goes away, stop quietly (exit 0,
/// as ripgrep does) instead of panicking in `println!`. Any other panic keeps the default
/// report.
fn quiet_on_closed_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.starts_with("failed printing to stdout") && msg.contains("Broken pipe") {
            std::process::exit(0);
        }
        default(info);
    }));
}
