//! Flights scored on the simulator's **truth**, not on the vehicle's own estimate: true
//! altitude against the commanded height, true excursions, every ground contact with its speeds
//! and tilt, time flown with the attitude loops off, and a crash / tip-over model.
//!
//! Ground contacts are recorded by [`super::sim::Sim`] at the physics substep in which the
//! landing gear first touches the terrain after the vehicle was truly airborne. Each is
//! classified by [`classify_contact`]:
//!
//! - **crash**: vertical speed beyond what the gear absorbs (`v_z > CRASH_VZ_MPS`);
//! - **tip-over**: the horizontal kinetic energy at contact lifts the centre of mass over the
//!   gear's edge. With the gear half-span `r`, the centre of mass `h` above the contact plane,
//!   `L = √(r² + h²)`, the edge angle `α = atan(r/h)` and the touchdown tilt `φ` leaning into the
//!   motion, a point mass pivoting about the leading foot tips when
//!   `½·v_h² ≥ g·L·(1 − cos(α − φ))`; a tilt beyond `α` tips at any speed.
//!
//! A crash or tip-over ends the run (the simulator keeps a landed vehicle level, so without this
//! nothing downstream would notice). A contact outside LAND (or the pilot's mode) is an
//! **unplanned ground contact**.

use super::log::{FlightLog, LogSample, PlanPhase};
use fcc_firmware::commands::Mode;
use std::fmt;

/// Vertical touchdown speed the landing gear absorbs without damage, m/s (its stroke of a few
/// cm at ≈3 g, see `physics::GEAR_MAX_DECEL_MPS2`, stops ≈ 2 m/s).
pub const CRASH_VZ_MPS: f64 = 2.0;
/// Landing-gear half-span (centre to foot), m: paper A's octorotor, ≈ 0.6 m skid spacing.
pub const GEAR_HALF_SPAN_M: f64 = 0.3;
/// Truly airborne: gear this far above the terrain, m (the 0.1 m).
pub const AIRBORNE_CLEARANCE_M: f64 = 0.1;
/// A true horizontal excursion beyond this from the hold point or the intended line is a
/// flyaway, m.
pub const FLYAWAY_M: f64 = 10.0;

/// How a ground contact ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactOutcome {
    Landed,
    TipOver,
    Crash,
}

/// The landing gear touching the ground after flight.
#[derive(Clone, Copy, Debug)]
pub struct Contact {
    pub t_s: f64,
    /// Vertical speed (down positive), horizontal speed over the ground, m/s.
    pub vz_down_mps: f64,
    pub v_horiz_mps: f64,
    /// Tilt of the body z axis from the vertical, deg.
    pub tilt_deg: f64,
    /// The flight core's mode at contact.
    pub mode: Mode,
    /// In LAND (or the R/C pilot's hands): a landing, not a strike.
    pub planned: bool,
    pub outcome: ContactOutcome,
    /// LAND's touchdown gate at contact: seconds waited for a lull, and whether the timeout
    /// (not a lull) committed the descent.
    pub gate_wait_s: f64,
    pub gate_forced: bool,
}

/// Clearance of the lowest foot over the ground, m: `plane_clearance_m` is the contact plane's
/// (the centre of mass `cg_height_m` above it when standing level), `tilt_deg` the body's tilt.
/// The gear turns with the body about the centre of mass, and the foot on the side of the lean
/// comes down by [`fcc_firmware::geometry::foot_drop_m`] — the same geometry the firmware's
/// touchdown gate judges, with the simulated airframe's gear (ASSUMPTION: feet at
/// [`GEAR_HALF_SPAN_M`] in every direction, the worst case of paper A's skids): holding 12 cm
/// up leaning 20° into a gust, the foot is 8.8 cm lower than level, 3 cm from the ground.
pub fn foot_clearance_m(plane_clearance_m: f64, tilt_deg: f64, cg_height_m: f64) -> f64 {
    let drop_m = fcc_firmware::geometry::foot_drop_m(
        tilt_deg.to_radians() as f32,
        GEAR_HALF_SPAN_M as f32,
        cg_height_m as f32,
    );
    plane_clearance_m - drop_m as f64
}

/// The crash / tip-over model (module doc). `cg_height_m`: centre of mass above the contact
/// plane when standing (the simulator's gear height).
pub fn classify_contact(
    vz_down_mps: f64,
    v_horiz_mps: f64,
    tilt_deg: f64,
    cg_height_m: f64,
) -> ContactOutcome {
    if vz_down_mps > CRASH_VZ_MPS {
        return ContactOutcome::Crash;
    }
    let h = cg_height_m.max(0.01);
    let l = (GEAR_HALF_SPAN_M * GEAR_HALF_SPAN_M + h * h).sqrt();
    let alpha = (GEAR_HALF_SPAN_M / h).atan();
    let margin = alpha - tilt_deg.to_radians();
    let g = fcc_nav::GRAVITY_MPS2 as f64;
    if margin <= 0.0 || 0.5 * v_horiz_mps * v_horiz_mps >= g * l * (1.0 - margin.cos()) {
        ContactOutcome::TipOver
    } else {
        ContactOutcome::Landed
    }
}

