//! The mission node's goals, one at a time: a goal starts a [`MissionRun`]; a new goal preempts
//! the running one; cancel ends it and holds the vehicle where it is: the MCU's HOLD mode at
//! the next cycle (it brakes at once, harder than velocity mode's 2 m/s² setpoint slew: 0.8 s
//! from 3 m/s through the stack, against 1.5 s for a zero setpoint), then HOLD again once the
//! estimate is still ([`STILL_MPS`], within [`STOP_TIMEOUT_S`]): HOLD keeps the point it is
//! entered at, and entered at speed that is where braking began — the vehicle would fly back
//! to it (2.9 m of drift after a cancel at 3 m/s with one HOLD); the second one holds where it
//! stopped. Each cycle gives what to send, the feedback when due, and the result of a goal that
//! ended. Generic over the goal id (the action's UUID in the node, a number in the
//! tests): pure logic, time passed in, no ROS types.
//!
//! A mission file (`fcc-mission --mission FILE`) is one goal of kind
//! [`RunKind::MissionFile`] started through the same [`Executive::start`].

use crate::run::{Input, MissionRun, Outcome, RunConfig, RunKind, RunProgress, Step};
use crate::Mission;

/// Feedback period (wall clock), s: 4 Hz.
pub const FEEDBACK_PERIOD_S: f64 = 0.25;
/// After a cancel, HOLD is sent again once the estimated speed is at most this, m/s ...
pub const STILL_MPS: f32 = 0.3;
/// ... if that happens within this long (wall clock) after the cancel, s.
pub const STOP_TIMEOUT_S: f64 = 3.0;

/// How a goal ended.
#[derive(Debug, Clone, PartialEq)]
pub enum GoalEnd {
    Succeeded,
    /// The run failed (could not arm, timeout, disarmed in flight) or an MCU failsafe ended it.
    Failsafe(String),
    PilotOverride(String),
    /// A newer goal replaced it.
    Preempted,
    /// Canceled: the vehicle holds.
    Canceled,
}

/// A goal that ended, with the waypoints it reached.
#[derive(Debug, Clone, PartialEq)]
pub struct Finished<Id> {
    pub id: Id,
    pub end: GoalEnd,
    pub reached: usize,
}

/// The settings of every run.
#[derive(Debug, Clone, Copy)]
pub struct ExecConfig {
    pub timeout_s: f64,
    pub arm_timeout_s: f64,
    pub hover_s: f64,
}

/// One cycle's output.
#[derive(Debug, Clone, PartialEq)]
pub struct ExecStep<Id> {
    /// What to send and log (the run's, or the hold after a cancel).
    pub step: Step,
    /// The running goal's progress, when feedback is due.
    pub feedback: Option<(Id, RunProgress)>,
    pub finished: Option<Finished<Id>>,
}

struct Active<Id> {
    id: Id,
    run: MissionRun,
    /// Wall time at the start, s (the run's clock counts from it).
    started_s: f64,
}

/// The goals: see the [module docs](self).
pub struct Executive<Id> {
    cfg: ExecConfig,
    active: Option<Active<Id>>,
    /// Canceled at this wall time: HOLD, and again once still (see the module docs); with
    /// whether the first HOLD went out.
    stopping_since: Option<(f64, bool)>,
    last_feedback_s: Option<f64>,
}

impl<Id: Clone> Executive<Id> {
    pub fn new(cfg: ExecConfig) -> Self {
        Executive {
            cfg,
            active: None,
            stopping_since: None,
            last_feedback_s: None,
        }
    }

    /// The running goal's id.
    pub fn active(&self) -> Option<&Id> {
        self.active.as_ref().map(|a| &a.id)
    }

    fn finish(a: Active<Id>, end: GoalEnd) -> Finished<Id> {
        Finished {
            reached: a.run.progress().map_or(0, |p| p.reached),
            id: a.id,
            end,
        }
    }

    /// Starts a goal (its mission already checked) at wall time `wall_s`; the goal it preempts.
    pub fn start(
        &mut self,
        id: Id,
        mission: Mission,
        kind: RunKind,
        wall_s: f64,
    ) -> Option<Finished<Id>> {
        let run = MissionRun::new(RunConfig {
            mission,
            timeout_s: self.cfg.timeout_s,
            arm_timeout_s: self.cfg.arm_timeout_s,
            hover_s: self.cfg.hover_s,
            kind,
        });
        self.stopping_since = None;
        self.last_feedback_s = None;
        let old = self.active.replace(Active {
            id,
            run,
            started_s: wall_s,
        });
        old.map(|a| Self::finish(a, GoalEnd::Preempted))
    }

    /// Cancels the running goal if it is `id` at wall time `wall_s` (the vehicle brakes from the
    /// next cycle, then holds).
    pub fn cancel(&mut self, id: &Id, wall_s: f64) -> Option<Finished<Id>>
    where
        Id: PartialEq,
    {
        if self.active.as_ref()?.id != *id {
            return None;
        }
        self.stopping_since = Some((wall_s, false));
        self.active
            .take()
            .map(|a| Self::finish(a, GoalEnd::Canceled))
    }

    /// The run published the setpoint of its last step (counted in its final log line).
    pub fn setpoint_published(&mut self) {
        if let Some(a) = self.active.as_mut() {
            a.run.setpoint_published();
        }
    }

