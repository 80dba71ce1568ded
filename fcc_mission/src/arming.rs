//! Arming, as the mission node asks the flight MCU for it.
//!
//! While the [`WaypointFollower`](crate::WaypointFollower) asks to arm (its takeoff phase) and
//! the MCU is not armed, the node sends `cmd/arm` true at most once every [`ARM_RESEND_S`] (the
//! command travels best-effort and the MCU may refuse it, e.g. before its estimator is ready);
//! after more attempts than the arm timeout has seconds, it gives up.
//!
//! Pure logic, time passed in (seconds of the node's wall clock, monotonic).

/// Re-send the arm command after this long, s (wall clock).
pub const ARM_RESEND_S: f64 = 1.0;

/// What to do about arming at one cycle of the node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArmAction {
    /// Nothing to send now (not asked to arm, or the last command is recent).
    Wait,
    /// Send `cmd/arm` true now.
    Send,
    /// The arm timeout is spent: the mission fails.
    GiveUp,
}

/// The arm command's re-sends and timeout: see the [module docs](self).
#[derive(Debug, Clone)]
pub struct ArmRequests {
    timeout_s: f64,
    attempts: u32,
    last_sent_s: Option<f64>,
}

impl ArmRequests {
    /// `timeout_s`: give up after more than this many attempts (one a second: about as many
    /// seconds).
    pub fn new(timeout_s: f64) -> Self {
        ArmRequests {
            timeout_s,
            attempts: 0,
            last_sent_s: None,
        }
    }

    /// Arm commands sent so far.
    pub fn attempts(&self) -> u32 {
        self.attempts
    }

    /// One step while the MCU is not armed: `wall_s` now (s, monotonic), `wants_arm` the
    /// follower asks to arm.
    pub fn update(&mut self, wall_s: f64, wants_arm: bool) -> ArmAction {
        let due = self.last_sent_s.is_none_or(|t| wall_s - t >= ARM_RESEND_S);
        if !wants_arm || !due {
            return ArmAction::Wait;
        }
        if self.attempts as f64 > self.timeout_s {
            return ArmAction::GiveUp;
        }
        self.last_sent_s = Some(wall_s);
        self.attempts += 1;
        ArmAction::Send
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steps at `dt` from 0 for `n` steps; the times at which each action came out.
    fn run(
        a: &mut ArmRequests,
        dt: f64,
        n: usize,
        wants: impl Fn(f64) -> bool,
    ) -> Vec<(f64, ArmAction)> {
        (0..n)
            .map(|k| k as f64 * dt)
            .map(|t| (t, a.update(t, wants(t))))
            .filter(|(_, x)| *x != ArmAction::Wait)
            .collect()
    }

    #[test]
    fn sends_at_once_then_once_a_second() {
        let mut a = ArmRequests::new(60.0);
        let sent = run(&mut a, 0.02, 176, |_| true);
        let times: Vec<f64> = sent.iter().map(|s| s.0).collect();
        assert!(sent.iter().all(|s| s.1 == ArmAction::Send), "{sent:?}");
        assert_eq!(times.len(), 4, "{times:?}");
        for (k, t) in times.iter().enumerate() {
            assert!((t - k as f64).abs() < 0.02 + 1e-9, "{times:?}");
        }
        assert_eq!(a.attempts(), 4);
    }

    #[test]
    fn nothing_is_sent_unless_the_follower_asks() {
        let mut a = ArmRequests::new(60.0);
        assert!(run(&mut a, 0.02, 500, |_| false).is_empty());
        assert_eq!(a.attempts(), 0);
        // Asked from t = 3 s on: the first command goes at once.
        let sent = run(&mut a, 0.02, 200, |t| t >= 3.0);
        assert_eq!(sent.len(), 1, "{sent:?}");
        assert!((sent[0].0 - 3.0).abs() < 0.02 + 1e-9);
    }

    #[test]
    fn gives_up_after_more_attempts_than_the_timeout_has_seconds() {
        let mut a = ArmRequests::new(3.0);
        let out = run(&mut a, 0.1, 100, |_| true);
        let sends = out.iter().filter(|s| s.1 == ArmAction::Send).count();
        assert_eq!(sends, 4, "{out:?}");
        let first_give_up = out
            .iter()
            .find(|s| s.1 == ArmAction::GiveUp)
            .expect("give up");
        assert!((first_give_up.0 - 4.0).abs() < 0.1 + 1e-9, "{out:?}");
        assert_eq!(a.attempts(), 4);
    }
}
