//! Every gain and limit of the flight core in one struct, with documented defaults for paper A's
//! octorotor (4.5 kg, 1.05 m, 8 × 10×4.5" props, 650 Kv, 5S).
//!
//! Units are in the field names. Defaults were tuned in the SITL against noisy sensor models
//! (see `fcc_sim::sensor_models`), not against perfect sensors.

use fcc_msgs::{param_default, Stream, StreamRates, BAUD_921600_BYTES_PER_S};
use fcc_nav::complementary::CfGains;
use fcc_nav::observer::AccelObserverParams;

/// Airframe constants the controller needs (the mixer's allocation and the thrust model).
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AirframeParams {
    pub mass_kg: f32,
    /// Motor distance from the centre (1.05 m diameter frame → 0.525 m).
    pub arm_m: f32,
    /// Rotor torque / thrust ratio (m), for yaw allocation.
    pub torque_to_thrust_m: f32,
    /// Static thrust of one motor at full command (N). ESC command ∝ rotor speed, thrust ∝ speed².
    pub max_thrust_per_motor_n: f32,
    /// Motor command while armed on the ground (spinning, no lift).
    pub idle_cmd: f32,
    /// Height of the downward rangefinders above the ground when standing on the gear, m
    /// (they sit at the centre of mass).
    pub sensor_height_on_ground_m: f32,
    /// Distance from the centre to the landing gear's feet, m (paper A's skids ≈ 0.6 m
    /// apart): leaning, the foot on that side comes down ([`crate::geometry::foot_drop_m`]).
    pub gear_half_span_m: f32,
}

impl Default for AirframeParams {
    fn default() -> Self {
        Self {
            mass_kg: 4.5,
            arm_m: 0.525,
            torque_to_thrust_m: 0.016,
            max_thrust_per_motor_n: 12.0,
            idle_cmd: 0.1,
            sensor_height_on_ground_m: 0.25,
            gear_half_span_m: 0.3,
        }
    }
}

