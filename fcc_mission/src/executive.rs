//! The mission node's goals, one at a time: a goal starts a [`MissionRun`]; a new goal preempts
//! the running one; cancel ends it and holds the vehicle where it is (the MCU's HOLD mode, sent
//! at the next cycle); each cycle gives what to send, the feedback when due, and the result of
//! a goal that ended. Generic over the goal id (the action's UUID in the node, a number in the
//! tests): pure logic, time passed in, no ROS types.
//!
//! A mission file (`fcc-mission --mission FILE`) is one goal of kind
//! [`RunKind::MissionFile`] started through the same [`Executive::start`].

use crate::run::{Input, MissionRun, Outcome, RunConfig, RunKind, RunProgress, Step};
use crate::Mission;

/// Feedback period (wall clock), s: 4 Hz.
pub const FEEDBACK_PERIOD_S: f64 = 0.25;

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
    /// A cancel asked the MCU to hold: send it at the next cycle (when armed and flying).
    hold_due: bool,
    last_feedback_s: Option<f64>,
}

impl<Id: Clone> Executive<Id> {
    pub fn new(cfg: ExecConfig) -> Self {
        Executive {
            cfg,
            active: None,
            hold_due: false,
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
        self.hold_due = false;
        self.last_feedback_s = None;
        let old = self.active.replace(Active {
            id,
            run,
            started_s: wall_s,
        });
        old.map(|a| Self::finish(a, GoalEnd::Preempted))
    }

    /// Cancels the running goal if it is `id` (the MCU holds from the next cycle).
    pub fn cancel(&mut self, id: &Id) -> Option<Finished<Id>>
    where
        Id: PartialEq,
    {
        if self.active.as_ref()?.id != *id {
            return None;
        }
        self.hold_due = true;
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
            if let (true, Input::Ready(s)) = (self.hold_due, input) {
                self.hold_due = false;
                if s.mcu.armed && !s.mcu.landed && !s.mcu.pilot {
                    out.step.mode_commands.push("hold");
                }
            }
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
}
