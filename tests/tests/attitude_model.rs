//! The acceleration observer's model of the closed attitude loop, `θ̇ = −a·θ + b·θ_cmd`
//! (`ControlParams::att_model_a_per_s` / `att_model_b_per_s`, paper A eq. 14), is derived from
//! the roll/pitch PID and the airframe, not typed by hand: this test flies the firmware's own
//! [`TiltPid`] against one rigid axis of the simulated airframe (`fcc_sim::physics`: inertia,
//! aerodynamic damping, the rotors' first-order lag on the torque) and fits the first-order
//! model to its step response. The model must lie within 10 % of the fit, `b = a` (the loop
//! holds the commanded angle: unity gain), and the response must be well damped (the
//! model has no overshoot).
//!
//! ```text
//! cargo test --release -p fcc_tests --test attitude_model -- --nocapture
//! ```
//!
//! Change the attitude gains and this fails until the observer's model follows them (gains
//! 6.0 / 1.4 N·m per rad, rad/s: a = 4.1 /s fitted, 4.0 in the model; 15 / 2.5: 5.9).

use fcc_firmware::control::attitude::TiltPid;
use fcc_firmware::params::ControlParams;
use fcc_sim::physics::VehicleParams;

/// Integration step, s.
const DT_S: f64 = 1e-4;
/// Step size, rad.
const STEP_RAD: f64 = 0.1;
/// Length of the response, s.
const SPAN_S: f64 = 2.0;

/// The roll angle's response (rad, every `DT_S`) to a step of `STEP_RAD` in the command.
fn step_response(c: &ControlParams, v: &VehicleParams) -> Vec<f64> {
    let mut pid = TiltPid::new(
        c.att_p_nm_per_rad,
        c.att_i_nm_per_rad_s,
        c.att_d_nm_per_radps,
        c.att_i_limit_nm,
    );
    let inertia = v.inertia_diag_kgm2[0];
    let damping = v.angular_damping_nms[0];
    let (mut angle, mut rate, mut torque) = (0.0f64, 0.0f64, 0.0f64);
    let n = (SPAN_S / DT_S) as usize;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let cmd = pid.update(
            DT_S as f32,
            STEP_RAD as f32,
            angle as f32,
            rate as f32,
            true,
        ) as f64;
        // The rotors' speed lags the command (first order); the torque follows the speed.
        torque += (cmd - torque) * DT_S / v.motor_time_constant_s;
        rate += (torque - damping * rate) / inertia * DT_S;
        angle += rate * DT_S;
        out.push(angle / STEP_RAD);
    }
    out
}

/// Least-squares first-order fit `1 − e^(−a·t)` to a unit step response: a, 1/s.
fn first_order_fit_per_s(y: &[f64]) -> f64 {
    let cost = |a: f64| -> f64 {
        y.iter()
            .enumerate()
            .step_by(10)
            .map(|(i, &v)| {
                let m = 1.0 - (-a * i as f64 * DT_S).exp();
                (v - m) * (v - m)
            })
            .sum()
    };
    // Golden-section search on 0.5 … 50 1/s (the cost is unimodal in a).
    let (mut lo, mut hi) = (0.5f64, 50.0f64);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..80 {
        let a1 = hi - g * (hi - lo);
        let a2 = lo + g * (hi - lo);
        if cost(a1) < cost(a2) {
            hi = a2;
        } else {
            lo = a1;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn the_observer_models_the_attitude_loop_it_flies_with() {
    let c = ControlParams::default();
    let v = VehicleParams::default();
    let y = step_response(&c, &v);
    let a_fit = first_order_fit_per_s(&y);
    let overshoot = y.iter().cloned().fold(f64::MIN, f64::max) - 1.0;
    let t63_s = y.iter().position(|&x| x >= 1.0 - (-1f64).exp()).unwrap() as f64 * DT_S;
    let a_model = c.att_model_a_per_s as f64;
    let b_model = c.att_model_b_per_s as f64;
    println!(
        "attitude loop (Kp {} N·m/rad, Kd {} N·m·s/rad, I {} kg·m², rotor lag {} s): \
         first-order fit a = {a_fit:.2} /s (t63 {:.0} ms, overshoot {:.1} %); model a = {a_model}, b = {b_model}",
        c.att_p_nm_per_rad,
        c.att_d_nm_per_radps,
        v.inertia_diag_kgm2[0],
        v.motor_time_constant_s,
        t63_s * 1e3,
        overshoot * 100.0
    );
    assert!(
        (a_model - a_fit).abs() <= 0.1 * a_fit,
        "att_model_a_per_s {a_model} is not the loop's {a_fit:.2} /s (±10 %)"
    );
    assert_eq!(
        a_model, b_model,
        "the loop holds the commanded angle: b = a"
    );
    // Well damped: the integral's slow creep aside (≈ 4 % with the old gains), no ringing.
    assert!(overshoot < 0.06, "overshoot {:.1} %", overshoot * 100.0);
}
