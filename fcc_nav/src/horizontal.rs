//! Horizontal position/velocity (paper A): GPS through `F_L`, gravity-compensated NED
//! acceleration double-integrated through `F_H`, one [`PosVelCf`] per axis (north, east).
//!
//! GPS latency is handled by the filters' predicted-position history: `HIST = 128` steps,
//! i.e. 256 ms at 500 Hz. GPS positions are local NED metres (see `fcc_msgs::geodesy`).

use crate::complementary::{CfGains, PosVelCf};

/// North/east complementary position-velocity estimator.
#[derive(Clone, Copy, Debug)]
pub struct HorizontalEstimator {
    /// North axis filter \[m, m/s].
    pub n: PosVelCf<128>,
    /// East axis filter \[m, m/s].
    pub e: PosVelCf<128>,
}

impl HorizontalEstimator {
    /// Both axes with the same gains.
    pub fn new(g: CfGains) -> Self {
        Self {
            n: PosVelCf::new(g),
            e: PosVelCf::new(g),
        }
    }

    /// Set position \[m] and velocity \[m/s] (NE); drops any held GPS fix.
    pub fn reset(&mut self, pos_ne_m: [f32; 2], vel_ne_mps: [f32; 2]) {
        self.n.reset(pos_ne_m[0], vel_ne_mps[0]);
        self.e.reset(pos_ne_m[1], vel_ne_mps[1]);
    }

    /// New GPS position fix (local NE \[m]) taken `delay_steps` updates ago (clamped to 127).
    pub fn gps(&mut self, pos_ne_m: [f32; 2], delay_steps: usize) {
        self.n.set_measurement(pos_ne_m[0], delay_steps);
        self.e.set_measurement(pos_ne_m[1], delay_steps);
    }

    /// GPS velocity (NE \[m/s]) measured `delay_steps` updates ago, applied once with gain
    /// `gain` per fix, the accelerometer bias learnt from it with `bias_gain` per fix
    /// ([`PosVelCf::velocity_measurement_with_bias`]; 0 = no bias learning).
    pub fn gps_velocity(
        &mut self,
        vel_ne_mps: [f32; 2],
        delay_steps: usize,
        gain: f32,
        bias_gain: f32,
    ) {
        self.n
            .velocity_measurement_with_bias(vel_ne_mps[0], delay_steps, gain, bias_gain);
        self.e
            .velocity_measurement_with_bias(vel_ne_mps[1], delay_steps, gain, bias_gain);
    }

    /// Drop the held GPS fix (dead reckoning).
    pub fn clear_gps(&mut self) {
        self.n.clear_measurement();
        self.e.clear_measurement();
    }

    /// Whether a GPS fix is currently held and applied.
    pub fn has_gps(&self) -> bool {
        self.n.has_measurement()
    }

    /// One step with gravity-compensated NE acceleration \[m/s²].
    pub fn update(&mut self, accel_ne_mps2: [f32; 2], dt_s: f32) {
        self.n.update(accel_ne_mps2[0], dt_s);
        self.e.update(accel_ne_mps2[1], dt_s);
    }

    /// Position estimate NE \[m].
    pub fn pos_ne_m(&self) -> [f32; 2] {
        [self.n.pos(), self.e.pos()]
    }

