//! What a robot's own software gets by depending on the runtime: none of
//! the simulator's physics, the link's zenoh, the command line's terminal
//! or the plots — `cargo tree` of its normal dependencies says so.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::process::Command;

/// Crates the runtime must never pull in, with why.
const KEPT_OUT: [(&str, &str); 7] = [
    ("rapier3d", "the simulator's physics"),
    ("parry3d", "the simulator's geometry"),
    ("zenoh", "the link"),
    ("plotters", "plots"),
    ("resvg", "pictures"),
    ("clap", "the command line"),
    ("mcap", "recordings"),
];

#[test]
fn the_runtime_depends_on_no_simulator_link_terminal_or_plots() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned());
    let out = Command::new(cargo)
        .args([
            "tree",
            "-p",
            "stucco-runtime",
            "-e",
            "normal",
            "--prefix",
            "none",
        ])
        .args(["--format", "{p}"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "cargo tree: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let tree = String::from_utf8(out.stdout).unwrap();
    let names: Vec<&str> = tree
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    // The tree is the runtime's (its own crates listed).
    assert_eq!(names.first(), Some(&"stucco-runtime"), "{tree}");
    assert!(names.contains(&"stucco-mission"), "{tree}");
    for (name, what) in KEPT_OUT {
        assert!(
            !names.contains(&name),
            "stucco-runtime pulls in {name} ({what}):\n{tree}"
        );
    }
}
