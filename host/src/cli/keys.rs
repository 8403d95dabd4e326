//! Keys during `upload` when stdin is a terminal: space holds and
//! resumes, `+`/`-` change the feed override in 10 % steps, `s` or Ctrl-C
//! stop along the path, a second Ctrl-C quick-stops. The terminal is put in
//! non-canonical mode without echo or signals (so Ctrl-C arrives as a
//! key, not SIGINT) and restored when the keys are dropped. When stdin is
//! not a terminal (or the process is in the background) there are no keys
//! and Ctrl-C kills the process as before.

use std::io::IsTerminal;

use triquint_link::Feed;

/// One override step (per mille).
const STEP: u16 = 100;

/// The terminal in key mode; restored on drop.
pub struct Keys {
    saved: libc::termios,
    /// Hold requested (space toggles).
    held: bool,
    /// The override asked for (per mille).
    pub override_pm: u16,
    /// Ctrl-C and `s` presses that stopped.
    stops: u32,
    /// The drives' override as last learnt from the session.
    learnt: Option<u32>,
}

impl Keys {
    /// Key mode if stdin is a terminal, else `None`.
    pub fn open(override_pm: u16) -> Option<Self> {
        if !std::io::stdin().is_terminal() {
            return None;
        }
        // In the background (`upload … &`) reading or setting the terminal
        // would stop the process (SIGTTIN, SIGTTOU): no keys there.
        // SAFETY: plain queries of this process and fd 0.
        if unsafe { libc::tcgetpgrp(0) != libc::getpgrp() } {
            return None;
        }
        // SAFETY: termios is plain data; tcgetattr fills it for fd 0.
        let mut saved: libc::termios = unsafe { std::mem::zeroed() };
        if unsafe { libc::tcgetattr(0, &mut saved) } != 0 {
            return None;
        }
        let mut raw = saved;
        raw.c_lflag &= !(libc::ICANON | libc::ECHO | libc::ISIG);
        // Reads return at once, with or without a key.
        raw.c_cc[libc::VMIN] = 0;
        raw.c_cc[libc::VTIME] = 0;
        // SAFETY: fd 0 is a terminal; `raw` is a valid termios.
        if unsafe { libc::tcsetattr(0, libc::TCSANOW, &raw) } != 0 {
            return None;
        }
        Some(Self {
            saved,
            held: false,
            override_pm,
            stops: 0,
            learnt: None,
        })
    }

    /// The override the drives hold, as the session knows it (`None`: not
    /// known): `+`/`-` step from it. Taken when it changes, so a key
    /// pressed before its own acknowledgement is not undone by the old value.
    pub fn learn(&mut self, drives_pm: Option<u32>) {
        if drives_pm != self.learnt {
            self.learnt = drives_pm;
            if let Some(pm) = drives_pm.and_then(|pm| u16::try_from(pm).ok()) {
                self.override_pm = pm.max(1);
            }
        }
    }

    /// The commands for the keys pressed since the last call; `cap_pm` is
    /// the configured plan's override cap.
    pub fn poll(&mut self, cap_pm: u16) -> Vec<Feed> {
        let mut buf = [0u8; 16];
        // SAFETY: reading into a local buffer of its length from fd 0.
        let n = unsafe { libc::read(0, buf.as_mut_ptr().cast(), buf.len()) };
        let n = usize::try_from(n).unwrap_or(0);
        buf[..n]
            .iter()
            .filter_map(|k| self.key(*k, cap_pm))
            .collect()
    }

    fn key(&mut self, k: u8, cap_pm: u16) -> Option<Feed> {
        match k {
            b' ' => {
                self.held = !self.held;
                Some(if self.held { Feed::Hold } else { Feed::Resume })
            }
            b'+' | b'=' => {
                self.override_pm = (self.override_pm + STEP).min(cap_pm.max(1000));
                Some(Feed::Override(self.override_pm))
            }
            b'-' | b'_' => {
                self.override_pm = self.override_pm.saturating_sub(STEP).max(STEP);
                Some(Feed::Override(self.override_pm))
            }
            b's' | b'S' | 3 => {
                self.stops += 1;
                // A second Ctrl-C: the quick stop.
                Some(if k == 3 && self.stops > 1 {
                    Feed::QuickStop
                } else {
                    Feed::Stop
                })
            }
            _ => None,
        }
    }

    /// For the progress line.
    pub fn help() -> &'static str {
        "space hold/resume, +/- override, s or Ctrl-C stop"
    }
}

impl Drop for Keys {
    fn drop(&mut self) {
        // SAFETY: restores the settings read in `open`.
        unsafe {
            libc::tcsetattr(0, libc::TCSANOW, &self.saved);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys() -> Keys {
        Keys {
            // SAFETY: plain data, never applied in this test.
            saved: unsafe { std::mem::zeroed() },
            held: false,
            override_pm: 1000,
            stops: 0,
            learnt: None,
        }
    }

    #[test]
    fn each_key_gives_its_command() {
        let mut k = keys();
        let cap = 1177;
        assert_eq!(k.key(b' ', cap), Some(Feed::Hold));
        assert_eq!(k.key(b' ', cap), Some(Feed::Resume));
        assert_eq!(k.key(b'+', cap), Some(Feed::Override(1100)));
        // Not above the cap.
        assert_eq!(k.key(b'+', cap), Some(Feed::Override(1177)));
        assert_eq!(k.key(b'-', cap), Some(Feed::Override(1077)));
        for _ in 0..20 {
            k.key(b'-', cap);
        }
        assert_eq!(k.override_pm, 100, "never below 10 %");
        assert_eq!(k.key(b'x', cap), None);
        assert_eq!(k.key(3, cap), Some(Feed::Stop));
        assert_eq!(k.key(3, cap), Some(Feed::QuickStop));
        // Never dropped for real here: nothing to restore.
        std::mem::forget(k);
    }

    #[test]
    fn override_keys_step_from_the_override_the_drives_hold() {
        let mut k = keys();
        let cap = 1500;
        // Set to 50 % before the upload (another process), learnt at Arm.
        k.learn(Some(500));
        assert_eq!(k.key(b'+', cap), Some(Feed::Override(600)));
        // Pressed again before the drives acknowledged 60 %: the learnt
        // value, unchanged, does not undo it.
        k.learn(Some(500));
        assert_eq!(k.key(b'+', cap), Some(Feed::Override(700)));
        k.learn(Some(700));
        // Changed by another process during the upload.
        k.learn(Some(300));
        assert_eq!(k.key(b'-', cap), Some(Feed::Override(200)));
        // Not known (a drive older than the Arm answer): as it was.
        k.learn(None);
        assert_eq!(k.key(b'+', cap), Some(Feed::Override(300)));
        std::mem::forget(k);
    }
}