/// Truth counters the simulator accumulates every 2 ms tick.
#[derive(Clone, Copy, Debug, Default)]
pub struct TruthCounters {
    /// Time truly airborne (gear > [`AIRBORNE_CLEARANCE_M`] up) while armed with the attitude
    /// loops off, s.
    pub attitude_off_airborne_s: f64,
    /// Largest true tilt while airborne, deg; largest true horizontal speed, m/s.
    pub max_tilt_deg: f64,
    pub max_speed_mps: f64,
    /// True height of the take-off point's gear contact (NED down of the body at rest), m.
    pub start_down_m: f64,
}

/// Every truth figure of one flight.
#[derive(Clone, Debug, Default)]
pub struct TruthReport {
    pub contacts: Vec<Contact>,
    pub crashed: bool,
    pub unplanned_contacts: usize,
    pub attitude_off_airborne_s: f64,
    /// Hold windows: max |true altitude − commanded height|, m, and max true horizontal
    /// distance from where the hold started, m.
    pub hold_alt_err_m: Option<f64>,
    pub hold_excursion_m: Option<f64>,
    /// Hold windows: max drift of the navigation error (true − estimated horizontal position)
    /// from its value at the hold start, m — the part of the true excursion the vehicle cannot
    /// see (GPS error wander), however well it holds its estimate.
    pub hold_nav_drift_m: Option<f64>,
    /// Legs: max true distance from the intended line (m) and max |true alt − leg altitude|.
    pub leg_line_max_m: Option<f64>,
    pub leg_alt_err_m: Option<f64>,
    pub max_tilt_deg: f64,
    pub max_speed_mps: f64,
    pub flyaway: bool,
}

impl TruthReport {
    /// The worst planned touchdown (largest vertical, horizontal speed and tilt).
    pub fn worst_touchdown(&self) -> Option<[f64; 3]> {
        let mut w: Option<[f64; 3]> = None;
        for c in self.contacts.iter().filter(|c| c.planned) {
            let x = w.get_or_insert([0.0; 3]);
            x[0] = x[0].max(c.vz_down_mps);
            x[1] = x[1].max(c.v_horiz_mps);
            x[2] = x[2].max(c.tilt_deg);
        }
        w
    }
}

/// True altitude above the take-off point (the estimate's zero), m.
fn true_alt_m(s: &LogSample, start_down_m: f64) -> f64 {
    start_down_m - s.true_pos_ned_m[2]
}

