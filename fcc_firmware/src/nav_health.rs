//! Estimator health: innovation / consistency monitors for each navigation filter. A filter
//! whose measurements keep disagreeing with its prediction has diverged (or its sensor lies);
//! the flight core answers a fault with hold, then land ([`crate::flight`]).
//!
//! | bit | filter | innovation | fault when |
//! |---|---|---|---|
//! | [`FAULT_VERTICAL`] | vertical | \|barometer (offset-corrected) − estimate\| | > [`VERT_INNOV_M`] for [`VERT_FAULT_S`] |
//! | [`FAULT_HORIZONTAL`] | horizontal (GPS) | \|GPS position − estimate\| (fix refused beyond the gate) | > [`gps_gate_m`] for [`GPS_FAULT_S`] |
//! | [`FAULT_ATTITUDE`] | roll/pitch | angle between the accelerometer's and the estimate's gravity | > [`TILT_INNOV_RAD`] for [`TILT_FAULT_S`] |
//!
//! The magnetometer has its own gate (`fcc_nav::attitude`): a disturbed field is reported, not
//! a fault (the heading is held on the gyro).
//! A terrain step is not a vertical fault: the ground filter re-acquires and the range aid
//! re-anchors its terrain reference; the barometer is unaffected.

/// Vertical filter fault bit.
pub const FAULT_VERTICAL: u8 = 1;
/// Horizontal filter (GPS) fault bit.
pub const FAULT_HORIZONTAL: u8 = 2;
/// Attitude (tilt) fault bit.
pub const FAULT_ATTITUDE: u8 = 4;

/// Barometer-vs-estimate disagreement beyond which the vertical filter is suspect, m (the
/// barometer's prop-wash noise is ≈1 m at 1σ over seconds; a range-aided estimate that left
/// it by 3 m, or a baro-only one that did, has diverged).
pub const VERT_INNOV_M: f32 = 3.0;
/// … for this long, s.
pub const VERT_FAULT_S: f32 = 2.0;
/// A GPS fix further from the estimate than this many of the receiver's own accuracy
/// estimates (`GpsFix::h_acc_m`, 1σ) is refused (multipath, a jump) …
///
/// The position estimate follows the GPS position only through a crossover of hundreds of
/// seconds (`NavParams::horiz_omega_radps`): the receiver's slowly wandering error is what it
/// leaves out, so the distance of a fix from the estimate is that error's change since the
/// estimate last agreed with it — per axis ≈ √2 × the receiver's per-axis σ, ≈ its `h_acc`
/// (the 2-D figure). Five of them leave a healthy fix out about once in 3·10⁵ (Rayleigh,
/// e^(−12.5)); a fixed 5 m gate refused 2 s of fixes in a gale hover whose error had wandered
/// 5.2 m from home's (`hover_gale` 35016: an estimator fault and a GPS-less landing).
pub const GPS_GATE_SIGMAS: f32 = 5.0;
/// … the gate never narrower than this, m …
pub const GPS_GATE_MIN_M: f32 = 5.0;
/// … nor wider (a receiver reporting a poor accuracy does not open it further), m.
pub const GPS_GATE_MAX_M: f32 = 10.0;

/// The GPS gate for a fix whose receiver reports `h_acc_m` (1σ), m: [`GPS_GATE_SIGMAS`] of it
/// within [`GPS_GATE_MIN_M`] … [`GPS_GATE_MAX_M`] (the minimum for a missing or non-finite
/// accuracy).
pub fn gps_gate_m(h_acc_m: f32) -> f32 {
    let g = GPS_GATE_SIGMAS * h_acc_m;
    if g.is_finite() {
        fcc_nav::math::clampf(g, GPS_GATE_MIN_M, GPS_GATE_MAX_M)
    } else {
        GPS_GATE_MIN_M
    }
}

/// Fixes refused for this long: the horizontal filter has lost GPS agreement, s.
pub const GPS_FAULT_S: f32 = 2.0;
/// Tilt innovation (accelerometer vs estimate) beyond which the attitude is suspect, rad (15°).
pub const TILT_INNOV_RAD: f32 = 0.26;
/// … for this long, s (manoeuvres the GPS compensation misses last well under it).
pub const TILT_FAULT_S: f32 = 5.0;

