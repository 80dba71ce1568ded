//! The flight's figures from a bag, computed like the flight core's metrics
//! (`fcc_firmware::sitl::metrics`) but from the recorded ROS topics (ENU → NED).

use fcc_bridge::record::from_cdr;
use fcc_bridge::report::bag::{euler, odom_ned, BagMsg};
use fcc_bridge::ros_types::*;
use serde::Serialize;

/// Decoded time series (t in s of ROS time).
#[derive(Default)]
pub struct Series {
    /// t, pos NED, vel NED, euler (roll, pitch, yaw).
    pub odom: Vec<(f64, [f64; 3], [f64; 3], [f64; 3])>,
    /// t, accelerometer roll/pitch (rad) from imu/data_raw.
    pub acc_angles: Vec<(f64, f64, f64)>,
    /// t, baro altitude, fused altitude, ground height, laser, sonar.
    pub alt: Vec<(f64, f64, f64, f64, f64, f64)>,
    /// t, commanded velocity NED (received setpoints).
    pub vel_cmd: Vec<(f64, [f64; 3])>,
    /// t, armed, mode.
    pub status: Vec<(f64, bool, u8)>,
    /// first cmd/arm receive time.
    pub first_arm_cmd: Option<f64>,
    pub topics: std::collections::BTreeMap<String, u64>,
}

fn t_of(h: &Header) -> f64 {
    h.stamp.to_nanos() as f64 * 1e-9
}

pub fn decode(msgs: &[BagMsg]) -> Series {
    let mut s = Series::default();
    for m in msgs {
        *s.topics.entry(m.topic.clone()).or_default() += 1;
        let log_t = m.log_time as f64 * 1e-9;
        match (m.schema.as_str(), m.topic.rsplit('/').next().unwrap_or("")) {
            ("nav_msgs/msg/Odometry", _) => {
                if let Some(o) = from_cdr::<Odometry>(&m.data) {
                    let (p, v, q) = odom_ned(&o);
                    s.odom.push((t_of(&o.header), p, v, euler(q)));
                }
            }
            ("sensor_msgs/msg/Imu", "data_raw") => {
                if let Some(i) = from_cdr::<Imu>(&m.data) {
                    let a = i.linear_acceleration.to_array(); // FLU specific force
                    let roll = a[1].atan2(a[2]);
                    let pitch = a[0].atan2(a[1].hypot(a[2]));
                    s.acc_angles.push((t_of(&i.header), roll, pitch));
                }
            }
            ("fcc_msgs/msg/Altitude", _) => {
                if let Some(a) = from_cdr::<Altitude>(&m.data) {
                    s.alt.push((
                        t_of(&a.header),
                        a.baro_alt_m as f64,
                        a.alt_m as f64,
                        a.ground_height_m as f64,
                        a.laser_range_m as f64,
                        a.sonar_range_m as f64,
                    ));
                }
            }
            ("geometry_msgs/msg/TwistStamped", _) => {
                if let Some(tw) = from_cdr::<TwistStamped>(&m.data) {
                    let v = tw.twist.linear.to_array();
                    s.vel_cmd.push((log_t, [v[1], v[0], -v[2]]));
                }
            }
            ("fcc_msgs/msg/Status", _) => {
                if let Some(st) = from_cdr::<Status>(&m.data) {
                    s.status.push((t_of(&st.header), st.armed, st.mode));
                }
            }
            ("std_msgs/msg/Bool", "arm") => {
                if from_cdr::<Bool>(&m.data).is_some_and(|b| b.data) && s.first_arm_cmd.is_none() {
                    s.first_arm_cmd = Some(log_t);
                }
            }
            _ => {}
        }
    }
    s.odom.sort_by(|a, b| a.0.total_cmp(&b.0));
    s
}

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

#[derive(Clone, Debug, Default, Serialize)]
pub struct Figures {
    pub duration_s: f64,
    pub messages: u64,
    pub topics: std::collections::BTreeMap<String, u64>,
    /// Hover box while in HOLD mode (≥ 10 s): max |est − hold point| N, E, alt (m).
    pub hover_box_m: Option<[f64; 3]>,
    pub hover_s: f64,
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
    /// k1 (m/s² per rad), k2 (1/s), R², samples.
    pub k1_k2_fit: Option<(f64, f64, f64, u32)>,
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
    // Hover box (HOLD mode while armed).
    let hold: Vec<_> = s
        .odom
        .iter()
        .filter(|o| {
            let (a, m) = armed_at(o.0);
            a && m == Status::MODE_HOLD
        })
        .collect();
    if hold.len() > 2 && hold.last().unwrap().0 - hold[0].0 >= 10.0 {
        let h = hold[0].1;
        let mut b = [0.0f64; 3];
        for o in &hold {
            for k in 0..3 {
                b[k] = b[k].max((o.1[k] - h[k]).abs());
            }
        }
        f.hover_box_m = Some(b);
        f.hover_s = hold.last().unwrap().0 - hold[0].0;
    } else {
        f.missing
            .push("hover box: no HOLD-mode period ≥ 10 s in this flight".into());
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
    // k1/k2 fit (paper A Fig. 12): a = k1·tilt − k2·v per horizontal body-heading axis.
    let mut fit = fcc_nav::sysid::PlaneFit::new();
    let o = &s.odom;
    for i in 5..o.len().saturating_sub(5) {
        let dt = o[i + 5].0 - o[i - 5].0;
        if dt <= 0.0 || !armed_at(o[i].0).0 || -o[i].1[2] < 1.0 {
            continue;
        }
        let yaw = o[i].3[2];
        let (c, sn) = (yaw.cos(), yaw.sin());
        let h = |v: [f64; 3]| [c * v[0] + sn * v[1], -sn * v[0] + c * v[1]];
        let v = h(o[i].2);
        let a0 = h(o[i - 5].2);
        let a1 = h(o[i + 5].2);
        let acc = [(a1[0] - a0[0]) / dt, (a1[1] - a0[1]) / dt];
        let (roll, pitch) = (o[i].3[0], o[i].3[1]);
        fit.add(-pitch as f32, v[0] as f32, acc[0] as f32);
        fit.add(roll as f32, v[1] as f32, acc[1] as f32);
    }
    if let Some(r) = fit.solve() {
        f.k1_k2_fit = Some((
            r.k1_mps2_per_rad as f64,
            r.k2_per_s as f64,
            r.r_squared as f64,
            fit.count(),
        ));
    }
    f.missing.push("observer vs raw acceleration (Fig. 13): the link carries no observer acceleration, so the bag cannot show it (fcc-sitl's CSV has it)".into());
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
        if let Some(b) = self.hover_box_m {
            writeln!(w, "hover {:.0} s, estimated position max |dev| from hold point: N {:.3} m  E {:.3} m  alt {:.3} m", self.hover_s, b[0], b[1], b[2])?;
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
        if let Some((k1, k2, r2, n)) = self.k1_k2_fit {
            writeln!(w, "k1/k2 fit (a = k1·tilt − k2·v, {n} samples): k1 = {k1:.3} m/s²/rad, k2 = {k2:.3} 1/s, R² = {r2:.3} → suggested params: k1_mps2_per_rad = {k1:.2}, k2_per_s = {k2:.3}")?;
        }
        for m in &self.missing {
            writeln!(w, "missing: {m}")?;
        }
        Ok(())
    }
}
