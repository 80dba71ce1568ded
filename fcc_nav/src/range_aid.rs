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
//! still re-acquiring, a slope; meanwhile the corrected barometer stands in, and the vertical
//! filter takes it at the barometer's crossover, [`RangeAid::range_measured`]): so over a step the
//! vehicle keeps its altitude (it neither jumps nor follows the step); over flat or gently
//! varying ground the height is held to the rangefinder's few centimetres.

use crate::math::fabsf;

/// The baro offset's time constant τ_b, s: long against the barometer's prop-wash noise
/// (coloured, ~1 s), short against its drift (tens of Pa over minutes).
pub const BARO_OFFSET_TAU_S: f32 = 20.0;
/// A range altitude this far from the estimate is suspect (a terrain edge, a step the ground
/// filter is still re-acquiring): the barometer stands in meanwhile, m.
pub const SUSPECT_M: f32 = 0.3;
/// Suspect for this long: the terrain changed (a step, a slope) — re-anchor, s.
pub const REANCHOR_S: f32 = 0.5;

/// Range-aided altitude measurement and baro offset.
#[derive(Clone, Copy, Debug, Default)]
pub struct RangeAid {
    terrain_alt_m: Option<f32>,
    reinit_seen: u32,
    baro_offset_m: f32,
    /// How long the range altitude has been suspect, s.
    suspect_s: f32,
}

impl RangeAid {
    /// No terrain reference, zero baro offset.
    pub const fn new() -> Self {
        Self {
            terrain_alt_m: None,
            reinit_seen: 0,
            baro_offset_m: 0.0,
            suspect_s: 0.0,
        }
    }

    /// The altitude measurement for the vertical filter (m, up). `agl_m`: paper B's fused
    /// height when valid and within the aid's range, else `None`; `reinit_count`: the ground
    /// filter's step re-acquisitions so far; `alt_est_m`: the filter's current altitude.
    pub fn measurement(
        &mut self,
        dt_s: f32,
        alt_est_m: f32,
        baro_alt_m: f32,
        agl_m: Option<f32>,
        reinit_count: u32,
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
        if fabsf(z - alt_est_m) > SUSPECT_M {
            self.suspect_s += dt_s;
            if self.suspect_s < REANCHOR_S {
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
        assert_eq!(a.measurement(0.02, 0.0, 0.0, Some(0.25), 0), 0.0);
        // At 5 m the baro reads 1.5 m high: the measurement is the range altitude.
        let z = a.measurement(0.02, 5.0, 6.5, Some(5.25), 0);
        assert!((z - 5.0).abs() < 1e-6);
        // The baro offset converges to 1.5 m over a few τ.
        for _ in 0..(200.0 / 0.02) as usize {
            a.measurement(0.02, 5.0, 6.5, Some(5.25), 0);
        }
        assert!(
            (a.baro_offset_m() - 1.5).abs() < 0.01,
            "{}",
            a.baro_offset_m()
        );
        // Range lost: the corrected baro continues where the range left off.
        assert!((a.measurement(0.02, 5.0, 6.5, None, 0) - 5.0).abs() < 0.01);
        assert!(!a.aiding());
    }

    #[test]
    fn an_unannounced_step_is_bridged_by_the_baro_then_re_anchored() {
        let mut a = RangeAid::new();
        a.measurement(0.02, 0.0, 0.0, Some(0.25), 0);
        a.measurement(0.02, 5.0, 5.0, Some(5.25), 0);
        // The ground drops 0.6 m without a re-acquisition: the baro stands in …
        let z = a.measurement(0.02, 5.0, 5.1, Some(5.85), 0);
        assert!((z - 5.1).abs() < 1e-3, "{z}");
        for _ in 0..30 {
            a.measurement(0.02, 5.0, 5.0, Some(5.85), 0);
        }
        // … then the terrain reference moves, not the altitude.
        let z = a.measurement(0.02, 5.0, 5.0, Some(5.85), 0);
        assert!((z - 5.0).abs() < 1e-3, "{z}");
        assert!((a.terrain_alt_m().unwrap() + 0.85).abs() < 1e-3);
    }

    #[test]
    fn a_terrain_step_does_not_move_the_altitude() {
        let mut a = RangeAid::new();
        a.measurement(0.02, 0.0, 0.0, Some(0.25), 0);
        assert!((a.measurement(0.02, 5.0, 5.0, Some(5.25), 0) - 5.0).abs() < 1e-6);
        // Flying over a 1 m box: the ground filter re-acquires at 4.25 m.
        let z = a.measurement(0.02, 5.0, 5.0, Some(4.25), 1);
        assert!((z - 5.0).abs() < 1e-6, "{z}");
        assert!((a.terrain_alt_m().unwrap() - 0.75).abs() < 1e-6);
    }
}
