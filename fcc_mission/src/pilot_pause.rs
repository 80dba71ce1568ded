//! The mission's view of a pilot override (the S.BUS switch on the MCU).
//!
//! While the MCU is in Pilot mode the pilot flies and the MCU refuses the node's setpoints and
//! commands, so the mission pauses and sends none. When the pilot hands back (the MCU holds),
//! the mission resumes from where the vehicle is: `cmd/mode` "velocity", re-sent at most every
//! [`RESUME_RESEND_S`] until the MCU reports velocity mode again (commands travel best-effort).
//! Setpoints flow meanwhile (the MCU holds and keeps them; none is stale on resume).
//!
//! Pure logic, time passed in (seconds of ROS time).

use crate::McuMode;

/// Re-send `cmd/mode` "velocity" after this long without the MCU in velocity mode, s.
pub const RESUME_RESEND_S: f64 = 1.0;

/// Something worth a log line, emitted once when it happens.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PauseEvent {
    /// The pilot took over: the mission is paused, no setpoints. A warning.
    Paused,
    /// The pilot handed back but the MCU is not in velocity mode yet: first resume command.
    Released,
    /// The MCU flies velocity again: the mission goes on.
    Resumed,
}

/// The output of one [`PilotPause::update`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PauseStep {
    /// The pilot flies: send no setpoints and no commands this cycle.
    pub paused: bool,
    /// Publish `cmd/mode` "velocity" now.
    pub send_resume: bool,
    /// Log this.
    pub event: Option<PauseEvent>,
}

/// Pause and resume around a pilot override: see the [module docs](self).
#[derive(Debug, Clone, Default)]
pub struct PilotPause {
    paused: bool,
    last_resume_s: Option<f64>,
}

impl PilotPause {
    pub fn new() -> Self {
        Self::default()
    }

    /// True from the pilot's take-over until the MCU flies velocity again.
    pub fn is_paused(&self) -> bool {
        self.paused
    }

