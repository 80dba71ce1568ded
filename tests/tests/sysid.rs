//! Paper A's "3D curve fitting" (Fig. 12): fit `a_x = k1·θ − k2·v_x` by least squares on logged
//! flight data, as an operator would on a real flight log. This is also how the defaults of
//! `ControlParams::model_k1_mps2_per_rad` / `model_k2_per_s` were obtained:
//!
//! ```text
//! cargo test --release -p fcc_tests --test sysid -- --nocapture
//! ```

mod common;

use fcc_firmware::params::ControlParams;
use fcc_nav::sysid::PlaneFit;

#[test]
fn fitted_k1_k2_match_the_defaults() {
    // Calm air, so ground speed is airspeed (the model's drag term is about air-relative speed).
    let mut s = common::load("square");
    s.wind = Default::default();
    let log = common::fly_scenario(s);
    let mut fit = PlaneFit::new();
    for x in log
        .samples
        .iter()
        .filter(|x| x.armed && !x.landed && -x.nav.pos_ned_m[2] > 2.0)
    {
        let (sy, cy) = (x.nav.euler.yaw_rad.sin(), x.nav.euler.yaw_rad.cos());
        let v = x.nav.vel_ned_mps;
        let v_fr = [cy * v[0] + sy * v[1], -sy * v[0] + cy * v[1]];
        // Forward: nose-down tilt accelerates forward; right: right-wing-down accelerates right.
        let tilt_fr = [-x.nav.euler.pitch_rad, x.nav.euler.roll_rad];
        for k in 0..2 {
            fit.add(tilt_fr[k], v_fr[k], x.tel.accel_meas_fr_mps2[k]);
        }
    }
    let r = fit.solve().expect("well-conditioned fit");
    let d = ControlParams::default();
    println!(
        "fit on {} samples: k1 = {:.3} m/s²/rad, k2 = {:.3} 1/s (R² {:.3}, residual RMS {:.3} m/s²); defaults k1 = {:.3}, k2 = {:.3}",
        fit.count(),
        r.k1_mps2_per_rad,
        r.k2_per_s,
        r.r_squared,
        r.rms_residual_mps2,
        d.model_k1_mps2_per_rad,
        d.model_k2_per_s
    );
    assert!(fit.count() > 5000);
    assert!((r.k1_mps2_per_rad - d.model_k1_mps2_per_rad).abs() <= 0.05 * d.model_k1_mps2_per_rad);
    assert!(
        (r.k2_per_s - d.model_k2_per_s).abs() <= 0.05,
        "k2 {}",
        r.k2_per_s
    );
}
