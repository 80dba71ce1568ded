//! The figures paper A reports, computed from a flight log: hover box (Fig. 16), straightness of
//! waypoint legs (Fig. 17), attitude estimate vs truth (Fig. 5), vertical estimate vs truth and
//! barometer (Fig. 9), observer vs raw accelerometer (Fig. 13).

use super::log::{FlightLog, LogSample, PlanPhase};
use std::fmt;

fn rms(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

fn std_dev(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return f64::NAN;
    }
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

use fcc_nav::complementary::wrap_pi_f64 as wrap_pi;

/// Hover: largest deviation from the hold point per axis, estimated and true.
#[derive(Clone, Copy, Debug, Default)]
pub struct HoverBox {
    pub duration_s: f64,
    /// Estimated position: max |est − hold point| (m) north, east, altitude.
    pub est_max_m: [f64; 3],
    /// True position: max |true − mean true position over the hold| (m) north, east, altitude.
    pub true_max_m: [f64; 3],
    pub true_rms_m: [f64; 3],
}

pub fn hover_box(log: &FlightLog) -> Option<HoverBox> {
    let hold: Vec<(&LogSample, [f32; 3])> = log
        .samples
        .iter()
        .filter_map(|s| match s.plan {
            PlanPhase::Holding { hold_ned_m } if s.armed => Some((s, hold_ned_m)),
            _ => None,
        })
        .collect();
    if hold.len() < 10 {
        return None;
    }
    let mut out = HoverBox {
        duration_s: hold.last()?.0.t_s - hold[0].0.t_s,
        ..Default::default()
    };
    for axis in 0..3 {
        let est: Vec<f64> = hold
            .iter()
            .map(|(s, h)| (s.nav.pos_ned_m[axis] - h[axis]) as f64)
            .collect();
        out.est_max_m[axis] = max_abs(&est);
        let tr: Vec<f64> = hold.iter().map(|(s, _)| s.true_pos_ned_m[axis]).collect();
        let mean = tr.iter().sum::<f64>() / tr.len() as f64;
        let dev: Vec<f64> = tr.iter().map(|x| x - mean).collect();
        out.true_max_m[axis] = max_abs(&dev);
        out.true_rms_m[axis] = rms(&dev);
    }
    Some(out)
}

impl fmt::Display for HoverBox {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "hover {:.0} s (paper A: N 0.7 m, E 1.1 m, alt 0.3 m box)",
            self.duration_s
        )?;
        writeln!(
            f,
            "  estimated position, max |dev| from hold point: N {:.3} m  E {:.3} m  alt {:.3} m",
            self.est_max_m[0], self.est_max_m[1], self.est_max_m[2]
        )?;
        write!(
            f,
            "  true position, max |dev| from its mean:        N {:.3} m  E {:.3} m  alt {:.3} m  (RMS {:.3} / {:.3} / {:.3})",
            self.true_max_m[0], self.true_max_m[1], self.true_max_m[2], self.true_rms_m[0], self.true_rms_m[1], self.true_rms_m[2]
        )
    }
}

/// Cross-track error of one straight leg.
#[derive(Clone, Copy, Debug, Default)]
pub struct LegTrack {
    pub index: usize,
    pub length_m: f64,
    pub est_rms_m: f64,
    pub est_max_m: f64,
    /// True path: distance from its own least-squares line (straightness), and offset of its
    /// mean from the commanded line (GPS error).
    pub true_rms_m: f64,
    pub true_max_m: f64,
}

fn cross_track(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let n = (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-9);
    ((p[0] - a[0]) * d[1] - (p[1] - a[1]) * d[0]) / n
}

/// Least-squares line through points; distances of the points from it.
fn line_fit_residuals(pts: &[[f64; 2]]) -> Vec<f64> {
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p[0]).sum::<f64>() / n;
    let my = pts.iter().map(|p| p[1]).sum::<f64>() / n;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in pts {
        sxx += (p[0] - mx).powi(2);
        syy += (p[1] - my).powi(2);
        sxy += (p[0] - mx) * (p[1] - my);
    }
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let (c, s) = (theta.cos(), theta.sin());
    pts.iter()
        .map(|p| -(p[0] - mx) * s + (p[1] - my) * c)
        .collect()
}

