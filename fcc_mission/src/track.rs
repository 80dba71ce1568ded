//! Cross-track report of a flown mission from `fcc-sitl --csv` (the 50 Hz truth/estimate log),
//! for flights whose mission ran outside the simulator (the full stack: `fcc-sitl --link-pty` +
//! `fcc-bridge` + `fcc-mission`), where the simulator does not know the legs.
//!
//! Legs are rebuilt from the mission (home = estimated position at arming) and samples are
//! assigned to a leg while the MCU's horizontal velocity command points along it (within 10°,
//! faster than 0.3 m/s). Cross-track is the horizontal distance to the leg line, for the
//! estimated position (against legs from the estimated home) and for the true position (against
//! the same legs from the true home).

use crate::Mission;

/// Per-leg figures.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LegTrack {
    pub index: usize,
    pub length_m: f64,
    pub samples: usize,
    pub est_rms_m: f64,
    pub est_max_m: f64,
    pub true_rms_m: f64,
    pub true_max_m: f64,
    /// RMS distance of the true positions from their own best-fit line (path straightness,
    /// free of the GPS error the estimate and the flown leg share).
    pub true_straight_rms_m: f64,
}

/// Whole-flight figures.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrackReport {
    pub legs: Vec<LegTrack>,
    pub armed_s: f64,
    pub first_armed_s: f64,
    pub est_rms_m: f64,
    pub est_max_m: f64,
    pub true_rms_m: f64,
    pub true_max_m: f64,
    /// Largest horizontal distance of the true end position from home, m.
    pub landed_from_home_m: f64,
}

impl std::fmt::Display for TrackReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for l in &self.legs {
            writeln!(
                f,
                "leg {} ({:.1} m, {} samples): cross-track est RMS {:.3} m max {:.3} m | true vs ideal leg RMS {:.3} m max {:.3} m | true path straightness RMS {:.3} m",
                l.index, l.length_m, l.samples, l.est_rms_m, l.est_max_m, l.true_rms_m, l.true_max_m, l.true_straight_rms_m
            )?;
        }
        writeln!(
            f,
            "all {} legs: cross-track est RMS {:.3} m max {:.3} m | true vs ideal leg RMS {:.3} m max {:.3} m (includes the GPS error)",
            self.legs.len(),
            self.est_rms_m,
            self.est_max_m,
            self.true_rms_m,
            self.true_max_m
        )?;
        write!(
            f,
            "armed {:.1} s (from t={:.1} s); landed {:.2} m from home (truth)",
            self.armed_s, self.first_armed_s, self.landed_from_home_m
        )
    }
}

struct Row {
    t: f64,
    armed: bool,
    tru: [f64; 3],
    est: [f64; 3],
    cmd: [f64; 2],
}

fn parse(csv: &str) -> Result<Vec<Row>, String> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().ok_or("empty CSV")?.split(',').collect();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| *h == n)
            .ok_or(format!("CSV has no column '{n}'"))
    };
    let c = [
        col("t_s")?,
        col("armed")?,
        col("true_n_m")?,
        col("true_e_m")?,
        col("true_d_m")?,
        col("est_n_m")?,
        col("est_e_m")?,
        col("est_d_m")?,
        col("vel_cmd_n_mps")?,
        col("vel_cmd_e_mps")?,
    ];
    let mut rows = Vec::new();
    for (i, l) in lines.enumerate() {
        let f: Vec<&str> = l.split(',').collect();
        let g = |k: usize| -> Result<f64, String> {
            f.get(c[k])
                .and_then(|s| s.trim().parse::<f64>().ok())
                .ok_or(format!(
                    "CSV line {}: bad value in column {}",
                    i + 2,
                    header[c[k]]
                ))
        };
        rows.push(Row {
            t: g(0)?,
            armed: g(1)? != 0.0,
            tru: [g(2)?, g(3)?, g(4)?],
            est: [g(5)?, g(6)?, g(7)?],
            cmd: [g(8)?, g(9)?],
        });
    }
    Ok(rows)
}

fn cross(from: [f64; 2], to: [f64; 2], p: [f64; 2]) -> Option<f64> {
    let d = [to[0] - from[0], to[1] - from[1]];
    let len = d[0].hypot(d[1]);
    let q = [p[0] - from[0], p[1] - from[1]];
    let along = (q[0] * d[0] + q[1] * d[1]) / len;
    if !(0.0..=len).contains(&along) {
        return None;
    }
    Some((q[0] * d[1] - q[1] * d[0]).abs() / len)
}

