//! The `umbra` binary: `umbra render` for one case at a desk, `umbra conformance` for CI.

use std::process::ExitCode;

use umbra_runner::{conformance, render_cmd};

fn main() -> ExitCode {
    quiet_on_closed_pipe();
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let code = match argv.first().map(String::as_str) {
        Some("render") => render_cmd::main(&argv[1..]),
        Some("conformance") => conformance::main(&argv[1..]),
        Some("worker") => umbra_runner::worker::main(&argv[1..]),
        Some("selftest") => umbra_runner::selftest::main(&argv[1..]),
        Some("sweep") => umbra_runner::sweep::main(&argv[1..]),
        Some("drivers") => umbra_runner::drivers::main(&argv[1..]),
        Some("bisect") => umbra_runner::bisect::main(&argv[1..]),
        Some("bisect-step") => umbra_runner::bisect::step(&argv[1..]),
        Some("reduce") => umbra_runner::reduce::main(&argv[1..]),
        Some("-h" | "--help" | "help") => {
            println!(
                "usage:\n  {}\n  {}\n  {}\n  {}\n  {}\n  {}\n  {}",
                render_cmd::USAGE,
                conformance::USAGE,
                umbra_runner::selftest::USAGE,
                umbra_runner::sweep::USAGE,
                umbra_runner::drivers::USAGE,
                umbra_runner::bisect::USAGE,
                umbra_runner::reduce::USAGE
            );
            0
        }
        other => {
            eprintln!(
                "error: {}\nusage:\n  {}\n  {}",
                other.map_or("no command given".to_string(), |c| format!(
                    "unknown command {c:?}"
                )),
                render_cmd::USAGE,
                conformance::USAGE
            );
            2
        }
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
