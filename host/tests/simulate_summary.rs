//! `triquint simulate`'s summary for people: the bus named once with each
//! bit rate, axes numbered as everywhere else, and the stop ramp called
//! what it is.

mod common;

use std::path::Path;

fn summary(fd: bool) -> String {
    let plan = Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata/hil/paper-case1.json");
    let dir = common::scratch("simulate_summary", if fd { "fd" } else { "classic" });
    let mut args = vec!["simulate", plan.to_str().unwrap()];
    if fd {
        args.push("--fd");
    }
    let (status, out, err) = common::triquint(&dir, &args);
    assert_eq!(status, 0, "{err}");
    out
}

#[test]
fn the_summary_names_the_bus_the_axes_and_the_stop_ramp() {
    let classic = summary(false);
    assert!(
        classic.contains(", classic CAN (1 Mbit/s), 1000 Hz"),
        "{classic}"
    );
    let fd = summary(true);
    assert!(
        fd.contains(", CAN-FD (1 Mbit/s arbitration, 5 Mbit/s data), 1000 Hz"),
        "{fd}"
    );
    for out in [&classic, &fd] {
        assert!(!out.contains("Mbit/s CAN"), "{out}");
        assert!(out.contains("; stop ramp T_s "), "{out}");
        assert!(!out.contains("stop time"), "{out}");
        let rows: Vec<&str> = out
            .lines()
            .skip_while(|l| !l.starts_with("axis "))
            .skip(1)
            .take(3)
            .collect();
        for (i, row) in rows.iter().enumerate() {
            assert!(row.starts_with(&format!("{} ", i + 1)), "{row}");
        }
    }
}