/// Navigation filter tuning (complementary-filter crossovers, paper eq. 1).
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NavParams {
    /// Roll/pitch: accelerometer angles through F_L, gyro through F_H. Low crossover because the
    /// in-flight accelerometer carries motor vibration and manoeuvre accelerations.
    pub tilt_omega_radps: f32,
    /// Roll/pitch damping: 0.5 (was 1.0) halves the proportional correction `2ζω` for the same
    /// gyro-bias integrator `ω²`, so less of the gusts' uncompensated acceleration reaches the
    /// tilt. Attitude bench (`tests/benches/attitude_filter.rs`) RMS roll/pitch, square
    /// 0.404/0.363° → 0.310/0.283°, manoeuvre 0.411/0.858° → 0.238/0.576°; the dead-reckoned
    /// velocity integrates the tilt error after a GPS loss, and the campaign's GPS-loss
    /// touchdowns beyond 0.3 m/s fell from 0 / 2 / 8 to 0 / 1 / 3 (seed sets 1000 / 3000 /
    /// 5000; ζ = 0.35: 0 / 1 / 5, and cruises at the speed limit wobbled more).
    pub tilt_zeta: f32,
    /// Yaw: tilt-compensated magnetometer through F_L (rides through short disturbances).
    pub yaw_omega_radps: f32,
    pub yaw_zeta: f32,
    /// Horizontal: GPS position through F_L, NED acceleration through F_H. Low (≈ 8-min
    /// time constant): the GPS Doppler velocity ([`Self::gps_vel_gain`]) carries the short
    /// term, and the position follows the receiver's slowly wandering error (σ ≈ 1 m, τ ≈ 1
    /// min) only slowly — with ω = 0.3 the hold point wandered with it (BENCHMARKS.md, campaign).
    /// 0.005 → 0.002 rad/s, 10 seed sets of `fcc-campaign --per-family 72 --long` (5,760
    /// flights), the truth: `hover` true box p95 0.64 → 0.42 m, hold excursion p95 1.27 →
    /// 0.78 m; `hover_gale` hold excursion p95 1.32 → 0.83 m, worst 1.99 → 1.27 m; `mission`
    /// distance from the intended line p95 0.95 → 0.63 m; the Doppler noise's random walk,
    /// which grows as the crossover falls, stays below the wander it leaves out. The GPS gate
    /// widens with it (`nav_health::gps_gate_m`): the fix's distance from the estimate is the
    /// receiver's error's change, and at 5 m a gale hover refused 2 s of healthy fixes.
    /// Not lower: a Doppler velocity biased by `b` holds the estimate `b/ω` from the GPS
    /// position — 0.01 m/s leaves 5 m here, inside the gate's 10-m cap, and would reach the
    /// cap (an estimator fault) at 0.001 rad/s, which the simulator's unbiased Doppler
    /// cannot show (there, 5 seed sets: hover true box p95 0.41 → 0.35 m, no fault).
    pub horiz_omega_radps: f32,
    pub horiz_zeta: f32,
    /// Vertical: barometric altitude through F_L, vertical acceleration through F_H (eqs. 5–6).
    pub vert_omega_radps: f32,
    pub vert_zeta: f32,
    /// Magnetic declination (east positive). Paper A's site in Korea: about 8° west.
    pub declination_deg: f32,
    /// GPS receiver latency compensated by the horizontal filter.
    pub gps_latency_s: f32,
    /// A GPS fix older than this is no longer applied (GPS lost).
    pub gps_timeout_s: f32,
    /// Low-pass cut-off on the accelerometer for the tilt correction (motor vibration).
    pub tilt_accel_lpf_hz: f32,
    /// Skip the accelerometer tilt correction when | |f| − g | exceeds this.
    pub accel_gate_mps2: f32,
    /// Time on the ground, disarmed and still, used to calibrate gyro bias and baro reference.
    pub calibration_s: f32,
    /// Accelerometer offsets from the pre-flight 6-orientation calibration (subtracted), FRD.
    pub accel_offset_frd_mps2: [f32; 3],
    /// Magnetometer hard-iron offsets from the compass calibration (subtracted), FRD.
    pub mag_offset_frd_ut: [f32; 3],
    /// Third pole of the vertical/horizontal filters that estimates the remaining accelerometer
    /// bias (vibration rectification, drift); 0 = the paper's plain 2nd-order filter. Vertical:
    /// learnt from the altitude innovation; horizontal: from the GPS velocity innovation
    /// (`fcc_nav::complementary::bias_gain_per_fix`), the position crossover being far slower.
    pub vert_bias_pole_radps: f32,
    /// Horizontal: 0.2 rad/s (5 s). Besides the accelerometer's own bias it must follow `g·δθ`,
    /// the acceleration error of the tilt estimate's wander (the attitude filter's crossover is
    /// 10 s, and a quarter of a degree is 0.04 m/s²): what it has not absorbed when the GPS is
    /// lost, dead reckoning integrates (0.3 m/s after a 7 s GPS-lost landing). 0.05 → 0.2: the
    /// campaign's GPS-loss family 12 → 8 failed of 720 flights (10 seed sets), all 5,760 27 → 21.
    pub horiz_bias_pole_radps: f32,
    /// Range-aided height (`fcc_nav::range_aid`): paper B's fused height above ground replaces
    /// the barometer in the vertical filter below this height, m (the MB7076 sonar reaches
    /// 10.68 m); 0 turns the aid off.
    pub range_aid_max_m: f32,
    /// Vertical filter crossover while range-aided (the measurement is then good to cm).
    pub vert_aided_omega_radps: f32,
    /// GPS velocity aiding of the horizontal filter: gain per fix (0 = position only, paper
    /// A's filter). The receiver's Doppler velocity (u-blox M8: 0.05 m/s) is far better than
    /// differentiated positions with a metre of slowly wandering error. Each fix's noise
    /// passes into the estimate as `σ·√(k/(2 − k))`: 0.021 m/s per axis at 0.3, 0.013 at 0.12
    /// (the optimal filter on these sensors, `scripts/gps_loss_bound.py`, weighs a fix by 0.118
    /// and is left with 0.017 m/s, the accelerometer's errors included) — and at a GPS loss
    /// that noise is where the dead reckoning starts from (seed set 1000's 72 GPS-lost
    /// landings: 0.023 m/s per axis at the loss with 0.3). 40 seed sets of `fcc-campaign
    /// --per-family 72 --long` (`gps_loss`, 2,880 landings) at 0.3 / 0.15 / 0.12: the
    /// dead-reckoned error at the contact σ 0.078 / 0.071 / 0.070 m/s, touchdowns beyond 0.25
    /// m/s 54 / 30 / 25, beyond 0.3 m/s 9 / 6 / 3; the other families' figures within their
    /// spread (the horizontal touchdowns' p95 1–5 % lower than at 0.3, the boxes and lines
    /// unchanged; the gale's failures 5 / 6 / 7, its touchdowns beyond 0.25 m/s 19 / 22 / 23).
    pub gps_vel_gain: f32,
}

