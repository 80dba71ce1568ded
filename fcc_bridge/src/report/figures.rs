//! The flight's figures from a bag, computed like the flight core's metrics
//! (`fcc_sim::metrics`) but from the recorded ROS topics (ENU → NED).

pub use super::series::{decode, Series};
use fcc_msgs::ros::Status;
use serde::Serialize;

fn rms(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}
fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}
/// Signed distance of `p` from the line a→b (as `metrics::cross_track`).
pub fn cross_track(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let n = (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-9);
    ((p[0] - a[0]) * d[1] - (p[1] - a[1]) * d[0]) / n
}

#[derive(Clone, Debug, Serialize)]
pub struct Leg {
    pub index: usize,
    pub t0_s: f64,
    pub t1_s: f64,
    pub from_ned_m: [f64; 3],
    pub to_ned_m: [f64; 3],
    pub length_m: f64,
    pub samples: usize,
    pub est_rms_m: f64,
    pub est_max_m: f64,
}

/// The mission's legs with their time windows: the follower re-run on the recorded odometry
/// from the odom at which the mission computer sent its first arm command (its first update).
pub fn legs(s: &Series, mission: &fcc_mission::Mission) -> Vec<Leg> {
    let Some(t_arm) = s.first_arm_cmd else {
        return Vec::new();
    };
    // The odom the driver answered with the arm command: the last one at or before it (log
    // time ≥ stamp, so compare stamps to the receive time of the command).
    let start = s
        .odom
        .iter()
        .rposition(|o| o.0 <= t_arm + 1e-9)
        .unwrap_or(0);
    let mut f = fcc_mission::WaypointFollower::new(mission.clone());
    let mut cur: Option<(usize, f64, [f64; 3], [f64; 3], Vec<f64>)> = None;
    let mut out: Vec<Leg> = Vec::new();
    let close = |c: (usize, f64, [f64; 3], [f64; 3], Vec<f64>), t1: f64, out: &mut Vec<Leg>| {
        let (index, t0, a, b, e) = c;
        let length = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        if e.len() > 10 && length > 1.0 {
            out.push(Leg {
                index,
                t0_s: t0,
                t1_s: t1,
                from_ned_m: a,
                to_ned_m: b,
                length_m: length,
                samples: e.len(),
                est_rms_m: rms(&e),
                est_max_m: max_abs(&e),
            });
        }
    };
    for o in &s.odom[start..] {
        let (t, p, v, _) = *o;
        let g = f.update(
            t,
            [p[0] as f32, p[1] as f32, p[2] as f32],
            [v[0] as f32, v[1] as f32, v[2] as f32],
        );
        let leg = match (g.phase, g.leg) {
            (fcc_mission::Phase::Leg(i), Some(l)) => Some((i, l)),
            _ => None,
        };
        match (leg, cur.as_mut()) {
            (Some((i, _)), Some(c)) if c.0 == i => c.4.push(cross_track(
                [p[0], p[1]],
                [c.2[0], c.2[1]],
                [c.3[0], c.3[1]],
            )),
            (l, _) => {
                if let Some(c) = cur.take() {
                    close(c, t, &mut out);
                }
                if let Some((i, l)) = l {
                    let a = l.from_ned_m.map(|x| x as f64);
                    let b = l.to_ned_m.map(|x| x as f64);
                    cur = Some((
                        i,
                        t,
                        a,
                        b,
                        vec![cross_track([p[0], p[1]], [a[0], a[1]], [b[0], b[1]])],
                    ));
                }
            }
        }
    }
    if let Some(c) = cur.take() {
        let t = s.odom.last().map_or(0.0, |o| o.0);
        close(c, t, &mut out);
    }
    out
}

/// A hover must last this long to count (s).
pub const MIN_HOVER_S: f64 = 10.0;

