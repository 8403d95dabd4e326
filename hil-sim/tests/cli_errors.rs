//! Bad input to the built `triquint-sim` binary (the machine and `proxy`):
//! the exit status of the table in docs/cli.md, exactly one stderr line naming
//! what is wrong, no panic.

use std::process::{Command, Stdio};

#[test]
fn bad_input_and_unknown_interfaces_get_one_line_and_their_exit_status() {
    let cases: &[(&[&str], i32, &str)] = &[
        (
            &["--iface", "triquint-nosuch0"],
            4,
            "triquint-nosuch0: cannot open SocketCAN interface",
        ),
        (&["--iface", "vcan0", "--rate", "5"], 2, "--rate"),
        (&["--iface", "vcan0", "--nodes", "1,16"], 2, "--nodes"),
        (
            &[
                "proxy",
                "--a",
                "triquint-nosuch0",
                "--b",
                "triquint-nosuch1",
            ],
            4,
            "triquint-nosuch0: cannot open SocketCAN interface",
        ),
        (
            &["proxy", "--a", "vcan0", "--b", "vcan1", "--loss", "2"],
            2,
            "--loss",
        ),
        (
            &[
                "proxy",
                "--a",
                "vcan0",
                "--b",
                "vcan1",
                "--ids",
                "0x900-0x901",
            ],
            2,
            "--ids",
        ),
    ];
    let mut failures = Vec::new();
    for (args, status, _) in cases {
        // Standard error a pipe whose reader is gone: the status stays.
        let mut reader = Command::new("true").stdin(Stdio::piped()).spawn().unwrap();
        let closed = reader.stdin.take().unwrap();
        reader.wait().unwrap();
        let code = Command::new(env!("CARGO_BIN_EXE_triquint-sim"))
            .args(*args)
            .stderr(Stdio::from(closed))
            .status()
            .unwrap()
            .code();
        if code != Some(*status) {
            failures.push(format!("{args:?} with stderr closed: exit {code:?}"));
        }
    }
    for (args, status, says) in cases {
        let out = Command::new(env!("CARGO_BIN_EXE_triquint-sim"))
            .args(*args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let lines = stderr.lines().filter(|l| !l.trim().is_empty()).count();
        if out.status.code() != Some(*status)
            || lines != 1
            || !stderr.contains(says)
            || stderr.contains("panicked")
        {
            failures.push(format!("{args:?}: exit {:?}: {stderr}", out.status.code()));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}