impl Default for NavParams {
    fn default() -> Self {
        Self {
            tilt_omega_radps: 0.1,
            tilt_zeta: 0.5,
            yaw_omega_radps: 0.1,
            yaw_zeta: 1.0,
            horiz_omega_radps: 0.002,
            horiz_zeta: 0.8,
            vert_omega_radps: 0.08,
            vert_zeta: 0.7,
            declination_deg: -8.0,
            gps_latency_s: 0.12,
            gps_timeout_s: 1.0,
            tilt_accel_lpf_hz: 5.0,
            accel_gate_mps2: 2.0,
            calibration_s: 2.0,
            accel_offset_frd_mps2: [0.0; 3],
            mag_offset_frd_ut: [0.0; 3],
            vert_bias_pole_radps: 0.02,
            horiz_bias_pole_radps: 0.2,
            range_aid_max_m: 8.0,
            vert_aided_omega_radps: 1.0,
            gps_vel_gain: 0.12,
        }
    }
}

impl NavParams {
    pub fn tilt_gains(&self) -> CfGains {
        CfGains::new(self.tilt_omega_radps, self.tilt_zeta)
    }
    pub fn yaw_gains(&self) -> CfGains {
        CfGains::new(self.yaw_omega_radps, self.yaw_zeta)
    }
    pub fn horiz_gains(&self) -> CfGains {
        CfGains::new(self.horiz_omega_radps, self.horiz_zeta)
    }
    pub fn vert_gains(&self) -> CfGains {
        CfGains::new(self.vert_omega_radps, self.vert_zeta)
    }
    pub fn vert_aided_gains(&self) -> CfGains {
        CfGains::new(self.vert_aided_omega_radps, self.vert_zeta)
    }
}

