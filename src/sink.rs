//! Where `gap` and `fit` say what they find out on the way (warnings, notes, replay progress):
//! stderr for the CLI ([`Stderr`]), nowhere for the Python API ([`Silent`]: every warning and
//! note is also in the result's `warnings` / `notes`).

pub trait Sink: Sync {
    /// Something the user should act on (`modellint: warning: …`).
    fn warning(&self, msg: &str);
    /// The record of a decision or a fact found (`modellint: note: …`); `--quiet` hides it.
    fn note(&self, msg: &str);
    /// A note `--quiet` does not hide (what was written where).
    fn note_always(&self, msg: &str);
    /// A message of its own (`modellint: …`), never hidden: e.g. "report written to …".
    fn said(&self, msg: &str);
    /// `k` of `total` episodes replayed (`gap`).
    fn replayed(&self, _k: usize, _total: usize) {}
    /// The replays of [`Sink::replayed`] are done.
    fn replays_done(&self) {}
}

/// The CLI: everything on stderr; the replay counter only on a terminal.
pub struct Stderr {
    /// `--quiet`: no [`Sink::note`].
    pub quiet: bool,
    /// stderr is a terminal (the replay counter rewrites its line).
    pub tty: bool,
}

impl Stderr {
    pub fn new(quiet: bool) -> Self {
        use std::io::IsTerminal;
        Stderr { quiet, tty: std::io::stderr().is_terminal() }
    }
}

impl Sink for Stderr {
    fn warning(&self, msg: &str) {
        eprintln!("modellint: warning: {msg}");
    }
    fn note(&self, msg: &str) {
        if !self.quiet {
            eprintln!("modellint: note: {msg}");
        }
    }
    fn note_always(&self, msg: &str) {
        eprintln!("modellint: note: {msg}");
    }
    fn said(&self, msg: &str) {
        eprintln!("modellint: {msg}");
    }
    fn replayed(&self, k: usize, total: usize) {
        if self.tty {
            eprint!("\rreplaying {k}/{total}");
        }
    }
    fn replays_done(&self) {
        if self.tty {
            eprintln!();
        }
    }
}

/// Says nothing (the Python API: the result carries the warnings and notes).
pub struct Silent;

impl Sink for Silent {
    fn warning(&self, _: &str) {}
    fn note(&self, _: &str) {}
    fn note_always(&self, _: &str) {}
    fn said(&self, _: &str) {}
}
