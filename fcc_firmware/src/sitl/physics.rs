//! 6-DOF rigid-body model of the paper's octorotor (paper A, "Flight results").
//!
//! Vehicle: X-layout octorotor, 1.05 m diameter (arm 0.525 m), 0.33 m high, 4.5 kg with battery,
//! eight 10×4.5" props on 650 Kv motors, 40 A ESCs, 5S 5200 mAh battery.
//!
//! Frames: world NED, body FRD. The motor layout and the torque sign conventions come from
//! [`crate::geometry`] so that the simulator and the mixer can never disagree:
//! motor `i` at `(x_i, y_i)` with thrust `T_i` (along body −z) gives roll `−y_i·T_i`,
//! pitch `x_i·T_i`, yaw `−s_i·c_q·T_i` (`s_i = spin_cw(i)`).
//!
//! Rotor model: the ESC command `u ∈ [0, 1]` sets the steady rotor speed fraction `ω = u`
//! (speed ∝ command); the rotor speed follows it with a first-order lag (time constant
//! `motor_time_constant_s`); thrust `T = T_max·ω²`, reaction torque `c_q·T`.
//!
//! Integration: semi-implicit (symplectic) Euler at the caller's `dt` (the SITL uses 0.5 ms,
//! four times finer than needed for the ~0.05 s motor lag and ~20 rad/s attitude modes). The
//! quaternion is advanced by the exact exponential of the body rate over the step.
//!
//! Ground: a flat plane at NED down = `ground_down_m` (the vehicle's reference point, its
//! centre of mass, cannot go below it). In contact the ground supplies exactly the normal force
//! and the friction force/torque needed to stop vertical motion, sliding and yaw spinning
//! (friction limited by `ground_friction_coeff`·N), and keeps the vehicle level (no tipping):
//! roll and pitch decay to zero with `ground_level_time_constant_s`. A vehicle resting on the
//! ground therefore reads a specific force of exactly `[0, 0, −g]` in body.

use nalgebra::{UnitQuaternion, Vector3};
use serde::Deserialize;

use crate::geometry::{motor_position_m, spin_cw, MOTOR_COUNT};

/// Largest deceleration the landing gear applies while absorbing a touchdown (≈3 g), m/s².
pub const GEAR_MAX_DECEL_MPS2: f64 = 30.0;
/// Landing-gear stroke: penetration below the ground plane before a hard stop, m.
pub const GEAR_STROKE_M: f64 = 0.05;

