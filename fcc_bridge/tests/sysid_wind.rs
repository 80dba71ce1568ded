//! Acceptance of fcc-report's k1/k2 fit in a wind (issue 13 point 8), on synthetic flights with
//! a known k1/k2: a vehicle obeying paper A's model `a = k1·θ − k2·(v − w)` flies a square
//! with stops under a velocity controller with integral action (which leans into the wind, as
//! the flight core does), in a wind made of a constant, a slow swing and gusts, with noisy
//! attitude, velocity and accelerometer. The flight is turned into the decoded bag series
//! (`state/odom` Euler angles with the heading along each leg, `accel/measured`, the
//! velocity setpoints, `status`) and fitted by `fcc_bridge::report::sysid::from_series`, exactly as
//! `fcc-report` does on a bag.
//!
//! `cargo test --release -p fcc_bridge --test sysid_wind -- --nocapture` prints the fits.

use fcc_bridge::report::figures::Series;
use fcc_bridge::report::sysid;

/// The calm-air fit of the simulated octorotor (tests/tests/sysid.rs) — the truth here.
const K1: f64 = 10.14;
const K2: f64 = 0.28;

/// xorshift64* with Box–Muller normals (deterministic, no crates).
struct Rng(u64);
impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }
    fn normal(&mut self, std: f64) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos() * std
    }
}

struct Flight {
    /// Mean wind N, E (m/s): the air's velocity.
    wind_ne_mps: [f64; 2],
    /// Amplitude of the slow swing of the wind (m/s, period 80 s) and σ of the gusts (m/s,
    /// first-order, 2 s correlation time).
    swing_mps: f64,
    gust_mps: f64,
    /// Speed on the legs (m/s); 0 = hover in place.
    cruise_mps: f64,
    /// σ of the accelerometer's noise (m/s²).
    accel_noise_mps2: f64,
    duration_s: f64,
    seed: u64,
}

