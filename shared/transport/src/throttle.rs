//! Refusal logging that a flood cannot turn into a flood of log lines.
//!
//! The first refusal from a source in a window is logged at once; the rest are counted and summed up
//! when the window closes, in at most a bounded number of lines.

use std::collections::HashMap;
use std::fmt::Display;
use std::net::{IpAddr, SocketAddr};

/// Seconds per window.
pub const WINDOW_S: f64 = 10.0;
/// Lines logged per window at most (the rest go into one summary line).
pub const LINES_PER_WINDOW: usize = 20;
/// Sources remembered per window; further ones are only counted.
const SOURCES_PER_WINDOW: usize = 1024;

#[derive(Debug, Default)]
struct Source {
    suppressed: u64,
    last: String,
}

/// Logs refusals with their peer address, throttled per source.
#[derive(Debug)]
pub struct RefusalLog {
    target: &'static str,
    what: &'static str,
    window_start_s: f64,
    lines: usize,
    sources: HashMap<IpAddr, Source>,
    unlisted: u64,
}

impl RefusalLog {
    /// Lines go to log target `target`; `what` names the refusing part in each ("UDP intake").
    pub fn new(target: &'static str, what: &'static str) -> Self {
        Self { target, what, window_start_s: 0.0, lines: 0, sources: HashMap::new(), unlisted: 0 }
    }

    /// Records one refusal of something from `peer` at `now_s`.
    pub fn refused(&mut self, peer: SocketAddr, reason: &dyn Display, now_s: f64) {
        self.roll(now_s);
        let known = self.sources.contains_key(&peer.ip());
        if !known && self.sources.len() >= SOURCES_PER_WINDOW {
            self.unlisted += 1;
            return;
        }
        let source = self.sources.entry(peer.ip()).or_default();
        if !known && self.lines < LINES_PER_WINDOW {
            self.lines += 1;
            log::warn!(target: self.target, "{}: refused {peer}: {reason}", self.what);
        } else {
            source.suppressed += 1;
            source.last = reason.to_string();
        }
    }

    /// Closes the window if it is over, summing up what was not logged.
    pub fn roll(&mut self, now_s: f64) {
        if now_s - self.window_start_s < WINDOW_S {
            return;
        }
        let mut quiet: u64 = 0;
        let mut lines = 0;
        for (ip, s) in self.sources.drain() {
            if s.suppressed == 0 {
                continue;
            }
            if lines < LINES_PER_WINDOW {
                lines += 1;
                log::warn!(
                    target: self.target,
                    "{}: refused {} more from {ip} in {WINDOW_S} s (last: {})",
                    self.what,
                    s.suppressed,
                    s.last
                );
            } else {
                quiet += s.suppressed;
            }
        }
        quiet += self.unlisted;
        if quiet > 0 {
            log::warn!(target: self.target, "{}: refused {quiet} more from other addresses in {WINDOW_S} s", self.what);
        }
        self.window_start_s = now_s;
        self.lines = 0;
        self.unlisted = 0;
    }
}
