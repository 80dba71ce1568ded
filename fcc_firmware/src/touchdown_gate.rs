//! Touchdown gate: LAND's last decimetres wait for a lull.
//!
//! Near the ground the gusts keep their strength while the mean wind drops (MIL-F-8785C: σ_u
//! does not shrink with height, the mean follows the log law), and a multirotor answers a gust
//! either by leaning into it (tilt ≈ `k2·v_air/k1`, ≈ 1.75° per m/s with paper A's fit) or,
//! with its tilt limited, by sliding with it. A touchdown during a gust is therefore tilted or
//! sliding, and a tilted or sliding gear catches a foot. So LAND's final descent stops at
//! [`GATE_CLEARANCE_M`] of gear clearance and holds that height, leaning as far as the wind
//! needs to stay put, until it is calm for [`CALM_S`]: the **tilt demand** `d` — the larger of
//! the estimated tilt and the tilt the horizontal loops ask for before any limit, i.e. how far
//! the vehicle must lean to stay put in the wind of the moment — at most [`CALM_TILT_DEG`], and
//! the estimated ground speed at most [`CALM_SPEED_MPS`]. Then it commits and descends at the
//! touchdown speed `v_t` (`limits.land_touchdown_speed_mps`, on the inertial vertical
//! velocity) with the tilt limited to [`LEVEL_TILT_DEG`] (flight.rs). A committed descent
//! whose demand the level limit clips (`d > LEVEL_TILT_DEG`: a gust it cannot hold without
//! sliding) or that would meet the ground faster than [`ABORT_SPEED_MPS`] — the estimated
//! ground speed `v`, plus its rise `v̇` (low-passed over [`SPEED_RATE_TAU_S`]) until the contact
//! at the touchdown speed while the level limit clips the demand or the command — while still above
//! [`ABORT_ABOVE_M`] (for a clipped demand, [`ABORT_LEAN_ABOVE_M`]; the mean of the fused
//! clearance and the one dead-reckoned since the commit: [`HOLD_CLEARANCE_TAU_S`]) goes back
//! to the gate — unless the gear meets the ground on its way
//! back ([`REFEEL_S`]): sent back 1–3 cm up, it touches anyway, and climbing on is a hop;
//! the same for a gust that pushes the hold at the gate down onto the gear. Sent back, it stays
//! level until the descent has stopped ([`TouchdownGate::arresting`]): a lean during the
//! arrest's dip lowers a foot onto the ground.
//! Judging the demand, not the tilt alone, is what keeps a commit out of a gust the controller
//! is already leaning into (mag seed 1014 committed at 2.3° of tilt with the command at the
//! then 4.5° limit, and slid to 0.40 m/s).
//! Judging the speed the gust *will* have given the vehicle at the contact, not the speed it
//! has, is what catches a gust that builds on the way down once the waits have widened the
//! abort's demand past the level limit: the limit clips the lean, the speed rises at ≈ 1 m/s²
//! from ≈ 0.1 m/s, and the speed alone crosses the abort threshold only in the last 3 cm,
//! below [`ABORT_ABOVE_M`]. Within the level limit the loops still oppose the push, and the
//! rise is not extrapolated: the estimate's own acceleration noise (≈ 0.4 m/s² at 0.05 s) then
//! sent calm descents back 1–2 cm above the ground, and two of them hopped. But the wind's
//! demand leaves out the committed descent's stiffer velocity loop, and when the limit clips
//! the *command* (that loop's lean against the slide denied) nothing opposes the push either:
//! that is extrapolated too ([`TouchdownGate::command_limited`]; 40 seed sets of `hover_gale`,
//! 2,880 flights: touchdowns beyond 0.25 m/s 41 → 24, failed 11 → 9).
//!
//! The longer the wait, the wider the calm thresholds (by their own value per [`RELAX_S`]), at
//! first by no more than the factor [`RELAX_MAX`] (the widest calm demand stays below the level
//! limit: a lull the level limit would clip is no lull). After [`PATIENCE_S`] every tilt
//! threshold, the abort's too, widens again at the same rate: in a gale the strict lull may not
//! come, and a slightly worse lull is better than the timeout's. The calm speed never widens
//! beyond [`CALM_SPEED_CAP_MPS`]: the estimated ground speed lags and misses the true one by
//! ≈ 0.1 m/s in a gale, and a commit at 0.26 m/s estimated touched down at 0.34 m/s true
//! (`hover_gale` seed 1019, waited 24 s). The abort's speed does not widen at all: it is the
//! speed at which the gear may cross the abort's floor, and under the floor a gust still adds
//! up to ≈ 0.24 m/s ([`ABORT_SPEED_MPS`]). After [`MAX_WAIT_S`] the first instant with a demand
//! within the level limit and a speed within `ABORT_SPEED` commits without the calm time, still
//! sent back by a gust on the way down; after
//! [`LAST_CHANCE_S`] it commits whatever the wind (a vehicle hovering over its landing spot
//! until the battery ends is worse), **forced** (never held again), and
//! [`TouchdownGate::forced`] reports it. (With the forced 30-s commit and the last chance at
//! 40 s, 10 seed sets of `fcc-campaign --per-family 72 --long` failed 56 flights, the gale's
//! touchdowns at up to 18.7° and 0.61 m/s; see BENCHMARKS.md for the figures now.) A
//! last-chance commit in a wind whose
//! demand the level limit would clip is **unlevel** ([`TouchdownGate::unlevel`]): the vehicle
//! cannot touch down level there without sliding with the wind, so it touches down holding its
//! position, its tilt capped near the ground (flight.rs).
//!
//! ```text
//!   clearance c = h_agl − h_on_ground − (r·sin φ − h_on_ground·(1 − cos φ))
//!       (the lowest foot's: φ the estimated lean, r the gear's half-span; flight.rs)
//!   d = max(tilt, |θ_cmd| unlimited);  v = |v_NE|
//!   late = max(0, wait_s − PATIENCE_S) / RELAX_S
//!   k = min(1 + wait_s/RELAX_S, RELAX_MAX) + late;   k_abort = 1 + late
//!   v_c = v + max(0, v̇)·c/v_t  if d > LEVEL_TILT or the limit clips the command, else v
//!         (v̇ = d|v|/dt low-passed, v_t the touchdown speed)
//!   c_dr = c low-passed while waiting; at the commit on, c_dr −= v_down·dt
//!   d_lp = d low-passed over DEMAND_TAU_S (a 2-ms spike of the command is no gust)
//!   committed, not forced, not felt, and (c + c_dr)/2 > ABORT_LEAN_ABOVE, d_lp > k_abort·LEVEL_TILT
//!       or (c + c_dr)/2 > ABORT_ABOVE, v_c > ABORT_SPEED → waiting
//!       (v_c extrapolated while d_lp > LEVEL_TILT or the command clipped, low-passed)
//!   waiting (at the gate, or < REFEEL_S after that), c < IMPACT_BELOW, a contact → committed, felt
//!   committed:  descend (touchdown speed)
//!   never within ARRIVED of the gate yet:  hold (the approach)
//!   waiting:  hold c = GATE;  wait_s += dt;  calm_s += dt while d ≤ k·CALM_TILT and
//!             v ≤ min(k·CALM_SPEED, CALM_SPEED_CAP), else 0
//!   calm_s ≥ CALM_S → committed
//!   wait_s ≥ MAX_WAIT_S, d ≤ LEVEL_TILT, v ≤ ABORT_SPEED → committed
//!   wait_s ≥ LAST_CHANCE_S → committed, forced
//! ```
//!
//! "Hold" is the height loop on the gate clearance, never descending faster than the final
//! speed (flight.rs): the gate is approached at the final speed and held without the step
//! between "descend" just above it and "climb" just below it that made the vehicle bob ±0.3 m/s
//! at the gate.
//!
//! Measured on the simulator's truth (576-flight campaign, `fcc-campaign --per-family 72
//! --long`): see BENCHMARKS.md. Pure logic, time passed in (`dt_s`).