pub fn leg_tracks(log: &FlightLog) -> Vec<LegTrack> {
    let mut out = Vec::new();
    let mut i = 0;
    let s = &log.samples;
    while i < s.len() {
        if let PlanPhase::Leg {
            index,
            from_ned_m,
            to_ned_m,
        } = s[i].plan
        {
            let a = [from_ned_m[0] as f64, from_ned_m[1] as f64];
            let b = [to_ned_m[0] as f64, to_ned_m[1] as f64];
            let mut est = Vec::new();
            let mut tru = Vec::new();
            while i < s.len() && matches!(s[i].plan, PlanPhase::Leg { index: j, .. } if j == index)
            {
                let p = s[i].nav.pos_ned_m;
                est.push(cross_track([p[0] as f64, p[1] as f64], a, b));
                tru.push([s[i].true_pos_ned_m[0], s[i].true_pos_ned_m[1]]);
                i += 1;
            }
            let length = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            if est.len() > 10 && length > 1.0 {
                let res = line_fit_residuals(&tru);
                out.push(LegTrack {
                    index,
                    length_m: length,
                    est_rms_m: rms(&est),
                    est_max_m: max_abs(&est),
                    true_rms_m: rms(&res),
                    true_max_m: max_abs(&res),
                });
            }
        } else {
            i += 1;
        }
    }
    out
}

/// Cross-track error over all legs together.
#[derive(Clone, Copy, Debug, Default)]
pub struct TrackSummary {
    pub legs: usize,
    pub est_rms_m: f64,
    pub est_max_m: f64,
    pub true_rms_m: f64,
    pub true_max_m: f64,
}

pub fn track_summary(legs: &[LegTrack]) -> TrackSummary {
    let n = legs.len().max(1) as f64;
    TrackSummary {
        legs: legs.len(),
        est_rms_m: (legs.iter().map(|l| l.est_rms_m.powi(2)).sum::<f64>() / n).sqrt(),
        est_max_m: legs.iter().fold(0.0, |m, l| m.max(l.est_max_m)),
        true_rms_m: (legs.iter().map(|l| l.true_rms_m.powi(2)).sum::<f64>() / n).sqrt(),
        true_max_m: legs.iter().fold(0.0, |m, l| m.max(l.true_max_m)),
    }
}

/// Attitude estimate vs truth while airborne (deg).
#[derive(Clone, Copy, Debug, Default)]
pub struct AttitudeError {
    pub samples: usize,
    pub rms_deg: [f64; 3],
    pub max_deg: [f64; 3],
}

pub fn attitude_error(log: &FlightLog, airborne_only: bool) -> AttitudeError {
    let mut e: [Vec<f64>; 3] = Default::default();
    for s in &log.samples {
        if airborne_only && (s.landed || !s.armed) {
            continue;
        }
        let est = [
            s.nav.euler.roll_rad as f64,
            s.nav.euler.pitch_rad as f64,
            s.nav.euler.yaw_rad as f64,
        ];
        for k in 0..3 {
            e[k].push(wrap_pi(est[k] - s.true_euler_rad[k]).to_degrees());
        }
    }
    AttitudeError {
        samples: e[0].len(),
        rms_deg: [rms(&e[0]), rms(&e[1]), rms(&e[2])],
        max_deg: [max_abs(&e[0]), max_abs(&e[1]), max_abs(&e[2])],
    }
}

/// Carried scenarios: the filters start after the ground calibration; score from then on.
pub const ELEVATOR_SETTLE_S: f64 = 5.0;

/// Vertical estimate vs truth, with barometer-only beside it.
#[derive(Clone, Copy, Debug, Default)]
pub struct VerticalError {
    pub est_rms_m: f64,
    pub est_max_m: f64,
    pub baro_rms_m: f64,
    /// Noise: standard deviation of the 1 s-differenced error (removes slow bias).
    pub est_noise_m: f64,
    pub baro_noise_m: f64,
}

