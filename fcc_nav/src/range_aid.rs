//! Range-aided height (as PX4's EKF2 does with a rangefinder): while paper B's fused height
//! above ground `h_agl` is valid and in range, the vertical filter's position measurement is
//! the rangefinder altitude instead of the barometer, and the barometer's offset is learnt so
//! that it takes over seamlessly when the range is lost.
//!
//! ```text
//!   aided:    z_meas = t + h_agl            t: terrain altitude under the vehicle (nav frame, up)
//!             b ← b + (dt/τ_b)·(h_baro − z_meas − b)      baro offset, low-passed
//!   unaided:  z_meas = h_baro − b
//! ```
//! `t` is anchored (`t = ĥ − h_agl`, with ĥ the current altitude estimate) when the aid starts,
//! whenever the ground filter re-acquires after a **terrain step**, and when the range altitude
//! stays more than [`SUSPECT_M`] from the estimate for [`REANCHOR_S`] (an edge the filter is
//! still re-acquiring, a slope). While the range altitude is suspect — that far off, or, as the
//! vehicle moves over the ground at [`RAMP_MIN_SPEED_MPS`] or faster, moving against the
//! inertial vertical velocity faster than [`SUSPECT_RATE_MPS`] for up to [`RAMP_MAX_S`] (the
//! ground filter's residual rate `r`, `ḣ_agl = −v_down + r`) — the corrected barometer stands
//! in, and the vertical filter takes it at the barometer's crossover
//! ([`RangeAid::range_measured`]). So over a step the vehicle keeps its altitude (it neither
//! jumps nor follows the step); over flat or gently varying ground the height is held to the
//! rangefinder's few centimetres.
//!
//! The rate test is for an edge the sonar sees gradually: its 15° cone keeps the nearest point
//! of a box's edge in view for `h·tan 15°` of travel, so flying off a 0.5-m box at 4.5 m the
//! fused height ramps down over ≈ 0.6 s instead of stepping, the ground filter follows the ramp
//! with its residual rate (0.49 m/s) and never re-acquires, and the range altitude never left
//! the estimate by [`SUSPECT_M`] because the estimate followed it: the vehicle's altitude
//! followed the terrain down (campaign `landing` 5063: 0.75 m of true altitude error,
//! `tests/tests/ground_altitude.rs`).

use crate::math::fabsf;

/// The baro offset's time constant τ_b, s: long against the barometer's prop-wash noise
/// (coloured, ~1 s), short against its drift (tens of Pa over minutes).
pub const BARO_OFFSET_TAU_S: f32 = 20.0;
/// A range altitude this far from the estimate is suspect (a terrain edge, a step the ground
/// filter is still re-acquiring): the barometer stands in meanwhile, m.
pub const SUSPECT_M: f32 = 0.3;
/// Suspect for this long: the terrain changed (a step, a slope) — re-anchor, s.
pub const REANCHOR_S: f32 = 0.5;
/// A range altitude that moves against the inertial vertical velocity faster than this is
/// suspect too (the ground filter's residual rate; over flat ground it stays within a few
/// cm/s), m/s.
pub const SUSPECT_RATE_MPS: f32 = 0.15;
/// … for at most this long (the longest ramp an edge makes in the sonar's cone), s …
pub const RAMP_MAX_S: f32 = 1.0;
/// … and only while the vehicle moves over the ground at least this fast (a terrain ramp needs
/// horizontal motion, `ḣ ≤ v·sin 15°` at an edge; hovering in a gale, the vertical velocity's
/// own error moves `r` by 0.1–0.4 m/s, and cutting the range then let it run away: 7.7 m in
/// `hover_gale` 17058), m/s.
pub const RAMP_MIN_SPEED_MPS: f32 = 1.0;

/// Range-aided altitude measurement and baro offset.
#[derive(Clone, Copy, Debug, Default)]
pub struct RangeAid {
    terrain_alt_m: Option<f32>,
    reinit_seen: u32,
    baro_offset_m: f32,
    /// How long the range altitude has been suspect, s.
    suspect_s: f32,
    /// How long the range altitude has been moving against the inertial velocity, s.
    moving_s: f32,
}

