//! The command line's own tests: every command parses, a value is refused alike everywhere,
//! defaults are the declared ones.

use super::*;
use std::path::Path;

fn argv(words: &[&str]) -> Vec<String> {
    words.iter().map(|s| s.to_string()).collect()
}

#[test]
fn clap_accepts_the_definitions() {
    command().debug_assert();
}

/// `--check`'s help names every check the judge has (it once left out `nan`).
#[test]
fn check_help_names_every_check() {
    for c in umbra_report::check::FIXED {
        assert!(help::CHECK.contains(&c.name()), "--check's help lacks {c}");
    }
    assert!(help::CHECK.contains("twin:NAME"));
}

#[test]
fn flags_reach_the_command_typed() {
    let c = parse(&argv(&[
        "umbra",
        "render",
        "c.json",
        "-o",
        "x",
        "--backend",
        "ref",
    ]));
    let Ok(Command::Render(a)) = c else {
        panic!("render parses: {c:?}");
    };
    assert_eq!(a.positional, Path::new("c.json"));
    assert_eq!(a.out, Path::new("x"));
    assert_eq!(a.backend.as_ref().map(BackendName::as_str), Some("ref"));
}

#[test]
fn shared_groups_are_the_same_flags_everywhere() {
    let c = parse(&argv(&[
        "umbra",
        "soak",
        "--jobs",
        "2",
        "--mesa",
        "system",
        "-o",
        "o",
        "--verbose",
    ]));
    let Ok(Command::Soak(a)) = c else {
        panic!("soak parses: {c:?}");
    };
    assert_eq!(a.execution.jobs.map(Jobs::get), Some(2));
    assert_eq!(a.execution.mesa, Some(MesaChoice::System));
    let e = parse(&argv(&["umbra", "conformance", "--mesa", ""]))
        .expect_err("an empty --mesa is refused")
        .to_string();
    assert!(e.contains("invalid value '' for '--mesa"), "{e}");
    assert_eq!(a.output.out.as_deref(), Some(Path::new("o")));
    assert!(a.output.verbose);
}

#[test]
fn selftest_modes_are_named_or_spelt_as_before() {
    for (words, mode) in [
        (&["umbra", "selftest"][..], SelftestMode::Faults),
        (
            &["umbra", "selftest", "thresholds", "--backend", "ref"][..],
            SelftestMode::Thresholds,
        ),
        (
            &["umbra", "selftest", "--orientations"][..],
            SelftestMode::Orientations,
        ),
    ] {
        let Ok(Command::Selftest(a)) = parse(&argv(words)) else {
            panic!("{words:?} parses");
        };
        assert_eq!(a.mode(), mode, "{words:?}");
    }
}

/// A bad number is refused by clap, the same way whichever command takes the flag, and
/// each command's help states the default it uses (selftest's --timeout once said 300 and
/// ran 120; `--timeout 10s` once ran with the default without a word).
#[test]
fn values_are_refused_alike_and_defaults_are_the_declared_ones() {
    for words in [
        &["umbra", "conformance", "--timeout", "ten"][..],
        &["umbra", "selftest", "--timeout", "ten"],
        &["umbra", "soak", "--timeout", "ten"],
        &["umbra", "sweep", "--timeout", "ten"],
        &["umbra", "card", "--timeout", "ten"],
        &[
            "umbra",
            "reduce",
            "c.json",
            "--point",
            "p",
            "--backend",
            "gl33/llvmpipe",
            "--timeout",
            "ten",
        ],
        &[
            "umbra",
            "drivers",
            "--baseline",
            "a",
            "--candidate",
            "b",
            "--timeout",
            "ten",
        ],
    ] {
        let e = parse(&argv(words)).expect_err("refused").to_string();
        assert!(
            e.contains("invalid value 'ten' for '--timeout <SECS>'")
                && e.contains("give whole seconds"),
            "{words:?}: {e}"
        );
    }
    // A backend name is refused alike by every command that takes one; a device id's
    // form and the aliases pass (whether this machine has the device is for the run).
    for command in [
        "conformance",
        "selftest",
        "soak",
        "sweep",
        "card",
        "render",
        "bisect",
    ] {
        let e = parse(&argv(&["umbra", command, "--backend", "vulkan/nvidia"]))
            .expect_err("refused")
            .to_string();
        assert!(
            e.contains("invalid value 'vulkan/nvidia' for '--backend <ID>': unknown backend"),
            "{command}: {e}"
        );
    }
    for name in ["gl33/radeonsi", "wgpu-vk/radv", "hw", "all", "gles2/zink"] {
        assert!(
            name.parse::<BackendName>().is_ok(),
            "{name} is refused by clap"
        );
    }
    let timeout = |words: &[&str]| match parse(&argv(words)) {
        Ok(Command::Conformance(a)) => a.execution.timeout,
        Ok(Command::Selftest(a)) => a.execution.timeout,
        Ok(Command::Sweep(a)) => a.timeout,
        Ok(Command::Card(a)) => a.timeout,
        other => panic!("{words:?}: {other:?}"),
    };
    assert_eq!(timeout(&["umbra", "conformance"]), Seconds(300));
    assert_eq!(timeout(&["umbra", "selftest"]), Seconds(120));
    assert_eq!(
        timeout(&["umbra", "selftest", "--timeout", "10s"]),
        Seconds(10)
    );
    assert_eq!(timeout(&["umbra", "sweep"]), Seconds(600));
    assert_eq!(timeout(&["umbra", "card"]), Seconds(300));
    let mut root = command();
    root.build();
    for (name, default) in [
        ("conformance", "300"),
        ("selftest", "120"),
        ("sweep", "600"),
    ] {
        let help = root
            .find_subcommand_mut(name)
            .expect("a command")
            .render_help()
            .to_string();
        assert!(
            help.contains(&format!("[default: {default}]")),
            "{name}'s help: {help}"
        );
    }
    for words in [
        &["umbra", "conformance", "--jobs", "0"][..],
        &["umbra", "soak", "--jobs", "0"],
        &["umbra", "selftest", "--jobs", "0"],
    ] {
        let e = parse(&argv(words)).expect_err("refused").to_string();
        assert!(e.contains("at least one worker"), "{words:?}: {e}");
    }
    let e = parse(&argv(&["umbra", "conformance", "--shard", "4/4"]))
        .expect_err("refused")
        .to_string();
    assert!(e.contains("0 ≤ I < N"), "{e}");
}

#[test]
fn an_unknown_flag_is_named() {
    let e = parse(&argv(&["umbra", "conformance", "--filtre", "x"]))
        .expect_err("unknown flag")
        .to_string();
    assert!(e.contains("--filtre") && e.contains("--filter"), "{e}");
}