fn dist_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let t = if len2 > 1e-12 {
        (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = [a[0] + t * d[0], a[1] + t * d[1]];
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
}

/// Score a flight log on the truth.
pub fn report(log: &FlightLog) -> TruthReport {
    let c = log.truth;
    let mut r = TruthReport {
        contacts: log.contacts.clone(),
        crashed: log
            .contacts
            .iter()
            .any(|x| x.outcome != ContactOutcome::Landed),
        unplanned_contacts: log.contacts.iter().filter(|x| !x.planned).count(),
        attitude_off_airborne_s: c.attitude_off_airborne_s,
        max_tilt_deg: c.max_tilt_deg,
        max_speed_mps: c.max_speed_mps,
        ..Default::default()
    };
    let mut hold_start: Option<[f64; 2]> = None;
    let mut hold_nav_err0: Option<[f64; 2]> = None;
    let max_opt = |o: &mut Option<f64>, v: f64| *o = Some(o.map_or(v, |x: f64| x.max(v)));
    for s in &log.samples {
        let p = [s.true_pos_ned_m[0], s.true_pos_ned_m[1]];
        match s.plan {
            PlanPhase::Holding { hold_ned_m } if s.armed && s.mode == Mode::Hold => {
                let start = *hold_start.get_or_insert(p);
                let cmd_alt = log.commanded_alt_m.unwrap_or(-hold_ned_m[2] as f64);
                max_opt(
                    &mut r.hold_alt_err_m,
                    (true_alt_m(s, c.start_down_m) - cmd_alt).abs(),
                );
                let d = ((p[0] - start[0]).powi(2) + (p[1] - start[1]).powi(2)).sqrt();
                max_opt(&mut r.hold_excursion_m, d);
                let est = [s.nav.pos_ned_m[0] as f64, s.nav.pos_ned_m[1] as f64];
                let err = [p[0] - est[0], p[1] - est[1]];
                let e0 = *hold_nav_err0.get_or_insert(err);
                let drift = ((err[0] - e0[0]).powi(2) + (err[1] - e0[1]).powi(2)).sqrt();
                max_opt(&mut r.hold_nav_drift_m, drift);
            }
            PlanPhase::Leg {
                from_ned_m,
                to_ned_m,
                ..
            } if s.armed => {
                hold_start = None;
                hold_nav_err0 = None;
                let a = [from_ned_m[0] as f64, from_ned_m[1] as f64];
                let b = [to_ned_m[0] as f64, to_ned_m[1] as f64];
                max_opt(&mut r.leg_line_max_m, dist_to_segment(p, a, b));
                // Leg altitude: linear from the start to the end waypoint along the track.
                let d = [b[0] - a[0], b[1] - a[1]];
                let len2 = d[0] * d[0] + d[1] * d[1];
                let t = if len2 > 1e-9 {
                    (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                let alt = -(from_ned_m[2] as f64 + t * (to_ned_m[2] - from_ned_m[2]) as f64);
                max_opt(
                    &mut r.leg_alt_err_m,
                    (true_alt_m(s, c.start_down_m) - alt).abs(),
                );
            }
            _ => hold_start = None,
        }
    }
    r.flyaway = r.hold_excursion_m.unwrap_or(0.0) > FLYAWAY_M
        || r.leg_line_max_m.unwrap_or(0.0) > FLYAWAY_M;
    r
}

fn opt(v: Option<f64>, unit: &str) -> String {
    v.map_or("—".into(), |x| format!("{x:.3} {unit}"))
}

impl fmt::Display for TruthReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "truth (simulator):")?;
        writeln!(
            f,
            "  ground contacts {} (unplanned {}), crash/tip-over {}, flyaway {}",
            self.contacts.len(),
            self.unplanned_contacts,
            if self.crashed { "YES" } else { "no" },
            if self.flyaway { "YES" } else { "no" }
        )?;
        for c in &self.contacts {
            writeln!(
                f,
                "    t={:7.2} s {:?}{}: down {:.2} m/s, horizontal {:.2} m/s, tilt {:.1}° → {:?} \
                 (touchdown gate: waited {:.1} s{})",
                c.t_s,
                c.mode,
                if c.planned { "" } else { " UNPLANNED" },
                c.vz_down_mps,
                c.v_horiz_mps,
                c.tilt_deg,
                c.outcome,
                c.gate_wait_s,
                if c.gate_forced {
                    ", committed without a lull (timeout, or GPS lost)"
                } else {
                    ""
                }
            )?;
        }
        writeln!(
            f,
            "  hold: true altitude error max {}, true excursion from hold start max {} \
             (navigation error drift, unseen by the vehicle: max {})",
            opt(self.hold_alt_err_m, "m"),
            opt(self.hold_excursion_m, "m"),
            opt(self.hold_nav_drift_m, "m")
        )?;
        writeln!(
            f,
            "  legs: true distance from the intended line max {}, true altitude error max {}",
            opt(self.leg_line_max_m, "m"),
            opt(self.leg_alt_err_m, "m")
        )?;
        write!(
            f,
            "  airborne with attitude loops off {:.2} s; max true tilt {:.1}°, max true speed {:.2} m/s",
            self.attitude_off_airborne_s, self.max_tilt_deg, self.max_speed_mps
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crash_model() {
        let h = 0.25;
        assert_eq!(classify_contact(0.4, 0.1, 2.0, h), ContactOutcome::Landed);
        assert_eq!(classify_contact(2.5, 0.0, 0.0, h), ContactOutcome::Crash);
        // α = atan(0.3/0.25) = 50.2°: beyond it, tipped at any speed.
        assert_eq!(classify_contact(0.3, 0.0, 51.0, h), ContactOutcome::TipOver);
        // Level: v_tip = √(2·g·L·(1 − cos α)) ≈ 1.66 m/s.
        assert_eq!(classify_contact(0.3, 1.5, 0.0, h), ContactOutcome::Landed);
        assert_eq!(classify_contact(0.3, 1.8, 0.0, h), ContactOutcome::TipOver);
        // Leaning 20° lowers it (≈ 1.0 m/s).
        assert_eq!(classify_contact(0.3, 1.2, 20.0, h), ContactOutcome::TipOver);
    }

    #[test]
    fn a_leaning_foot_comes_down() {
        let h = 0.25;
        assert_eq!(foot_clearance_m(0.12, 0.0, h), 0.12);
        // Holding 12 cm up leaning 20°: the foot 3.3 cm up; leaning 35°, on the ground.
        assert!((foot_clearance_m(0.12, 20.0, h) - 0.0325).abs() < 1e-3);
        assert!(foot_clearance_m(0.12, 35.0, h) < 0.0);
    }

    #[test]
    fn segment_distance() {
        assert!((dist_to_segment([1.0, 1.0], [0.0, 0.0], [2.0, 0.0]) - 1.0).abs() < 1e-12);
        assert!((dist_to_segment([3.0, 0.0], [0.0, 0.0], [2.0, 0.0]) - 1.0).abs() < 1e-12);
    }
}
