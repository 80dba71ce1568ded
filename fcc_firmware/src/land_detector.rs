//! Land detector: is the vehicle on the ground or in the air? Decided from several signals with
//! hysteresis, never from the estimated altitude alone (PX4's `MulticopterLandDetector` is the
//! model: ground contact → maybe landed → landed, each held for a while).
//!
//! Signals (all from the flight core's own sensors):
//! - collective thrust `T` against the hover thrust `T_h = m·g`: a vehicle resting on its gear
//!   needs `T < k·T_h` (the gear carries the rest);
//! - vertical speed `v_z` (relative to the ground where the rangefinders see it): ≈ 0;
//! - height above ground `h` from paper B's fusion when it is usable: within
//!   [`CONTACT_MARGIN_M`] of the sensors' height standing on the gear; without a usable
//!   rangefinder the barometric height above the take-off point stands in;
//! - body rates `|ω|`: quiet (a vehicle sliding or tipping on its gear rotates);
//! - the controller is asking to go down (a land, or a descent command): resting on the
//!   ground while climbing is impossible.
//!
//! ```text
//!   Airborne ──(contact held CONTACT_S)──► GroundContact ──(landed held `landed_s`)──► Landed
//!      ▲                                        │                                       │
//!      └───────────────(any signal fails)───────┘◄──────── climb commanded ─────────────┘
//! ```
//! Only `Landed` turns the attitude and horizontal loops off; `GroundContact` still flies.

/// Above the sensors' height when standing on the gear, this margin (m) still counts as
/// touching the ground (gear compression, rangefinder noise of a few cm).
pub const CONTACT_MARGIN_M: f32 = 0.1;
/// |v_z| below this (m/s) counts as not moving vertically.
const STILL_VZ_MPS: f32 = 0.25;
/// Body rates below this (rad/s) count as quiet (30 °/s: a tipping vehicle rotates faster).
const QUIET_RATE_RADPS: f32 = 0.5;
/// Thrust below this fraction of hover while near the ground (the gear carries weight).
const NEAR_GROUND_THRUST_FRAC: f32 = 0.9;
/// Thrust below this fraction of hover when the height signal is not near the ground (a
/// rangefinder blocked, a baro offset): the thrust must have wound down further.
const FAR_THRUST_FRAC: f32 = 0.8;
/// Ground contact must hold this long before it is declared, s.
const CONTACT_S: f32 = 0.2;

/// What the detector concluded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LandState {
    /// Flying: every loop active.
    Airborne,
    /// Touching the ground (or about to): every loop still active; landing not yet confirmed.
    GroundContact,
    /// Confirmed on the ground: motors may idle, loops off, disarm allowed.
    Landed,
}

/// The signals of one step.
#[derive(Clone, Copy, Debug, Default)]
pub struct LandInputs {
    /// Collective thrust commanded last step, N.
    pub thrust_n: f32,
    /// Thrust that holds the vehicle in hover, N.
    pub hover_thrust_n: f32,
    /// Vertical speed, up positive, m/s (ground-relative near the ground).
    pub climb_rate_mps: f32,
    /// Height of the rangefinders above the ground (or its barometric stand-in), m.
    pub height_agl_m: f32,
    /// That height when the vehicle stands on its gear, m.
    pub height_on_ground_m: f32,
    /// |body rate|, rad/s.
    pub rate_norm_radps: f32,
    /// The controller commands a descent (or holds at the ground): resting is plausible.
    pub descending: bool,
}

/// The detector: time each condition has held, and the state.
#[derive(Clone, Copy, Debug)]
pub struct LandDetector {
    state: LandState,
    contact_s: f32,
    landed_s: f32,
}

impl Default for LandDetector {
    fn default() -> Self {
        Self::new()
    }
}

impl LandDetector {
    /// A vehicle starts on the ground.
    pub const fn new() -> Self {
        Self {
            state: LandState::Landed,
            contact_s: 0.0,
            landed_s: 0.0,
        }
    }

    pub fn state(&self) -> LandState {
        self.state
    }

    pub fn landed(&self) -> bool {
        self.state == LandState::Landed
    }

    /// Take-off: a climb was commanded from the ground; the loops come on at once.
    pub fn take_off(&mut self) {
        self.state = LandState::Airborne;
        self.contact_s = 0.0;
        self.landed_s = 0.0;
    }