/// Clearance of the lowest foot at which the final descent waits, m (0.32 s at the touchdown
/// speed, 0.4 s at the 0.3 m/s the figures below were measured with: the shorter the committed
/// descent, the less a gust that rises on the way down slides the level vehicle — failing flights of 576 per seed set 1000 / 3000 / 5000 at 0.15 m: 8 / 10 / 14,
/// at 0.12 m: 6 / 6 / 11; at 0.10 m the hold's dips touch the ground leaning, at 0.07 m most gale
/// landings do; these on the gear's plane, before the gate judged the lowest foot).
pub const GATE_CLEARANCE_M: f32 = 0.12;
/// The gate is reached (the wait starts) within this above it, m.
pub const ARRIVED_M: f32 = 0.02;
/// Calm: the tilt demand, deg.
pub const CALM_TILT_DEG: f32 = 3.0;
/// Calm: the estimated horizontal ground speed, m/s.
pub const CALM_SPEED_MPS: f32 = 0.12;
/// Calm for this long commits the touchdown, s.
pub const CALM_S: f32 = 0.2;
/// The tilt limit of the committed descent, deg (flight.rs applies it): touch down level.
/// The limit holds the *estimated* tilt, and in a gale the true one is up to ≈ 0.8° more at
/// touchdown: at 4.5°, 10 seed sets of `fcc-campaign --per-family 72 --long` failed 12 gale
/// flights (6 of them touchdowns at 5.1–6.7° true); at 4.0°, 8 (one forced last-chance
/// touchdown at 8.7°, the rest sliding 0.32–0.38 m/s), the gale's waits 2 s longer (median);
/// every family together 21 → 14 of 5,760 (a hover at 5.1° and two GPS-lost ones level now).
pub const LEVEL_TILT_DEG: f32 = 4.0;
/// A committed descent goes back to waiting when a gust hits above this clearance of the
/// lowest foot, m… (The fused height has ≈ 2 cm σ, so an abort at 3–4 cm estimated can come
/// with the gear already touching: it hops. At 0.07 m, 10 seed sets of `fcc-campaign
/// --per-family 72 --long`: 3 flights of 5,760 touched down twice, but the gale's late gusts
/// were no longer waited out: 26 gale touchdowns beyond 0.3 m/s or 5°, one at 19.8° and 0.77
/// m/s; it was 0.03 on the gear's plane. Since the simulator scores the first foot to touch —
/// 1.5–2 cm before the plane at the committed descent's 3–4° — the same 10 seed sets, the six
/// families the gate judges, hopped 32 times at 0.03 on the foot (36 failed), 9 at 0.045 (15
/// failed), none at 0.06 (the gale's slides beyond 0.3 m/s 4 / 6 / 7).)
pub const ABORT_ABOVE_M: f32 = 0.06;
/// … and for a **lean** (the demand past the level limit, the speed within the abort's) only
/// above this, m: sent back, the vehicle leaves the level limit and leans into the gust while
/// the climb arrests the descent, and both bring the lowest foot down — the arrest dips 2–3 cm
/// at the touchdown speed, leaning from level to the 4° limit lowers a foot by another 2 cm. A
/// push (the speed at the contact) is answered down to [`ABORT_ABOVE_M`]: the lean it needs is
/// already the vehicle's. (`hover` 1067: a 4.07° demand sent it back at 4 cm true, 6 cm
/// estimated, leaning 1.1°; a foot met the ground at the bottom of the dip, leaning 2.9° — a
/// hop. 40 seed sets of `fcc-campaign --per-family 72 --long`, the six families the gate
/// judges, 17,280 flights: failed 6 → 5 at 0.07 m (the hop gone; the gale's 5 → 5, one slide
/// traded for another, touchdowns beyond 0.25 m/s 20 → 19); at 0.08 m the gale alone failed 8
/// in its first 36 sets; a floor at the foot drop of the lean asked for, 0.06 m plus
/// `r·(sin d − sin φ)` (1.5 cm for 1067, less for a vehicle already leaning), failed 8 in the
/// gale.) Since the arrest is levelled ([`TouchdownGate::arresting`], 2026-12-08) the lean
/// waits until the descent has stopped, and the arrest's dip alone still needs this floor: at
/// 0.06 m the 40 gale sets hopped twice (failed 2 → 4), with [`ABORT_ABOVE_M`] at 0.05 as well
/// three times (failed 6).
pub const ABORT_LEAN_ABOVE_M: f32 = 0.07;
/// The clearance that floor is judged on is the mean of the fused one and the one
/// dead-reckoned since the commit: the hold's clearance low-passed over
/// [`HOLD_CLEARANCE_TAU_S`] at the commit, less the inertial descent integrated since (the
/// baro+accel vertical velocity, ≈ 1 cm over the 0.4-s descent). The fused height follows
/// each 10-Hz sonar reading (σ 2 cm, steps of 4–6 cm): `mission` 1013's gust was cut off at 6
/// cm true by a reading 4 cm low (and slid into the ground at 0.35 m/s), `mission` 1007's
/// abort came at 1.4 cm true on a reading 1 cm high (a hop). The two errors are partly
/// independent (the dead reckoning starts from the hold's mean). (20 seed sets of
/// `fcc-campaign --per-family 72 --long`, the six families the gate judges, 8,640 flights:
/// failed 5 → 2 with the mean, 3 on the dead-reckoned clearance alone, 3 requiring both above
/// the floor.)
pub const HOLD_CLEARANCE_TAU_S: f32 = 0.1;
/// … that would meet the ground faster than this, m/s (or demanding more than
/// [`LEVEL_TILT_DEG`]); it does not widen with the wait. Under the floor no gust sends the
/// descent back, and in the gale its last 0.16 s added up to 0.24 m/s (campaign figure
/// `touchdown_late_gain_mps`, 40 seed sets of `hover_gale`: p99 0.13 m/s): what crosses the
/// floor must leave room for that. At 0.2 m/s, widened after [`PATIENCE_S`] up to 0.25, the
/// gale's 23 touchdowns beyond 0.25 m/s had crossed the floor at 0.13–0.23 m/s. 40 seed sets of
/// `fcc-campaign --per-family 72 --long --family hover_gale` (2,880 flights), the abort's (and
/// the last chance's) speed at most 0.25 (widened from 0.2, as before) / 0.2 / 0.17 / 0.15 m/s:
/// touchdowns beyond 0.25 m/s 23 / 15 / 8 / 6, horizontal p99 0.244 / 0.227 / 0.204 / 0.209,
/// failed 5 / 4 / 4 / 4, median wait 16.1 / 16.6 / 17.5 / 18.5 s, waits past 30 s 308 / 378 /
/// 451 / 550; the floor crossed at p99 0.202 → 0.161 m/s (0.25 → 0.17). (The calm speed,
/// widened, reaches [`CALM_SPEED_CAP_MPS`] = 0.18 after ≈ 13 s of waiting: a commit between the
/// two is sent back at once while above the floor; measured so, not tuned apart.) The other
/// five families (40 seed sets, 14,400 flights): none failed, before or after; touchdown
/// horizontal RMS lower in each (0.0492–0.0583 → 0.0486–0.0566 m/s), waits up to 1.2 s longer
/// (p95).
pub const ABORT_SPEED_MPS: f32 = 0.17;
/// The time constant of the ground speed's rate of change `v̇` the abort extrapolates with, s:
/// the estimate's 2-ms differences are noise, a gust's push builds over ≈ 0.1–0.3 s. (20 seed
/// sets of `hover_gale`, 1,440 flights, extrapolating whatever the demand: touchdowns beyond
/// 0.25 m/s 57 without the extrapolation, 26 at 0.05 s, 27 at 0.1 s, 44 at 0.2 s.)
pub const SPEED_RATE_TAU_S: f32 = 0.05;
/// The time constant of the tilt demand a committed descent's abort judges, s: a gust's lean
/// builds over ≈ 0.1–0.3 s, while single 2-ms steps of the command spike by 1–2° (the
/// acceleration loop on the observer's noisy â, the velocity loop on the estimate's noise —
/// more at the committed descent's touchdown gain). One such spike past the level limit sent
/// `mag` 33030's calm descent (0.03 m/s, 3° of command) back 2 cm above the ground: a hop.
pub const DEMAND_TAU_S: f32 = 0.02;
/// The calm thresholds widen by their own value per this much waiting, s …
pub const RELAX_S: f32 = 15.0;
/// … up to this factor (`RELAX_MAX·CALM_TILT_DEG` < [`LEVEL_TILT_DEG`]).
pub const RELAX_MAX: f32 = 1.25;
/// After this much waiting every threshold (the abort's too) widens again, by its own value
/// per [`RELAX_S`] beyond the cap: a worse lull is better than the timeout's, s.
pub const PATIENCE_S: f32 = 10.0;
/// Longest wait for a lull, s: then the first instant with a tilt demand within the level
/// limit and a ground speed within [`ABORT_SPEED_MPS`] commits, without the calm time …
pub const MAX_WAIT_S: f32 = 30.0;
/// … and after this whatever the wind (forced: never held again), s. At 40 s, 4–7 of 360
/// gale flights (`--family hover_gale`, 5 seed sets) committed there at 10–23° of tilt; at
/// 60 s 1 of 1,440 (20 seed sets, `hover_gale` 19070: touched down at 8.2°, the lull came
/// 10.6 s later); at 90 s none waited that long (19070 landed after 70.6 s at 4.1°). The
/// campaign's flights leave room for it (their durations follow it).
pub const LAST_CHANCE_S: f32 = 90.0;
/// The widened calm speed never exceeds this, m/s (0.3 m/s is the touchdown limit; the
/// estimate misses the truth by ≈ 0.1 m/s in a gale).
pub const CALM_SPEED_CAP_MPS: f32 = 0.18;

