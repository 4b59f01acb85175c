//! The `umbra` binary: `umbra render` for one case at a desk, `umbra conformance` for CI, and
//! the tools around them. The command line is parsed in [`umbra_runner::cli`]; each command is
//! a library function of [`umbra_runner::commands`] (the worker, of the harness).

use std::process::ExitCode;

use umbra_runner::commands::{
    backends, bisect, conformance, deqp, drivers, merge, reduce, render, repro, selftest_modes,
    soak, sweep,
};
use umbra_runner::{cli, harness};

fn main() -> ExitCode {
    quiet_on_closed_pipe();
    match umbra_case::fault::Fault::check_env() {
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(125);
        }
        Ok(Some(warning)) => eprintln!("warning: {warning}"),
        Ok(None) => {}
    }
    let argv: Vec<String> = std::env::args().collect();
    // dEQP's protocol (deqp-runner): its `--deqp-*=V` flags are not umbra's to parse.
    if argv.get(1).is_some_and(|a| a == "deqp") {
        return ExitCode::from(deqp::main(&argv[2..]).clamp(0, 255) as u8);
    }
    let code = match cli::parse(&argv) {
        Err(e) => {
            let usage_error = e.use_stderr();
            let _ = e.print();
            if usage_error { 125 } else { 0 }
        }
        Ok((name, args)) => match name.as_str() {
            "render" => render::main(&args),
            "conformance" => conformance::main(&args),
            "merge" => merge::main(&args),
            "selftest" => selftest_modes::main(&args),
            "soak" => soak::main(&args),
            "sweep" => sweep::main(&args),
            "drivers" => drivers::main(&args),
            "bisect" => bisect::main(&args),
            "reduce" => reduce::main(&args),
            "repro" => repro::main(&args),
            "backends" => backends::main(&args),
            "worker" => harness::worker::main(&args),
            "bisect-step" => bisect::step(&args),
            "completions" => cli::completions(args.positional.first().map_or("", String::as_str)),
            other => {
                eprintln!("error: command {other:?} is in the command table but not dispatched");
                125
            }
        },
    };
    ExitCode::from(code.clamp(0, 255) as u8)
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