/// Innovations of one step (`None`: no measurement of that kind this step).
#[derive(Clone, Copy, Debug, Default)]
pub struct Innovations {
    /// |offset-corrected barometric altitude − estimate|, m.
    pub baro_alt_m: Option<f32>,
    /// A GPS fix arrived: its distance from the estimate and its gate.
    pub gps: Option<GpsInnovation>,
    pub tilt_rad: Option<f32>,
}

/// A GPS fix's distance from the position estimate, and the gate it is judged by
/// ([`gps_gate_m`]), m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpsInnovation {
    pub distance_m: f32,
    pub gate_m: f32,
}

impl GpsInnovation {
    /// Within the gate (a NaN distance is not).
    pub fn acceptable(&self) -> bool {
        self.distance_m <= self.gate_m
    }
}

/// One monitor: whether its latest innovation was beyond the limit, and for how long (the
/// timer runs every step, between samples too, while the latest sample is bad).
#[derive(Clone, Copy, Debug, Default)]
struct Monitor {
    bad: bool,
    bad_s: f32,
}

impl Monitor {
    const fn new() -> Self {
        Self {
            bad: false,
            bad_s: 0.0,
        }
    }

    /// A sample (`None`: none this step), its limit; returns the time it has been bad.
    fn update(&mut self, dt_s: f32, sample: Option<f32>, limit: f32) -> f32 {
        if let Some(v) = sample {
            // NaN counts as bad (hence the negated comparison).
            #[allow(clippy::neg_cmp_op_on_partial_ord)]
            let bad = !(v <= limit);
            self.bad = bad;
            if !self.bad {
                self.bad_s = 0.0;
            }
        }
        if self.bad {
            self.bad_s += dt_s;
        }
        self.bad_s
    }
}

/// Per-filter monitors and the latched fault bits.
#[derive(Clone, Copy, Debug, Default)]
pub struct NavHealth {
    vert: Monitor,
    gps: Monitor,
    tilt: Monitor,
    faults: u8,
    gps_refused: u32,
}

impl NavHealth {
    pub const fn new() -> Self {
        Self {
            vert: Monitor::new(),
            gps: Monitor::new(),
            tilt: Monitor::new(),
            faults: 0,
            gps_refused: 0,
        }
    }

    /// One step (`dt_s`: the step's length; samples arrive at their own rates); returns the
    /// fault bits (latched until [`Self::clear`]).
    pub fn update(&mut self, dt_s: f32, x: &Innovations) -> u8 {
        if x.gps.is_some_and(|g| !g.acceptable()) {
            self.gps_refused = self.gps_refused.wrapping_add(1);
        }
        if self.vert.update(dt_s, x.baro_alt_m, VERT_INNOV_M) >= VERT_FAULT_S {
            self.faults |= FAULT_VERTICAL;
        }
        // Judged as the distance in gates (a NaN stays NaN: bad).
        let gates = x.gps.map(|g| g.distance_m / g.gate_m);
        if self.gps.update(dt_s, gates, 1.0) >= GPS_FAULT_S {
            self.faults |= FAULT_HORIZONTAL;
        }
        if self.tilt.update(dt_s, x.tilt_rad, TILT_INNOV_RAD) >= TILT_FAULT_S {
            self.faults |= FAULT_ATTITUDE;
        }
        self.faults
    }

    pub fn faults(&self) -> u8 {
        self.faults
    }

    /// GPS fixes refused by the gate since start.
    pub fn gps_refused(&self) -> u32 {
        self.gps_refused
    }