/// A committed descent that stops this suddenly has met the ground: the descent rate
/// (estimated, down positive) fell this far below its own recent value
/// ([`IMPACT_TAU_S`]-low-passed), m/s … The vertical loop alone decelerates the final descent
/// at ≤ 2.7 m/s² (thrust 56 N of 43 N hover), ≈ 0.05 m/s of lag at the time constant below;
/// the gear meeting the ground stops 0.3–0.4 m/s in 10–40 ms (`hover` seed 1008: 0.37 → 0.32
/// → 0.26 m/s in two 2-ms steps, the gust check fired on the second at 5.2° of demand).
pub const IMPACT_DROP_MPS: f32 = 0.07;
/// … or fell faster than this in one step, m/s² (the estimate's step-to-step jitter in the
/// final descent reads ≤ 6.5 m/s², the contact 25–30).
pub const IMPACT_DECEL_MPS2: f32 = 12.0;
/// Within [`REFEEL_S`] after a gust sent a committed descent back, only a step this sharp is
/// the ground, m/s²: the climb back decelerates the descent at up to ≈ 7 m/s² (thrust 75 N
/// of 43 N hover), which the low-passed drop above would read as an impact …
pub const REFEEL_DECEL_MPS2: f32 = 20.0;
/// … and a contact felt then commits the descent again, felt, s. The gust that sent it back
/// 1–3 cm above the ground (estimated: the fused height's σ is ≈ 2 cm) had come too late: the
/// gear touches within tens of milliseconds anyway, and the climb back to the gate lifted it
/// off again — a hop and a second touchdown (`landing` seed 1020: sent back at 1 cm true,
/// 0.25 m/s down, touched 30 ms later, hopped 17 cm).
pub const REFEEL_S: f32 = 0.3;
/// The time constant of that recent value, s.
pub const IMPACT_TAU_S: f32 = 0.02;
/// … and only if the accelerometer felt the jolt: its vertical reading (gravity-compensated)
/// beyond this upwards within the last [`IMPACT_JOLT_WINDOW_S`], m/s². The gear meeting the
/// ground reads −30 to −35 m/s² at the final speed; the hold's climb back with the
/// accelerometer's vibration (3 m/s² RMS) reads down to ≈ −12.5. Without it, in ≈ 1 % of the
/// gale's landings a step of the estimated descent rate (a low sonar reading, the climb back
/// it asked for, one vibration sample) read as the contact 3–10 cm above the ground, no gust
/// sent the descent back any more, and `hover_gale` 25006 slid into the ground at 0.43 m/s
/// (20 seed sets of `hover_gale`: 15 such of 1,368 logged; none with this check).
pub const IMPACT_JOLT_MPS2: f32 = 20.0;
/// The window of that jolt, s.
pub const IMPACT_JOLT_WINDOW_S: f32 = 0.02;
/// The impact is looked for below this gear clearance (estimated), m: the fused height
/// follows a sonar of 2 cm σ at 10 Hz, so a gear truly on the ground has read up to ≈ 5 cm.
pub const IMPACT_BELOW_M: f32 = 0.1;

/// What the final descent does this step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GateAction {
    /// Descend at the touchdown speed.
    Descend,
    /// Hold the gear at [`GATE_CLEARANCE_M`] (and approach it at no more than the final speed).
    Hold,
}

/// The gate's state for one landing (reset when LAND is entered).
#[derive(Clone, Copy, Debug, Default)]
pub struct TouchdownGate {
    calm_s: f32,
    wait_s: f32,
    arrived: bool,
    committed: bool,
    forced: bool,
    unlevel: bool,
    /// The committed descent felt the ground ([`TouchdownGate::feel_ground`]): no gust sends
    /// it back to the gate any more.
    felt: bool,
    /// Time since a gust last sent the committed descent back, s (∞: none yet).
    since_abort_s: f32,
    /// The descent rate low-passed with [`IMPACT_TAU_S`], m/s (down positive).
    descent_lp_mps: f32,
    /// Last step's descent rate, m/s (down positive).
    descent_prev_mps: f32,
    /// Time since the accelerometer last read a jolt beyond [`IMPACT_JOLT_MPS2`], s.
    since_jolt_s: f32,
    /// Last step's ground speed, m/s (NaN: none yet).
    speed_prev_mps: f32,
    /// The ground speed's rate of change, low-passed with [`SPEED_RATE_TAU_S`], m/s².
    speed_rate_mps2: f32,
    /// The tilt demand low-passed with [`DEMAND_TAU_S`], rad (NaN: none yet).
    demand_lp_rad: f32,
    /// Whether the tilt limit clipped the command (1) or not (0), low-passed with
    /// [`DEMAND_TAU_S`] ([`TouchdownGate::command_limited`]).
    limited_lp: f32,
    /// Waiting: the clearance low-passed with [`HOLD_CLEARANCE_TAU_S`]; committed: that at the
    /// commit less the descent since, m (NaN: none yet).
    dead_reckoned_clearance_m: f32,
}

