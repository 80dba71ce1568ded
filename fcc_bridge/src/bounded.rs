//! Bounded input and bounded logs (issue 14: hostile or mistaken input never endangers the
//! vehicle, nor the bridge).
//!
//! - [`cap_string`]: incoming ROS strings (`header.frame_id` of a setpoint, the `cmd/mode`
//!   text) are cut to [`MAX_FRAME_ID`] / [`MAX_MODE`] bytes as soon as they arrive, before they
//!   are queued, recorded or looked at; the message is then refused with the original length
//!   (a 1 MB `frame_id` costs one transient copy, never a log line or a diagnostic of that size).
//! - [`log_value`]: how a rejected value appears in a log line, `/rosout` or `/diagnostics`:
//!   at most [`LOG_CHARS`] characters, control and other invisible characters escaped
//!   (`\n`, `\u{1b}`, …), and the size of what was cut.
//! - [`WarnLimiter`]: at most one warning per kind per period (1 s); the next one that gets
//!   through says how many were suppressed meanwhile. Counters still count every event.

use std::collections::HashMap;

/// Longest `header.frame_id` accepted (bytes). ROS frame names are short; tf2 has no limit,
/// but no real frame comes near this.
pub const MAX_FRAME_ID: usize = 256;
/// Longest `cmd/mode` text accepted (bytes).
pub const MAX_MODE: usize = 64;
/// Characters of a rejected value shown in logs.
pub const LOG_CHARS: usize = 64;

/// A string that arrived longer than its limit: which field, and its length in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Oversize {
    pub field: &'static str,
    pub len: usize,
    pub max: usize,
}

impl std::fmt::Display for Oversize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} too long ({} B > {} B)",
            self.field, self.len, self.max
        )
    }
}

/// Cut `s` to at most `max` bytes (at a character boundary) and release the rest of its
/// memory; returns the original length if it was longer.
pub fn cap_string(s: &mut String, max: usize) -> Option<usize> {
    let len = s.len();
    if len <= max {
        return None;
    }
    let mut cut = max;
    while !s.is_char_boundary(cut) {
        cut -= 1;
    }
    s.truncate(cut);
    s.shrink_to_fit();
    Some(len)
}

/// A value for a log line: at most `max_chars` characters, every control or invisible
/// character escaped (as Rust's `escape_debug` does: `\n`, `\t`, `\u{1b}`, …; quotes and
/// backslashes too, so the value cannot fake the end of the quoted field), followed by
/// `… (N B)` with the value's full size when it was cut.
pub fn log_value(s: &str, max_chars: usize) -> String {
    let mut out = String::new();
    for (shown, c) in s.chars().enumerate() {
        if shown == max_chars {
            out.push_str(&format!("… ({} B)", s.len()));
            return out;
        }
        out.extend(c.escape_debug());
    }
    out
}

/// Per-kind rate limit for warnings: [`WarnLimiter::check`] says whether to log now and how
/// many of that kind were suppressed since the last one logged.
#[derive(Debug)]
pub struct WarnLimiter {
    period_ns: i64,
    kinds: HashMap<&'static str, (i64, u64)>,
}

impl Default for WarnLimiter {
    fn default() -> Self {
        Self::new(1_000_000_000)
    }
}

impl WarnLimiter {
    /// At most one warning per kind per `period_ns`.
    pub fn new(period_ns: i64) -> Self {
        WarnLimiter {
            period_ns,
            kinds: HashMap::new(),
        }
    }

    /// A warning of `kind` at `now_ns` (any monotonic-enough clock): `Some(suppressed)` = log
    /// it (noting `suppressed` earlier ones that were not), `None` = suppress it (counted).
    pub fn check(&mut self, kind: &'static str, now_ns: i64) -> Option<u64> {
        match self.kinds.get_mut(kind) {
            None => {
                self.kinds.insert(kind, (now_ns, 0));
                Some(0)
            }
            Some((last, suppressed)) => {
                // A clock that went back starts a new period (never a stuck limiter).
                if now_ns.saturating_sub(*last) >= self.period_ns || now_ns < *last {
                    *last = now_ns;
                    Some(std::mem::take(suppressed))
                } else {
                    *suppressed += 1;
                    None
                }
            }
        }
    }

    /// Suppressed warnings of `kind` not yet reported.
    pub fn pending(&self, kind: &str) -> u64 {
        self.kinds.get(kind).map_or(0, |k| k.1)
    }
}