/// Physical parameters of the vehicle. All defaults are for the paper's octorotor.
#[derive(Clone, Debug, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VehicleParams {
    /// Take-off mass including battery (paper A): 4.5 kg.
    pub mass_kg: f64,
    /// Principal moments of inertia [Ixx, Iyy, Izz] in kg·m², body FRD.
    ///
    /// Estimate from the geometry (4.5 kg total):
    /// - 8 motor+prop point masses of 0.08 kg at r = 0.525 m:
    ///   Izz = 8·0.08·0.525² = 0.176; Ixx = Iyy = half of that (Σsin² = Σcos² = 4) = 0.088.
    /// - 8 arms, 0.03 kg each, thin rods 0…0.525 m: Izz = 8·0.03·0.525²/3 = 0.022; Ixx = 0.011.
    /// - centre (frame plates, ESCs, FCC, battery), 3.62 kg, box 0.22×0.22×0.15 m:
    ///   Izz = 3.62·(0.22²+0.22²)/12 = 0.029; Ixx = 3.62·(0.22²+0.15²)/12 = 0.021.
    /// - landing gear and battery offset along z add ~0.01 to Ixx/Iyy.
    ///
    /// Total ≈ [0.13, 0.13, 0.23] kg·m².
    pub inertia_diag_kgm2: [f64; 3],
    /// Motor arm (centre to motor axis): half the 1.05 m diameter = 0.525 m.
    pub arm_m: f64,
    /// Static thrust of one rotor at full command, N.
    ///
    /// 650 Kv × 18.5 V (5S nominal) = 12 000 rpm unloaded, ~9 000 rpm loaded with a 10×4.5"
    /// prop (n = 150 rev/s). Static thrust `T = C_T·ρ·n²·D⁴` with C_T ≈ 0.11 (slow-flyer
    /// 10×4.5), ρ = 1.225, D = 0.254 m: T ≈ 0.11·1.225·150²·0.254⁴ ≈ 12.6 N → 12 N.
    /// Thrust-to-weight 8·12/(4.5·9.81) ≈ 2.2; hover command √(5.5/12) ≈ 0.68.
    pub max_thrust_per_motor_n: f64,
    /// Reaction-torque to thrust ratio c_q, metres: `C_P·D/(2π·C_T)` ≈ 0.045·0.254/(2π·0.11)
    /// ≈ 0.0165 → 0.016 m.
    pub torque_to_thrust_m: f64,
    /// First-order time constant of the rotor speed (motor + ESC + prop inertia), s.
    pub motor_time_constant_s: f64,
    /// Rotor-speed fraction at full command (the lag target is `cmd·this`); 1.0.
    pub max_rotor_speed_frac: f64,
    /// Linear "rotor drag" (blade flapping / induced drag) of all rotors together, N per m/s
    /// of horizontal (body x/y) air-relative velocity, at hover rotor speed; it scales with the
    /// rotor speed. 4.5 kg × 0.25 1/s = 1.125 N/(m/s), i.e. paper A's `a_x = k1·θ − k2·v_x` with
    /// k2 ≈ 0.25 1/s at low speed.
    pub rotor_drag_n_per_mps: f64,
    /// Quadratic body drag Cd·A for air-relative velocity along body x/y, m²
    /// (frame, battery, legs seen from the side ≈ 0.1 m² at Cd ≈ 1).
    pub body_cda_horizontal_m2: f64,
    /// Quadratic body drag Cd·A along body z, m² (top view of the frame and rotor disks in
    /// axial flow ≈ 0.25 m²).
    pub body_cda_vertical_m2: f64,
    /// Air density, kg/m³ (ISA sea level).
    pub air_density_kgpm3: f64,
    /// Aerodynamic angular damping, N·m per rad/s, [roll, pitch, yaw].
    pub angular_damping_nms: [f64; 3],
    /// Gravity, m/s².
    pub gravity_mps2: f64,
    /// Coulomb friction coefficient between the landing gear and the ground.
    pub ground_friction_coeff: f64,
    /// Lever arm of the ground friction that resists yaw (landing-gear radius), m.
    pub ground_yaw_friction_radius_m: f64,
    /// Time constant with which roll/pitch return to level while in ground contact, s.
    pub ground_level_time_constant_s: f64,
    /// Overall propulsion efficiency (rotor figure of merit × motor/ESC efficiency) used by
    /// [`Octorotor::electrical_power_w`]: 0.65 × 0.75 ≈ 0.5 → 0.45 (slightly pessimistic).
    pub propulsion_efficiency: f64,
    /// Avionics power (FCC, Linux CoM, GPS, radios), W.
    pub avionics_power_w: f64,
    /// Height of the body reference point (centre of mass, where the rangefinders sit) above
    /// the ground when standing on the landing gear, m. The simulation places the contact plane
    /// this far above the terrain.
    pub gear_height_m: f64,
}

impl Default for VehicleParams {
    fn default() -> Self {
        Self {
            mass_kg: 4.5,
            inertia_diag_kgm2: [0.13, 0.13, 0.23],
            arm_m: 0.525,
            max_thrust_per_motor_n: 12.0,
            torque_to_thrust_m: 0.016,
            motor_time_constant_s: 0.05,
            max_rotor_speed_frac: 1.0,
            rotor_drag_n_per_mps: 4.5 * 0.25,
            body_cda_horizontal_m2: 0.10,
            body_cda_vertical_m2: 0.25,
            air_density_kgpm3: 1.225,
            angular_damping_nms: [0.02, 0.02, 0.03],
            gravity_mps2: 9.80665,
            ground_friction_coeff: 1.0,
            ground_yaw_friction_radius_m: 0.2,
            ground_level_time_constant_s: 0.05,
            propulsion_efficiency: 0.45,
            avionics_power_w: 8.0,
            gear_height_m: 0.25,
        }
    }
}

impl VehicleParams {
    /// Rotor speed fraction at which the rotors together carry the weight.
    pub fn hover_rotor_speed_frac(&self) -> f64 {
        let t =
            self.mass_kg * self.gravity_mps2 / (MOTOR_COUNT as f64 * self.max_thrust_per_motor_n);
        t.max(0.0).sqrt()
    }
}