/// Control gains, paper A Fig. 10 cascade.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ControlParams {
    /// Position hold: velocity command per metre of position error (1/s).
    pub pos_p_per_s: f32,
    /// Cross-track compensation gain K_ct (eq. 9), 1/s.
    pub cross_track_k_per_s: f32,
    /// Horizontal velocity PI → acceleration command.
    pub vel_p_per_s: f32,
    /// The same gain in LAND's committed descent (the touchdown gate's last ≈ 0.3 s, the tilt
    /// limited to 4°): a gust that builds on the way down is answered by the lean the level
    /// limit allows before it has slid the vehicle. At 3 /s a 0.2-m/s slide asks for 0.6 m/s²,
    /// 3.4° — less than the limit — and the gale's slides ran on at 0.2 m/s into the
    /// touchdown (`hover_gale` 17071: committed at 0.23 m/s, touched down at 0.34 with 0.8° of
    /// tilt). Waiting at the gate the loop keeps the flight gain: stiffer there, the lean it
    /// commands is noisier, fewer instants are calm, the waits grow and more holds put a foot
    /// down. Measured: README.md (Landing), `scripts/bench_history.md`.
    pub vel_p_touchdown_per_s: f32,
    pub vel_i_per_s2: f32,
    pub vel_i_limit_mps2: f32,
    pub accel_cmd_limit_mps2: f32,
    /// Acceleration controller: feedback PI on (a_cmd − â) with forgetting factor λ (eqs. 16–17).
    /// The proportional gain is the gust rejection: a gust's drag is an acceleration the
    /// feed-forward `(a_cmd + k2·v)/k1` does not see (it uses the ground velocity), and the
    /// observer's â does. 0.16 rad per m/s² (≈ 1.5/k1) answers it within the attitude loop's lag
    /// instead of waiting for the velocity loop. Campaign on the truth (`fcc-campaign
    /// --per-family 72 --long`, three seed sets of 576 flights, 2026-11-28): failing flights
    /// 26 / 30 / 41 at 0.03 → 11 / 15 / 24 at 0.16 (seeds 1000 / 3000 / 5000; 0.08: 13 / 28,
    /// 0.11: 14 / 22, 0.25: 18 / 13, 0.4: 22 / 24 on the first two), mostly the gale's
    /// touchdowns (p95 0.45 → 0.41 m/s, failing 19 → 8 on seeds 1000) with the hover's and the
    /// mission's estimated boxes and cross-track no worse. The integral 0.06 → 0.2 was worse
    /// (19 / 21).
    pub accel_p_rad_per_mps2: f32,
    pub accel_i_rad_per_mps: f32,
    pub accel_forgetting: f32,
    /// Luenberger observer and feed-forward model a = k1·θ − k2·v (eqs. 11, 14, 15). k1, k2 from
    /// the instrumental-variables fit (`fcc_nav::sysid`) on calm-air SITL flights: reproduce with
    /// `cargo test -p fcc_tests --release --test sysid -- --nocapture` (k1 9.17 → 10.14 with the
    /// GPS-velocity tilt aid: the fit is on the estimated tilt; that test now reads
    /// 10.16 ± 0.75, k2 0.282 ± 0.053).
    pub model_k1_mps2_per_rad: f32,
    pub model_k2_per_s: f32,
    /// First-order model of the closed attitude loop θ̇ = −a·θ + b·θ_cmd, fitted to the step
    /// response of the roll/pitch PID below on the airframe (`tests/tests/attitude_model.rs`
    /// fails when the gains change and this does not follow: 6.0 fits 5.98 /s).
    pub att_model_a_per_s: f32,
    pub att_model_b_per_s: f32,
    pub observer_l_per_s: f32,
    /// LAND's committed descent: the gain of the observer the acceleration loop closes on
    /// (`control::cascade`), 1/s. A gust's change of drag reaches the loop through the
    /// observer's lag `1/(k2 + L)`: 0.23 s at the flight's 4 /s, 0.1 s at 10 — the committed
    /// descent lasts 0.3–0.4 s. Everywhere at 10 /s the noisier â moved the lean the gate
    /// judges, and the gale's landings hopped (7 of 1,440); here only the loop flies on it and
    /// the gate judges the flight observer's. `fcc-campaign --per-family 72 --long --seed S
    /// --per-flight`, `hover_gale` over 40 seed sets (S = 1000 … 79000, 2,880 flights): failed
    /// 9 → 5, touchdowns beyond 0.25 m/s 24 → 20, horizontal p95 0.199 / 0.198 → 0.191 / 0.186
    /// m/s (first / second 20 sets), no hop; 16 /s: first 20 sets as 10. Every family, S = 41000
    /// … 79000 (11,520): failed 9 → 7, the gated families' touchdown horizontal p95 3–10 %
    /// lower (`mission` 0.124 → 0.112), GPS-lost landings within noise. Measured:
    /// `scripts/bench_history.md`.
    pub observer_touchdown_l_per_s: f32,
    /// Vertical: altitude P (hold), vertical-speed PI → vertical acceleration → thrust.
    pub alt_p_per_s: f32,
    pub vz_p_per_s: f32,
    pub vz_i_per_s2: f32,
    pub vz_i_limit_mps2: f32,
    /// Roll/pitch PID: torque (N·m) per rad of error, per rad·s of integral, per rad/s of rate.
    /// On the simulated airframe (Ixx 0.13 kg·m², rotor lag 0.05 s) 15 / 2.5 give a t63 of
    /// 178 ms with 1.4 % overshoot (`tests/tests/attitude_model.rs`); 6 / 1.4 gave 264 ms, and a
    /// gust's change of wind then slid the vehicle for ≈ 0.3 s before its lean followed (the
    /// gale's touchdowns). Campaign, 10 seed sets of `fcc-campaign --per-family 72 --long`
    /// (2026-12-06): gale touchdown horizontal p95 0.250 → 0.230 m/s, estimated hover box p95
    /// −3 % (the gale's −4 %), velocity mode's tilt wobble p95 1.63° → 1.27°, touchdown tilt
    /// p95 +0.05 … 0.1°; failing flights 14 → 12 (gale 10 → 3, GPS loss 4 → 7 with the same
    /// distribution, mission 0 → 2). Other gains tried: scripts/bench_history.md.
    pub att_p_nm_per_rad: f32,
    pub att_i_nm_per_rad_s: f32,
    pub att_d_nm_per_radps: f32,
    pub att_i_limit_nm: f32,
    /// Yaw: r_cmd = Kψ·(ψ_cmd − ψ); u_r = K_ff·r_cmd + Kp·e_r + Ki·I_r (eq. 18), I with forgetting.
    pub yaw_p_per_s: f32,
    pub yaw_rate_ff_nm_per_radps: f32,
    pub yaw_rate_p_nm_per_radps: f32,
    pub yaw_rate_i_nm_per_rad: f32,
    pub yaw_rate_forgetting: f32,
    pub yaw_rate_limit_radps: f32,
}