    /// One step, at every cycle of the node once armed: `t_s` now (s), `pilot` the MCU is in
    /// Pilot mode, `mode` its mode otherwise.
    pub fn update(&mut self, t_s: f64, pilot: bool, mode: McuMode) -> PauseStep {
        let mut step = PauseStep {
            paused: false,
            send_resume: false,
            event: None,
        };
        if pilot {
            if !self.paused {
                self.paused = true;
                step.event = Some(PauseEvent::Paused);
            }
            step.paused = true;
            return step;
        }
        if !self.paused {
            return step;
        }
        if mode == McuMode::Velocity {
            self.paused = false;
            self.last_resume_s = None;
            step.event = Some(PauseEvent::Resumed);
        } else if self
            .last_resume_s
            .is_none_or(|t| t_s - t >= RESUME_RESEND_S)
        {
            if self.last_resume_s.is_none() {
                step.event = Some(PauseEvent::Released);
            }
            step.send_resume = true;
            self.last_resume_s = Some(t_s);
        }
        step
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use McuMode::*;

    /// Steps at 20 ms from `t0` for `n` steps with the MCU from `mcu(t)` = (pilot, mode);
    /// returns (t, step) for every step with a resume command or an event.
    fn run(
        p: &mut PilotPause,
        t0: f64,
        n: usize,
        mcu: impl Fn(f64) -> (bool, McuMode),
    ) -> Vec<(f64, PauseStep)> {
        let mut out = Vec::new();
        for k in 0..n {
            let t = t0 + k as f64 * 0.02;
            let (pilot, mode) = mcu(t);
            let s = p.update(t, pilot, mode);
            if s.send_resume || s.event.is_some() {
                out.push((t, s));
            }
        }
        out
    }

    #[test]
    fn no_override_no_pause() {
        let mut p = PilotPause::new();
        assert!(run(&mut p, 0.0, 500, |_| (false, Velocity)).is_empty());
        assert!(
            !p.update(10.0, false, Hold).paused,
            "a HOLD without the pilot is not a pause"
        );
        assert!(!p.is_paused());
    }

    #[test]
    fn pilot_pauses_then_resume_is_sent_each_second_until_velocity() {
        let mut p = PilotPause::new();
        // Pilot from 1 s to 3 s; the MCU then holds until 5.5 s, then flies velocity.
        let mcu = |t: f64| {
            if (1.0..3.0).contains(&t) {
                (true, Disarmed)
            } else if (3.0..5.5).contains(&t) {
                (false, Hold)
            } else {
                (false, Velocity)
            }
        };
        for k in 0..500 {
            let t = k as f64 * 0.02;
            let s = p.update(t, mcu(t).0, mcu(t).1);
            assert_eq!(s.paused, (1.0..3.0).contains(&t), "t {t}");
        }
        let mut p = PilotPause::new();
        let ev = run(&mut p, 0.0, 500, mcu);
        let e: Vec<(f64, Option<PauseEvent>, bool)> = ev
            .iter()
            .map(|(t, s)| (*t, s.event, s.send_resume))
            .collect();
        assert_eq!(e.len(), 5, "{e:?}");
        assert_eq!((e[0].1, e[0].2), (Some(PauseEvent::Paused), false));
        assert!((e[0].0 - 1.0).abs() < 1e-9);
        assert_eq!((e[1].1, e[1].2), (Some(PauseEvent::Released), true));
        assert!((e[1].0 - 3.0).abs() < 1e-9, "{e:?}");
        for (k, x) in e[2..4].iter().enumerate() {
            assert_eq!((x.1, x.2), (None, true), "{e:?}");
            assert!((x.0 - (4.0 + k as f64)).abs() < 0.02 + 1e-9, "{e:?}");
        }
        assert_eq!((e[4].1, e[4].2), (Some(PauseEvent::Resumed), false));
        assert!((e[4].0 - 5.5).abs() < 0.02 + 1e-9, "{e:?}");
        assert!(!p.is_paused());
    }

    #[test]
    fn a_second_override_pauses_again_and_logs_again() {
        let mut p = PilotPause::new();
        // Pilot from 1 to 2 s and from 4 to 5 s; the MCU holds for 0.5 s after each.
        let mcu = |t: f64| {
            let pilot = (1.0..2.0).contains(&t) || (4.0..5.0).contains(&t);
            let holding = (2.0..2.5).contains(&t) || (5.0..5.5).contains(&t);
            let mode = if pilot {
                Disarmed
            } else if holding {
                Hold
            } else {
                Velocity
            };
            (pilot, mode)
        };
        let ev = run(&mut p, 0.0, 400, mcu);
        let events: Vec<PauseEvent> = ev.iter().filter_map(|e| e.1.event).collect();
        use PauseEvent::*;
        assert_eq!(
            events,
            vec![Paused, Released, Resumed, Paused, Released, Resumed]
        );
    }

    #[test]
    fn back_to_the_pilot_before_resuming_keeps_the_resend_timer() {
        // Released (resume sent at 2 s), pilot again at 2.5 s, released at 2.7 s: the next
        // resume waits for the second since the last one, and is not announced again.
        let mut p = PilotPause::new();
        let mcu = |t: f64| ((1.0..2.0).contains(&t) || (2.5..2.7).contains(&t), Hold);
        let ev = run(&mut p, 0.0, 160, mcu);
        let e: Vec<(f64, Option<PauseEvent>, bool)> = ev
            .iter()
            .map(|(t, s)| (*t, s.event, s.send_resume))
            .collect();
        assert_eq!(e.len(), 3, "{e:?}");
        assert_eq!(e[0].1, Some(PauseEvent::Paused));
        assert_eq!((e[1].1, e[1].2), (Some(PauseEvent::Released), true));
        assert_eq!((e[2].1, e[2].2), (None, true));
        assert!((e[2].0 - 3.0).abs() < 0.02 + 1e-9, "{e:?}");
    }
}