/// ` (N suppressed)` after a warning that follows suppressed ones, else nothing.
pub fn suppressed_note(n: u64) -> String {
    if n == 0 {
        String::new()
    } else {
        format!(" ({n} suppressed)")
    }
}

/// Log a warning through `limiter` (kind, now): `warn_limited!(lim, "kind", now, "fmt", ..)`.
#[macro_export]
macro_rules! warn_limited {
    ($lim:expr, $kind:expr, $now:expr, $($arg:tt)+) => {
        if let Some(n) = $lim.check($kind, $now) {
            tracing::warn!("{}{}", format_args!($($arg)+), $crate::bounded::suppressed_note(n));
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cap_string_cuts_at_a_char_boundary_and_frees_the_rest() {
        let mut s = "x".repeat(1 << 20);
        assert_eq!(cap_string(&mut s, MAX_FRAME_ID), Some(1 << 20));
        assert_eq!(s.len(), MAX_FRAME_ID);
        assert!(s.capacity() < 1024, "capacity {}", s.capacity());
        let mut short = "map".to_string();
        assert_eq!(cap_string(&mut short, MAX_FRAME_ID), None);
        assert_eq!(short, "map");
        let mut exact = "a".repeat(MAX_FRAME_ID);
        assert_eq!(cap_string(&mut exact, MAX_FRAME_ID), None);
        // 'é' is 2 bytes: a cut in its middle backs off to the boundary.
        let mut u = "aé".repeat(10);
        assert_eq!(cap_string(&mut u, 2), Some(30));
        assert_eq!(u, "a");
    }

    #[test]
    fn log_value_escapes_and_truncates() {
        assert_eq!(log_value("map", 64), "map");
        assert_eq!(
            log_value("a\nb\x1b[31mc\td\0'\"\\", 64),
            "a\\nb\\u{1b}[31mc\\td\\0\\'\\\"\\\\"
        );
        let big = "y".repeat(1 << 20);
        let v = log_value(&big, LOG_CHARS);
        assert_eq!(v, format!("{}… (1048576 B)", "y".repeat(LOG_CHARS)));
        assert!(v.len() < 100);
        // Escapes count as one shown character; multi-byte text is not split.
        let v = log_value(&"é\u{7}".repeat(100), 4);
        assert_eq!(v, "é\\u{7}é\\u{7}… (300 B)");
        assert!(!log_value("\r\n\u{85}\u{2028}", 10).contains(['\r', '\n', '\u{85}', '\u{2028}']));
        assert_eq!(log_value("", 4), "");
        assert_eq!(log_value("abcd", 4), "abcd");
    }

    #[test]
    fn limiter_lets_one_per_second_per_kind_through_and_counts_the_rest() {
        let s = 1_000_000_000i64;
        let mut l = WarnLimiter::default();
        // A flood at 1 kHz for 3 s of one kind, interleaved with a rare other kind.
        let mut logged = Vec::new();
        let mut other = 0;
        for i in 0..3000i64 {
            let t = 10 * s + i * 1_000_000;
            if let Some(n) = l.check("not_finite", t) {
                logged.push((t, n));
            }
            if i % 1000 == 500 && l.check("unknown_frame", t).is_some() {
                other += 1;
            }
        }
        assert_eq!(
            logged,
            vec![(10 * s, 0), (11 * s, 999), (12 * s, 999)],
            "one per second, each with the count suppressed before it"
        );
        assert_eq!(other, 3, "another kind has its own budget");
        assert_eq!(l.pending("not_finite"), 999);
        // After a quiet spell the next one gets through with what was left.
        assert_eq!(l.check("not_finite", 20 * s), Some(999));
        assert_eq!(l.check("not_finite", 20 * s + 1), None);
        // A clock that steps back does not silence the kind for good.
        assert_eq!(l.check("not_finite", 5 * s), Some(1));
    }

    #[test]
    fn oversize_text() {
        let o = Oversize {
            field: "frame_id",
            len: 1 << 20,
            max: MAX_FRAME_ID,
        };
        assert_eq!(o.to_string(), "frame_id too long (1048576 B > 256 B)");
        assert_eq!(suppressed_note(0), "");
        assert_eq!(suppressed_note(7), " (7 suppressed)");
    }
}