/// The hover (paper A Fig. 16) and its box, defined as the flight core's hover test does
/// (`fcc_sim::metrics::hover_box`, `tests/tests/flight_core.rs`): the window is the
/// time the MCU holds position in HOLD mode while armed; the hold point is the estimated
/// position where the hold began (the MCU holds that point); the box is the largest
/// |estimate − hold point| per axis (N, E, altitude) over the window.
#[derive(Clone, Debug, Serialize)]
pub struct Hover {
    /// Window [t0, t1) in the bag's clock (s).
    pub t0_s: f64,
    pub t1_s: f64,
    /// What fixed each edge: `cmd/mode hold`, `cmd/mode land`, `setpoint`, or `status` (the
    /// first/last status reporting HOLD: the edge is known to a status period only).
    pub start_from: String,
    pub end_from: String,
    /// Status period around the edges (s): the uncertainty of a `status` edge.
    pub status_period_s: f64,
    /// Estimated position at the first odometry of the window (NED, m).
    pub hold_ned_m: [f64; 3],
    pub samples: usize,
    /// max |est − hold point| N, E, altitude (m).
    pub box_m: [f64; 3],
    /// Largest estimated speed per axis in the window (m/s), for judging edge effects.
    pub max_speed_mps: [f64; 3],
}

/// Finds the hover from the bag alone. The MCU's mode on `status` (HOLD and armed, the longest
/// run lasting ≥ [`MIN_HOVER_S`]) is the authority: it holds whether the hold came from
/// `cmd/mode`, the bridge's `hold` service or a failsafe. `status` comes at 10 Hz, so the mode
/// change lies somewhere between two status messages; an edge is refined to the command that
/// caused it when the bag holds one inside that interval (`cmd/mode` = hold at the start; a
/// mode command or the first velocity setpoint — which resumes velocity mode — at the end:
/// the MCU acts on it within a tick or two), else it is the status message itself (inside the
/// hold: no sample of another mode is counted).
pub fn hover(s: &Series) -> Option<Hover> {
    let st = &s.status;
    let holding = |x: &(f64, bool, u8, bool)| x.1 && x.2 == Status::MODE_HOLD;
    // Runs of consecutive HOLD statuses: (first, last) index.
    let mut runs = Vec::new();
    let mut i = 0;
    while i < st.len() {
        if holding(&st[i]) {
            let j0 = i;
            while i + 1 < st.len() && holding(&st[i + 1]) {
                i += 1;
            }
            runs.push((j0, i));
        }
        i += 1;
    }
    let mut best: Option<Hover> = None;
    for (a, b) in runs {
        let before = if a > 0 {
            st[a - 1].0
        } else {
            f64::NEG_INFINITY
        };
        let after = st.get(b + 1).map_or(f64::INFINITY, |x| x.0);
        let period = if st.len() > 1 {
            (st[st.len() - 1].0 - st[0].0) / (st.len() - 1) as f64
        } else {
            f64::NAN
        };
        let is_hold = |c: &str| matches!(c, "hold" | "loiter" | "position");
        let (t0, start_from) = s
            .mode_cmds
            .iter()
            .filter(|c| is_hold(&c.1) && c.0 > before && c.0 <= st[a].0)
            .map(|c| c.0)
            .next_back()
            .map_or((st[a].0, "status".to_string()), |t| {
                (t, "cmd/mode hold".into())
            });
        let end_cmd = s
            .mode_cmds
            .iter()
            .filter(|c| !is_hold(&c.1) && c.0 >= st[b].0 && c.0 < after)
            .map(|c| (c.0, format!("cmd/mode {}", c.1)))
            .next();
        let end_sp = s
            .setpoint_times
            .iter()
            .find(|&&t| t >= st[b].0 && t < after)
            .map(|&t| (t, "setpoint".to_string()));
        let (t1, end_from) = match (end_cmd, end_sp) {
            (Some(c), Some(p)) => {
                if c.0 <= p.0 {
                    c
                } else {
                    p
                }
            }
            (Some(x), None) | (None, Some(x)) => x,
            (None, None) => (st[b].0, "status".to_string()),
        };
        let win: Vec<_> = s.odom.iter().filter(|o| o.0 >= t0 && o.0 < t1).collect();
        if win.len() < 3 || t1 - t0 < MIN_HOVER_S {
            continue;
        }
        let h = win[0].1;
        let (mut bx, mut vmax) = ([0.0f64; 3], [0.0f64; 3]);
        for o in &win {
            for k in 0..3 {
                bx[k] = bx[k].max((o.1[k] - h[k]).abs());
                vmax[k] = vmax[k].max(o.2[k].abs());
            }
        }
        if best.as_ref().is_some_and(|x| x.t1_s - x.t0_s >= t1 - t0) {
            continue;
        }
        best = Some(Hover {
            t0_s: t0,
            t1_s: t1,
            start_from,
            end_from,
            status_period_s: period,
            hold_ned_m: h,
            samples: win.len(),
            box_m: bx,
            max_speed_mps: vmax,
        });
    }
    best
}