    /// One step. `landed_s`: how long the full landed condition must hold (parameter
    /// `limits.touchdown_s`). Returns the new state. `Landed` is left only by [`Self::take_off`].
    pub fn update(&mut self, dt_s: f32, x: &LandInputs, landed_s: f32) -> LandState {
        if self.state == LandState::Landed {
            return self.state;
        }
        let near_ground = x.height_agl_m < x.height_on_ground_m + CONTACT_MARGIN_M;
        let thrust_frac = if near_ground {
            NEAR_GROUND_THRUST_FRAC
        } else {
            FAR_THRUST_FRAC
        };
        let low_thrust = x.thrust_n < thrust_frac * x.hover_thrust_n;
        let still = fcc_nav::math::fabsf(x.climb_rate_mps) < STILL_VZ_MPS;
        let quiet = x.rate_norm_radps < QUIET_RATE_RADPS;
        let contact = x.descending && low_thrust && still;
        self.contact_s = if contact { self.contact_s + dt_s } else { 0.0 };
        let landed = contact && quiet;
        self.landed_s = if landed { self.landed_s + dt_s } else { 0.0 };
        self.state = if self.landed_s >= landed_s {
            LandState::Landed
        } else if self.contact_s >= CONTACT_S {
            LandState::GroundContact
        } else {
            LandState::Airborne
        };
        self.state
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn resting() -> LandInputs {
        LandInputs {
            thrust_n: 10.0,
            hover_thrust_n: 40.0,
            climb_rate_mps: 0.02,
            height_agl_m: 0.27,
            height_on_ground_m: 0.25,
            rate_norm_radps: 0.01,
            descending: true,
        }
    }

    fn run(d: &mut LandDetector, x: &LandInputs, s: f32) -> LandState {
        let mut st = d.state();
        for _ in 0..(s / 0.002) as usize {
            st = d.update(0.002, x, 1.0);
        }
        st
    }

    #[test]
    fn resting_on_the_gear_is_landed_after_the_hold_time() {
        let mut d = LandDetector::new();
        d.take_off();
        assert_eq!(run(&mut d, &resting(), 0.5), LandState::GroundContact);
        assert_eq!(run(&mut d, &resting(), 0.6), LandState::Landed);
        // Landed stays landed until a take-off, whatever the signals.
        let climbing = LandInputs {
            thrust_n: 60.0,
            climb_rate_mps: 1.0,
            ..resting()
        };
        assert_eq!(run(&mut d, &climbing, 1.0), LandState::Landed);
    }

    #[test]
    fn hovering_low_is_not_landed() {
        // Hover thrust, still, near the ground (a low hover or a stuck baro): never landed.
        let hover = LandInputs {
            thrust_n: 40.0,
            ..resting()
        };
        let mut d = LandDetector::new();
        d.take_off();
        assert_eq!(run(&mut d, &hover, 5.0), LandState::Airborne);
    }

    #[test]
    fn each_signal_vetoes_landing() {
        let cases = [
            LandInputs {
                climb_rate_mps: -0.6,
                ..resting()
            },
            LandInputs {
                descending: false,
                ..resting()
            },
            LandInputs {
                rate_norm_radps: 1.0,
                ..resting()
            },
            // Far from the ground per the rangefinder: the thrust must be lower still.
            LandInputs {
                height_agl_m: 1.0,
                thrust_n: 34.0,
                ..resting()
            },
        ];
        for (i, x) in cases.iter().enumerate() {
            let mut d = LandDetector::new();
            d.take_off();
            assert_ne!(run(&mut d, x, 5.0), LandState::Landed, "case {i}");
        }
    }

    #[test]
    fn a_bounce_restarts_the_hold_time() {
        let mut d = LandDetector::new();
        d.take_off();
        run(&mut d, &resting(), 0.9);
        let bounce = LandInputs {
            climb_rate_mps: 0.5,
            ..resting()
        };
        assert_eq!(run(&mut d, &bounce, 0.01), LandState::Airborne);
        assert_eq!(run(&mut d, &resting(), 0.9), LandState::GroundContact);
        assert_eq!(run(&mut d, &resting(), 0.2), LandState::Landed);
    }
}