impl Default for ControlParams {
    fn default() -> Self {
        Self {
            pos_p_per_s: 2.0,
            cross_track_k_per_s: param_default::CROSS_TRACK_K_PER_S,
            vel_p_per_s: param_default::VEL_P_PER_S,
            vel_p_touchdown_per_s: 5.0,
            vel_i_per_s2: 1.0,
            vel_i_limit_mps2: 1.5,
            accel_cmd_limit_mps2: 4.0,
            accel_p_rad_per_mps2: 0.16,
            accel_i_rad_per_mps: 0.06,
            accel_forgetting: 0.9995,
            model_k1_mps2_per_rad: 10.14,
            model_k2_per_s: 0.28,
            att_model_a_per_s: 6.0,
            att_model_b_per_s: 6.0,
            observer_l_per_s: 4.0,
            observer_touchdown_l_per_s: 10.0,
            alt_p_per_s: 5.0,
            vz_p_per_s: 10.0,
            vz_i_per_s2: 2.0,
            vz_i_limit_mps2: 3.0,
            att_p_nm_per_rad: 15.0,
            att_i_nm_per_rad_s: 1.0,
            att_d_nm_per_radps: 2.5,
            att_i_limit_nm: 0.5,
            yaw_p_per_s: 1.5,
            yaw_rate_ff_nm_per_radps: 0.1,
            yaw_rate_p_nm_per_radps: 0.8,
            yaw_rate_i_nm_per_rad: 0.3,
            yaw_rate_forgetting: 0.999,
            yaw_rate_limit_radps: 1.0,
        }
    }
}

impl ControlParams {
    pub fn observer_params(&self) -> AccelObserverParams {
        AccelObserverParams {
            k1_mps2_per_rad: self.model_k1_mps2_per_rad,
            k2_per_s: self.model_k2_per_s,
            att_a_per_s: self.att_model_a_per_s,
            att_b_per_s: self.att_model_b_per_s,
            gain_l_per_s: self.observer_l_per_s,
        }
    }

    /// The committed descent's observer: the flight observer's model, the faster gain.
    pub fn observer_touchdown_params(&self) -> AccelObserverParams {
        AccelObserverParams {
            gain_l_per_s: self.observer_touchdown_l_per_s,
            ..self.observer_params()
        }
    }
}