pub fn vertical_error(log: &FlightLog, after_s: f64) -> VerticalError {
    let s: Vec<&LogSample> = log.samples.iter().filter(|s| s.t_s >= after_s).collect();
    let est: Vec<f64> = s
        .iter()
        .map(|s| -(s.nav.pos_ned_m[2] as f64) - (-s.true_pos_ned_m[2]))
        .collect();
    let baro: Vec<f64> = s
        .iter()
        .map(|s| s.nav.baro_alt_m as f64 - (-s.true_pos_ned_m[2]))
        .collect();
    let hp = |v: &[f64]| -> Vec<f64> {
        // deviation from a centred 1 s moving average (50 samples at 50 Hz)
        let w = 25;
        (w..v.len().saturating_sub(w))
            .map(|i| v[i] - v[i - w..i + w].iter().sum::<f64>() / (2 * w) as f64)
            .collect()
    };
    VerticalError {
        est_rms_m: rms(&est),
        est_max_m: max_abs(&est),
        baro_rms_m: rms(&baro),
        est_noise_m: std_dev(&hp(&est)),
        baro_noise_m: std_dev(&hp(&baro)),
    }
}

/// Luenberger observer vs the raw accelerometer (heading frame, both axes pooled), in flight.
#[derive(Clone, Copy, Debug, Default)]
pub struct ObserverNoise {
    pub samples: usize,
    pub observer_std_mps2: f64,
    pub raw_std_mps2: f64,
}

pub fn observer_noise(log: &FlightLog) -> ObserverNoise {
    let (mut o, mut r) = (Vec::new(), Vec::new());
    for s in log
        .samples
        .iter()
        .filter(|s| s.armed && !s.landed && -s.true_pos_ned_m[2] > 1.0)
    {
        for k in 0..2 {
            o.push((s.tel.accel_est_fr_mps2[k] - s.accel_true_fr_mps2[k]) as f64);
            r.push((s.tel.accel_meas_fr_mps2[k] - s.accel_true_fr_mps2[k]) as f64);
        }
    }
    ObserverNoise {
        samples: o.len() / 2,
        observer_std_mps2: std_dev(&o),
        raw_std_mps2: std_dev(&r),
    }
}

/// Everything at once, for the summary the binary prints.
pub fn summary(log: &FlightLog) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    if let Some(h) = hover_box(log) {
        writeln!(out, "{h}").ok();
    }
    let legs = leg_tracks(log);
    if !legs.is_empty() {
        for l in &legs {
            writeln!(
                out,
                "leg {} ({:.1} m): cross-track est RMS {:.3} m max {:.3} m | true path straightness RMS {:.3} m max {:.3} m",
                l.index, l.length_m, l.est_rms_m, l.est_max_m, l.true_rms_m, l.true_max_m
            )
            .ok();
        }
        let t = track_summary(&legs);
        writeln!(
            out,
            "all {} legs: cross-track est RMS {:.3} m max {:.3} m | true RMS {:.3} m max {:.3} m",
            t.legs, t.est_rms_m, t.est_max_m, t.true_rms_m, t.true_max_m
        )
        .ok();
    }
    if log.plan_kind == "elevator" {
        let v = vertical_error(log, ELEVATOR_SETTLE_S);
        writeln!(
            out,
            "vertical (carried, no GPS): estimate error RMS {:.3} m max {:.3} m | barometer alone RMS {:.3} m | noise (1 s high-pass σ) estimate {:.3} m vs barometer {:.3} m",
            v.est_rms_m, v.est_max_m, v.baro_rms_m, v.est_noise_m, v.baro_noise_m
        )
        .ok();
    }
    if !log.ranges.is_empty() {
        writeln!(out, "ground altitude (height above ground, vs truth):").ok();
        writeln!(
            out,
            "  {:<28} {:>9} {:>9} {:>12}",
            "method", "RMS m", "max m", "diverged s"
        )
        .ok();
        for (name, g) in ground_comparison(log) {
            writeln!(
                out,
                "  {:<28} {:>9.3} {:>9.3} {:>12.1}",
                name, g.rms_m, g.max_m, g.diverged_s
            )
            .ok();
        }
    }
    let a = attitude_error(log, true);
    if a.samples > 0 {
        writeln!(
            out,
            "attitude est vs truth (airborne): RMS roll {:.3}° pitch {:.3}° yaw {:.3}° | max {:.2}° {:.2}° {:.2}°",
            a.rms_deg[0], a.rms_deg[1], a.rms_deg[2], a.max_deg[0], a.max_deg[1], a.max_deg[2]
        )
        .ok();
    }
    let o = observer_noise(log);
    if o.samples > 0 {
        writeln!(
            out,
            "acceleration observer: std(est − truth) {:.3} m/s² vs raw accelerometer {:.3} m/s² (ratio {:.3})",
            o.observer_std_mps2,
            o.raw_std_mps2,
            o.observer_std_mps2 / o.raw_std_mps2
        )
        .ok();
    }
    if log.plan_kind != "elevator" && log.plan_kind != "rig" {
        writeln!(out, "{}", super::truth::report(log)).ok();
    }
    for (t, e) in &log.events {
        writeln!(out, "  t={t:7.2} s  {e}").ok();
    }
    out
}