impl TouchdownGate {
    pub const fn new() -> Self {
        Self {
            calm_s: 0.0,
            wait_s: 0.0,
            arrived: false,
            committed: false,
            forced: false,
            unlevel: false,
            felt: false,
            since_abort_s: f32::INFINITY,
            descent_lp_mps: 0.0,
            descent_prev_mps: 0.0,
            since_jolt_s: f32::INFINITY,
            speed_prev_mps: f32::NAN,
            speed_rate_mps2: 0.0,
            demand_lp_rad: f32::NAN,
            limited_lp: 0.0,
            dead_reckoned_clearance_m: f32::NAN,
        }
    }

    /// Start a new landing.
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// Before [`Self::update`], each step: the estimated descent rate `descent_mps` (down
    /// positive) and the accelerometer's gravity-compensated vertical reading `accel_down_mps2`
    /// (NED, raw). A committed descent below [`IMPACT_BELOW_M`] whose rate drops
    /// [`IMPACT_DROP_MPS`] under its recent value, or faster than [`IMPACT_DECEL_MPS2`] in one
    /// step, with the accelerometer's jolt ([`IMPACT_JOLT_MPS2`]) in the last
    /// [`IMPACT_JOLT_WINDOW_S`], has touched down: from then on no gust
    /// aborts it. Without this the touchdown's own jolt (the gear levelling the vehicle,
    /// friction stopping its drift: the horizontal loops' demand jumps to 5–8°) read as a gust
    /// while the fused height still showed 4–5 cm of clearance, and the gate climbed back to
    /// its hold height — a hop off the ground and a second touchdown (`fcc-campaign
    /// --per-family 72 --long`, seed set 1000: 28 of 576 flights; `tests/zenoh/faults.sh`).
    pub fn feel_ground(
        &mut self,
        dt_s: f32,
        clearance_m: f32,
        descent_mps: f32,
        accel_down_mps2: f32,
    ) {
        self.dead_reckon(dt_s, clearance_m, descent_mps);
        self.since_jolt_s = if accel_down_mps2 < -IMPACT_JOLT_MPS2 {
            0.0
        } else {
            self.since_jolt_s + dt_s
        };
        let jolt = self.since_jolt_s <= IMPACT_JOLT_WINDOW_S;
        let k = (dt_s / IMPACT_TAU_S).min(1.0);
        self.descent_lp_mps += k * (descent_mps - self.descent_lp_mps);
        let step_drop_mps = self.descent_prev_mps - descent_mps;
        self.descent_prev_mps = descent_mps;
        let impact = jolt
            && (self.descent_lp_mps - descent_mps > IMPACT_DROP_MPS
                || step_drop_mps > IMPACT_DECEL_MPS2 * dt_s);
        if self.committed && clearance_m < IMPACT_BELOW_M && impact {
            self.felt = true;
        }
        // Just sent back by a gust, or holding at the gate: a contact now is the ground met
        // anyway (no hop). (`tests/zenoh/faults.sh`, uav3 through the stack: a dip of the hold
        // touched down at 0.36 m/s, the gate climbed back and touched down again 2.5 s later.)
        if !self.committed
            && (self.since_abort_s < REFEEL_S || self.arrived)
            && clearance_m < IMPACT_BELOW_M
            && step_drop_mps > REFEEL_DECEL_MPS2 * dt_s
            && jolt
        {
            self.committed = true;
            self.felt = true;
        }
    }

    /// After the control step, each step: did the tilt limit clip the command (`limited`)?
    /// The tilt demand [`Self::update`] judges is the lean the *wind* asks for: it leaves out
    /// what the committed descent's stiffer velocity loop adds (`Cascade::touchdown_extra_ne_mps2`),
    /// so the level limit can clip the command while that demand is within it — the loop asks
    /// for the lean against a slide that the limit denies, and nothing else opposes the push.
    /// The abort then extrapolates the ground speed to the contact as for a clipped demand.
    /// (`hover_gale` 17047: committed in a lull at 0.03 m/s; the wind's demand stayed at
    /// 1.6–3.4° while the command sat at the 4° limit for the whole descent, and the vehicle
    /// slid from 0.06 to 0.37 m/s true, the speed alone within the abort's 0.2 m/s until below
    /// the floor.) Low-passed over [`DEMAND_TAU_S`]: a single step at the limit is no push.
    pub fn command_limited(&mut self, dt_s: f32, limited: bool) {
        let x = if limited { 1.0 } else { 0.0 };
        self.limited_lp += (dt_s / DEMAND_TAU_S).min(1.0) * (x - self.limited_lp);
    }

    /// The committed descent has touched down ([`Self::feel_ground`]).
    pub fn felt(&self) -> bool {
        self.felt
    }

    /// One step: `clearance_m` of the gear over the ground, the tilt demand `demand_rad` (the
    /// larger of the estimated tilt and the horizontal loops' unlimited tilt command), the
    /// estimated horizontal `speed_mps` over the ground and the committed descent's speed
    /// `touchdown_speed_mps`.
    pub fn update(
        &mut self,
        dt_s: f32,
        clearance_m: f32,
        demand_rad: f32,
        speed_mps: f32,
        touchdown_speed_mps: f32,
    ) -> GateAction {
        self.track_speed(dt_s, speed_mps);
        let gust_demand_rad = self.track_demand(dt_s, demand_rad);
        let late = (self.wait_s - PATIENCE_S).max(0.0) / RELAX_S;
        let abort_c_m = self.abort_clearance_m(clearance_m);
        if self.committed && !self.forced && !self.felt && abort_c_m > ABORT_ABOVE_M {
            let k = 1.0 + late;
            let clipped = gust_demand_rad > LEVEL_TILT_DEG.to_radians() || self.limited_lp > 0.5;
            let lean =
                abort_c_m > ABORT_LEAN_ABOVE_M && gust_demand_rad > k * LEVEL_TILT_DEG.to_radians();
            let push = self.contact_speed_mps(speed_mps, clipped, clearance_m, touchdown_speed_mps)
                > ABORT_SPEED_MPS;
            if lean || push {
                self.committed = false;
                self.calm_s = 0.0;
                self.since_abort_s = 0.0;
            }
        }
        if !self.committed {
            self.since_abort_s += dt_s;
        }
        if self.committed {
            return GateAction::Descend;
        }
        self.arrived |= clearance_m <= GATE_CLEARANCE_M + ARRIVED_M;
        if !self.arrived {
            return GateAction::Hold;
        }
        // The longer the wait, the wider the thresholds: the best lull the wind offers.
        let relax = (1.0 + self.wait_s / RELAX_S).min(RELAX_MAX) + late;
        let calm = demand_rad <= relax * CALM_TILT_DEG.to_radians()
            && speed_mps <= (relax * CALM_SPEED_MPS).min(CALM_SPEED_CAP_MPS);
        self.calm_s = if calm { self.calm_s + dt_s } else { 0.0 };
        self.wait_s += dt_s;
        // Past the longest wait: the first instant the level limit would not clip and the
        // vehicle is not sliding fast commits (no calm time; a gust still sends it back); past
        // the last chance, any (forced).
        let last_chance = self.wait_s >= MAX_WAIT_S
            && demand_rad <= LEVEL_TILT_DEG.to_radians()
            && speed_mps <= ABORT_SPEED_MPS;
        if self.calm_s >= CALM_S || last_chance {
            self.committed = true;
        } else if self.wait_s >= LAST_CHANCE_S {
            self.committed = true;
            self.forced = true;
            self.unlevel = demand_rad > LEVEL_TILT_DEG.to_radians();
        }
        if self.committed {
            GateAction::Descend
        } else {
            GateAction::Hold
        }
    }