/// Hard limits and failsafe timing, enforced on the MCU whatever the Linux side sends.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LimitParams {
    pub max_horiz_speed_mps: f32,
    /// Position hold returns to its point no faster than this.
    pub hold_max_speed_mps: f32,
    pub max_climb_mps: f32,
    pub max_descent_mps: f32,
    pub max_tilt_deg: f32,
    /// Geofence: horizontal radius around home and ceiling above home.
    pub fence_radius_m: f32,
    pub fence_alt_m: f32,
    /// A velocity setpoint older than its time-to-live → hold; no fresh setpoint for this long
    /// (while in velocity mode or in the hold it caused) → land.
    pub setpoint_lost_land_s: f32,
    /// Landing: descent speed high up, and the slow final descent below `land_slow_alt_m`
    /// (to the touchdown gate, and while the rangefinders do not see the ground, to the ground).
    pub land_speed_mps: f32,
    pub land_final_speed_mps: f32,
    pub land_slow_alt_m: f32,
    /// Landing: the touchdown gate's committed descent, the last centimetres (the vertical speed
    /// the gear meets the ground with), on the inertial vertical velocity
    /// (`fcc_firmware::touchdown_gate`).
    pub land_touchdown_speed_mps: f32,
    /// Touchdown: on ground for this long (low vertical speed, thrust well below hover) → disarm.
    pub touchdown_s: f32,
    /// Terrain floor: outside LAND, a level or climbing command never lets the vehicle sink
    /// below this height of its gear over the ground the rangefinders see, m; 0 = off.
    pub min_agl_m: f32,
}

impl Default for LimitParams {
    fn default() -> Self {
        Self {
            max_horiz_speed_mps: param_default::MAX_HORIZ_SPEED_MPS,
            hold_max_speed_mps: 1.5,
            max_climb_mps: param_default::MAX_CLIMB_MPS,
            max_descent_mps: param_default::MAX_DESCENT_MPS,
            max_tilt_deg: param_default::MAX_TILT_DEG,
            fence_radius_m: param_default::FENCE_RADIUS_M,
            fence_alt_m: param_default::FENCE_ALT_M,
            setpoint_lost_land_s: 3.0,
            land_speed_mps: 0.8,
            land_final_speed_mps: 0.3,
            land_slow_alt_m: 2.0,
            land_touchdown_speed_mps: 0.38,
            touchdown_s: 1.0,
            min_agl_m: 1.0,
        }
    }
}

/// Telemetry rates of the link's streams, Hz (0 = off; whole Hz, fractions round down): the
/// `rates.*` rows of the one table, so they are set over the link like any parameter and the
/// link endpoint applies them at once (`LinkEndpoint`, on an accepted `ParamSet`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RateParams {
    pub status_hz: f32,
    pub nav_state_hz: f32,
    pub altitude_hz: f32,
    pub imu_hz: f32,
    pub mag_hz: f32,
    pub baro_hz: f32,
    pub gps_hz: f32,
    pub laser_hz: f32,
    pub sonar_hz: f32,
    pub battery_hz: f32,
}

impl Default for RateParams {
    fn default() -> Self {
        Self::from_stream_rates(&StreamRates::DEFAULT)
    }
}

impl RateParams {
    /// Every stream off.
    pub fn off() -> Self {
        Self::from_stream_rates(&StreamRates::OFF)
    }

    /// The parameters of a set of rates.
    pub fn from_stream_rates(r: &StreamRates) -> Self {
        let hz = |s: Stream| f32::from(r.hz(s));
        Self {
            status_hz: hz(Stream::Status),
            nav_state_hz: hz(Stream::NavState),
            altitude_hz: hz(Stream::Altitude),
            imu_hz: hz(Stream::ImuRaw),
            mag_hz: hz(Stream::MagRaw),
            baro_hz: hz(Stream::BaroRaw),
            gps_hz: hz(Stream::GpsRaw),
            laser_hz: hz(Stream::LaserRaw),
            sonar_hz: hz(Stream::SonarRaw),
            battery_hz: hz(Stream::Battery),
        }
    }
}

/// All parameters of the flight core.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Params {
    pub airframe: AirframeParams,
    pub nav: NavParams,
    pub control: ControlParams,
    pub limits: LimitParams,
    pub rates: RateParams,
}

impl Params {
    /// The link's telemetry rates these parameters ask for.
    pub fn stream_rates(&self) -> StreamRates {
        StreamRates::from_params(|id| self.link_param(id))
    }
}

/// Why a parameter set was refused: the field and a typed reason.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParamError {
    pub field: &'static str,
    pub reason: ParamFault,
}

/// The reason of a [`ParamError`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamFault {
    NotFinite,
    OutOfRange,
    /// No link-settable parameter with this id (`fcc_msgs::param_id`).
    UnknownId,
}