/// Simulates the flight at 500 Hz and records the series at 50 Hz (the bridge's odometry rate
/// order of magnitude); returns it with the true mean wind over the airborne part.
fn fly(f: &Flight) -> (Series, [f64; 2]) {
    let mut rng = Rng(f.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let dt = 0.002;
    let (mut v, mut th, mut p) = ([0.0f64; 2], [0.0f64; 2], [0.0f64; 2]);
    let mut integ = [0.0f64; 2];
    let mut gust = [0.0f64; 2];
    let mut yaw: f64 = 0.0;
    let mut s = Series::default();
    let mut wind_sum = [0.0f64; 2];
    let steps = (f.duration_s / dt) as usize;
    // Square of 20 m legs: N, E, S, W; each leg is flown at cruise, then 5 s of stop.
    let leg_dirs = [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]];
    let leg_s = if f.cruise_mps > 0.0 {
        20.0 / f.cruise_mps
    } else {
        1.0
    };
    for i in 0..steps {
        let t = i as f64 * dt;
        // Wind: constant + slow swing + first-order gusts.
        for g in gust.iter_mut() {
            *g += -*g / 2.0 * dt + f.gust_mps * (2.0 * dt / 2.0).sqrt() * rng.normal(1.0);
        }
        let swing = f.swing_mps * (std::f64::consts::TAU * t / 80.0).sin();
        let w = [
            f.wind_ne_mps[0] + swing + gust[0],
            f.wind_ne_mps[1] + 0.5 * swing + gust[1],
        ];
        // Mission: legs then stops; heading along the leg.
        let cycle = t % (leg_s + 5.0);
        let leg = (t / (leg_s + 5.0)) as usize % 4;
        let v_cmd = if cycle < leg_s {
            [
                leg_dirs[leg][0] * f.cruise_mps,
                leg_dirs[leg][1] * f.cruise_mps,
            ]
        } else {
            [0.0; 2]
        };
        if f.cruise_mps > 0.0 {
            let want = f64::atan2(leg_dirs[leg][1], leg_dirs[leg][0]);
            let e = (want - yaw + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            yaw += e.clamp(-0.8 * dt, 0.8 * dt);
        }
        // Velocity controller (PI) → acceleration → tilt with a slightly wrong model, tilt
        // limit 0.35 rad, tilt lag 0.1 s.
        for j in 0..2 {
            let e = v_cmd[j] - v[j];
            integ[j] = (integ[j] + 0.4 * e * dt).clamp(-1.5, 1.5);
            let a_cmd = (1.2 * e + integ[j]).clamp(-3.0, 3.0);
            let th_cmd = ((a_cmd + 0.25 * v[j]) / 9.0).clamp(-0.35, 0.35);
            th[j] += (th_cmd - th[j]) * dt / 0.1;
        }
        let a = [0, 1].map(|j| K1 * th[j] - K2 * (v[j] - w[j]));
        if i % 10 == 0 {
            // 50 Hz record: estimated attitude/velocity with noise, accelerometer with noise.
            let th_m = [th[0] + rng.normal(0.003), th[1] + rng.normal(0.003)];
            let (sy, cy) = yaw.sin_cos();
            let fwd = cy * th_m[0] + sy * th_m[1];
            let right = -sy * th_m[0] + cy * th_m[1];
            let (roll, pitch) = (right, -fwd);
            let v_m = [v[0] + rng.normal(0.03), v[1] + rng.normal(0.03), 0.0];
            s.odom
                .push((t, [p[0], p[1], -5.0], v_m, [roll, pitch, yaw]));
            s.accel_meas.push((
                t,
                [
                    a[0] + rng.normal(f.accel_noise_mps2),
                    a[1] + rng.normal(f.accel_noise_mps2),
                    0.0,
                ],
            ));
            // The mission's velocity setpoints (fcc-mission sends them at 50 Hz too).
            s.vel_cmd.push((t, [v_cmd[0], v_cmd[1], 0.0]));
            s.setpoint_times.push(t);
            wind_sum[0] += w[0];
            wind_sum[1] += w[1];
        }
        // Integrate after recording: the record holds tilt, velocity and acceleration of the
        // same instant.
        for j in 0..2 {
            v[j] += a[j] * dt;
            p[j] += v[j] * dt;
        }
        if i % 50 == 0 {
            s.status.push((t, true, 2, false));
        }
    }
    let n = s.odom.len() as f64;
    (s, [wind_sum[0] / n, wind_sum[1] / n])
}

fn windy() -> Flight {
    Flight {
        wind_ne_mps: [0.0, -3.0], // the air moves west at 3 m/s: wind from 090°
        swing_mps: 0.5,
        gust_mps: 0.3,
        cruise_mps: 3.0,
        accel_noise_mps2: 0.3,
        duration_s: 300.0,
        seed: 3,
    }
}

#[test]
fn windy_square_the_wind_term_removes_the_bias() {
    let (s, wind) = fly(&windy());
    let r = sysid::from_series(&s).expect("fit");
    println!("true mean wind N {:.2} E {:.2} m/s\n{r}", wind[0], wind[1]);
    // Paper A's plain fit is biased by the wind (the defect of issue 13 point 8).
    let [k1p, _, _] = r.no_wind_fit.expect("plain fit");
    assert!((k1p - K1).abs() > 0.2 * K1, "plain k1 {k1p}");
    // With the wind, by instrumental variables (the setpoints): within 10 %, the truth inside
    // the 95 % intervals, and the wind found.
    assert!(r.estimator.starts_with("instrumental variables"), "{r}");
    assert!((r.k1_mps2_per_rad - K1).abs() < 0.1 * K1, "{r}");
    assert!((r.k2_per_s - K2).abs() < 0.1 * K2, "{r}");
    assert!(
        (r.k1_mps2_per_rad - K1).abs() < r.k1_ci95_mps2_per_rad,
        "{r}"
    );
    assert!((r.k2_per_s - K2).abs() < r.k2_ci95_per_s, "{r}");
    // Least squares on the same windows is pulled low by the gusts the controller answers.
    let [k1_ls, _, k2_ls, _] = r.least_squares.expect("least squares shown");
    assert!(k1_ls < r.k1_mps2_per_rad && k2_ls < r.k2_per_s, "{r}");
    for (est, truth) in r.wind_mean_ne_mps.iter().zip(wind) {
        assert!((est - truth).abs() < 0.3, "{r}");
    }
    // Well excited and precise enough: suggested, and the suggestion is the fit.
    assert_eq!(r.suggested, Some([r.k1_mps2_per_rad, r.k2_per_s]), "{r}");
    assert!(r.to_string().contains("suggested params"));
}

#[test]
fn wind_without_gusts_the_truth_is_inside_the_intervals() {
    // Constant wind plus the slow swing only: the model with a wind per window holds (up to
    // the swing within 5 s), so the 95 % intervals must hold the truth.
    let (s, wind) = fly(&Flight {
        gust_mps: 0.0,
        ..windy()
    });
    let r = sysid::from_series(&s).expect("fit");
    println!("true mean wind N {:.2} E {:.2} m/s\n{r}", wind[0], wind[1]);
    assert!(
        (r.k1_mps2_per_rad - K1).abs() < r.k1_ci95_mps2_per_rad,
        "{r}"
    );
    assert!((r.k2_per_s - K2).abs() < r.k2_ci95_per_s, "{r}");
    assert!(
        r.k1_ci95_mps2_per_rad < 0.02 * K1 && r.k2_ci95_per_s < 0.05 * K2,
        "{r}"
    );
    let [k1p, _, _] = r.no_wind_fit.unwrap();
    assert!((k1p - K1).abs() > 0.2 * K1, "plain k1 {k1p}");
    for (est, truth) in r.wind_mean_ne_mps.iter().zip(wind) {
        assert!((est - truth).abs() < 0.1, "{r}");
    }
}

#[test]
fn the_accelerometer_gives_the_same_fit() {
    // The accelerometer (accel/measured) instead of the differenced odometry.
    let (s, _) = fly(&windy());
    let src = sysid::AccelSource::Measured;
    let x = sysid::samples(&s, src);
    let y = sysid::samples(&s, sysid::AccelSource::OdomDifferenced);
    assert!(y.len() + 20 >= x.len(), "{} vs {}", y.len(), x.len());
    let r = sysid::fit(&x, src.name(), sysid::WIND_WINDOW_S).expect("fit");
    println!("{r}");
    assert!((r.k1_mps2_per_rad - K1).abs() < 0.1 * K1, "{r}");
    assert!((r.k2_per_s - K2).abs() < 0.1 * K2, "{r}");
}

#[test]
fn calm_flight_fits_alike_with_or_without_the_wind_term() {
    let (s, _) = fly(&Flight {
        wind_ne_mps: [0.0, 0.0],
        swing_mps: 0.0,
        gust_mps: 0.0,
        ..windy()
    });
    let r = sysid::from_series(&s).expect("fit");
    println!("{r}");
    let [k1p, k2p, _] = r.no_wind_fit.unwrap();
    assert!(
        (k1p - K1).abs() < 0.05 * K1 && (k2p - K2).abs() < 0.1 * K2,
        "{r}"
    );
    assert!((r.k1_mps2_per_rad - K1).abs() < 0.05 * K1, "{r}");
    assert!(
        r.wind_mean_ne_mps[0].hypot(r.wind_mean_ne_mps[1]) < 0.3,
        "{r}"
    );
}

#[test]
fn windy_hover_is_no_suggestion_with_the_reason() {
    // Hover in place in gusty wind with a noisy accelerometer: tilt and velocity move only in
    // answer to gusts and noise.
    let (s, _) = fly(&Flight {
        cruise_mps: 0.0,
        accel_noise_mps2: 1.0,
        gust_mps: 0.5,
        duration_s: 120.0,
        ..windy()
    });
    let r = sysid::from_series(&s).expect("fit");
    println!("{r}");
    assert!(r.suggested.is_none(), "{r}");
    let why = r.no_suggestion.clone().unwrap();
    assert!(why.contains("excitation"), "{why}");
    assert!(r.to_string().contains("no suggestion: "), "{r}");
    assert!(!r.to_string().contains("suggested params"), "{r}");
}

#[test]
fn a_short_noisy_flight_is_no_suggestion_for_its_wide_intervals() {
    // 40 s with a very noisy accelerometer, fitted on accel/measured.
    let (s, _) = fly(&Flight {
        accel_noise_mps2: 3.0,
        duration_s: 40.0,
        ..windy()
    });
    let src = sysid::AccelSource::Measured;
    let r = sysid::fit(&sysid::samples(&s, src), src.name(), sysid::WIND_WINDOW_S).expect("fit");
    println!("{r}");
    let why = r.no_suggestion.clone().expect("no suggestion");
    assert!(why.contains("95 % interval"), "{why}");
    assert!(r.suggested.is_none());
}

#[test]
fn intervals_hold_the_truth_over_gusty_flights() {
    // 20 flights in strong gusts (σ 0.8 m/s): the widened 95 % intervals of the IV fit hold
    // the truth in (nearly) all of them, and every suggestion is within 10 %.
    let (mut in1, mut in2, mut suggested) = (0, 0, 0);
    for seed in 0..20 {
        let (s, _) = fly(&Flight {
            gust_mps: 0.8,
            seed: 100 + seed,
            ..windy()
        });
        let r = sysid::from_series(&s).expect("fit");
        in1 += ((r.k1_mps2_per_rad - K1).abs() < r.k1_ci95_mps2_per_rad) as u32;
        in2 += ((r.k2_per_s - K2).abs() < r.k2_ci95_per_s) as u32;
        if let Some([k1, k2]) = r.suggested {
            suggested += 1;
            assert!(
                (k1 - K1).abs() < 0.1 * K1 && (k2 - K2).abs() < 0.1 * K2,
                "{r}"
            );
        }
        println!(
            "seed {seed}: k1 {:.3} ± {:.3}, k2 {:.4} ± {:.4}, least squares k1 {:.3}; {}",
            r.k1_mps2_per_rad,
            r.k1_ci95_mps2_per_rad,
            r.k2_per_s,
            r.k2_ci95_per_s,
            r.least_squares.unwrap()[0],
            r.no_suggestion.as_deref().unwrap_or("suggested")
        );
    }
    println!("truth inside: k1 {in1}/20, k2 {in2}/20; suggested {suggested}/20");
    assert!(in1 >= 18 && in2 >= 18, "k1 {in1}/20, k2 {in2}/20");
}