    /// One cycle at wall time `wall_s` with what the node heard.
    pub fn tick(&mut self, wall_s: f64, input: Input<'_>) -> ExecStep<Id> {
        let mut out = ExecStep {
            step: Step::default(),
            feedback: None,
            finished: None,
        };
        let Some(a) = self.active.as_mut() else {
            self.stop(wall_s, input, &mut out.step);
            return out;
        };
        out.step = a.run.tick(wall_s - a.started_s, input);
        let due = self
            .last_feedback_s
            .is_none_or(|t| wall_s - t >= FEEDBACK_PERIOD_S);
        if let (true, Some(p)) = (due, a.run.progress()) {
            self.last_feedback_s = Some(wall_s);
            out.feedback = Some((a.id.clone(), p));
        }
        let end = match out.step.outcome.clone() {
            None => return out,
            Some(Outcome::Complete) => GoalEnd::Succeeded,
            Some(Outcome::Failed(m)) | Some(Outcome::Failsafe(m)) => GoalEnd::Failsafe(m),
            Some(Outcome::PilotOverride(m)) => GoalEnd::PilotOverride(m),
        };
        out.finished = self.active.take().map(|a| Self::finish(a, end));
        out
    }

    /// After a cancel: HOLD now, and HOLD again once still (within [`STOP_TIMEOUT_S`]). Not in
    /// the air (disarmed, landed) or with the pilot flying: nothing.
    fn stop(&mut self, wall_s: f64, input: Input<'_>, out: &mut Step) {
        let (Some((since, sent)), Input::Ready(s)) = (self.stopping_since, input) else {
            return;
        };
        if !s.mcu.armed || s.mcu.landed || s.mcu.pilot || wall_s - since > STOP_TIMEOUT_S {
            self.stopping_since = None;
            return;
        }
        if !sent {
            self.stopping_since = Some((since, true));
            out.mode_commands.push("hold");
            return;
        }
        let v = s.vel_ned_mps;
        let speed = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if speed <= STILL_MPS {
            self.stopping_since = None;
            out.logs.push((
                crate::run::Level::Info,
                format!(
                    "canceled: still after {:.2} s ({speed:.2} m/s): holding here (cmd/mode hold again)",
                    wall_s - since
                ),
            ));
            out.mode_commands.push("hold");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::from_yaml_str;
    use crate::run::tests::{Vehicle, DT_S, MISSION};
    use crate::McuMode;

    fn exec() -> Executive<u32> {
        Executive::new(ExecConfig {
            timeout_s: 600.0,
            arm_timeout_s: 60.0,
            hover_s: 0.0,
        })
    }

    fn mission() -> Mission {
        from_yaml_str(MISSION).unwrap()
    }

    /// Runs `n` cycles from `t0`; the steps with their times.
    fn cycles(
        e: &mut Executive<u32>,
        v: &mut Vehicle,
        t0: f64,
        n: usize,
    ) -> Vec<(f64, ExecStep<u32>)> {
        (0..n)
            .map(|k| {
                let t = t0 + k as f64 * DT_S;
                let out = e.tick(t, Input::Ready(v.sample(t)));
                v.apply(&out.step);
                (t, out)
            })
            .collect()
    }

    /// Feedback at 4 Hz while a goal runs; a second goal preempts the first (its result at
    /// once, with the waypoints it reached) and flies on from where the vehicle is.
    #[test]
    fn feedback_and_preemption() {
        let (mut e, mut v) = (exec(), Vehicle::new());
        assert_eq!(e.start(1, mission(), RunKind::ActionGoal, 0.0), None);
        let steps = cycles(&mut e, &mut v, 0.0, 300);
        let fb: Vec<f64> = steps
            .iter()
            .filter(|s| s.1.feedback.is_some())
            .map(|s| s.0)
            .collect();
        assert!(
            fb.windows(2)
                .all(|w| w[1] - w[0] <= FEEDBACK_PERIOD_S + DT_S + 1e-9),
            "{fb:?}"
        );
        assert!(fb.len() >= 20, "{}", fb.len());
        assert!(steps.iter().all(|s| s.1.finished.is_none()));
        assert!(v.armed && !v.landed);
        let old = e.start(2, mission(), RunKind::ActionGoal, 6.0).unwrap();
        assert_eq!((old.id, old.end), (1, GoalEnd::Preempted));
        assert_eq!(e.active(), Some(&2));
        let steps = cycles(&mut e, &mut v, 6.0, 3000);
        let done = steps
            .iter()
            .find_map(|s| s.1.finished.clone())
            .expect("the second goal ends");
        assert_eq!(
            (done.id, done.end, done.reached),
            (2, GoalEnd::Succeeded, 1)
        );
        // In the air already: no second arm command.
        assert!(steps.iter().all(|s| !s.1.step.arm));
    }

    /// Cancel: the result at once; then HOLD at the next cycle and again once still; no
    /// setpoints after it; another id is not canceled.
    #[test]
    fn cancel_holds_twice_and_sends_no_setpoint() {
        let (mut e, mut v) = (exec(), Vehicle::new());
        e.start(7, mission(), RunKind::ActionGoal, 0.0);
        cycles(&mut e, &mut v, 0.0, 250);
        assert_eq!(v.mode, McuMode::Velocity);
        assert_eq!(e.cancel(&8, 5.0), None);
        let f = e.cancel(&7, 5.0).unwrap();
        assert_eq!((f.id, f.end), (7, GoalEnd::Canceled));
        assert_eq!(e.active(), None);
        let steps = cycles(&mut e, &mut v, 5.0, 200);
        let holds: Vec<f64> = steps
            .iter()
            .filter(|s| s.1.step.mode_commands == ["hold"])
            .map(|s| s.0)
            .collect();
        // The test vehicle stops at once in HOLD: still at the next cycle.
        assert_eq!(holds, [5.0, 5.0 + DT_S], "{holds:?}");
        assert!(steps
            .iter()
            .all(|s| s.1.step.setpoint_ned_mps.is_none() && s.1.feedback.is_none()));
        assert_eq!(v.mode, McuMode::Hold);
    }
}
