//! Row 2 of BENCHMARKS.md (issues 9 and 20): the flight core's attitude estimate
//! (`fcc_nav::attitude::AttitudeEstimator` as `fcc_firmware::nav` runs it in the loop) against
//! the `ahrs` crate's Madgwick and Mahony filters on the same simulated samples of two flights:
//! the square (`square.yaml`) and a manoeuvring zig-zag (`manoeuvre.yaml`: 6 m/s, 3 m/s²
//! velocity-command limit, 90–150° turns without a stop, another seed), each flown with
//! [`SEEDS`] seeds. Run by `scripts/bench.sh`; alone: `cargo bench -p fcc_tests --features
//! bench-peers --bench attitude_filter`.
//!
//! ## Same inputs for every filter
//! The samples the flight core received (captured exactly, see `common/mod.rs`), with the
//! calibration the firmware applies: gyro bias = mean gyro over the core's ground calibration,
//! accelerometer and magnetometer offsets from the calibrated `Params`. Every filter starts at
//! the core's initial attitude (tilt of the mean accelerometer + tilt-compensated heading of the
//! mean magnetometer over the calibration) and runs at 500 Hz with the core's IMU period.
//!
//! The firmware removes the manoeuvre acceleration (GPS-differenced velocity, smoothed, NED)
//! from the low-passed specific force before reading it as a gravity direction. The peers get
//! the same: the very NED acceleration the core removed on that tick (captured from
//! `Navigator::tilt_accel_comp_ned_mps2`), rotated into the body with *their own* current
//! attitude (ours uses its own; nothing of our estimate reaches theirs). They may also take the
//! acceleration between the last two GPS velocities unsmoothed (less lag, more noise), which
//! the core does not use.
//!
//! ## Ours is the in-loop estimate
//! Ours is `AttitudeEstimator` with the production gains fed exactly what `Navigator::imu_update`
//! feeds it (same low-pass, same compensation, same magnetometer reference and gates); the
//! bench asserts on every tick that its output equals, bit for bit, the attitude the simulator's
//! flight core reported, so the figures are those of the estimate that flies. Above 1 m with GPS
//! velocities arriving, the core corrects the tilt and its rate bias from the GPS velocity's
//! innovation against the inertial one (`fcc_nav::tilt_kf`) instead of the accelerometer's
//! gravity direction; the
//! bench replays the core's flag and correction on each tick. The peers get the same GPS
//! information in their own form: the GPS-derived acceleration removed from their
//! accelerometer (smoothed as the core's, or unsmoothed).
//!
//! ## The peers are tuned, per flight
//! Each peer runs over a grid: gain(s) × accelerometer raw or through the firmware's low-pass ×
//! the core's manoeuvre compensation, the unsmoothed one or none × magnetometer held every
//! tick or only on new samples; each flight reports the peer's best setting for that flight
//! (lowest RMS over the three axes, over all its seeds). Ours is not tuned per flight: one set
//! of production gains.
//!
//! Truth is the physics' attitude at every tick; errors are RMS over the airborne ticks of all
//! the flight's seeds.
//! Speed: ns per update over the square's prepared sequence (the low-pass output prepared
//! beforehand for everyone; the compensation's rotation into the body is inside the timed loop
//! for everyone), best of 5, each peer in its best square setting.

mod common;

use ahrs::{Ahrs, Madgwick, Mahony};
use common::{best_of, capture_seeded, note, row, thousands, verdict};
use fcc_firmware::nav::GPS_ACCEL_MAX_AGE_US;
use fcc_firmware::params::NavParams;
use fcc_nav::attitude::{accel_tilt_rad, mag_heading_rad, AttitudeEstimator, Euler};
use fcc_nav::lowpass::LowPass2;
use fcc_nav::tilt_kf::TiltCorrection;
use nalgebra_034::{UnitQuaternion, Vector3};
use std::f64::consts::PI;

/// The flights of the comparison (scenario files), in table order.
const FLIGHTS: [&str; 2] = ["square", "manoeuvre"];