    /// Waiting, the clearance low-passed ([`HOLD_CLEARANCE_TAU_S`]); committed, dead-reckoned
    /// from it with the descent rate (down positive).
    fn dead_reckon(&mut self, dt_s: f32, clearance_m: f32, descent_mps: f32) {
        let c = &mut self.dead_reckoned_clearance_m;
        if !c.is_finite() {
            *c = clearance_m;
        } else if self.committed {
            *c -= descent_mps * dt_s;
        } else {
            *c += (dt_s / HOLD_CLEARANCE_TAU_S).min(1.0) * (clearance_m - *c);
        }
    }

    /// The clearance the abort's floor judges: the mean of the fused `clearance_m` and the
    /// dead-reckoned one ([`HOLD_CLEARANCE_TAU_S`]), m.
    fn abort_clearance_m(&self, clearance_m: f32) -> f32 {
        if self.dead_reckoned_clearance_m.is_finite() {
            0.5 * (clearance_m + self.dead_reckoned_clearance_m)
        } else {
            clearance_m
        }
    }

    /// The tilt demand the abort judges: low-passed ([`DEMAND_TAU_S`]), rad.
    fn track_demand(&mut self, dt_s: f32, demand_rad: f32) -> f32 {
        let d = &mut self.demand_lp_rad;
        if d.is_finite() {
            *d += (dt_s / DEMAND_TAU_S).min(1.0) * (demand_rad - *d);
        } else {
            *d = demand_rad;
        }
        *d
    }

    /// The ground speed's rate of change `v̇`, low-passed ([`SPEED_RATE_TAU_S`]).
    fn track_speed(&mut self, dt_s: f32, speed_mps: f32) {
        if dt_s > 0.0 && self.speed_prev_mps.is_finite() {
            let rate = (speed_mps - self.speed_prev_mps) / dt_s;
            let k = (dt_s / SPEED_RATE_TAU_S).min(1.0);
            self.speed_rate_mps2 += k * (rate - self.speed_rate_mps2);
        }
        self.speed_prev_mps = speed_mps;
    }

    /// The ground speed at the contact, m/s: while the level limit `clipped` the demand (or the
    /// command, [`Self::command_limited`]), if it keeps rising as now, `v + max(0, v̇)·c/v_t`
    /// (a falling speed is taken as it is); else `v` (the loops oppose the push).
    fn contact_speed_mps(
        &self,
        speed_mps: f32,
        clipped: bool,
        clearance_m: f32,
        touchdown_speed_mps: f32,
    ) -> f32 {
        if !clipped {
            return speed_mps;
        }
        let to_contact_s = clearance_m.max(0.0) / touchdown_speed_mps.max(0.05);
        speed_mps + self.speed_rate_mps2.max(0.0) * to_contact_s
    }

    /// Commit now, forced (never held again): the landing cannot judge a lull when the ground
    /// speed is not observed. With GPS lost the speed is dead-reckoned and its error grows
    /// with time (a slow acceleration and a tilt look alike to the accelerometer), so waiting
    /// for a calm that only the drifting estimate sees adds drift: the hover campaign with GPS
    /// lost at 40 s (`launch_configs/scenarios/gps_loss.yaml`) waited up to 40 s and slid into
    /// the ground at up to 14 m/s.
    pub fn commit_blind(&mut self) {
        self.committed = true;
        self.forced = true;
    }

    /// Committed at [`LAST_CHANCE_S`] with a tilt demand beyond [`LEVEL_TILT_DEG`]: a wind the
    /// vehicle cannot touch down level in (the wind limit's landing, beyond the vehicle's
    /// authority). Leveled, it would slide with the wind into the ground (`hover` in 16 m/s and
    /// W20 30 kt: 1.3 m/s, tipped over); it touches down holding its position instead, the
    /// tilt capped by flight.rs.
    pub fn unlevel(&self) -> bool {
        self.unlevel
    }

    /// A gust has just sent the committed descent back (at most [`REFEEL_S`] ago) and the
    /// vehicle, `descent_mps` (down positive), is still going down: the arrest. flight.rs keeps
    /// the level tilt limit until it climbs. Sent back a few centimetres up, the arrest dips
    /// 2–3 cm, and leaning into the gust at the same time lowers a foot by `r·sin φ`, another
    /// 2–3 cm at 5–7°: the foot meets the ground while the vehicle leans, too softly to feel,
    /// and the climb lifts it off again — a hop (`hover_gale` 77067: sent back at 4 cm of true
    /// clearance, the fused height 3 cm high; the lean rose from 2.4° to 6.6° during the 0.1-s
    /// arrest, a foot touched at 6°). Levelled until the descent has stopped, the lean waits
    /// those 0.1 s. 40 seed sets of `fcc-campaign --per-family 72 --long --family hover_gale`
    /// (2,880 flights): failed 4 → 2, touchdowns tilted beyond 4.5° 17 → 11, beyond 0.25 m/s 8
    /// → 7 (horizontal p99 0.204 → 0.211 m/s); the other five families (14,400 flights): none
    /// failed, before or after.
    pub fn arresting(&self, descent_mps: f32) -> bool {
        !self.committed && self.since_abort_s < REFEEL_S && descent_mps > 0.0
    }

    /// The final descent is committed (the level tilt limit applies).
    pub fn committed(&self) -> bool {
        self.committed
    }

    /// The gate has been reached (holding at it or waiting for a lull since) or the descent is
    /// committed: the last centimetres, where the climb-rate loop closes on the inertial
    /// vertical velocity (flight.rs).
    pub fn at_gate(&self) -> bool {
        self.arrived || self.committed
    }

    /// Seconds spent waiting at the gate so far.
    pub fn wait_s(&self) -> f32 {
        self.wait_s
    }