impl RangeAid {
    /// No terrain reference, zero baro offset.
    pub const fn new() -> Self {
        Self {
            terrain_alt_m: None,
            reinit_seen: 0,
            baro_offset_m: 0.0,
            suspect_s: 0.0,
            moving_s: 0.0,
        }
    }

    /// The altitude measurement for the vertical filter (m, up). `agl_m`: paper B's fused
    /// height when valid and within the aid's range, else `None`; `reinit_count`: the ground
    /// filter's step re-acquisitions so far, `rate_residual_mps` its residual rate (how fast the
    /// fused height moves against the inertial vertical velocity); `alt_est_m`: the filter's
    /// current altitude; `ground_speed_mps`: the horizontal speed (a ramp needs motion).
    #[allow(clippy::too_many_arguments)] // each is one of the filters' outputs, named in units
    pub fn measurement(
        &mut self,
        dt_s: f32,
        alt_est_m: f32,
        baro_alt_m: f32,
        agl_m: Option<f32>,
        reinit_count: u32,
        rate_residual_mps: f32,
        ground_speed_mps: f32,
    ) -> f32 {
        let Some(h) = agl_m else {
            self.terrain_alt_m = None;
            self.reinit_seen = reinit_count;
            return baro_alt_m - self.baro_offset_m;
        };
        if self.terrain_alt_m.is_none() || reinit_count != self.reinit_seen {
            self.anchor(alt_est_m, h);
            self.reinit_seen = reinit_count;
        }
        let mut z = self.terrain_alt_m.unwrap_or(0.0) + h;
        // A ramp: the fused height moving against the inertial velocity while the vehicle
        // moves over the ground, for no longer than an edge's ramp lasts (longer, the inertial
        // velocity is the likelier culprit, and the range corrects it).
        let moving =
            ground_speed_mps >= RAMP_MIN_SPEED_MPS && fabsf(rate_residual_mps) > SUSPECT_RATE_MPS;
        self.moving_s = if moving { self.moving_s + dt_s } else { 0.0 };
        let ramp = moving && self.moving_s < RAMP_MAX_S;
        let off = fabsf(z - alt_est_m) > SUSPECT_M;
        if ramp || off {
            self.suspect_s += dt_s;
            // Only an altitude persistently off re-anchors (a ramp's end may leave none).
            if ramp || self.suspect_s < REANCHOR_S {
                return baro_alt_m - self.baro_offset_m;
            }
            // Persistently off: the ground under the vehicle changed, not the vehicle's height.
            self.anchor(alt_est_m, h);
            z = alt_est_m;
        } else {
            self.suspect_s = 0.0;
        }
        let k = (dt_s / BARO_OFFSET_TAU_S).clamp(0.0, 1.0);
        self.baro_offset_m += k * (baro_alt_m - z - self.baro_offset_m);
        z
    }

    fn anchor(&mut self, alt_est_m: f32, h: f32) {
        self.terrain_alt_m = Some(alt_est_m - h);
        self.suspect_s = 0.0;
    }

    /// The aid is in use.
    pub fn aiding(&self) -> bool {
        self.terrain_alt_m.is_some()
    }

    /// The last measurement was the range altitude (not the barometer standing in while the
    /// range altitude is suspect).
    pub fn range_measured(&self) -> bool {
        self.terrain_alt_m.is_some() && self.suspect_s == 0.0
    }

    /// Terrain altitude under the vehicle in the navigation frame, m (while aiding).
    pub fn terrain_alt_m(&self) -> Option<f32> {
        self.terrain_alt_m
    }