impl core::fmt::Display for ParamFault {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ParamFault::NotFinite => "not finite",
            ParamFault::OutOfRange => "out of range",
            ParamFault::UnknownId => "unknown parameter",
        })
    }
}

impl From<fcc_msgs::params::ParamRangeError> for ParamFault {
    fn from(e: fcc_msgs::params::ParamRangeError) -> Self {
        match e {
            fcc_msgs::params::ParamRangeError::NotFinite => ParamFault::NotFinite,
            fcc_msgs::params::ParamRangeError::OutOfRange => ParamFault::OutOfRange,
        }
    }
}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}: {}", self.field, self.reason)
    }
}

/// The `Params` field of each link-settable parameter, generated from the one table
/// (`fcc_msgs::for_each_mcu_param!`): a compile-time `match`, no search, no heap.
macro_rules! impl_link_fields {
    ($($id:literal, $konst:ident, $sec:ident . $field:ident, $unit:literal, $def:literal,
       $min:literal, $max:literal, $doc:literal;)*) => {
        impl Params {
            /// Value of a link-settable parameter (`fcc_msgs::param_id`).
            pub fn link_param(&self, id: u16) -> Option<f32> {
                match id {
                    $(fcc_msgs::param_id::$konst => Some(self.$sec.$field),)*
                    _ => None,
                }
            }
            /// The field of a link-settable parameter (`fcc_msgs::param_id`).
            pub fn link_param_mut(&mut self, id: u16) -> Option<&mut f32> {
                match id {
                    $(fcc_msgs::param_id::$konst => Some(&mut self.$sec.$field),)*
                    _ => None,
                }
            }
        }
    };
}
fcc_msgs::for_each_mcu_param!(impl_link_fields);

