//! The pilot override from an R/C receiver (S.BUS on the board, a scripted pilot in the SITL).
//!
//! Treated the way PX4 and ArduPilot treat a manual override: a switch on the transmitter hands
//! the vehicle to the pilot, who flies an *assisted* velocity mode (PX4's Position mode /
//! ArduPilot's Loiter: sticks are velocity demands, centred sticks hold), with every limit of
//! the core still enforced (speed, climb/descent, tilt, geofence). While the pilot has the
//! vehicle, the Linux computer's setpoints and mode commands are refused
//! ([`crate::commands::CommandError::PilotOverride`]). The receiver has its own failsafe
//! (ArduPilot's RC failsafe, PX4's `COM_RC_LOSS_T`): a frame flagged failsafe by the receiver,
//! or no frame for [`RX_TIMEOUT_US`], counts as the switch off. When the override ends the core
//! holds where it is; the Linux side must command velocity mode again to resume.
//!
//! Plain struct, no clock: time is an argument, as everywhere in the core.

/// No receiver frame for longer than this → the override is off (receiver failsafe), µs.
pub const RX_TIMEOUT_US: u64 = 500_000;
/// Stick deadband around centre (fraction of full travel); the rest is rescaled to 0..1.
pub const DEADBAND: f32 = 0.05;
/// Yaw rate at full yaw stick, rad/s (45 °/s; PX4's `MPC_MAN_Y_MAX` defaults to 150 °/s, an
/// octorotor of paper A's size is flown gentler).
pub const MAX_YAW_RATE_RADPS: f32 = core::f32::consts::FRAC_PI_4;

/// Index of each stick in [`PilotInput::sticks`].
pub const ROLL: usize = 0;
pub const PITCH: usize = 1;
pub const THROTTLE: usize = 2;
pub const YAW: usize = 3;

/// One receiver frame as the core sees it.
///
/// `sticks` are `[roll, pitch, throttle, yaw]`, each normalised to −1..1 with 0 at centre
/// (S.BUS 172 → −1, 992 → 0, 1811 → +1 on every channel): roll + = right, pitch + = forward
/// (stick pushed away), throttle + = climb (centred throttle holds altitude, as in PX4's
/// Altitude/Position modes), yaw + = clockwise seen from above (nose right). Values outside
/// −1..1 or not finite are clamped / read as centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PilotInput {
    /// The override switch is on.
    pub override_on: bool,
    /// The receiver flags failsafe or frame lost: the channels are not the pilot's hand.
    pub failsafe: bool,
    pub sticks: [f32; 4],
    /// MCU µs at which the frame arrived.
    pub t_us: u64,
}

impl PilotInput {
    /// Switch off, sticks centred.
    pub const fn off(t_us: u64) -> Self {
        Self {
            override_on: false,
            failsafe: false,
            sticks: [0.0; 4],
            t_us,
        }
    }
}

/// What the sticks ask for, in the heading frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PilotDemand {
    /// Horizontal velocity (forward, right), m/s; `None` = sticks centred → hold position.
    pub vel_fr_mps: Option<[f32; 2]>,
    /// Climb rate (up), m/s; `None` = throttle centred → hold altitude.
    pub climb_mps: Option<f32>,
    /// Yaw rate, rad/s (clockwise from above, i.e. NED yaw increasing).
    pub yaw_rate_radps: f32,
}

/// The receiver state: the last frame and whether the pilot has the vehicle.
#[derive(Clone, Copy, Debug, Default)]
pub struct PilotReceiver {
    last: Option<PilotInput>,
    /// Frames received / flagged failsafe by the receiver / refused as out of order.
    pub frames: u32,
    pub failsafe_frames: u32,
}

/// Deadband, then rescale so the output still reaches ±1 at full deflection.
pub fn shape(x: f32) -> f32 {
    if !x.is_finite() {
        return 0.0;
    }
    let x = fcc_nav::math::clampf(x, -1.0, 1.0);
    let a = fcc_nav::math::fabsf(x);
    if a <= DEADBAND {
        0.0
    } else {
        let s = (a - DEADBAND) / (1.0 - DEADBAND);
        if x > 0.0 {
            s
        } else {
            -s
        }
    }
}

impl PilotReceiver {
    pub const fn new() -> Self {
        Self {
            last: None,
            frames: 0,
            failsafe_frames: 0,
        }
    }

    /// A new receiver frame (any order of calls with `active`; older frames than the last are
    /// ignored).
    pub fn input(&mut self, p: &PilotInput) {
        if self.last.is_some_and(|l| p.t_us < l.t_us) {
            return;
        }
        self.frames = self.frames.wrapping_add(1);
        if p.failsafe {
            self.failsafe_frames = self.failsafe_frames.wrapping_add(1);
        }
        self.last = Some(*p);
    }