/// The true state of the rigid body.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidBodyState {
    /// Position of the centre of mass, NED, metres from the simulation origin.
    pub pos_ned_m: Vector3<f64>,
    /// Velocity, NED, m/s.
    pub vel_ned_mps: Vector3<f64>,
    /// Attitude: rotates body FRD vectors into NED.
    pub q_body_to_ned: UnitQuaternion<f64>,
    /// Body angular rate, FRD, rad/s.
    pub omega_frd_radps: Vector3<f64>,
    /// Rotor speed of each motor as a fraction of the full-command speed (0..1).
    pub rotor_speed_frac: [f64; MOTOR_COUNT],
}

/// The simulated octorotor.
#[derive(Clone, Debug)]
pub struct Octorotor {
    pub params: VehicleParams,
    pub state: RigidBodyState,
    /// Motor positions (x, y) in body FRD, metres.
    motor_xy_m: [(f64, f64); MOTOR_COUNT],
    /// +1 clockwise, −1 counter-clockwise.
    motor_spin: [f64; MOTOR_COUNT],
    /// Kinematic acceleration over the last step, NED.
    last_accel_ned_mps2: Vector3<f64>,
    /// Whether the ground supported the vehicle during the last step.
    in_contact: bool,
}

impl Octorotor {
    /// A vehicle at `pos_ned_m` (normally on the ground: `pos_ned_m.z == ground_down_m`),
    /// level, heading `yaw_rad`, at rest, motors stopped.
    pub fn new(params: VehicleParams, pos_ned_m: Vector3<f64>, yaw_rad: f64) -> Self {
        let arm = params.arm_m;
        let mut motor_xy_m = [(0.0, 0.0); MOTOR_COUNT];
        let mut motor_spin = [0.0; MOTOR_COUNT];
        for i in 0..MOTOR_COUNT {
            // The layout documented in `crate::geometry` (azimuth 22.5° + i·45°), evaluated in
            // f64 so that a symmetric command gives exactly zero torque; checked against the
            // shared f32 function so the two can never diverge.
            let az = (22.5 + 45.0 * i as f64).to_radians();
            let (x, y) = (arm * az.cos(), arm * az.sin());
            let (xg, yg) = motor_position_m(i, arm as f32);
            assert!(
                (x - xg as f64).abs() < 1e-4 && (y - yg as f64).abs() < 1e-4,
                "motor layout differs from crate::geometry"
            );
            motor_xy_m[i] = (x, y);
            motor_spin[i] = spin_cw(i) as f64;
        }
        Self {
            params,
            state: RigidBodyState {
                pos_ned_m,
                vel_ned_mps: Vector3::zeros(),
                q_body_to_ned: UnitQuaternion::from_euler_angles(0.0, 0.0, yaw_rad),
                omega_frd_radps: Vector3::zeros(),
                rotor_speed_frac: [0.0; MOTOR_COUNT],
            },
            motor_xy_m,
            motor_spin,
            last_accel_ned_mps2: Vector3::zeros(),
            in_contact: true,
        }
    }

    /// Motor positions (x, y) in body FRD, metres (from `crate::geometry`).
    pub fn motor_xy_m(&self) -> &[(f64, f64); MOTOR_COUNT] {
        &self.motor_xy_m
    }

    /// Thrust of each rotor at the current rotor speeds, N.
    pub fn rotor_thrusts_n(&self) -> [f64; MOTOR_COUNT] {
        let mut t = [0.0; MOTOR_COUNT];
        for (ti, w) in t.iter_mut().zip(self.state.rotor_speed_frac.iter()) {
            *ti = self.params.max_thrust_per_motor_n * w * w;
        }
        t
    }

    /// Advance the simulation by `dt_s`.
    ///
    /// `motor_cmd`: ESC commands 0..1 (clamped); `wind_ned_mps`: air velocity over the ground;
    /// `ground_down_m`: NED down coordinate of the ground plane under the vehicle.
    pub fn step(
        &mut self,
        motor_cmd: &[f32; MOTOR_COUNT],
        wind_ned_mps: Vector3<f64>,
        ground_down_m: f64,
        dt_s: f64,
    ) {
        if dt_s.is_nan() || dt_s <= 0.0 {
            return;
        }
        let (thrust_n, speed_sum) = self.advance_rotors(motor_cmd, dt_s);
        let omega = self.state.omega_frd_radps;
        let total_thrust_n: f64 = thrust_n.iter().sum();
        let torque_frd_nm = self.body_torque_frd_nm(&thrust_n, &omega);
        let f_air_ned_n = self.air_force_ned_n(total_thrust_n, speed_sum, wind_ned_mps);
        let gravity = Vector3::new(0.0, 0.0, self.params.gravity_mps2);
        let mut accel_ned_mps2 = f_air_ned_n / self.params.mass_kg + gravity;
        let mut omega_dot_frd_radps2 = self.free_angular_accel_frd_radps2(&torque_frd_nm);
        let contact = self.apply_ground_reaction(
            &f_air_ned_n,
            &torque_frd_nm,
            ground_down_m,
            dt_s,
            &mut accel_ned_mps2,
            &mut omega_dot_frd_radps2,
        );
        self.integrate(
            accel_ned_mps2,
            omega_dot_frd_radps2,
            contact,
            ground_down_m,
            dt_s,
        );
    }