    /// Forget the faults (on the ground, before a new flight).
    pub fn clear(&mut self) {
        *self = Self {
            gps_refused: self.gps_refused,
            ..Self::new()
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(h: &mut NavHealth, x: Innovations, s: f32) -> u8 {
        for _ in 0..(s / 0.002) as usize {
            h.update(0.002, &x);
        }
        h.faults()
    }

    #[test]
    fn the_gps_gate_follows_the_receivers_accuracy_within_bounds() {
        // The simulated u-blox reports 1.4 m: 7 m.
        assert!((gps_gate_m(1.4) - 7.0).abs() < 1e-5);
        assert_eq!(gps_gate_m(0.3), GPS_GATE_MIN_M);
        assert_eq!(gps_gate_m(50.0), GPS_GATE_MAX_M);
        assert_eq!(gps_gate_m(f32::NAN), GPS_GATE_MIN_M);
        assert_eq!(gps_gate_m(f32::INFINITY), GPS_GATE_MIN_M);
        let at = |d: f32| GpsInnovation {
            distance_m: d,
            gate_m: gps_gate_m(1.4),
        };
        assert!(at(6.0).acceptable());
        assert!(!at(8.0).acceptable());
        assert!(!at(f32::NAN).acceptable());
        // A receiver claiming a poor accuracy still has a 36 m jump refused.
        let jump = GpsInnovation {
            distance_m: 36.0,
            gate_m: gps_gate_m(99.0),
        };
        assert!(!jump.acceptable());
    }

    #[test]
    fn healthy_innovations_raise_nothing() {
        let mut h = NavHealth::new();
        let x = Innovations {
            baro_alt_m: Some(1.5),
            gps: Some(GpsInnovation {
                distance_m: 4.0,
                gate_m: gps_gate_m(1.4),
            }),
            tilt_rad: Some(0.1),
        };
        assert_eq!(run(&mut h, x, 60.0), 0);
    }

    #[test]
    fn each_divergence_is_flagged_after_its_hold_time() {
        let mut h = NavHealth::new();
        let v = Innovations {
            baro_alt_m: Some(3.5),
            ..Default::default()
        };
        assert_eq!(run(&mut h, v, 1.9), 0);
        assert_eq!(run(&mut h, v, 0.2), FAULT_VERTICAL);
        let mut h = NavHealth::new();
        // A refused fix at 5 Hz, then silence between fixes: the timer keeps running.
        for _ in 0..12 {
            h.update(
                0.002,
                &Innovations {
                    gps: Some(GpsInnovation {
                        distance_m: 30.0,
                        gate_m: gps_gate_m(1.4),
                    }),
                    ..Default::default()
                },
            );
            run(&mut h, Innovations::default(), 0.198);
        }
        assert_eq!(h.faults(), FAULT_HORIZONTAL);
        assert!(h.gps_refused() == 12);
        let mut h = NavHealth::new();
        let t = Innovations {
            tilt_rad: Some(0.5),
            ..Default::default()
        };
        assert_eq!(run(&mut h, t, 5.1), FAULT_ATTITUDE);
        // Latched until cleared.
        assert_eq!(
            run(
                &mut h,
                Innovations {
                    tilt_rad: Some(0.0),
                    ..Default::default()
                },
                1.0
            ),
            FAULT_ATTITUDE
        );
        h.clear();
        assert_eq!(h.faults(), 0);
    }

    #[test]
    fn sparse_samples_time_in_real_time() {
        // A bad baro innovation every 10th step (50 Hz): the fault comes after VERT_FAULT_S of
        // real time, not ten times later.
        let mut h = NavHealth::new();
        let mut k = 0u32;
        let mut t = 0.0f32;
        while h.faults() == 0 && t < 10.0 {
            let x = Innovations {
                baro_alt_m: k.is_multiple_of(10).then_some(4.0),
                ..Default::default()
            };
            h.update(0.002, &x);
            k += 1;
            t += 0.002;
        }
        assert!((t - VERT_FAULT_S).abs() < 0.03, "fault after {t} s");
    }

    #[test]
    fn nan_innovation_counts_as_bad() {
        let mut h = NavHealth::new();
        let x = Innovations {
            baro_alt_m: Some(f32::NAN),
            ..Default::default()
        };
        assert_eq!(run(&mut h, x, 2.1), FAULT_VERTICAL);
    }
}
