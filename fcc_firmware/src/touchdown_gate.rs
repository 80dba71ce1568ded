//! Touchdown gate: LAND's last decimetres wait for a lull.
//!
//! Near the ground the gusts keep their strength while the mean wind drops (MIL-F-8785C: σ_u
//! does not shrink with height, the mean follows the log law), and a multirotor answers a gust
//! either by leaning into it (tilt ∝ air-relative speed) or, with its tilt limited, by sliding
//! with it. A touchdown during a gust is therefore tilted or sliding, and a tilted or sliding
//! gear catches a foot. So LAND's final descent stops at [`GATE_CLEARANCE_M`] of gear
//! clearance and holds that height with zero horizontal velocity until the estimate has been
//! calm — tilt ≤ [`CALM_TILT_DEG`] and ground speed ≤ [`CALM_SPEED_MPS`] — for [`CALM_S`];
//! then it commits and descends. A gust that hits the committed descent above
//! [`ABORT_ABOVE_M`] (tilt > [`ABORT_TILT_DEG`] or speed > [`ABORT_SPEED_MPS`]) sends it back
//! to the gate. The longer the wait, the wider every threshold (by its own value per
//! [`RELAX_S`]): the vehicle takes the best lull the wind offers. After [`MAX_WAIT_S`] it
//! commits whatever the wind and is never held again (a vehicle hovering over its landing
//! spot until the battery ends is worse): [`TouchdownGate::forced`] tells.
//!
//! ```text
//!   clearance c = h_agl − h_on_ground;  k = 1 + wait_s / RELAX_S
//!   committed, not forced, c > ABORT_ABOVE, tilt > k·ABORT_TILT or v > k·ABORT_SPEED → waiting
//!   c > GATE or committed:  descend (final speed)
//!   waiting:  hold c = GATE;  wait_s += dt;  calm_s += dt while tilt ≤ k·CALM_TILT and
//!             v ≤ k·CALM_SPEED, else 0
//!   calm_s ≥ CALM_S → committed;  wait_s ≥ MAX_WAIT_S → committed, forced
//! ```
//!
//! Measured on the simulator's truth (504-flight campaign, `fcc-campaign --per-family 72
//! --long`): see BENCHMARKS.md. Pure logic, time passed in (`dt_s`).

/// Gear clearance at which the final descent waits, m (≈ 0.8 s at the final descent speed).
pub const GATE_CLEARANCE_M: f32 = 0.15;
/// Calm: the estimated tilt (from level), deg.
pub const CALM_TILT_DEG: f32 = 2.5;
/// Calm: the estimated horizontal ground speed, m/s.
pub const CALM_SPEED_MPS: f32 = 0.12;
/// Calm for this long commits the touchdown, s.
pub const CALM_S: f32 = 0.2;
/// A committed descent goes back to waiting when a gust hits above this clearance, m…
pub const ABORT_ABOVE_M: f32 = 0.03;
/// … tilting it beyond this, deg, …
pub const ABORT_TILT_DEG: f32 = 4.0;
/// … or pushing it faster than this, m/s.
pub const ABORT_SPEED_MPS: f32 = 0.2;
/// Every threshold widens by its own value per this much waiting, s.
pub const RELAX_S: f32 = 15.0;
/// Longest wait: then the touchdown is committed whatever the wind (and never held again), s.
pub const MAX_WAIT_S: f32 = 30.0;

/// What the final descent does this step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GateAction {
    /// Descend at the final speed.
    Descend,
    /// Hold the gear at [`GATE_CLEARANCE_M`].
    Hold,
}

/// The gate's state for one landing (reset when LAND is entered).
#[derive(Clone, Copy, Debug, Default)]
pub struct TouchdownGate {
    calm_s: f32,
    wait_s: f32,
    committed: bool,
    forced: bool,
}

impl TouchdownGate {
    pub const fn new() -> Self {
        Self {
            calm_s: 0.0,
            wait_s: 0.0,
            committed: false,
            forced: false,
        }
    }