    /// Rotors: first-order lag on speed (exact discretisation) towards the clamped command,
    /// thrust ∝ speed². Returns each rotor's thrust (N) and the sum of the speed fractions.
    fn advance_rotors(
        &mut self,
        motor_cmd: &[f32; MOTOR_COUNT],
        dt_s: f64,
    ) -> ([f64; MOTOR_COUNT], f64) {
        let p = &self.params;
        let alpha = if p.motor_time_constant_s > 0.0 {
            1.0 - (-dt_s / p.motor_time_constant_s).exp()
        } else {
            1.0
        };
        let mut thrust = [0.0; MOTOR_COUNT];
        let mut speed_sum = 0.0;
        for i in 0..MOTOR_COUNT {
            let c = motor_cmd[i];
            let c = if c.is_finite() {
                (c as f64).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let target = c * p.max_rotor_speed_frac;
            let w = &mut self.state.rotor_speed_frac[i];
            *w += (target - *w) * alpha;
            thrust[i] = p.max_thrust_per_motor_n * *w * *w;
            speed_sum += *w;
        }
        (thrust, speed_sum)
    }

    /// Rotor torques (thrust lever arms and reaction torque) less the angular damping,
    /// body FRD, N·m.
    fn body_torque_frd_nm(
        &self,
        thrust_n: &[f64; MOTOR_COUNT],
        omega_frd_radps: &Vector3<f64>,
    ) -> Vector3<f64> {
        let p = &self.params;
        let mut torque = Vector3::zeros();
        #[allow(clippy::needless_range_loop)]
        for i in 0..MOTOR_COUNT {
            let (x, y) = self.motor_xy_m[i];
            torque.x += -y * thrust_n[i];
            torque.y += x * thrust_n[i];
            torque.z += -self.motor_spin[i] * p.torque_to_thrust_m * thrust_n[i];
        }
        let damping = Vector3::from(p.angular_damping_nms);
        torque -= damping.component_mul(omega_frd_radps);
        torque
    }

    /// Thrust, rotor drag (∝ airspeed and mean rotor speed) and body drag (∝ airspeed²),
    /// NED, N.
    fn air_force_ned_n(
        &self,
        total_thrust_n: f64,
        speed_sum: f64,
        wind_ned_mps: Vector3<f64>,
    ) -> Vector3<f64> {
        let p = &self.params;
        let q = self.state.q_body_to_ned;
        let v_air_b = q.inverse_transform_vector(&(self.state.vel_ned_mps - wind_ned_mps));
        let hover_w = p.hover_rotor_speed_frac().max(1e-6);
        let rotor_drag_scale =
            p.rotor_drag_n_per_mps * (speed_sum / (MOTOR_COUNT as f64 * hover_w));
        let half_rho = 0.5 * p.air_density_kgpm3;
        let v_h = (v_air_b.x * v_air_b.x + v_air_b.y * v_air_b.y).sqrt();
        let f_body = Vector3::new(
            -rotor_drag_scale * v_air_b.x - half_rho * p.body_cda_horizontal_m2 * v_h * v_air_b.x,
            -rotor_drag_scale * v_air_b.y - half_rho * p.body_cda_horizontal_m2 * v_h * v_air_b.y,
            -total_thrust_n - half_rho * p.body_cda_vertical_m2 * v_air_b.z.abs() * v_air_b.z,
        );
        q.transform_vector(&f_body)
    }

    /// The gyroscopic term `ω × (I·ω)`, body FRD, N·m.
    fn gyroscopic_torque_frd_nm(&self) -> Vector3<f64> {
        let omega = self.state.omega_frd_radps;
        let inertia = Vector3::from(self.params.inertia_diag_kgm2);
        let i_omega = inertia.component_mul(&omega);
        omega.cross(&i_omega)
    }

    /// Free angular acceleration: I·ω̇ = τ − ω × (I·ω), body FRD, rad/s².
    fn free_angular_accel_frd_radps2(&self, torque_frd_nm: &Vector3<f64>) -> Vector3<f64> {
        let inertia = Vector3::from(self.params.inertia_diag_kgm2);
        (torque_frd_nm - self.gyroscopic_torque_frd_nm()).component_div(&inertia)
    }

    /// Ground contact: at the plane, the normal force that brings the vertical velocity to 0
    /// (no harder than the landing gear's stroke allows, [`GEAR_MAX_DECEL_MPS2`]: a touchdown
    /// decelerates over tens of milliseconds, as the accelerometer then sees) and the friction
    /// that stops sliding and yaw spinning. Returns whether the ground pushed; then the
    /// accelerations include its reaction.
    fn apply_ground_reaction(
        &self,
        f_air_ned_n: &Vector3<f64>,
        torque_frd_nm: &Vector3<f64>,
        ground_down_m: f64,
        dt_s: f64,
        accel_ned_mps2: &mut Vector3<f64>,
        omega_dot_frd_radps2: &mut Vector3<f64>,
    ) -> bool {
        let at_ground = self.state.pos_ned_m.z >= ground_down_m - 1e-9;
        if !at_ground {
            return false;
        }
        let m = self.params.mass_kg;
        let vel = self.state.vel_ned_mps;
        // Normal force (NED z, negative = pushing up).
        let a_stop = (-vel.z / dt_s).max(-GEAR_MAX_DECEL_MPS2);
        let n_z = m * a_stop - f_air_ned_n.z - m * self.params.gravity_mps2;
        if n_z < 0.0 {
            let n = -n_z;
            accel_ned_mps2.z = a_stop;
            let fr = self.ground_friction_ned_n(f_air_ned_n, n, dt_s);
            accel_ned_mps2.x = (f_air_ned_n.x + fr.x) / m;
            accel_ned_mps2.y = (f_air_ned_n.y + fr.y) / m;
            omega_dot_frd_radps2.z += self.ground_yaw_torque_nm(torque_frd_nm, n, dt_s)
                / self.params.inertia_diag_kgm2[2];
            true
        } else {
            false
        }
    }

    /// Friction: whatever stops the horizontal sliding, limited by μ·N (`normal_n`), NED, N.
    fn ground_friction_ned_n(
        &self,
        f_air_ned_n: &Vector3<f64>,
        normal_n: f64,
        dt_s: f64,
    ) -> Vector3<f64> {
        let m = self.params.mass_kg;
        let vel = self.state.vel_ned_mps;
        let want = Vector3::new(
            -m * vel.x / dt_s - f_air_ned_n.x,
            -m * vel.y / dt_s - f_air_ned_n.y,
            0.0,
        );
        let lim = self.params.ground_friction_coeff * normal_n;
        if want.norm() <= lim {
            want
        } else {
            want * (lim / want.norm())
        }
    }

    /// Yaw friction torque that stops the yaw spin, limited by μ·N·r, N·m.
    fn ground_yaw_torque_nm(&self, torque_frd_nm: &Vector3<f64>, normal_n: f64, dt_s: f64) -> f64 {
        let p = &self.params;
        let inertia_z = p.inertia_diag_kgm2[2];
        let omega_z = self.state.omega_frd_radps.z;
        let want_tz =
            -inertia_z * omega_z / dt_s - (torque_frd_nm.z - self.gyroscopic_torque_frd_nm().z);
        let lim_tz = p.ground_friction_coeff * normal_n * p.ground_yaw_friction_radius_m;
        want_tz.clamp(-lim_tz, lim_tz)
    }

    /// Integrate (semi-implicit Euler), with the gear's hard stop and, in contact, the
    /// attitude returning to level; stores the new state and the step's acceleration.
    fn integrate(
        &mut self,
        accel_ned_mps2: Vector3<f64>,
        omega_dot_frd_radps2: Vector3<f64>,
        mut contact: bool,
        ground_down_m: f64,
        dt_s: f64,
    ) {
        let q = self.state.q_body_to_ned;
        let vel = self.state.vel_ned_mps;
        let mut new_vel = vel + accel_ned_mps2 * dt_s;
        let mut new_pos = self.state.pos_ned_m + new_vel * dt_s;
        let mut new_omega = self.state.omega_frd_radps + omega_dot_frd_radps2 * dt_s;
        if contact {
            // No tipping: roll/pitch rates chosen to return to level.
            let (roll, pitch, _) = q.euler_angles();
            let tc = self.params.ground_level_time_constant_s.max(dt_s);
            new_omega.x = -roll / tc;
            new_omega.y = -pitch / tc;
        }
        if new_pos.z > ground_down_m + GEAR_STROKE_M {
            // Bottomed out the gear (a crash-grade touchdown): hard stop.
            new_pos.z = ground_down_m + GEAR_STROKE_M;
            if new_vel.z > 0.0 {
                new_vel.z = 0.0;
            }
            contact = true;
        } else if new_pos.z > ground_down_m {
            // Touching down within this step: the gear takes over from the next step.
            contact = true;
        }
        let rot = UnitQuaternion::from_scaled_axis(new_omega * dt_s);
        let mut new_q = q * rot;
        new_q.renormalize();
        if contact && new_pos.z >= ground_down_m {
            new_q = Self::level_if_nearly_level(new_q);
        }
        self.last_accel_ned_mps2 = (new_vel - vel) / dt_s;
        self.state.vel_ned_mps = new_vel;
        self.state.pos_ned_m = new_pos;
        self.state.omega_frd_radps = new_omega;
        self.state.q_body_to_ned = new_q;
        self.in_contact = contact;
    }

    /// Remove any residual roll/pitch below numerical noise so that the resting attitude is
    /// exactly level.
    fn level_if_nearly_level(q: UnitQuaternion<f64>) -> UnitQuaternion<f64> {
        let (r, pt, y) = q.euler_angles();
        if r.abs() < 1e-12 && pt.abs() < 1e-12 {
            UnitQuaternion::from_euler_angles(0.0, 0.0, y)
        } else {
            q
        }
    }

    /// True kinematic acceleration over the last step, NED, m/s².
    pub fn accel_ned_mps2(&self) -> Vector3<f64> {
        self.last_accel_ned_mps2
    }

    /// What an ideal accelerometer reads: (acceleration − gravity) in body FRD, m/s²,
    /// including the ground reaction (≈ `[0, 0, −g]` resting level on the ground).
    pub fn specific_force_frd_mps2(&self) -> Vector3<f64> {
        let f_ned = self.last_accel_ned_mps2 - Vector3::new(0.0, 0.0, self.params.gravity_mps2);
        self.state.q_body_to_ned.inverse_transform_vector(&f_ned)
    }

    /// Whether the ground supported the vehicle during the last step.
    pub fn on_ground(&self) -> bool {
        self.in_contact
    }

    /// (roll, pitch, yaw) in radians, ZYX convention.
    pub fn euler_rad(&self) -> (f64, f64, f64) {
        self.state.q_body_to_ned.euler_angles()
    }

    /// The motor command (all motors equal) whose steady thrust equals the weight.
    pub fn hover_cmd(&self) -> f32 {
        (self.params.hover_rotor_speed_frac() / self.params.max_rotor_speed_frac) as f32
    }

    /// Mean rotor speed fraction over the motors.
    pub fn rotor_speed_frac_mean(&self) -> f64 {
        self.state.rotor_speed_frac.iter().sum::<f64>() / MOTOR_COUNT as f64
    }

    /// Electrical power drawn from the battery, W: momentum-theory induced power of each
    /// rotor `T^1.5/√(2ρA)` (A = disk area of a 10" prop) divided by the propulsion efficiency,
    /// plus the avionics. ≈ 660 W at hover (≈ 36 A at 18.5 V). Divide by the battery voltage
    /// for the current.
    pub fn electrical_power_w(&self) -> f64 {
        let p = &self.params;
        let disk_area = core::f64::consts::PI * 0.127 * 0.127;
        let k = 1.0 / (2.0 * p.air_density_kgpm3 * disk_area).sqrt();
        let rotor: f64 = self
            .rotor_thrusts_n()
            .iter()
            .map(|t| t.max(0.0).powf(1.5) * k)
            .sum();
        rotor / p.propulsion_efficiency.max(1e-3) + p.avionics_power_w
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    const DT: f64 = 0.0005;

    fn airborne(alt: f64) -> Octorotor {
        let mut o = Octorotor::new(VehicleParams::default(), Vector3::new(0.0, 0.0, -alt), 0.3);
        let w = o.params.hover_rotor_speed_frac();
        o.state.rotor_speed_frac = [w; MOTOR_COUNT];
        o
    }

    #[test]
    fn hover_stays_put() {
        let mut o = airborne(10.0);
        let c = [o.hover_cmd(); MOTOR_COUNT];
        for _ in 0..(10.0 / DT) as usize {
            o.step(&c, Vector3::zeros(), 0.0, DT);
        }
        let p = o.state.pos_ned_m;
        assert!((p - Vector3::new(0.0, 0.0, -10.0)).norm() < 0.05, "{p:?}");
        assert!(o.state.vel_ned_mps.norm() < 0.01);
        let (r, pt, y) = o.euler_rad();
        assert!(
            r.abs() < 1e-6 && pt.abs() < 1e-6 && (y - 0.3).abs() < 1e-3,
            "{r} {pt} {y}"
        );
        assert!(!o.on_ground());
        let sf = o.specific_force_frd_mps2();
        assert!(
            (sf - Vector3::new(0.0, 0.0, -9.80665)).norm() < 0.01,
            "{sf:?}"
        );
    }

    #[test]
    fn hover_cmd_value() {
        let o = Octorotor::new(VehicleParams::default(), Vector3::zeros(), 0.0);
        let h = o.hover_cmd();
        assert!((h - 0.6776).abs() < 0.01, "{h}");
    }

    #[test]
    fn roll_torque_gives_positive_roll() {
        let mut o = airborne(10.0);
        let h = o.hover_cmd();
        let mut c = [h; MOTOR_COUNT];
        for i in 0..MOTOR_COUNT {
            let (_, y) = o.motor_xy_m()[i];
            if y > 0.0 {
                c[i] = h - 0.05; // right motors lower
            } else {
                c[i] = h + 0.05;
            }
        }
        for _ in 0..400 {
            o.step(&c, Vector3::zeros(), 0.0, DT);
        }
        let (r, p, _) = o.euler_rad();
        assert!(r > 0.01, "roll {r}");
        assert!(o.state.omega_frd_radps.x > 0.0);
        assert!(p.abs() < 0.01 * r, "pitch {p}");
    }

    #[test]
    fn pitch_and_yaw_signs() {
        // Front motors stronger → nose up → positive pitch.
        let mut o = airborne(10.0);
        let h = o.hover_cmd();
        let mut c = [h; MOTOR_COUNT];
        for i in 0..MOTOR_COUNT {
            c[i] = if o.motor_xy_m()[i].0 > 0.0 {
                h + 0.05
            } else {
                h - 0.05
            };
        }
        for _ in 0..400 {
            o.step(&c, Vector3::zeros(), 0.0, DT);
        }
        assert!(o.euler_rad().1 > 0.01);
        // Counter-clockwise rotors (odd) faster → their reaction turns the body clockwise
        // seen from above → positive yaw rate in FRD.
        let mut o = airborne(10.0);
        let mut c = [h; MOTOR_COUNT];
        for (i, ci) in c.iter_mut().enumerate() {
            *ci = if spin_cw(i) < 0.0 { h + 0.05 } else { h - 0.05 };
        }
        for _ in 0..400 {
            o.step(&c, Vector3::zeros(), 0.0, DT);
        }
        assert!(
            o.state.omega_frd_radps.z > 0.01,
            "{:?}",
            o.state.omega_frd_radps
        );
    }

    #[test]
    fn free_fall() {
        let mut o = Octorotor::new(
            VehicleParams::default(),
            Vector3::new(0.0, 0.0, -100.0),
            0.0,
        );
        let c = [0.0; MOTOR_COUNT];
        // No drag when the air moves with the vehicle: pure ballistic check using wind = vel.
        for _ in 0..2000 {
            let wind = o.state.vel_ned_mps;
            o.step(&c, wind, 0.0, DT);
        }
        let t = 2000.0 * DT;
        let g = 9.80665;
        assert!((o.state.vel_ned_mps.z - g * t).abs() < 1e-9);
        assert!((o.state.pos_ned_m.z - (-100.0 + 0.5 * g * t * t)).abs() < 0.01);
        let sf = o.specific_force_frd_mps2();
        assert!(sf.norm() < 1e-9, "{sf:?}");
        assert!(!o.on_ground());
    }

    #[test]
    fn resting_on_ground() {
        let mut o = Octorotor::new(VehicleParams::default(), Vector3::new(1.0, 2.0, -3.0), 1.0);
        assert!(o.on_ground());
        assert_eq!(
            o.specific_force_frd_mps2(),
            Vector3::new(0.0, 0.0, -9.80665)
        );
        let c = [0.0; MOTOR_COUNT];
        for _ in 0..4000 {
            o.step(&c, Vector3::new(3.0, -2.0, 0.0), -3.0, DT);
        }
        assert!(o.on_ground());
        assert_eq!(o.state.pos_ned_m, Vector3::new(1.0, 2.0, -3.0));
        assert_eq!(o.state.vel_ned_mps, Vector3::zeros());
        let sf = o.specific_force_frd_mps2();
        assert!(
            (sf - Vector3::new(0.0, 0.0, -9.80665)).norm() < 1e-12,
            "{sf:?}"
        );
        // Idle spin on the ground (below hover) still rests.
        let c = [0.3; MOTOR_COUNT];
        for _ in 0..4000 {
            o.step(&c, Vector3::zeros(), -3.0, DT);
        }
        assert!(o.on_ground());
        assert!((o.state.pos_ned_m.z + 3.0).abs() < 1e-12);
        let sf = o.specific_force_frd_mps2();
        assert!(
            (sf - Vector3::new(0.0, 0.0, -9.80665)).norm() < 1e-9,
            "{sf:?}"
        );
    }

    #[test]
    fn falls_lands_and_takes_off() {
        let mut o = Octorotor::new(VehicleParams::default(), Vector3::new(0.0, 0.0, -2.0), 0.0);
        for _ in 0..4000 {
            o.step(&[0.0; MOTOR_COUNT], Vector3::zeros(), 0.0, DT);
        }
        assert!(o.on_ground());
        // A 2 m free fall (6.3 m/s) bottoms out the gear's stroke: resting within it, stopped.
        assert!(
            o.state.pos_ned_m.z >= 0.0 && o.state.pos_ned_m.z <= GEAR_STROKE_M,
            "{:?}",
            o.state.pos_ned_m
        );
        assert_eq!(o.state.vel_ned_mps.z, 0.0);
        // Full throttle → climbs.
        for _ in 0..2000 {
            o.step(&[0.9; MOTOR_COUNT], Vector3::zeros(), 0.0, DT);
        }
        assert!(!o.on_ground());
        assert!(o.state.pos_ned_m.z < -0.5, "{:?}", o.state.pos_ned_m);
    }

    #[test]
    fn wind_drag_pushes_downwind() {
        let mut o = airborne(20.0);
        let c = [o.hover_cmd(); MOTOR_COUNT];
        for _ in 0..2000 {
            o.step(&c, Vector3::new(0.0, 5.0, 0.0), 0.0, DT);
        }
        // Initial acceleration ≈ k2·v = 0.25·5 (+ body drag) towards east.
        assert!(o.state.vel_ned_mps.y > 0.5, "{:?}", o.state.vel_ned_mps);
    }

    #[test]
    fn hover_power_is_plausible() {
        let o = airborne(5.0);
        let p = o.electrical_power_w();
        assert!(p > 400.0 && p < 900.0, "{p}");
    }

    #[test]
    fn gentle_touchdown_decelerates_within_the_gear_limit() {
        let mut o = Octorotor::new(VehicleParams::default(), Vector3::new(0.0, 0.0, -0.2), 0.0);
        o.state.vel_ned_mps = Vector3::new(0.0, 0.0, 0.5);
        let h = o.hover_cmd() * 0.97;
        o.state.rotor_speed_frac = [h as f64 * o.params.max_rotor_speed_frac; MOTOR_COUNT];
        let mut peak: f64 = 0.0;
        for _ in 0..4000 {
            o.step(&[h; MOTOR_COUNT], Vector3::zeros(), 0.0, DT);
            peak = peak.max(o.specific_force_frd_mps2().norm());
        }
        assert!(
            o.on_ground() && o.state.vel_ned_mps.z.abs() < 1e-9,
            "{:?} {:?}",
            o.state.pos_ned_m,
            o.state.vel_ned_mps
        );
        // The accelerometer sees the touchdown, within its ±8 g range.
        assert!(
            peak > 15.0 && peak <= 9.81 + GEAR_MAX_DECEL_MPS2 + 1.0,
            "peak {peak}"
        );
        assert!(o.state.pos_ned_m.z < GEAR_STROKE_M);
    }
}