    /// Learnt barometer offset (baro altitude − true altitude), m.
    pub fn baro_offset_m(&self) -> f32 {
        self.baro_offset_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aided_measurement_follows_the_range_not_the_baro() {
        let mut a = RangeAid::new();
        // Anchored at take-off: estimate 0, sensors 0.25 m above the ground.
        assert_eq!(a.measurement(0.02, 0.0, 0.0, Some(0.25), 0, 0.0, 2.0), 0.0);
        // At 5 m the baro reads 1.5 m high: the measurement is the range altitude.
        let z = a.measurement(0.02, 5.0, 6.5, Some(5.25), 0, 0.0, 2.0);
        assert!((z - 5.0).abs() < 1e-6);
        // The baro offset converges to 1.5 m over a few τ.
        for _ in 0..(200.0 / 0.02) as usize {
            a.measurement(0.02, 5.0, 6.5, Some(5.25), 0, 0.0, 2.0);
        }
        assert!(
            (a.baro_offset_m() - 1.5).abs() < 0.01,
            "{}",
            a.baro_offset_m()
        );
        // Range lost: the corrected baro continues where the range left off.
        assert!((a.measurement(0.02, 5.0, 6.5, None, 0, 0.0, 2.0) - 5.0).abs() < 0.01);
        assert!(!a.aiding());
    }

    #[test]
    fn an_unannounced_step_is_bridged_by_the_baro_then_re_anchored() {
        let mut a = RangeAid::new();
        a.measurement(0.02, 0.0, 0.0, Some(0.25), 0, 0.0, 2.0);
        a.measurement(0.02, 5.0, 5.0, Some(5.25), 0, 0.0, 2.0);
        // The ground drops 0.6 m without a re-acquisition: the baro stands in …
        let z = a.measurement(0.02, 5.0, 5.1, Some(5.85), 0, 0.0, 2.0);
        assert!((z - 5.1).abs() < 1e-3, "{z}");
        for _ in 0..30 {
            a.measurement(0.02, 5.0, 5.0, Some(5.85), 0, 0.0, 2.0);
        }
        // … then the terrain reference moves, not the altitude.
        let z = a.measurement(0.02, 5.0, 5.0, Some(5.85), 0, 0.0, 2.0);
        assert!((z - 5.0).abs() < 1e-3, "{z}");
        assert!((a.terrain_alt_m().unwrap() + 0.85).abs() < 1e-3);
    }

    #[test]
    fn a_terrain_step_does_not_move_the_altitude() {
        let mut a = RangeAid::new();
        a.measurement(0.02, 0.0, 0.0, Some(0.25), 0, 0.0, 2.0);
        assert!((a.measurement(0.02, 5.0, 5.0, Some(5.25), 0, 0.0, 2.0) - 5.0).abs() < 1e-6);
        // Flying over a 1 m box: the ground filter re-acquires at 4.25 m.
        let z = a.measurement(0.02, 5.0, 5.0, Some(4.25), 1, 0.0, 2.0);
        assert!((z - 5.0).abs() < 1e-6, "{z}");
        assert!((a.terrain_alt_m().unwrap() - 0.75).abs() < 1e-6);
    }

    #[test]
    fn an_edge_seen_as_a_ramp_is_bridged_by_the_baro_not_followed() {
        let mut a = RangeAid::new();
        // Anchored over a 0.5-m box (ground at 0.25 m in the navigation frame).
        assert!((a.measurement(0.02, 5.0, 5.0, Some(4.75), 0, 0.0, 2.0) - 5.0).abs() < 1e-6);
        // Off a 0.5-m box's edge: the sonar's cone turns the step into a 0.6-s ramp, followed
        // by the ground filter's residual rate (no re-acquisition). The first 0.3 m of it would
        // pass the distance test; the rate test hands the height to the barometer …
        for i in 1..=30 {
            let h = 4.75 + 0.5 * i as f32 / 30.0;
            let z = a.measurement(0.02, 5.0, 5.0, Some(h), 0, 0.8, 2.0);
            assert!((z - 5.0).abs() < 1e-3, "step {i}: {z}");
            assert!(!a.range_measured());
        }
        // … and when the fused height is steady again, 0.5 m from the estimate, the terrain
        // reference moves, not the height.
        for _ in 0..30 {
            let z = a.measurement(0.02, 5.0, 5.0, Some(5.25), 0, 0.02, 2.0);
            assert!((z - 5.0).abs() < 1e-3, "{z}");
        }
        assert!(a.range_measured());
        assert!((a.terrain_alt_m().unwrap() + 0.25).abs() < 1e-3);
        // Hovering (no horizontal motion), the same rate is the vertical velocity's error, and
        // the range keeps correcting it.
        let z = a.measurement(0.02, 5.0, 5.0, Some(5.35), 0, 0.8, 0.2);
        assert!((z - 5.1).abs() < 1e-3, "{z}");
    }
}