impl Params {
    /// Range checks, so a bad parameter file or a bad set over the link is refused with a reason.
    pub fn validate(&self) -> Result<(), ParamError> {
        fn check(field: &'static str, v: f32, lo: f32, hi: f32) -> Result<(), ParamError> {
            let reason = if !v.is_finite() {
                ParamFault::NotFinite
            } else if v < lo || v > hi {
                ParamFault::OutOfRange
            } else {
                return Ok(());
            };
            Err(ParamError { field, reason })
        }
        // The link-settable parameters: ranges from the one table.
        for spec in fcc_msgs::params::PARAMS {
            let v = self.link_param(spec.id).unwrap_or(f32::NAN);
            spec.check_f32(v).map_err(|e| ParamError {
                field: spec.name,
                reason: e.into(),
            })?;
        }
        let a = &self.airframe;
        check("airframe.mass_kg", a.mass_kg, 0.2, 50.0)?;
        check("airframe.arm_m", a.arm_m, 0.05, 3.0)?;
        check(
            "airframe.torque_to_thrust_m",
            a.torque_to_thrust_m,
            0.001,
            0.2,
        )?;
        check(
            "airframe.max_thrust_per_motor_n",
            a.max_thrust_per_motor_n,
            0.5,
            500.0,
        )?;
        check("airframe.idle_cmd", a.idle_cmd, 0.0, 0.3)?;
        check("airframe.gear_half_span_m", a.gear_half_span_m, 0.0, 3.0)?;
        let n = &self.nav;
        check("nav.tilt_omega_radps", n.tilt_omega_radps, 0.001, 20.0)?;
        check("nav.yaw_omega_radps", n.yaw_omega_radps, 0.001, 20.0)?;
        check("nav.horiz_omega_radps", n.horiz_omega_radps, 0.001, 20.0)?;
        check("nav.vert_omega_radps", n.vert_omega_radps, 0.001, 20.0)?;
        check("nav.tilt_zeta", n.tilt_zeta, 0.1, 3.0)?;
        check("nav.yaw_zeta", n.yaw_zeta, 0.1, 3.0)?;
        check("nav.horiz_zeta", n.horiz_zeta, 0.1, 3.0)?;
        check("nav.vert_zeta", n.vert_zeta, 0.1, 3.0)?;
        check("nav.declination_deg", n.declination_deg, -180.0, 180.0)?;
        check("nav.gps_latency_s", n.gps_latency_s, 0.0, 0.25)?;
        check("nav.gps_timeout_s", n.gps_timeout_s, 0.2, 10.0)?;
        check("nav.tilt_accel_lpf_hz", n.tilt_accel_lpf_hz, 0.5, 100.0)?;
        check("nav.calibration_s", n.calibration_s, 0.1, 30.0)?;
        check("nav.vert_bias_pole_radps", n.vert_bias_pole_radps, 0.0, 1.0)?;
        check("nav.range_aid_max_m", n.range_aid_max_m, 0.0, 150.0)?;
        check(
            "nav.vert_aided_omega_radps",
            n.vert_aided_omega_radps,
            0.01,
            5.0,
        )?;
        check(
            "nav.horiz_bias_pole_radps",
            n.horiz_bias_pole_radps,
            0.0,
            1.0,
        )?;
        for v in n.accel_offset_frd_mps2 {
            check("nav.accel_offset_frd_mps2", v, -3.0, 3.0)?;
        }
        for v in n.mag_offset_frd_ut {
            check("nav.mag_offset_frd_ut", v, -200.0, 200.0)?;
        }
        let l = &self.limits;
        check(
            "limits.hold_max_speed_mps",
            l.hold_max_speed_mps,
            0.1,
            l.max_horiz_speed_mps,
        )?;
        check(
            "limits.setpoint_lost_land_s",
            l.setpoint_lost_land_s,
            0.1,
            60.0,
        )?;
        check("limits.land_speed_mps", l.land_speed_mps, 0.1, 3.0)?;
        check(
            "limits.land_final_speed_mps",
            l.land_final_speed_mps,
            0.1,
            1.0,
        )?;
        check(
            "limits.land_touchdown_speed_mps",
            l.land_touchdown_speed_mps,
            0.1,
            1.0,
        )?;
        check("limits.touchdown_s", l.touchdown_s, 0.2, 10.0)?;
        check("limits.min_agl_m", l.min_agl_m, 0.0, 50.0)?;
        let c = &self.control;
        check(
            "control.vel_p_touchdown_per_s",
            c.vel_p_touchdown_per_s,
            0.05,
            10.0,
        )?;
        check(
            "control.observer_touchdown_l_per_s",
            c.observer_touchdown_l_per_s,
            0.5,
            50.0,
        )?;
        check("control.accel_forgetting", c.accel_forgetting, 0.9, 1.0)?;
        check(
            "control.yaw_rate_forgetting",
            c.yaw_rate_forgetting,
            0.9,
            1.0,
        )?;
        check(
            "control.model_k1_mps2_per_rad",
            c.model_k1_mps2_per_rad,
            1.0,
            30.0,
        )?;
        check("control.model_k2_per_s", c.model_k2_per_s, 0.0, 5.0)?;
        // The telemetry must fit the UART (921600 baud) even with every frame at its largest.
        if self.stream_rates().worst_case_bytes_per_s() > BAUD_921600_BYTES_PER_S {
            return Err(ParamError {
                field: "rates",
                reason: ParamFault::OutOfRange,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row of the one table (`fcc_msgs::params`) is a `Params` field with the table's
    /// default, and `validate` applies the table's range to it.
    #[test]
    fn link_parameters_follow_the_table() {
        let d = Params::default();
        assert_eq!(d.validate(), Ok(()));
        for spec in fcc_msgs::params::PARAMS {
            assert_eq!(d.link_param(spec.id), Some(spec.default), "{}", spec.name);
            let mut p = d;
            *p.link_param_mut(spec.id).unwrap() = spec.max;
            assert_eq!(p.validate(), Ok(()), "{}", spec.name);
            for (v, reason) in [
                (spec.max + 1.0, ParamFault::OutOfRange),
                (spec.min - 1.0, ParamFault::OutOfRange),
                (f32::NAN, ParamFault::NotFinite),
            ] {
                *p.link_param_mut(spec.id).unwrap() = v;
                let e = p.validate().unwrap_err();
                assert_eq!((e.field, e.reason), (spec.name, reason));
            }
        }
        assert_eq!(d.link_param(0), None);
        assert!(Params::default().link_param_mut(999).is_none());
    }
}