/// Paper A Fig. 13: the MCU's acceleration observer against the measured acceleration, in
/// flight (armed, not landed, estimated altitude > 1 m, as `metrics::observer_noise`). The bag
/// has no truth, so the noise of each is its high-pass part: the deviation from a centred 1 s
/// moving average, N and E pooled; the figure is std(observer) / std(measured) (the flight
/// core's own figure, std(est − truth) / std(raw − truth), is below 0.3).
#[derive(Clone, Debug, Serialize)]
pub struct ObserverFig {
    pub samples: usize,
    pub observer_hp_std_mps2: f64,
    pub measured_hp_std_mps2: f64,
    pub ratio: f64,
}

/// Deviation of each sample from the centred moving average of ±`w` samples (`None` at the
/// ends).
fn high_pass(v: &[f64], w: usize) -> Vec<Option<f64>> {
    let mut c = vec![0.0; v.len() + 1];
    for (i, x) in v.iter().enumerate() {
        c[i + 1] = c[i] + x;
    }
    (0..v.len())
        .map(|i| {
            (i >= w && i + w < v.len())
                .then(|| v[i] - (c[i + w + 1] - c[i - w]) / (2 * w + 1) as f64)
        })
        .collect()
}

pub fn observer(s: &Series) -> Result<ObserverFig, String> {
    if s.accel_obs.is_empty() || s.accel_meas.is_empty() {
        return Err("the bag has no accel/observer and accel/measured topics (recorded by an older bridge); skipped".into());
    }
    let airborne = |t: f64| -> bool {
        let i = s.status.partition_point(|x| x.0 <= t);
        let j = s.odom.partition_point(|o| o.0 <= t);
        i > 0 && s.status[i - 1].1 && !s.status[i - 1].3 && j > 0 && -s.odom[j - 1].1[2] > 1.0
    };
    let hp_std = |series: Vec<(f64, [f64; 2])>| -> (f64, usize) {
        if series.len() < 3 {
            return (f64::NAN, 0);
        }
        let rate = (series.len() - 1) as f64 / (series[series.len() - 1].0 - series[0].0);
        let w = ((0.5 * rate).round() as usize).max(1);
        let mut d = Vec::new();
        for k in 0..2 {
            let v: Vec<f64> = series.iter().map(|x| x.1[k]).collect();
            for (x, h) in series.iter().zip(high_pass(&v, w)) {
                if let Some(h) = h.filter(|_| airborne(x.0)) {
                    d.push(h);
                }
            }
        }
        let n = d.len();
        if n < 2 {
            return (f64::NAN, n / 2);
        }
        let m = d.iter().sum::<f64>() / n as f64;
        let var = d.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64;
        (var.sqrt(), n / 2)
    };
    let (o, n) = hp_std(s.accel_obs.clone());
    let (r, _) = hp_std(
        s.accel_meas
            .iter()
            .map(|x| (x.0, [x.1[0], x.1[1]]))
            .collect(),
    );
    if n < 100 {
        return Err(format!("only {n} airborne samples of accel/observer"));
    }
    Ok(ObserverFig {
        samples: n,
        observer_hp_std_mps2: o,
        measured_hp_std_mps2: r,
        ratio: o / r,
    })
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct Figures {
    pub duration_s: f64,
    pub messages: u64,
    pub topics: std::collections::BTreeMap<String, u64>,
    /// Hover box while in HOLD mode (≥ 10 s): max |est − hold point| N, E, alt (m).
    pub hover_box_m: Option<[f64; 3]>,
    pub hover_s: f64,
    /// The hover window and how it was found ([`hover`]).
    pub hover: Option<Hover>,
    /// Paper A Fig. 13 from `accel/observer` and `accel/measured` ([`observer`]).
    pub observer: Option<ObserverFig>,
    pub legs: Vec<Leg>,
    pub cross_track_rms_m: Option<f64>,
    pub cross_track_max_m: Option<f64>,
    pub velocity_tracking_rms_mps: Option<f64>,
    /// Estimated attitude − accelerometer angles (roll, pitch), RMS deg, airborne.
    pub attitude_vs_accel_rms_deg: Option<[f64; 2]>,
    /// std of the 1 s high-passed fused altitude vs barometer (m).
    pub vertical_noise_m: Option<[f64; 2]>,
    /// ground height − laser, − sonar RMS (m), where both are valid.
    pub ground_vs_laser_sonar_rms_m: Option<[f64; 2]>,
    /// Paper A Fig. 12: k1/k2 with the wind, uncertainty, and the suggestion or why not
    /// ([`super::sysid`]).
    pub sysid: Option<super::sysid::SysId>,
    pub missing: Vec<String>,
}

pub fn compute(s: &Series, mission: Option<&fcc_mission::Mission>) -> Figures {
    let mut f = Figures {
        topics: s.topics.clone(),
        messages: s.topics.values().sum(),
        ..Default::default()
    };
    if let (Some(a), Some(b)) = (s.odom.first(), s.odom.last()) {
        f.duration_s = b.0 - a.0;
    }
    let armed_at = |t: f64| -> (bool, u8) {
        let i = s.status.partition_point(|x| x.0 <= t);
        if i == 0 {
            (false, 0)
        } else {
            (s.status[i - 1].1, s.status[i - 1].2)
        }
    };
    match hover(s) {
        Some(h) => {
            f.hover_box_m = Some(h.box_m);
            f.hover_s = h.t1_s - h.t0_s;
            f.hover = Some(h);
        }
        None => f.missing.push(format!(
            "hover box: no HOLD-mode period ≥ {MIN_HOVER_S} s on status in this flight"
        )),
    }
    match mission {
        Some(m) => {
            f.legs = legs(s, m);
            if !f.legs.is_empty() {
                let n = f.legs.len() as f64;
                f.cross_track_rms_m =
                    Some((f.legs.iter().map(|l| l.est_rms_m.powi(2)).sum::<f64>() / n).sqrt());
                f.cross_track_max_m = Some(f.legs.iter().fold(0.0, |m, l| m.max(l.est_max_m)));
            } else {
                f.missing
                    .push("cross-track: no leg found (no cmd/arm in the bag?)".into());
            }
        }
        None => f
            .missing
            .push("cross-track: pass --mission FILE (the bag has no mission path)".into()),
    }
    // Velocity tracking: commanded vs estimated horizontal velocity at each command.
    let mut e = Vec::new();
    for (t, c) in &s.vel_cmd {
        let i = s.odom.partition_point(|o| o.0 <= *t);
        if i > 0 && i < s.odom.len() {
            let v = s.odom[i].2;
            e.push(((v[0] - c[0]).powi(2) + (v[1] - c[1]).powi(2)).sqrt());
        }
    }
    if !e.is_empty() {
        f.velocity_tracking_rms_mps = Some(rms(&e));
    } else {
        f.missing
            .push("velocity tracking: no setpoints received".into());
    }
    // Attitude vs accelerometer angles (nearest odom), airborne.
    let (mut er, mut ep) = (Vec::new(), Vec::new());
    for (t, r, p) in &s.acc_angles {
        let i = s.odom.partition_point(|o| o.0 <= *t);
        if i > 0 && armed_at(*t).0 {
            let eu = s.odom[i - 1].3;
            er.push((eu[0] - r).to_degrees());
            ep.push((eu[1] - p).to_degrees());
        }
    }
    if !er.is_empty() {
        f.attitude_vs_accel_rms_deg = Some([rms(&er), rms(&ep)]);
    }
    // Vertical: noise of fused altitude vs barometer (1 s centred moving average removed).
    if s.alt.len() > 200 {
        let hp = |v: Vec<f64>| -> f64 {
            let w = 25;
            let d: Vec<f64> = (w..v.len() - w)
                .map(|i| v[i] - v[i - w..i + w].iter().sum::<f64>() / (2 * w) as f64)
                .collect();
            let m = d.iter().sum::<f64>() / d.len() as f64;
            (d.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (d.len() - 1) as f64).sqrt()
        };
        f.vertical_noise_m = Some([
            hp(s.alt.iter().map(|a| a.2).collect()),
            hp(s.alt.iter().map(|a| a.1).collect()),
        ]);
    }
    let (mut gl, mut gs) = (Vec::new(), Vec::new());
    for a in &s.alt {
        if a.4.is_finite() && a.4 > 0.0 {
            gl.push(a.3 - a.4);
        }
        if a.5.is_finite() && a.5 > 0.0 {
            gs.push(a.3 - a.5);
        }
    }
    if !gl.is_empty() || !gs.is_empty() {
        f.ground_vs_laser_sonar_rms_m = Some([rms(&gl), rms(&gs)]);
    }
    // k1/k2 fit (paper A Fig. 12) with the wind estimated from the log (super::sysid).
    match super::sysid::from_series(s) {
        Ok(x) => f.sysid = Some(x),
        Err(why) => f.missing.push(format!("k1/k2 fit (Fig. 12): {why}")),
    }
    match observer(s) {
        Ok(o) => f.observer = Some(o),
        Err(why) => f
            .missing
            .push(format!("observer vs raw acceleration (Fig. 13): {why}")),
    }
    f
}

impl std::fmt::Display for Figures {
    fn fmt(&self, w: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            w,
            "flight: {:.1} s of odometry, {} messages on {} topics",
            self.duration_s,
            self.messages,
            self.topics.len()
        )?;
        if let Some(h) = &self.hover {
            let b = h.box_m;
            writeln!(w, "hover {:.1} s in HOLD ({:.1}–{:.1} s, from {} to {}), estimated position max |dev| from hold point: N {:.3} m  E {:.3} m  alt {:.3} m (paper A: N 0.7, E 1.1, alt 0.3 m)", h.t1_s - h.t0_s, h.t0_s, h.t1_s, h.start_from, h.end_from, b[0], b[1], b[2])?;
        }
        for l in &self.legs {
            writeln!(
                w,
                "leg {} ({:.1} m, {:.1}–{:.1} s): cross-track est RMS {:.3} m max {:.3} m",
                l.index, l.length_m, l.t0_s, l.t1_s, l.est_rms_m, l.est_max_m
            )?;
        }
        if let (Some(r), Some(m)) = (self.cross_track_rms_m, self.cross_track_max_m) {
            writeln!(
                w,
                "all {} legs: cross-track est RMS {:.3} m max {:.3} m",
                self.legs.len(),
                r,
                m
            )?;
        }
        if let Some(v) = self.velocity_tracking_rms_mps {
            writeln!(w, "velocity tracking: |v_est − v_cmd| RMS {v:.3} m/s")?;
        }
        if let Some(a) = self.attitude_vs_accel_rms_deg {
            writeln!(w, "attitude estimate − accelerometer angles (armed): RMS roll {:.2}° pitch {:.2}° (the accelerometer alone is noisy and sees manoeuvres)", a[0], a[1])?;
        }
        if let Some(v) = self.vertical_noise_m {
            writeln!(
                w,
                "vertical: noise (1 s high-pass σ) fused altitude {:.3} m vs barometer {:.3} m",
                v[0], v[1]
            )?;
        }
        if let Some(g) = self.ground_vs_laser_sonar_rms_m {
            writeln!(
                w,
                "ground altitude fusion − laser RMS {:.3} m, − sonar RMS {:.3} m",
                g[0], g[1]
            )?;
        }
        if let Some(o) = &self.observer {
            writeln!(w, "acceleration observer vs measured (in flight, {} samples): high-pass (1 s) σ observer {:.3} m/s² vs measured {:.3} m/s², ratio {:.3} (flight core goal on est − truth: < 0.3)", o.samples, o.observer_hp_std_mps2, o.measured_hp_std_mps2, o.ratio)?;
        }
        if let Some(x) = &self.sysid {
            write!(w, "{x}")?;
        }
        for m in &self.missing {
            writeln!(w, "missing: {m}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 100 Hz odometry with a known path, 10 Hz status in HOLD over [20.014, 50.024) s.
    fn flight(hold_cmd: bool) -> Series {
        let mut s = Series::default();
        let pos = |t: f64| {
            [
                0.1 * (t * 0.7).sin(),
                -0.2 * (t * 0.3).cos(),
                -5.0 + 0.05 * t.sin(),
            ]
        };
        for i in 0..7000 {
            let t = i as f64 * 0.01;
            s.odom.push((t, pos(t), [0.0; 3], [0.0; 3]));
        }
        let (t_hold, t_land) = (20.014, 50.024);
        for i in 0..700 {
            let t = i as f64 * 0.1 + 0.005;
            let mode = if t < 5.0 {
                Status::MODE_DISARMED
            } else if (t_hold..t_land).contains(&t) {
                Status::MODE_HOLD
            } else if t < t_hold {
                Status::MODE_VELOCITY
            } else {
                Status::MODE_LAND
            };
            s.status.push((t, t >= 5.0, mode, false));
        }
        if hold_cmd {
            s.mode_cmds.push((t_hold, "hold".into()));
            s.mode_cmds.push((t_land, "land".into()));
        }
        s
    }

    #[test]
    fn hover_window_from_status_refined_by_the_commands() {
        let s = flight(true);
        let h = hover(&s).expect("hover");
        assert_eq!((h.t0_s, h.t1_s), (20.014, 50.024));
        assert_eq!(h.start_from, "cmd/mode hold");
        assert_eq!(h.end_from, "cmd/mode land");
        // Same definition as metrics::hover_box: first sample of the window is the hold point.
        let win: Vec<_> = s
            .odom
            .iter()
            .filter(|o| o.0 >= 20.014 && o.0 < 50.024)
            .collect();
        assert_eq!(h.hold_ned_m, win[0].1);
        for k in 0..3 {
            let want = win
                .iter()
                .fold(0.0f64, |m, o| m.max((o.1[k] - win[0].1[k]).abs()));
            assert_eq!(h.box_m[k], want);
        }
    }

    #[test]
    fn hover_window_from_status_alone_stays_inside_the_hold() {
        let h = hover(&flight(false)).expect("hover");
        assert_eq!(
            (h.start_from.as_str(), h.end_from.as_str()),
            ("status", "status")
        );
        assert!(h.t0_s >= 20.014 && h.t0_s < 20.014 + 0.1, "{}", h.t0_s);
        assert!(h.t1_s <= 50.024 && h.t1_s > 50.024 - 0.1, "{}", h.t1_s);
    }

    #[test]
    fn short_hold_is_no_hover_and_old_bags_skip_the_observer() {
        let mut s = flight(true);
        for x in s.status.iter_mut().filter(|x| x.0 > 25.0 && x.0 < 26.0) {
            x.2 = Status::MODE_VELOCITY; // splits the hold into 5 s and 24 s
        }
        let h = hover(&s).expect("the longer part");
        assert!(h.t0_s > 25.0 && h.t1_s == 50.024);
        s.status
            .iter_mut()
            .for_each(|x| x.2 = Status::MODE_VELOCITY);
        assert!(hover(&s).is_none());
        let e = observer(&s).unwrap_err();
        assert!(e.contains("no accel/observer"), "{e}");
    }

    #[test]
    fn high_pass_removes_the_slow_part() {
        let v: Vec<f64> = (0..1000)
            .map(|i| 0.01 * i as f64 + if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let h = high_pass(&v, 50);
        assert!(h[..50].iter().all(|x| x.is_none()) && h[950..].iter().all(|x| x.is_none()));
        for x in h[50..950].iter().flatten() {
            assert!((x.abs() - 1.0).abs() < 0.02, "{x}");
        }
    }
}