/// RMS distance of points from their total-least-squares line.
fn straightness(p: &[[f64; 2]]) -> f64 {
    if p.len() < 3 {
        return 0.0;
    }
    let n = p.len() as f64;
    let m = [
        p.iter().map(|q| q[0]).sum::<f64>() / n,
        p.iter().map(|q| q[1]).sum::<f64>() / n,
    ];
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for q in p {
        let (x, y) = (q[0] - m[0], q[1] - m[1]);
        sxx += x * x;
        syy += y * y;
        sxy += x * y;
    }
    // Smallest eigenvalue of the scatter matrix = sum of squared perpendicular distances.
    let tr = sxx + syy;
    let det = sxx * syy - sxy * sxy;
    let lmin = 0.5 * (tr - (tr * tr - 4.0 * det).max(0.0).sqrt());
    (lmin.max(0.0) / n).sqrt()
}

/// Analyse a `fcc-sitl --csv` log of a flight of `mission`.
pub fn report(csv: &str, mission: &Mission) -> Result<TrackReport, String> {
    let rows = parse(csv)?;
    let armed: Vec<&Row> = rows.iter().filter(|r| r.armed).collect();
    let (first, last) = match (armed.first(), armed.last()) {
        (Some(a), Some(b)) => (a, b),
        _ => return Err("the vehicle never armed".into()),
    };
    let (home_est, home_true) = ([first.est[0], first.est[1]], [first.tru[0], first.tru[1]]);
    // Horizontal legs (relative to home): from the takeoff point (above home) to wp 0, ...
    let mut pts = vec![[0.0, 0.0]];
    pts.extend(
        mission
            .waypoints
            .iter()
            .map(|w| [w.north_m as f64, w.east_m as f64]),
    );
    let mut legs: Vec<LegTrack> = Vec::new();
    let mut acc: Vec<(f64, f64, f64, f64)> = Vec::new(); // est sum_sq, est max, true sum_sq, true max
    for i in 0..mission.waypoints.len() {
        let length_m = (pts[i + 1][0] - pts[i][0]).hypot(pts[i + 1][1] - pts[i][1]);
        legs.push(LegTrack {
            index: i,
            length_m,
            ..Default::default()
        });
        acc.push((0.0, 0.0, 0.0, 0.0));
    }
    let mut pts_true: Vec<Vec<[f64; 2]>> = vec![Vec::new(); legs.len()];
    let mut k = 0usize;
    for r in &armed {
        let sp = r.cmd[0].hypot(r.cmd[1]);
        if sp < 0.3 {
            continue;
        }
        let along = |i: usize| -> bool {
            let d = [pts[i + 1][0] - pts[i][0], pts[i + 1][1] - pts[i][1]];
            let len = d[0].hypot(d[1]);
            len > 1.0 && (r.cmd[0] * d[0] + r.cmd[1] * d[1]) / (len * sp) > 10f64.to_radians().cos()
        };
        let i = if k < legs.len() && along(k) {
            k
        } else if k + 1 < legs.len() && along(k + 1) {
            k += 1;
            k
        } else {
            continue;
        };
        let rel = |h: [f64; 2], p: [f64; 3]| [p[0] - h[0], p[1] - h[1]];
        let (Some(e), Some(t)) = (
            cross(pts[i], pts[i + 1], rel(home_est, r.est)),
            cross(pts[i], pts[i + 1], rel(home_true, r.tru)),
        ) else {
            continue;
        };
        let a = &mut acc[i];
        a.0 += e * e;
        a.1 = a.1.max(e);
        a.2 += t * t;
        a.3 = a.3.max(t);
        legs[i].samples += 1;
        pts_true[i].push([r.tru[0], r.tru[1]]);
    }
    for (l, p) in legs.iter_mut().zip(&pts_true) {
        l.true_straight_rms_m = straightness(p);
    }
    let mut rep = TrackReport {
        armed_s: last.t - first.t,
        first_armed_s: first.t,
        ..Default::default()
    };
    let (mut n, mut se, mut st) = (0usize, 0.0, 0.0);
    for (l, a) in legs.iter_mut().zip(&acc) {
        if l.samples > 0 {
            l.est_rms_m = (a.0 / l.samples as f64).sqrt();
            l.true_rms_m = (a.2 / l.samples as f64).sqrt();
        }
        l.est_max_m = a.1;
        l.true_max_m = a.3;
        n += l.samples;
        se += a.0;
        st += a.2;
        rep.est_max_m = rep.est_max_m.max(a.1);
        rep.true_max_m = rep.true_max_m.max(a.3);
    }
    if n > 0 {
        rep.est_rms_m = (se / n as f64).sqrt();
        rep.true_rms_m = (st / n as f64).sqrt();
    }
    let end = rows.last().map(|r| r.tru).unwrap_or(first.tru);
    rep.landed_from_home_m = (end[0] - home_true[0]).hypot(end[1] - home_true[1]);
    rep.legs = legs;
    Ok(rep)
}