    /// The last frame is fresh, not a failsafe frame, and its switch is on.
    pub fn active(&self, now_us: u64) -> bool {
        match self.last {
            Some(p) => {
                p.override_on && !p.failsafe && now_us.saturating_sub(p.t_us) <= RX_TIMEOUT_US
            }
            None => false,
        }
    }

    /// The receiver is in failsafe or silent (whatever the switch was).
    pub fn lost(&self, now_us: u64) -> bool {
        match self.last {
            Some(p) => p.failsafe || now_us.saturating_sub(p.t_us) > RX_TIMEOUT_US,
            None => true,
        }
    }

    /// The sticks as velocity demands under the core's limits (only meaningful when
    /// [`Self::active`]).
    pub fn demand(
        &self,
        max_horiz_mps: f32,
        max_climb_mps: f32,
        max_descent_mps: f32,
    ) -> PilotDemand {
        let s = self.last.map_or([0.0; 4], |p| p.sticks);
        let (fwd, right) = (shape(s[PITCH]), shape(s[ROLL]));
        let vel_fr_mps = if fwd == 0.0 && right == 0.0 {
            None
        } else {
            // Square stick box → circle: the diagonal is no faster than a single axis.
            let n = fcc_nav::math::hypotf(fwd, right).max(1.0);
            Some([max_horiz_mps * fwd / n, max_horiz_mps * right / n])
        };
        let t = shape(s[THROTTLE]);
        let climb_mps = if t == 0.0 {
            None
        } else if t > 0.0 {
            Some(t * max_climb_mps)
        } else {
            Some(t * max_descent_mps)
        };
        PilotDemand {
            vel_fr_mps,
            climb_mps,
            yaw_rate_radps: shape(s[YAW]) * MAX_YAW_RATE_RADPS,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(t_us: u64, on: bool, sticks: [f32; 4]) -> PilotInput {
        PilotInput {
            override_on: on,
            failsafe: false,
            sticks,
            t_us,
        }
    }

    #[test]
    fn switch_failsafe_and_timeout() {
        let mut r = PilotReceiver::new();
        assert!(!r.active(0) && r.lost(0));
        r.input(&input(1_000, true, [0.0; 4]));
        assert!(r.active(1_000) && !r.lost(1_000));
        assert!(r.active(1_000 + RX_TIMEOUT_US));
        assert!(
            !r.active(1_001 + RX_TIMEOUT_US),
            "no frame for > 0.5 s → off"
        );
        assert!(r.lost(1_001 + RX_TIMEOUT_US));
        r.input(&PilotInput {
            failsafe: true,
            ..input(2_000_000, true, [0.0; 4])
        });
        assert!(!r.active(2_000_000), "receiver failsafe → off");
        assert!(r.lost(2_000_000));
        r.input(&input(2_010_000, false, [0.0; 4]));
        assert!(!r.active(2_010_000) && !r.lost(2_010_000));
        // An older frame does not replace a newer one.
        r.input(&input(1_500_000, true, [0.0; 4]));
        assert!(!r.active(2_010_000));
        assert_eq!((r.frames, r.failsafe_frames), (3, 1));
    }

    #[test]
    fn deadband_and_scaling() {
        assert_eq!(shape(0.0), 0.0);
        assert_eq!(shape(DEADBAND), 0.0);
        assert_eq!(shape(-DEADBAND), 0.0);
        assert_eq!(shape(1.0), 1.0);
        assert_eq!(shape(-1.0), -1.0);
        assert_eq!(shape(3.0), 1.0);
        assert_eq!(shape(f32::NAN), 0.0);
        assert!((shape(0.525) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn demand_respects_limits() {
        let mut r = PilotReceiver::new();
        r.input(&input(0, true, [0.0, 1.0, 0.0, 0.0]));
        let d = r.demand(5.0, 2.0, 1.0);
        assert_eq!(d.vel_fr_mps, Some([5.0, 0.0]));
        assert_eq!(d.climb_mps, None);
        assert_eq!(d.yaw_rate_radps, 0.0);
        // Full diagonal: no faster than the limit.
        r.input(&input(1, true, [1.0, 1.0, 1.0, -1.0]));
        let d = r.demand(5.0, 2.0, 1.0);
        let v = d.vel_fr_mps.unwrap();
        assert!((fcc_nav::math::hypotf(v[0], v[1]) - 5.0).abs() < 1e-5);
        assert!(v[0] > 0.0 && v[1] > 0.0);
        assert_eq!(d.climb_mps, Some(2.0));
        assert!((d.yaw_rate_radps + MAX_YAW_RATE_RADPS).abs() < 1e-6);
        // Throttle down uses the descent limit; centred sticks → hold.
        r.input(&input(2, true, [0.02, -0.03, -1.0, 0.0]));
        let d = r.demand(5.0, 2.0, 1.0);
        assert_eq!(d.vel_fr_mps, None);
        assert_eq!(d.climb_mps, Some(-1.0));
    }
}
