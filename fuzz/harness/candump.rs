// Shared by the `candump` fuzz target and host/tests/fuzz_candump_corpus.rs
// (via include!): any bytes as a `candump -L` log, as `triquint monitor
// --web --replay` reads one. The includer brings `candump` into scope: the
// host's module (the test) or the same file by path (the fuzz crate, which
// does not build the whole CLI for one parser).

/// Runs one fuzz input: `parse_log` accepts a text exactly when every
/// non-blank line is a frame; its frames come in time order from 0; each
/// frame, written back as a log line, reads back the same.
pub fn fuzz_candump(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let lines: Vec<_> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(candump::parse_line)
        .collect();
    match candump::parse_log(text) {
        Ok(frames) => {
            assert!(lines.iter().all(Option::is_some));
            assert_eq!(frames.len(), lines.len());
            assert_eq!(frames[0].t_us, 0);
            assert!(frames.windows(2).all(|w| w[0].t_us <= w[1].t_us));
        }
        Err(e) => {
            assert!(!e.contains('\n'), "multi-line message {e:?}");
            assert!(lines.is_empty() || lines.iter().any(Option::is_none), "{e}");
        }
    }
    for l in lines.into_iter().flatten() {
        let f = &l.frame;
        assert!(f.id <= 0x7FF && (f.fd || f.len <= 8), "{f:?}");
        let hex: String = f.payload().iter().map(|b| format!("{b:02X}")).collect();
        let sep = if f.fd { "##0" } else { "#" };
        let again = format!(
            "({}.{:06}) vcan0 {:03X}{sep}{hex}",
            l.t_us / 1_000_000,
            l.t_us % 1_000_000,
            f.id
        );
        assert_eq!(candump::parse_line(&again), Some(l), "{again}");
    }
}