/// Each flight is flown with this many seeds: the scenario's own, then the next ones (every
/// random process of the run: sensor noise and biases, the calibration residuals, the wind).
/// One seed decides too much: the magnetometer calibration's residual sets a heading error of
/// 0.2–1.5° that every filter starts from, and a filter that hardly corrects its yaw wins or
/// loses on whether its gyro drift happens to cancel it on that seed.
const SEEDS: u64 = 12;

/// Prepared inputs of one tick.
#[derive(Clone, Copy)]
struct In {
    gyro: [f32; 3],
    accel_raw: [f32; 3],
    accel_lpf: [f32; 3],
    /// The manoeuvre acceleration (NED) the core removed from the specific force this tick.
    comp_ned: [f32; 3],
    /// The acceleration between the last two GPS velocities (NED, unsmoothed; zero when the
    /// last is older than the core's `GPS_ACCEL_MAX_AGE_US`).
    comp_diff_ned: [f32; 3],
    /// The core corrected the tilt from the GPS velocity this tick (not the accelerometer).
    gps_tilt_aided: bool,
    /// The GPS velocity's tilt correction, after this tick's step.
    gps_tilt: Option<TiltCorrection>,
    /// New magnetometer sample this tick.
    mag_new: Option<[f32; 3]>,
    /// Newest magnetometer sample so far (held).
    mag_held: [f32; 3],
    dt_s: f32,
    truth: [f64; 3],
    airborne: bool,
    /// The simulator core's own estimate after this tick.
    core: [f32; 3],
}