    /// Start a new landing.
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// One step: `clearance_m` of the gear over the ground, the estimated `tilt_rad` from
    /// level and horizontal `speed_mps` over the ground.
    pub fn update(
        &mut self,
        dt_s: f32,
        clearance_m: f32,
        tilt_rad: f32,
        speed_mps: f32,
    ) -> GateAction {
        // The longer the wait, the wider the thresholds: the best lull the wind offers.
        let relax = 1.0 + self.wait_s / RELAX_S;
        if self.committed && !self.forced && clearance_m > ABORT_ABOVE_M {
            let gust = tilt_rad > relax * ABORT_TILT_DEG.to_radians()
                || speed_mps > relax * ABORT_SPEED_MPS;
            if gust {
                self.committed = false;
                self.calm_s = 0.0;
            }
        }
        if self.committed || clearance_m > GATE_CLEARANCE_M {
            return GateAction::Descend;
        }
        let calm =
            tilt_rad <= relax * CALM_TILT_DEG.to_radians() && speed_mps <= relax * CALM_SPEED_MPS;
        self.calm_s = if calm { self.calm_s + dt_s } else { 0.0 };
        self.wait_s += dt_s;
        if self.calm_s >= CALM_S {
            self.committed = true;
        } else if self.wait_s >= MAX_WAIT_S {
            self.committed = true;
            self.forced = true;
        }
        if self.committed {
            GateAction::Descend
        } else {
            GateAction::Hold
        }
    }

    /// Seconds spent waiting at the gate so far.
    pub fn wait_s(&self) -> f32 {
        self.wait_s
    }

    /// The touchdown was committed by the timeout, not by a lull.
    pub fn forced(&self) -> bool {
        self.forced
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    const DT: f32 = 0.002;

    fn run(g: &mut TouchdownGate, s: f32, clearance: f32, tilt_deg: f32, speed: f32) -> GateAction {
        let mut a = GateAction::Hold;
        for _ in 0..(s / DT) as usize {
            a = g.update(DT, clearance, tilt_deg.to_radians(), speed);
        }
        a
    }

    #[test]
    fn descends_above_the_gate() {
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 1.0, 0.5, 10.0, 1.0), GateAction::Descend);
        assert_eq!(g.wait_s(), 0.0);
    }

    #[test]
    fn holds_in_a_gust_and_commits_in_the_lull() {
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 1.0, 0.1, 6.0, 0.1), GateAction::Hold);
        assert_eq!(run(&mut g, 1.0, 0.1, 1.0, 0.4), GateAction::Hold);
        // Calm, but not for long enough: a short dip is not a lull.
        assert_eq!(run(&mut g, 0.1, 0.1, 1.0, 0.05), GateAction::Hold);
        assert_eq!(run(&mut g, 0.1, 0.1, 6.0, 0.05), GateAction::Hold);
        assert_eq!(run(&mut g, 0.25, 0.1, 1.0, 0.05), GateAction::Descend);
        assert!(!g.forced());
        // Committed: the last centimetres are not held again, whatever the gust.
        assert_eq!(run(&mut g, 0.5, 0.02, 8.0, 0.5), GateAction::Descend);
    }

    #[test]
    fn a_gust_on_the_way_down_sends_it_back_to_the_gate() {
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 0.3, 0.1, 1.0, 0.05), GateAction::Descend);
        // Still 6 cm up, pushed at 0.3 m/s: back to waiting.
        assert_eq!(run(&mut g, 0.01, 0.06, 1.0, 0.3), GateAction::Hold);
        assert_eq!(run(&mut g, 0.3, 0.1, 1.0, 0.05), GateAction::Descend);
    }

    #[test]
    fn thresholds_widen_with_the_wait() {
        let mut g = TouchdownGate::new();
        // 4° is not calm for the first 9 s (k·2.5° < 4° while k < 1.6) …
        assert_eq!(run(&mut g, 8.9, 0.1, 4.0, 0.05), GateAction::Hold);
        // … then it is.
        assert_eq!(run(&mut g, 0.5, 0.1, 4.0, 0.05), GateAction::Descend);
        assert!(!g.forced());
    }

    #[test]
    fn commits_after_the_longest_wait() {
        let mut g = TouchdownGate::new();
        assert_eq!(
            run(&mut g, MAX_WAIT_S - 0.1, 0.1, 20.0, 1.5),
            GateAction::Hold
        );
        assert_eq!(run(&mut g, 0.2, 0.1, 20.0, 1.5), GateAction::Descend);
        assert!(g.forced());
        // Forced: no gust sends it back.
        assert_eq!(run(&mut g, 0.2, 0.1, 20.0, 1.5), GateAction::Descend);
        g.reset();
        assert!(!g.forced());
        assert_eq!(run(&mut g, 0.1, 0.1, 20.0, 1.5), GateAction::Hold);
    }
}