    /// The touchdown was committed by the timeout ([`MAX_WAIT_S`], [`LAST_CHANCE_S`]) or
    /// blind ([`Self::commit_blind`]), not by a lull.
    pub fn forced(&self) -> bool {
        self.forced
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    const DT: f32 = 0.002;
    /// At the gate clearance.
    const GATE: f32 = GATE_CLEARANCE_M;
    /// The final descent speed, m/s.
    const FINAL: f32 = 0.3;

    /// `s` seconds of constant inputs; the last action. (Without [`TouchdownGate::feel_ground`]
    /// nothing is dead-reckoned: the abort's floor judges the fused clearance alone.)
    fn run(
        g: &mut TouchdownGate,
        s: f32,
        clearance: f32,
        demand_deg: f32,
        speed: f32,
    ) -> GateAction {
        let mut a = GateAction::Hold;
        for _ in 0..(s / DT).round() as usize {
            a = g.update(DT, clearance, demand_deg.to_radians(), speed, FINAL);
        }
        a
    }

    /// A gate that has reached the gate clearance and waited `s` seconds in a gust.
    fn waited(s: f32) -> TouchdownGate {
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, s, GATE, 20.0, 1.0), GateAction::Hold);
        g
    }

    #[test]
    fn the_approach_holds_without_counting_the_wait() {
        let mut g = TouchdownGate::new();
        // Above the gate, calm or not: the height loop's approach, no wait, no commit.
        assert_eq!(run(&mut g, 1.0, 0.5, 0.0, 0.0), GateAction::Hold);
        assert_eq!(g.wait_s(), 0.0);
        assert!(!g.committed());
        // At the gate the wait starts; once arrived, a bob above it still counts.
        run(&mut g, 0.1, GATE_CLEARANCE_M + ARRIVED_M, 20.0, 1.0);
        run(&mut g, 0.1, 0.3, 20.0, 1.0);
        assert!((g.wait_s() - 0.2).abs() < 0.01, "{}", g.wait_s());
    }

    #[test]
    fn the_last_chance_in_a_wind_beyond_the_level_limit_is_unlevel() {
        // 40 s of a gust the level limit would clip: committed, forced, unlevel.
        let mut g = waited(LAST_CHANCE_S - 0.01);
        assert!(!g.committed());
        run(&mut g, 0.05, GATE, 20.0, 1.0);
        assert!(g.committed() && g.forced() && g.unlevel());
        assert_eq!(run(&mut g, 0.5, 0.1, 20.0, 1.0), GateAction::Descend);
        // The 30-s path commits only within the level limit: level, not forced.
        let mut g = waited(MAX_WAIT_S - 0.01);
        run(&mut g, 0.05, GATE, LEVEL_TILT_DEG - 0.5, 0.0);
        assert!(g.committed() && !g.forced() && !g.unlevel());
        // A lull: level.
        let mut g = TouchdownGate::new();
        run(&mut g, 1.0, GATE, 0.0, 0.0);
        assert!(g.committed() && !g.forced() && !g.unlevel());
    }

    #[test]
    fn blind_commit_descends_at_once_and_is_never_held_again() {
        let mut g = TouchdownGate::new();
        // Still on the approach, gusty: nothing to wait for without a ground speed.
        g.commit_blind();
        assert!(g.committed() && g.forced());
        assert_eq!(run(&mut g, 0.5, 0.5, 8.0, 1.0), GateAction::Descend);
        assert_eq!(run(&mut g, 0.5, 0.1, 8.0, 1.0), GateAction::Descend);
        assert_eq!(g.wait_s(), 0.0);
    }

    #[test]
    fn holds_in_a_gust_and_commits_in_the_lull() {
        let mut g = TouchdownGate::new();
        // Leaning 6° (or asked to): no lull, whatever the speed.
        assert_eq!(run(&mut g, 1.0, GATE, 6.0, 0.05), GateAction::Hold);
        assert_eq!(run(&mut g, 1.0, GATE, 1.0, 0.4), GateAction::Hold);
        // Calm, but not for long enough: a short dip is not a lull.
        assert_eq!(run(&mut g, 0.1, GATE, 2.0, 0.05), GateAction::Hold);
        assert_eq!(run(&mut g, 0.1, GATE, 6.0, 0.05), GateAction::Hold);
        assert_eq!(run(&mut g, 0.25, GATE, 2.0, 0.05), GateAction::Descend);
        assert!(g.committed() && !g.forced());
        // Committed: the last centimetres are not held again, whatever the gust.
        assert_eq!(run(&mut g, 0.5, 0.02, 8.0, 0.5), GateAction::Descend);
    }

    #[test]
    fn a_clipped_demand_or_a_push_on_the_way_down_sends_it_back() {
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 0.3, GATE, 2.0, 0.05), GateAction::Descend);
        // Still 8 cm up, the controller asks for more than the level limit (for 0.1 s: the
        // demand is low-passed, DEMAND_TAU_S): back to waiting.
        assert_eq!(
            run(&mut g, 0.1, 0.08, LEVEL_TILT_DEG + 0.5, 0.05),
            GateAction::Hold
        );
        assert!(!g.committed());
        assert_eq!(run(&mut g, 0.3, GATE, 2.0, 0.05), GateAction::Descend);
        // Pushed at 0.25 m/s: back to waiting.
        assert_eq!(run(&mut g, 0.01, 0.08, 2.0, 0.25), GateAction::Hold);
        assert_eq!(run(&mut g, 0.3, GATE, 2.0, 0.05), GateAction::Descend);
        // Below ABORT_ABOVE the same gust no longer stops it.
        assert_eq!(run(&mut g, 0.1, 0.02, 10.0, 0.5), GateAction::Descend);
    }

    #[test]
    fn a_spike_of_the_demand_is_no_gust() {
        // `mag` 33030: a calm descent at 3° of command, one 2-ms step of it past the level
        // limit: it goes on down (sent back, 2 cm above the ground, it hopped) …
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 0.3, GATE, 2.0, 0.05), GateAction::Descend);
        assert_eq!(run(&mut g, 0.05, 0.09, 3.0, 0.05), GateAction::Descend);
        assert_eq!(run(&mut g, DT, 0.09, 6.0, 0.05), GateAction::Descend);
        assert_eq!(run(&mut g, 0.05, 0.09, 3.0, 0.05), GateAction::Descend);
        // … while the same demand held for 0.05 s is a gust.
        assert_eq!(run(&mut g, 0.05, 0.09, 6.0, 0.05), GateAction::Hold);
    }

    #[test]
    fn a_speed_rising_while_the_level_limit_clips_sends_it_back() {
        // After 25 s of waiting (k_abort = 2: a demand up to 8° goes on down), committed, then
        // 8 cm up (0.27 s from the contact at the final speed) sliding at 0.05 m/s.
        let rising_limited = |demand_deg: f32, rate_mps2: f32, clearance: f32, limited: bool| {
            let mut g = waited(25.0);
            assert_eq!(run(&mut g, 0.3, GATE, 2.0, 0.1), GateAction::Descend);
            let mut a = GateAction::Descend;
            for i in 0..50 {
                let v = 0.05 + rate_mps2 * DT * i as f32;
                g.command_limited(DT, limited);
                a = g.update(DT, clearance, demand_deg.to_radians(), v, FINAL);
            }
            a
        };
        let rising = |demand_deg: f32, rate_mps2: f32, clearance: f32| {
            rising_limited(demand_deg, rate_mps2, clearance, false)
        };
        let clipped = LEVEL_TILT_DEG + 1.0;
        // Steady: 0.05 m/s at the contact, it goes on.
        assert_eq!(rising(clipped, 0.0, 0.08), GateAction::Descend);
        // Rising at 1 m/s² (0.15 m/s after 0.1 s) with the lean clipped: 0.42 m/s at the
        // contact, back to the gate, though 0.15 m/s alone is within the abort speed.
        assert_eq!(rising(clipped, 1.0, 0.08), GateAction::Hold);
        // Falling: taken as it is.
        assert_eq!(rising(clipped, -1.0, 0.08), GateAction::Descend);
        // Within the level limit the loops oppose the push: not extrapolated …
        assert_eq!(rising(LEVEL_TILT_DEG - 1.0, 1.0, 0.08), GateAction::Descend);
        // … unless the limit clips the command all the same (the touchdown gain's lean
        // against the slide, which the wind's demand leaves out): extrapolated.
        let within = LEVEL_TILT_DEG - 1.0;
        assert_eq!(rising_limited(within, 1.0, 0.08, true), GateAction::Hold);
        assert_eq!(rising_limited(within, 0.0, 0.08, true), GateAction::Descend);
        // Below ABORT_ABOVE the same rise no longer stops it.
        assert_eq!(rising(clipped, 1.0, 0.02), GateAction::Descend);
    }

    #[test]
    fn thresholds_widen_with_the_wait_but_stay_below_the_level_limit() {
        // 3.5° is not calm at first (k·3° < 3.5° while k < 1.17, i.e. for 2.5 s) …
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 2.4, GATE, 3.5, 0.05), GateAction::Hold);
        // … then it is.
        assert_eq!(run(&mut g, 0.5, GATE, 3.5, 0.05), GateAction::Descend);
        // Up to PATIENCE_S the widest calm demand is RELAX_MAX·3° = 3.75° < the level limit.
        let mut g = waited(PATIENCE_S - 0.5);
        assert_eq!(run(&mut g, 0.45, GATE, 3.9, 0.05), GateAction::Hold);
        // After it, 3.9° becomes calm (k = 1.25 + (t − 10 s)/15 s ≥ 1.3 from t = 10.75 s).
        assert_eq!(run(&mut g, 1.5, GATE, 3.9, 0.05), GateAction::Descend);
        assert!(!g.forced());
    }

    #[test]
    fn late_aborts_widen_too() {
        // After 25 s: k_abort = 2, so a 7° demand at 8 cm does not send it back …
        let mut g = waited(25.0);
        assert_eq!(run(&mut g, 0.3, GATE, 2.0, 0.05), GateAction::Descend);
        assert_eq!(run(&mut g, 0.1, 0.08, 7.0, 0.05), GateAction::Descend);
        // … 10° does.
        assert_eq!(run(&mut g, 0.1, 0.08, 10.0, 0.05), GateAction::Hold);
        // The abort speed does not widen: just over it sends it back after 25 s too.
        assert_eq!(run(&mut g, 0.3, GATE, 2.0, 0.05), GateAction::Descend);
        assert_eq!(
            run(&mut g, 0.01, 0.08, 2.0, ABORT_SPEED_MPS + 0.02),
            GateAction::Hold
        );
    }

    #[test]
    fn the_calm_speed_stops_widening_at_its_cap() {
        // After 25 s the widened calm speed would be 2.25·0.12 = 0.27 m/s; capped at 0.18.
        let mut g = waited(25.0);
        assert_eq!(
            run(&mut g, 0.5, GATE, 2.0, CALM_SPEED_CAP_MPS + 0.02),
            GateAction::Hold
        );
        assert_eq!(
            run(&mut g, 0.5, GATE, 2.0, CALM_SPEED_CAP_MPS - 0.02),
            GateAction::Descend
        );
        assert!(!g.forced());
    }

    #[test]
    fn after_the_longest_wait_the_first_fitting_instant_commits() {
        let mut g = waited(MAX_WAIT_S + 0.1);
        // One instant (no calm time) within the level limit and at the abort speed commits …
        assert_eq!(
            run(&mut g, DT, GATE, 4.0, ABORT_SPEED_MPS),
            GateAction::Descend
        );
        assert!(!g.forced());
        // … and a gust on the way down still sends it back.
        assert_eq!(run(&mut g, 0.2, 0.1, 20.0, 1.5), GateAction::Hold);
        // The speed allowed does not grow with the wait: just over the abort speed never fits
        // (until the last chance).
        let mut g = waited(MAX_WAIT_S + 0.1);
        assert_eq!(
            run(&mut g, 20.0, GATE, 4.0, ABORT_SPEED_MPS + 0.02),
            GateAction::Hold
        );
        assert!(!g.committed());
    }

    /// `steps` steps of a committed descent at `clearance`, the descent rate from `rate(i)`,
    /// with a gust's demand (8°) on each: the last action.
    fn descend(
        g: &mut TouchdownGate,
        steps: usize,
        clearance: f32,
        rate: impl Fn(usize) -> f32,
    ) -> GateAction {
        descend_at(g, steps, clearance, 8.0, rate)
    }

    /// The same with a demand of `demand_deg`.
    fn descend_at(
        g: &mut TouchdownGate,
        steps: usize,
        clearance: f32,
        demand_deg: f32,
        rate: impl Fn(usize) -> f32,
    ) -> GateAction {
        let mut a = GateAction::Hold;
        for i in 0..steps {
            // An accelerometer that agrees with the descent rate.
            let accel = (rate(i) - g.descent_prev_mps) / DT;
            g.feel_ground(DT, clearance, rate(i), accel);
            a = g.update(DT, clearance, demand_deg.to_radians(), 0.05, FINAL);
        }
        a
    }

    /// Three steps of a contact's descent rates at `clearance`: the gate takes it as the
    /// touchdown (committed, felt, descending).
    fn assert_touches_down(g: &mut TouchdownGate, clearance: f32, contact: [f32; 3]) {
        assert_eq!(
            descend(g, 3, clearance, |i| contact[i]),
            GateAction::Descend
        );
        assert!(g.felt() && g.committed());
    }

    /// Committed at the gate, then 0.1 s of a calm descent at `rate` (m/s) down to
    /// `clearance`.
    fn committed_descent(clearance: f32, rate: f32) -> TouchdownGate {
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 0.3, GATE, 2.0, 0.05), GateAction::Descend);
        for i in 0..50 {
            let c = clearance + rate * DT * (49 - i) as f32;
            assert_eq!(descend_at(&mut g, 1, c, 2.0, |_| rate), GateAction::Descend);
        }
        g
    }

    #[test]
    fn the_ground_felt_is_not_a_gust() {
        let committed = || committed_descent(0.09, 0.36);
        // `hover` seed 1008's contact: 0.37 → 0.32 → 0.26 m/s in two steps while the fused
        // height still reads 9 cm; the touchdown's jolt asks for 8°: it stays down.
        let mut g = committed();
        let contact = [0.316, 0.256, 0.15, 0.05, 0.0];
        let a = descend(&mut g, contact.len(), 0.09, |i| contact[i]);
        assert!(g.felt());
        assert_eq!(a, GateAction::Descend);
        assert_eq!(descend(&mut g, 100, 0.09, |_| 0.0), GateAction::Descend);
        // The vertical loop's own braking (2.7 m/s², 0.36 → 0.2 m/s) is no contact: the same
        // demand sends it back (above ABORT_ABOVE).
        let mut g = committed();
        assert_eq!(
            descend(&mut g, 30, 0.09, |i| 0.36 - 2.7 * DT * i as f32),
            GateAction::Hold
        );
        assert!(!g.felt());
        // Only a committed descent near the ground feels it: not at the gate, not higher.
        let mut g = TouchdownGate::new();
        for (i, r) in [0.36, 0.36, 0.0, 0.0].into_iter().enumerate() {
            let accel = (r - g.descent_prev_mps) / DT;
            g.feel_ground(DT, if i < 2 { 0.5 } else { 0.05 }, r, accel);
        }
        assert!(!g.felt());
        let mut g = committed();
        for r in [0.36, 0.0, 0.0] {
            let accel = (r - g.descent_prev_mps) / DT;
            g.feel_ground(DT, IMPACT_BELOW_M + 0.01, r, accel);
        }
        assert!(!g.felt());
        g.reset();
        assert!(!g.felt());
    }

    #[test]
    fn a_step_of_the_descent_rate_the_accelerometer_did_not_feel_is_no_contact() {
        // `hover_gale` 25006: holding 5.7 cm up (estimated; 6.8 cm true) after a low sonar
        // reading, the climb back brakes the descent, and one step of the estimated rate drops
        // 0.05 m/s while the accelerometer reads the braking, −12 m/s²: no contact.
        let mut g = TouchdownGate::new();
        run(&mut g, 1.0, GATE, 10.0, 0.5);
        for (r, a) in [(0.1, -4.0), (0.05, -12.0), (0.03, -8.0), (-0.01, -9.0)] {
            g.feel_ground(DT, 0.057, r, a);
        }
        assert!(!g.felt() && !g.committed());
        // The same on a committed descent: a 0.1-m/s step, no jolt, no contact …
        let mut g = committed_descent(0.05, 0.3);
        for r in [0.2, 0.2, 0.2] {
            g.feel_ground(DT, 0.05, r, -8.0);
        }
        assert!(!g.felt());
        // … with the gear's jolt (−30 m/s² 10 ms before), the contact.
        let mut g = committed_descent(0.05, 0.3);
        g.feel_ground(DT, 0.05, 0.29, -30.0);
        for _ in 0..4 {
            g.feel_ground(DT, 0.05, 0.29, -2.0);
        }
        g.feel_ground(DT, 0.05, 0.19, -8.0);
        assert!(g.felt());
    }

    /// Committed after a calm hold at the gate, `s` seconds of a calm descent at the final
    /// speed, the fused clearance following it; then 20 ms with the fused clearance `fused`
    /// and a gust's demand (8°): the last action.
    fn gust_after_descending(s: f32, fused: f32) -> GateAction {
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 0.5, GATE, 2.0, 0.05), GateAction::Descend);
        for i in 0..(s / DT).round() as usize {
            let c = GATE - FINAL * DT * (i + 1) as f32;
            g.feel_ground(DT, c, FINAL, 0.0);
            assert_eq!(
                g.update(DT, c, 2f32.to_radians(), 0.05, FINAL),
                GateAction::Descend
            );
        }
        let mut a = GateAction::Descend;
        for _ in 0..10 {
            g.feel_ground(DT, fused, FINAL, 0.0);
            a = g.update(DT, fused, 8f32.to_radians(), 0.05, FINAL);
        }
        a
    }

    #[test]
    fn the_abort_floor_judges_the_dead_reckoned_clearance_too() {
        // The seconds below the gate at which the gear is `c` up.
        let at = |c: f32| (GATE - c) / FINAL;
        // (The gust here is a lean, so its floor is ABORT_LEAN_ABOVE_M.)
        // `mission` 1013: 3 cm above the floor, a sonar reading 4 cm low puts the fused
        // clearance under it as the gust comes: still sent back.
        let c = ABORT_LEAN_ABOVE_M + 0.03;
        assert_eq!(gust_after_descending(at(c), c - 0.04), GateAction::Hold);
        // `mission` 1007: 2 cm under the floor, a reading 2.5 cm high (above it): the gear is
        // about to touch, no abort (it would be a hop).
        let c = ABORT_LEAN_ABOVE_M - 0.02;
        assert_eq!(gust_after_descending(at(c), c + 0.025), GateAction::Descend);
        // Both agreeing above the floor: sent back; below: not.
        let c = ABORT_LEAN_ABOVE_M + 0.03;
        assert_eq!(gust_after_descending(at(c), c), GateAction::Hold);
        let c = ABORT_LEAN_ABOVE_M - 0.02;
        assert_eq!(gust_after_descending(at(c), c), GateAction::Descend);
    }

    #[test]
    fn a_lean_just_above_the_floor_goes_on_down_a_push_is_sent_back() {
        // Between the two floors: a demand past the level limit would be answered by leaning
        // out of it while the climb dips the gear (`hover` 1067, a hop) — it goes on down …
        let between = 0.5 * (ABORT_ABOVE_M + ABORT_LEAN_ABOVE_M);
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 0.3, GATE, 2.0, 0.05), GateAction::Descend);
        let lean = LEVEL_TILT_DEG + 0.5;
        assert_eq!(run(&mut g, 0.1, between, lean, 0.05), GateAction::Descend);
        // … while a push that would meet the ground at 0.25 m/s is still sent back.
        assert_eq!(run(&mut g, 0.01, between, 2.0, 0.25), GateAction::Hold);
        // Above both floors the same lean is sent back.
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 0.3, GATE, 2.0, 0.05), GateAction::Descend);
        let above = ABORT_LEAN_ABOVE_M + 0.005;
        assert_eq!(run(&mut g, 0.1, above, lean, 0.05), GateAction::Hold);
    }

    #[test]
    fn a_contact_just_after_a_gust_sent_it_back_stays_down() {
        // `landing` seed 1020: committed, a gust sends it back just above the abort's floor
        // (estimated); 30 ms later the gear meets the ground (0.29 → 0.01 m/s): it stays
        // down, felt.
        let up = ABORT_LEAN_ABOVE_M + 0.01;
        let sent_back = || {
            let mut g = committed_descent(up, 0.3);
            let mut a = GateAction::Descend;
            for _ in 0..10 {
                g.feel_ground(DT, up - 0.005, 0.3, 0.0);
                a = g.update(DT, up - 0.005, 8f32.to_radians(), 0.05, FINAL);
                if a == GateAction::Hold {
                    break;
                }
            }
            assert_eq!(a, GateAction::Hold);
            g
        };
        let mut g = sent_back();
        // The climb back brakes the descent at 7 m/s² for 30 ms: no contact.
        let climb = descend(&mut g, 15, up, |i| 0.3 - 7.0 * DT * (i + 1) as f32);
        assert_eq!(climb, GateAction::Hold);
        assert!(!g.felt());
        // Then the gear stops the rest in a few steps.
        let contact = [0.12, 0.05, 0.01];
        assert_touches_down(&mut g, up, contact);
        // Felt: no gust sends it back any more.
        assert_eq!(run(&mut g, 0.2, up, 10.0, 0.5), GateAction::Descend);
        // The same contact later, still waiting at the gate: the ground met anyway, taken too.
        let mut g = sent_back();
        descend(&mut g, (REFEEL_S / DT) as usize + 1, up, |_| 0.3);
        assert_touches_down(&mut g, up, contact);
    }

    #[test]
    fn the_arrest_after_a_gust_is_levelled_until_the_descent_stops() {
        // A calm committed descent is no arrest, nor is the wait at the gate.
        let mut g = committed_descent(0.08, 0.38);
        assert!(!g.arresting(0.38));
        assert!(!waited(1.0).arresting(0.1));
        // A gust sends it back 8 cm up: arresting while it still goes down …
        assert_eq!(
            descend_at(&mut g, 10, 0.08, 2.0 * LEVEL_TILT_DEG, |_| 0.38),
            GateAction::Hold
        );
        assert!(g.arresting(0.38) && g.arresting(0.01));
        // … not once it climbs, …
        assert!(!g.arresting(-0.01));
        // … and not after REFEEL_S, whatever the descent (the hold's own dips lean freely).
        run(&mut g, REFEEL_S, GATE, 2.0 * LEVEL_TILT_DEG, 0.05);
        assert!(!g.arresting(0.38));
    }

    #[test]
    fn a_dip_of_the_hold_onto_the_ground_stays_down() {
        // Waiting at the gate (never committed), a gust pushes the hold down onto the gear
        // (`tests/zenoh/faults.sh`, uav3): the contact is the touchdown, no climb back.
        let mut g = TouchdownGate::new();
        assert_eq!(run(&mut g, 1.0, GATE, 10.0, 0.5), GateAction::Hold);
        assert!(!g.committed());
        assert_touches_down(&mut g, 0.02, [0.36, 0.12, 0.02]);
        // A gentle sink at the gate is not a contact.
        let mut g = TouchdownGate::new();
        run(&mut g, 1.0, GATE, 10.0, 0.5);
        assert_eq!(
            descend(&mut g, 50, 0.05, |i| 0.1 + 0.004 * i as f32),
            GateAction::Hold
        );
        assert!(!g.felt());
    }

    #[test]
    fn commits_whatever_the_wind_at_the_last_chance() {
        let mut g = TouchdownGate::new();
        assert_eq!(
            run(&mut g, LAST_CHANCE_S - 0.1, GATE, 20.0, 1.5),
            GateAction::Hold
        );
        assert_eq!(run(&mut g, 0.2, GATE, 20.0, 1.5), GateAction::Descend);
        assert!(g.forced());
        g.reset();
        assert!(!g.forced() && !g.committed());
        assert_eq!(run(&mut g, 0.1, GATE, 20.0, 1.5), GateAction::Hold);
    }
}