/// One captured flight, prepared.
struct Flight {
    seed: u64,
    nav: NavParams,
    xs: Vec<In>,
    init: Euler,
    /// Magnetometer sample, roll, pitch the core took its field reference from.
    mag_ref: ([f32; 3], f32, f32),
    decl: f64,
    sim_s: f64,
    airborne_n: usize,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum AccelIn {
    Raw,
    LowPass,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Comp {
    /// The manoeuvre acceleration the core's accelerometer path removes (GPS-differenced,
    /// smoothed) removed.
    Gps,
    /// The acceleration between the last two GPS velocities (unsmoothed: less lag, more noise)
    /// removed.
    GpsDiff,
    /// The specific force as measured.
    Off,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum MagIn {
    /// 9-DOF update every tick with the newest magnetometer sample.
    Held,
    /// 9-DOF update when a sample arrives, 6-DOF (`update_imu`) in between.
    NewOnly,
}

/// A peer's input configuration.
#[derive(Clone, Copy, Debug)]
struct Setting {
    accel: AccelIn,
    comp: Comp,
    mag: MagIn,
}

impl Setting {
    fn all() -> Vec<Setting> {
        let mut v = Vec::new();
        for accel in [AccelIn::Raw, AccelIn::LowPass] {
            for comp in [Comp::Gps, Comp::GpsDiff, Comp::Off] {
                for mag in [MagIn::Held, MagIn::NewOnly] {
                    v.push(Setting { accel, comp, mag });
                }
            }
        }
        v
    }
    fn text(&self) -> String {
        let comp = match self.comp {
            Comp::Gps => "compensated",
            Comp::GpsDiff => "compensated (unsmoothed)",
            Comp::Off => "uncompensated",
        };
        format!("{:?} {comp} accel, mag {:?}", self.accel, self.mag)
    }
}

fn wrap(a: f64) -> f64 {
    let mut a = a % (2.0 * PI);
    if a > PI {
        a -= 2.0 * PI;
    } else if a < -PI {
        a += 2.0 * PI;
    }
    a
}

/// RMS errors (deg) of roll, pitch, yaw over the airborne ticks.
#[derive(Clone, Copy, Debug, Default)]
struct Rms {
    roll: f64,
    pitch: f64,
    yaw: f64,
}

impl Rms {
    fn axes(&self) -> [f64; 3] {
        [self.roll, self.pitch, self.yaw]
    }
    fn total(&self) -> f64 {
        (self.axes().iter().map(|x| x * x).sum::<f64>() / 3.0).sqrt()
    }
    fn text(&self) -> String {
        format!(
            "roll {:.3}°, pitch {:.3}°, yaw {:.3}°",
            self.roll, self.pitch, self.yaw
        )
    }
}

struct Scorer {
    sum: [f64; 3],
    n: usize,
}

impl Scorer {
    fn new() -> Self {
        Self {
            sum: [0.0; 3],
            n: 0,
        }
    }
    fn add(&mut self, est: [f64; 3], truth: [f64; 3]) {
        for i in 0..3 {
            let e = wrap(est[i] - truth[i]);
            self.sum[i] += e * e;
        }
        self.n += 1;
    }
    fn rms(&self) -> Rms {
        let f = |s: f64| (s / self.n as f64).sqrt().to_degrees();
        Rms {
            roll: f(self.sum[0]),
            pitch: f(self.sum[1]),
            yaw: f(self.sum[2]),
        }
    }
}

fn v3(a: [f32; 3]) -> Vector3<f32> {
    Vector3::new(a[0], a[1], a[2])
}

/// Capture `name` and prepare every filter's inputs exactly as `fcc_firmware::nav` does.
fn prepare(name: &'static str, seed_add: u64) -> Flight {
    let cap = capture_seeded(name, seed_add, false);
    let nav = cap.params.nav;
    let decl_f32 = nav.declination_deg.to_radians();
    // The core's calibration: every tick up to and including the one it completes on (the
    // vehicle is still on the ground, disarmed, from the first tick).
    let n_cal = cap
        .ticks
        .iter()
        .position(|t| t.calibrated)
        .expect("the core calibrates");
    assert!(n_cal > 100, "calibration window too short");
    let (mut gyro_sum, mut acc_sum, mut mag_sum) = ([0.0f32; 3], [0.0f32; 3], [0.0f32; 3]);
    let mut mag_n = 0u32;
    let off = |m: [f32; 3], o: [f32; 3]| -> [f32; 3] { std::array::from_fn(|i| m[i] - o[i]) };
    for t in &cap.ticks[..=n_cal] {
        let imu = t.inputs.imu.unwrap();
        let acc = off(imu.accel_frd_mps2, nav.accel_offset_frd_mps2);
        for i in 0..3 {
            gyro_sum[i] += imu.gyro_frd_radps[i];
            acc_sum[i] += acc[i];
        }
        if let Some(m) = t.inputs.mag {
            let m = off(m.mag_frd_ut, nav.mag_offset_frd_ut);
            for i in 0..3 {
                mag_sum[i] += m[i];
            }
            mag_n += 1;
        }
    }
    let n = (n_cal + 1) as f32;
    let bias = gyro_sum.map(|s| s / n);
    let (r0, p0) = accel_tilt_rad(acc_sum.map(|s| s / n));
    assert!(mag_n > 0, "mag during calibration");
    let m0 = mag_sum.map(|s| s / mag_n as f32);
    let init = Euler {
        roll_rad: r0,
        pitch_rad: p0,
        yaw_rad: mag_heading_rad(m0, r0, p0, decl_f32),
    };

    let mut lpf = [LowPass2::new(nav.tilt_accel_lpf_hz, 500.0); 3];
    let mut held = m0;
    let mut last_imu_us: Option<u64> = None;
    let mut comp_ned = [0.0f32; 3];
    let mut comp_diff_ned = [0.0f32; 3];
    let mut gps_diff = [0.0f32; 3];
    let mut last_gps: Option<(u64, [f32; 3])> = None;
    let mut gps_tilt_aided = false;
    let mut xs = Vec::new();
    for (k, t) in cap.ticks.iter().enumerate() {
        let imu = t.inputs.imu.unwrap();
        let dt_s = match last_imu_us {
            Some(t0) if imu.t_us > t0 => ((imu.t_us - t0) as f32 * 1e-6).min(0.02),
            _ => 0.002,
        };
        last_imu_us = Some(imu.t_us);
        let acc = off(imu.accel_frd_mps2, nav.accel_offset_frd_mps2);
        let acc_lp = std::array::from_fn(|i| lpf[i].update(acc[i]));
        let mag_new = t
            .inputs
            .mag
            .map(|m| off(m.mag_frd_ut, nav.mag_offset_frd_ut));
        if k >= n_cal {
            if let Some(m) = mag_new {
                held = m;
            }
            xs.push(In {
                gyro: std::array::from_fn(|i| imu.gyro_frd_radps[i] - bias[i]),
                accel_raw: acc,
                accel_lpf: acc_lp,
                comp_ned,
                comp_diff_ned,
                gps_tilt_aided,
                gps_tilt: t.gps_tilt,
                mag_new,
                mag_held: held,
                dt_s,
                truth: t.true_euler_rad,
                airborne: t.airborne,
                core: t.core_euler_rad,
            });
        }
        comp_ned = t.tilt_comp_next_ned_mps2;
        gps_tilt_aided = t.gps_tilt_aided_next;
        if let Some(g) = t.inputs.gps.filter(|g| g.fix_ok) {
            if let Some((t0, v0)) = last_gps {
                let dt = (t.t_us - t0) as f32 * 1e-6;
                if dt > 0.05 && dt < 1.0 {
                    gps_diff = std::array::from_fn(|i| (g.vel_ned_mps[i] - v0[i]) / dt);
                }
            }
            last_gps = Some((t.t_us, g.vel_ned_mps));
        }
        let fresh = last_gps.is_some_and(|(t0, _)| t.t_us - t0 <= GPS_ACCEL_MAX_AGE_US);
        comp_diff_ned = if fresh { gps_diff } else { [0.0; 3] };
    }
    let airborne_n = xs.iter().filter(|x| x.airborne).count();
    assert!(airborne_n > 1000, "the flight must be airborne for a while");
    Flight {
        seed: cap.seed,
        nav,
        xs,
        init,
        mag_ref: (m0, r0, p0),
        decl: decl_f32 as f64,
        sim_s: cap.sim_s,
        airborne_n,
    }
}

fn ours_new(f: &Flight) -> AttitudeEstimator {
    let p = &f.nav;
    let mut est = AttitudeEstimator::new(
        p.tilt_gains(),
        p.yaw_gains(),
        p.declination_deg.to_radians(),
    );
    est.reset(f.init);
    let (m, r, p) = f.mag_ref;
    est.set_mag_reference(m, r, p);
    est
}

/// One step of ours as `Navigator::imu_update` runs it: the manoeuvre acceleration rotated
/// into the body with the current estimate and removed from the low-passed specific force.
#[inline]
fn ours_step(est: &mut AttitudeEstimator, x: &In) -> Euler {
    est.accel_tilt = !x.gps_tilt_aided;
    let e = est.update_compensated(x.gyro, x.accel_lpf, x.comp_ned, x.mag_new, x.dt_s);
    if let Some(c) = &x.gps_tilt {
        est.apply_tilt_correction(c);
    }
    e
}

/// One flight shape flown with [`SEEDS`] seeds.
struct Shape {
    name: &'static str,
    flights: Vec<Flight>,
}

impl Shape {
    fn airborne_n(&self) -> usize {
        self.flights.iter().map(|f| f.airborne_n).sum()
    }
    fn sim_s(&self) -> f64 {
        self.flights.iter().map(|f| f.sim_s).sum()
    }
}

/// Ours over every flight of the shape (RMS over all their airborne ticks); asserts it
/// reproduces the simulator core's estimate on every tick.
fn run_ours(sh: &Shape) -> Rms {
    let mut s = Scorer::new();
    for f in &sh.flights {
        run_ours_on(f, sh.name, &mut s);
    }
    s.rms()
}

fn run_ours_on(f: &Flight, name: &str, s: &mut Scorer) {
    let mut est = ours_new(f);
    for (k, x) in f.xs.iter().enumerate() {
        let e = ours_step(&mut est, x);
        let got = [e.roll_rad, e.pitch_rad, e.yaw_rad];
        assert_eq!(
            got.map(f32::to_bits),
            x.core.map(f32::to_bits),
            "{name} seed {}: tick {k} after calibration: the bench's estimator ({got:?}) is not the core's ({:?})",
            f.seed,
            x.core
        );
        if x.airborne {
            s.add(got.map(|v| v as f64), x.truth);
        }
    }
}

/// Madgwick/Mahony inputs: body FRD, NED earth frame. Their accelerometer reference is the
/// earth z axis (down) seen in the body, i.e. minus the specific force; with `Comp::Gps` the
/// manoeuvre acceleration is first removed, rotated into the body with the peer's own
/// attitude `q` (body → NED).
#[inline]
fn peer_step<F: Ahrs<f32>>(
    f: &mut F,
    q: &UnitQuaternion<f32>,
    x: &In,
    s: Setting,
) -> UnitQuaternion<f32> {
    let g = v3(x.gyro);
    let mut sf = v3(match s.accel {
        AccelIn::Raw => x.accel_raw,
        AccelIn::LowPass => x.accel_lpf,
    });
    match s.comp {
        Comp::Gps => sf -= q.inverse_transform_vector(&v3(x.comp_ned)),
        Comp::GpsDiff => sf -= q.inverse_transform_vector(&v3(x.comp_diff_ned)),
        Comp::Off => {}
    }
    let acc = -sf;
    let mag = match s.mag {
        MagIn::Held => Some(x.mag_held),
        MagIn::NewOnly => x.mag_new,
    };
    let out = match mag {
        Some(mg) => f.update(&g, &acc, &v3(mg)).map(|q| *q),
        None => f.update_imu(&g, &acc).map(|q| *q),
    };
    out.unwrap_or_else(|_| *f.update_gyro(&g))
}

fn peer_euler(q: &UnitQuaternion<f32>, decl: f64) -> [f64; 3] {
    let (r, p, y) = q.euler_angles();
    [r as f64, p as f64, wrap(y as f64 + decl)]
}

/// The peers' initial quaternion (magnetic heading: they know nothing of the declination).
fn peer_q0(f: &Flight) -> UnitQuaternion<f32> {
    let e = f.init;
    UnitQuaternion::from_euler_angles(e.roll_rad, e.pitch_rad, (e.yaw_rad as f64 - f.decl) as f32)
}

/// A peer made by `new` (from a flight's start attitude) over every flight of the shape, in
/// one setting: RMS over all their airborne ticks.
fn run_peer<F: Ahrs<f32>>(new: impl Fn(UnitQuaternion<f32>) -> F, sh: &Shape, s: Setting) -> Rms {
    let mut sc = Scorer::new();
    for f in &sh.flights {
        let mut q = peer_q0(f);
        let mut p = new(q);
        for x in &f.xs {
            q = peer_step(&mut p, &q, x, s);
            if x.airborne {
                sc.add(peer_euler(&q, f.decl), x.truth);
            }
        }
    }
    sc.rms()
}

const DT_S: f32 = 0.002;
const MADGWICK_BETAS: [f32; 9] = [0.0002, 0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1];
const MAHONY_KPS: [f32; 9] = [0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0];
const MAHONY_KIS: [f32; 4] = [0.0, 0.001, 0.005, 0.02];

/// Madgwick's best β and setting on the shape (one setting for all its seeds).
fn tune_madgwick(sh: &Shape) -> (f32, Setting, Rms) {
    let mut best: Option<(f32, Setting, Rms)> = None;
    for beta in MADGWICK_BETAS {
        for s in Setting::all() {
            let r = run_peer(|q| Madgwick::new_with_quat(DT_S, beta, q), sh, s);
            if best.as_ref().is_none_or(|b| r.total() < b.2.total()) {
                best = Some((beta, s, r));
            }
        }
    }
    best.unwrap()
}

/// Mahony's best (kp, ki) and setting on the shape (one setting for all its seeds).
fn tune_mahony(sh: &Shape) -> ((f32, f32), Setting, Rms) {
    let mut best: Option<((f32, f32), Setting, Rms)> = None;
    for kp in MAHONY_KPS {
        for ki in MAHONY_KIS {
            for s in Setting::all() {
                let r = run_peer(|q| Mahony::new_with_quat(DT_S, kp, ki, q), sh, s);
                if best.as_ref().is_none_or(|b| r.total() < b.2.total()) {
                    best = Some(((kp, ki), s, r));
                }
            }
        }
    }
    best.unwrap()
}

/// ns per update of `step` over the flight, best of 5.
fn ns_per_update(f: &Flight, mut run: impl FnMut(&[In]) -> f32) -> f64 {
    1e9 / f.xs.len() as f64 * best_of(5, || run(&f.xs))
}

struct Result1 {
    shape: Shape,
    ours: Rms,
    core: Rms,
    mad: (f32, Setting, Rms),
    mah: ((f32, f32), Setting, Rms),
}

/// Worst per-axis ratio ours ÷ peer over every flight.
fn worst_ratio(rs: &[Result1], peer: impl Fn(&Result1) -> Rms) -> f64 {
    rs.iter()
        .flat_map(|r| {
            let p = peer(r).axes();
            let o = r.ours.axes();
            (0..3).map(move |i| o[i] / p[i])
        })
        .fold(0.0, f64::max)
}

fn per_flight(rs: &[Result1], text: impl Fn(&Result1) -> String) -> String {
    rs.iter()
        .map(|r| format!("{}: {}", r.shape.name, text(r)))
        .collect::<Vec<_>>()
        .join("; ")
}

fn main() {
    let rs: Vec<Result1> = FLIGHTS
        .iter()
        .map(|&name| {
            let shape = Shape {
                name,
                flights: (0..SEEDS).map(|k| prepare(name, k)).collect(),
            };
            let ours = run_ours(&shape);
            let mut core = Scorer::new();
            for f in &shape.flights {
                for x in f.xs.iter().filter(|x| x.airborne) {
                    core.add(x.core.map(|v| v as f64), x.truth);
                }
            }
            let mad = tune_madgwick(&shape);
            let mah = tune_mahony(&shape);
            Result1 {
                ours,
                core: core.rms(),
                mad,
                mah,
                shape,
            }
        })
        .collect();
    for r in &rs {
        // Ours *is* the core's estimate (asserted tick by tick in `run_ours`).
        assert_eq!(r.ours.axes(), r.core.axes());
    }

    // Speed on the square (its first seed), each peer in its best square setting.
    let sq = &rs[0].shape.flights[0];
    let ours_ns = ns_per_update(sq, |xs| {
        let mut est = ours_new(sq);
        let mut acc = 0.0f32;
        for x in xs {
            acc += ours_step(&mut est, std::hint::black_box(x)).yaw_rad;
        }
        acc
    });
    let (beta, mad_s, _) = rs[0].mad;
    let mad_ns = ns_per_update(sq, |xs| {
        let mut p = Madgwick::new_with_quat(DT_S, beta, peer_q0(sq));
        let mut q = peer_q0(sq);
        for x in xs {
            q = peer_step(&mut p, &q, std::hint::black_box(x), mad_s);
        }
        q.w
    });
    let ((kp, ki), mah_s, _) = rs[0].mah;
    let mah_ns = ns_per_update(sq, |xs| {
        let mut p = Mahony::new_with_quat(DT_S, kp, ki, peer_q0(sq));
        let mut q = peer_q0(sq);
        for x in xs {
            q = peer_step(&mut p, &q, std::hint::black_box(x), mah_s);
        }
        q.w
    });

    let ours_text = per_flight(&rs, |r| r.ours.text());
    let mad_ratio = worst_ratio(&rs, |r| r.mad.2);
    let mah_ratio = worst_ratio(&rs, |r| r.mah.2);
    row(
        "2a",
        "Attitude error vs truth, RMS (airborne): the flight core's in-loop estimate vs Madgwick, same inputs, square and manoeuvring flights",
        &ours_text,
        &format!(
            "Madgwick, best of grid per flight: {}",
            per_flight(&rs, |r| format!("(β = {}) {}", r.mad.0, r.mad.2.text()))
        ),
        &format!("{mad_ratio:.2} (worst axis)"),
        "≤ Madgwick's on every axis, both flights (≤ 1.00)",
        verdict(mad_ratio <= 1.0),
    );
    row(
        "2b",
        "Attitude filter speed: ns per 500 Hz update (with the manoeuvre compensation's rotation)",
        &format!("{ours_ns:.1} ns"),
        &format!("Madgwick: {mad_ns:.1} ns"),
        &format!("{:.2}× as fast", mad_ns / ours_ns),
        "≥ Madgwick's speed (≥ 1.00×)",
        verdict(ours_ns <= mad_ns),
    );
    row(
        "2c",
        "Attitude error vs Mahony (same inputs, both flights)",
        &ours_text,
        &format!(
            "Mahony, best of grid per flight: {}",
            per_flight(&rs, |r| format!(
                "(kp = {}, ki = {}) {}",
                r.mah.0 .0,
                r.mah.0 .1,
                r.mah.2.text()
            ))
        ),
        &format!("{mah_ratio:.2} (worst axis)"),
        "≤ Mahony's on every axis, both flights (≤ 1.00)",
        verdict(mah_ratio <= 1.0),
    );
    row(
        "2d",
        "Attitude filter speed vs Mahony",
        &format!("{ours_ns:.1} ns"),
        &format!("Mahony: {mah_ns:.1} ns"),
        &format!("{:.2}× as fast", mah_ns / ours_ns),
        "— (no goal; for information)",
        "info",
    );
    let flights = per_flight(&rs, |r| {
        format!(
            "seeds {}–{}, {} airborne ticks, {:.0} s simulated; Madgwick best with {}, Mahony with {}",
            r.shape.flights[0].seed,
            r.shape.flights[r.shape.flights.len() - 1].seed,
            thousands(r.shape.airborne_n() as f64),
            r.shape.sim_s(),
            r.mad.1.text(),
            r.mah.1.text()
        )
    });
    note(
        "2",
        &format!(
            "Flights: `square.yaml` and `manoeuvre.yaml` (zig-zag at 6 m/s, 3 m/s² command limit, 90–150° turns without a stop, 5 m/s wind), each with {SEEDS} seeds (the scenario's and the next; every random process of a run follows its seed: noise, biases, calibration residuals, wind) — {flights}. RMS over all the airborne ticks of a flight's seeds: on one seed the magnetometer calibration's residual sets a heading error of 0.2–1.5° every filter starts from, and a peer that hardly corrects its yaw wins or loses on whether its gyro drift happens to cancel it there. Ours = the flight core's in-loop estimate (the bench re-runs `AttitudeEstimator` with the core's exact inputs and asserts on every tick that it equals the core's output bit for bit): production gains, the same on both flights. Peers get the same samples, calibration and start attitude, and the same GPS-derived manoeuvre acceleration the core removes from the accelerometer (rotated into the body with their own attitude), or the unsmoothed one the core does not use; each is tuned per flight over a grid (Madgwick β ∈ {{0.0002 … 0.1}}, Mahony kp ∈ {{0.005 … 2}} × ki ∈ {{0 … 0.02}}, each × accelerometer raw or through the firmware's {} Hz low-pass × the core's compensation, the unsmoothed one or none × magnetometer held every tick or only on new samples), one setting for all the flight's seeds, best RMS over the three axes. Ratio column of 2a/2c: the worst of ours ÷ peer over the three axes and both flights. Speed: square flight (first seed), best of 5, the compensation's rotation inside the loop for every filter. Source: tests/benches/attitude_filter.rs",
            rs[0].shape.flights[0].nav.tilt_accel_lpf_hz
        ),
    );
}