    /// Velocity estimate NE \[m/s].
    pub fn vel_ne_mps(&self) -> [f32; 2] {
        [self.n.vel(), self.e.vel()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::Rng;

    const DT: f32 = 0.002;

    /// 5 Hz GPS, 120 ms latency, vibration-noisy accel with bias: position tracks a manoeuvre.
    #[test]
    fn gps_5hz_with_latency_tracks_manoeuvre() {
        let mut rng = Rng::new(42);
        let mut est = HorizontalEstimator::new(CfGains::new(1.0, 0.8));
        est.reset([0.0, 0.0], [0.0, 0.0]);
        let delay = 60usize; // 120 ms
        let steps = (40.0 / DT) as usize;
        let mut pos = [0.0f64; 2];
        let mut vel = [0.0f64; 2];
        let mut hist_pos: std::vec::Vec<[f64; 2]> = std::vec::Vec::new();
        let (mut sq, mut sqv, mut n, mut max_err) = (0.0f64, 0.0f64, 0usize, 0.0f64);
        let mut max_speed = 0.0f64;
        for k in 0..steps {
            let t = k as f64 * DT as f64;
            // manoeuvre: figure-like accelerations, peak speed ≈ 2–3 m/s
            let acc = [
                0.8 * libm::sin(0.5 * t),
                1.0 * libm::sin(0.8 * t + 0.3) * if t > 10.0 { 1.0 } else { 0.0 },
            ];
            hist_pos.push(pos); // truth at the start of step k
                                // the update advances to step k + 1; the fix is `delay` steps older than that
            if k % 100 == 0 && k + 1 >= delay {
                let p = hist_pos[k + 1 - delay];
                est.gps(
                    [p[0] as f32 + rng.normal(0.2), p[1] as f32 + rng.normal(0.2)],
                    delay,
                );
            }
            let meas = [
                acc[0] as f32 + 0.1 + rng.normal(2.0),
                acc[1] as f32 - 0.08 + rng.normal(2.0),
            ];
            est.update(meas, DT);
            for i in 0..2 {
                pos[i] += vel[i] * DT as f64 + 0.5 * acc[i] * (DT * DT) as f64;
                vel[i] += acc[i] * DT as f64;
                max_speed = max_speed.max(vel[i].abs());
            }
            if t > 5.0 {
                let p = est.pos_ne_m();
                let v = est.vel_ne_mps();
                for i in 0..2 {
                    let e = p[i] as f64 - pos[i];
                    sq += e * e;
                    sqv += (v[i] as f64 - vel[i]).powi(2);
                    max_err = max_err.max(e.abs());
                }
                n += 2;
            }
        }
        let rms = (sq / n as f64).sqrt();
        let rmsv = (sqv / n as f64).sqrt();
        assert!(rms < 0.35, "pos rms {rms}");
        assert!(max_err < 1.0, "pos max {max_err}");
        assert!(rmsv < 0.35, "vel rms {rmsv}");
        std::println!("pos rms {rms} max {max_err} vel rms {rmsv} max speed {max_speed}");
        assert!(max_speed > 2.0, "manoeuvre is real");
    }

    #[test]
    fn gps_loss_dead_reckons() {
        let mut est = HorizontalEstimator::new(CfGains::new(1.0, 0.8));
        est.reset([1.0, 2.0], [0.5, -0.5]);
        est.gps([1.0, 2.0], 0);
        assert!(est.has_gps());
        est.clear_gps();
        assert!(!est.has_gps());
        for _ in 0..500 {
            est.update([0.0, 0.0], DT);
        }
        let p = est.pos_ne_m();
        assert!(
            (p[0] - 1.5).abs() < 1e-4 && (p[1] - 1.5).abs() < 1e-4,
            "{p:?}"
        );
        assert_eq!(est.vel_ne_mps(), [0.5, -0.5]);
    }

    /// The production structure (position crossover ω = 0.002 rad/s, Doppler velocity at 5 Hz
    /// with 0.3 per fix, the bias learnt from the velocity — its pole at 0.05 rad/s here, 0.2 in
    /// flight, `NavParams::horiz_bias_pole_radps`) at rest
    /// with a 0.1 m/s² accelerometer bias and a GPS position error wandering ±1 m: the bias is
    /// learnt, the velocity stays true, and the position ignores most of the GPS wander (0.33 m
    /// worst after 200 s in this one realisation, 0.22 m at the earlier 0.005 rad/s: the
    /// Doppler noise's random walk weighs more at the lower crossover; over many flights the
    /// lower one drifts less, `fcc_firmware::params`). Without the bias learning the same bias
    /// leaves ≈ 10 m of position error and a steady velocity error `k1·x̃`.
    #[test]
    fn velocity_learnt_bias_with_slow_position_crossover() {
        let run = |bias_pole: f32| {
            let mut rng = Rng::new(7);
            let mut est = HorizontalEstimator::new(CfGains::new(0.002, 0.8));
            est.n.set_bias_limit(0.5);
            est.e.set_bias_limit(0.5);
            est.reset([0.0, 0.0], [0.0, 0.0]);
            let kb = crate::complementary::bias_gain_per_fix(bias_pole, 0.3, 0.2);
            let (mut gps_err, mut worst_pos, mut vel_sum, mut n) = (0.0f32, 0.0f32, 0.0f32, 0u32);
            for k in 0..(300.0 / DT) as usize {
                if k % 100 == 0 {
                    // σ 1 m, τ 60 s Gauss–Markov error sampled at 5 Hz (the simulator's model).
                    let a = libm::expf(-0.2 / 60.0);
                    gps_err = a * gps_err + rng.normal(libm::sqrtf(1.0 - a * a));
                    est.gps([gps_err, -gps_err], 0);
                    let v = [rng.normal(0.05), rng.normal(0.05)];
                    est.gps_velocity(v, 0, 0.3, kb);
                }
                est.update([0.1, 0.1], DT);
                if k as f32 * DT > 200.0 {
                    worst_pos = worst_pos.max(libm::fabsf(est.pos_ne_m()[0]));
                    vel_sum += est.vel_ne_mps()[0];
                    n += 1;
                }
            }
            (est.n.bias(), worst_pos, vel_sum / n as f32)
        };
        let (bias, pos, vel) = run(0.05);
        std::println!("learnt: bias {bias} pos {pos} vel {vel}");
        assert!((bias - 0.1).abs() < 0.02, "bias {bias}");
        assert!(pos < 1.5, "pos {pos}");
        assert!(vel.abs() < 0.01, "mean vel {vel}");
        let (bias, pos, vel) = run(0.0);
        std::println!("not learnt: bias {bias} pos {pos} vel {vel}");
        assert!(
            bias == 0.0 && pos > 4.0 && vel.abs() > 0.03,
            "pos {pos} mean vel {vel}"
        );
    }
}