/// Error of a height-above-ground estimate against the truth.
#[derive(Clone, Copy, Debug, Default)]
pub struct GroundStats {
    pub samples: usize,
    pub rms_m: f64,
    pub max_m: f64,
    /// Time with |error| > [`DIVERGED_M`].
    pub diverged_s: f64,
}

/// An estimate this far off counts as diverged.
pub const DIVERGED_M: f64 = 0.5;

fn ground_stats(errs: &[(f64, f64)]) -> GroundStats {
    let e: Vec<f64> = errs.iter().map(|x| x.1).collect();
    let mut diverged = 0.0;
    for w in errs.windows(2) {
        if w[1].1.abs() > DIVERGED_M {
            diverged += w[1].0 - w[0].0;
        }
    }
    GroundStats {
        samples: e.len(),
        rms_m: rms(&e),
        max_m: max_abs(&e),
        diverged_s: diverged,
    }
}

/// Paper B's comparison on the same data (after the navigation has calibrated, `from_s`):
/// the laser alone and the sonar alone (latest raw reading, as the paper plots them), the
/// paper's own filter (fixed 2 m switch, `fcc_nav::ground_altitude::PaperSwitchFilter`), and
/// the flight core's fusion (`NavState::ground`), each against the true height above ground.
pub fn ground_comparison_from(log: &FlightLog, from_s: f64) -> Vec<(&'static str, GroundStats)> {
    use fcc_nav::ground_altitude::{PaperSwitchFilter, PaperSwitchParams};
    let (mut laser, mut sonar, mut paper) = (Vec::new(), Vec::new(), Vec::new());
    let mut pf = PaperSwitchFilter::new(PaperSwitchParams::default());
    let (mut last_l, mut last_s) = (None, None);
    for r in log.ranges.iter().filter(|r| r.t_s >= from_s) {
        if r.laser {
            last_l = Some(r.range_m);
        } else {
            last_s = Some(r.range_m);
        }
        if let Some(l) = last_l {
            laser.push((r.t_s, l as f64 - r.true_agl_m));
        }
        if let Some(s) = last_s {
            sonar.push((r.t_s, s as f64 - r.true_agl_m));
        }
        if let (Some(l), Some(s)) = (last_l, last_s) {
            paper.push((r.t_s, pf.step(l, s) as f64 - r.true_agl_m));
        }
    }
    let ours: Vec<(f64, f64)> = log
        .samples
        .iter()
        .filter(|s| s.t_s >= from_s && s.nav.calibrated)
        .map(|s| (s.t_s, s.nav.ground.height_m as f64 - s.true_agl_m))
        .collect();
    vec![
        ("laser alone", ground_stats(&laser)),
        ("sonar alone", ground_stats(&sonar)),
        ("paper B (fixed 2 m switch)", ground_stats(&paper)),
        ("ours (gated Kalman fusion)", ground_stats(&ours)),
    ]
}

/// [`ground_comparison_from`] after the ground calibration.
pub fn ground_comparison(log: &FlightLog) -> Vec<(&'static str, GroundStats)> {
    ground_comparison_from(log, ELEVATOR_SETTLE_S)
}
