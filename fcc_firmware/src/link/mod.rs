//! The MCU end of the serial link to the Linux computer ([`fcc_msgs`] frames).
//!
//! [`LinkEndpoint`] is sans-IO like the rest of the core: the board's UART driver (or the SITL's
//! pseudo-terminal) hands it received bytes with [`LinkEndpoint::on_bytes`] and asks it for bytes
//! to send with [`LinkEndpoint::poll_tx`], once per 500 Hz tick. No heap, no clock, no blocking.
//!
//! - Received setpoints and commands go to [`FlightCore::setpoint`] / [`FlightCore::command`];
//!   refusals are counted and reported in `Status` (and, for commands, in a `CommandAck`).
//! - `TimeSyncPing` is answered with `TimeSyncPong` (receive and transmit MCU µs).
//! - `HelloRequest` is answered with `Hello` (protocol version, schema hash, firmware version);
//!   a `Hello` is also sent once at start-up. If the peer announced another version or schema,
//!   its setpoints and commands are refused (`CommandResult::Incompatible`). A `HelloRequest`
//!   starts a new session: a jump of the Linux side's sequence number onto it (a restarted
//!   bridge counts from 0 again) is a sequence reset, not lost frames (see
//!   [`LinkEndpoint::rx_counters`]).
//! - Telemetry streams go out at [`StreamRates`], phase-staggered so they do not all fall on one
//!   tick. Raw sensor streams send the newest sample (never the same one twice) with the
//!   sample's own time in the header.

use crate::commands::{self, CommandError, VelocitySetpoint as CoreSetpoint};
use crate::flight::FlightCore;
use crate::params::ParamFault;
use crate::sensors::{
    BaroSample, BatterySample, GpsFix, ImuSample, MagSample, RangeSample, SensorInputs,
};
use fcc_msgs::{
    period_us, AltitudeFusion, AltitudeSource, BaroRaw, Battery, CommandAck, CommandKind,
    CommandResult, EncodeError, Encoder, FrameDecoder, GpsRaw, HandshakeError, Hello, HomePosition,
    ImuRaw, LinkCounters, MagRaw, Message, NavState, ParamAck, ParamResult, RangeRaw, RangeSensor,
    SensorHealth, Status, Stream, StreamRates, TimeSyncPong,
};
use fcc_nav::ground_altitude::GroundSource;

#[cfg(test)]
mod tests;

/// Firmware version sent in `Hello` (this crate's version).
pub const FIRMWARE_VERSION: [u8; 3] = [
    parse_u8(env!("CARGO_PKG_VERSION_MAJOR")),
    parse_u8(env!("CARGO_PKG_VERSION_MINOR")),
    parse_u8(env!("CARGO_PKG_VERSION_PATCH")),
];

const fn parse_u8(s: &str) -> u8 {
    let b = s.as_bytes();
    let mut v: u32 = 0;
    let mut i = 0;
    while i < b.len() {
        v = v * 10 + (b[i] - b'0') as u32;
        i += 1;
    }
    if v > 255 {
        255
    } else {
        v as u8
    }
}

/// Pending command acknowledgements kept when the transmit buffer is full.
const ACK_QUEUE: usize = 4;
/// Number of telemetry streams ([`Stream::ALL`]).
const STREAMS: usize = Stream::COUNT;
/// First-due offset of a stream after start (µs), so the streams' frames spread over different
/// 2 ms ticks.
const fn phase_us(s: Stream) -> u64 {
    match s {
        Stream::Status => 0,
        Stream::NavState => 2_000,
        Stream::Altitude => 4_000,
        Stream::ImuRaw => 0,
        Stream::MagRaw => 7_000,
        Stream::BaroRaw => 9_000,
        Stream::GpsRaw => 11_000,
        Stream::LaserRaw => 13_000,
        Stream::SonarRaw => 15_000,
        Stream::Battery => 17_000,
    }
}

/// What the peer said in its last `HelloRequest`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PeerState {
    /// No `HelloRequest` yet: setpoints and commands are accepted.
    Unknown,
    Compatible,
    Incompatible(HandshakeError),
}

/// The MCU side's link statistics (receive counters are in [`LinkEndpoint::rx_counters`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    pub tx_frames: u32,
    pub tx_bytes: u32,
    /// Telemetry frames that did not fit the caller's buffer (or acks that overflowed the queue).
    pub tx_dropped: u32,
    pub setpoints_applied: u32,
    pub setpoint_rejects: u32,
    pub commands_applied: u32,
    pub command_rejects: u32,
    /// Most recent refusal (`Accepted` = none yet).
    pub last_reject: CommandResult,
    /// Valid frames of MCU → Linux messages received from the Linux side.
    pub unexpected: u32,
}

/// The decoder's sequence-tracking counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct SeqCounters {
    seq_gaps: u32,
    frames_lost: u32,
    seq_resets: u32,
}

impl SeqCounters {
    fn of(c: &LinkCounters) -> Self {
        Self {
            seq_gaps: c.seq_gaps,
            frames_lost: c.frames_lost,
            seq_resets: c.seq_resets,
        }
    }

    /// A new session began with the frame that moved the decoder's counters from `before` to
    /// `after`: forgive the gap it counted (if any) and count one reset instead (unless the
    /// decoder already counted the jump as one).
    fn new_session(&mut self, before: &Self, after: &Self) {
        let gaps = after.seq_gaps.wrapping_sub(before.seq_gaps);
        if gaps != 0 {
            self.seq_gaps = self.seq_gaps.wrapping_add(gaps);
            self.frames_lost = self
                .frames_lost
                .wrapping_add(after.frames_lost.wrapping_sub(before.frames_lost));
            self.seq_resets = self.seq_resets.wrapping_add(1);
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct Latest<T> {
    sample: Option<T>,
    fresh: bool,
}

impl<T: Copy> Latest<T> {
    fn update(&mut self, s: Option<T>) {
        if s.is_some() {
            self.sample = s;
            self.fresh = true;
        }
    }
    fn take_fresh(&mut self) -> Option<T> {
        if self.fresh {
            self.fresh = false;
            self.sample
        } else {
            None
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct LatestSamples {
    imu: Latest<ImuSample>,
    mag: Latest<MagSample>,
    baro: Latest<BaroSample>,
    gps: Latest<GpsFix>,
    laser: Latest<RangeSample>,
    sonar: Latest<RangeSample>,
    battery: Latest<BatterySample>,
}

/// The MCU end of the link.
pub struct LinkEndpoint {
    decoder: FrameDecoder,
    encoder: Encoder,
    rates: StreamRates,
    next_due_us: [Option<u64>; STREAMS],
    latest: LatestSamples,
    pending_hello: bool,
    /// (echoed Linux ns, MCU receive µs)
    pending_pong: Option<(u64, u64)>,
    acks: [Option<CommandAck>; ACK_QUEUE],
    param_acks: [Option<ParamAck>; ACK_QUEUE],
    peer: PeerState,
    stats: LinkStats,
    /// The decoder's sequence counters before the frame being decoded.
    seq_before: SeqCounters,
    /// Sequence gaps / lost frames the decoder counted on `HelloRequest` frames (new sessions),
    /// taken out of [`LinkEndpoint::rx_counters`], and the resets counted for them instead.
    seq_forgiven: SeqCounters,
    loop_max_us: u32,
    loop_sum_us: u64,
    loop_n: u32,
    /// The home last put in a `NavState` and when (MCU µs): it goes again after
    /// [`HOME_RESEND_US`], when it changes, and at a new session.
    home_sent: Option<(HomePosition, u64)>,
}

/// `NavState` carries the home about once a second (and at once when it changes): it is
/// 20 of a frame's bytes, at 100 Hz a fifth of the link's, for a value that rarely changes.
pub const HOME_RESEND_US: u64 = 1_000_000;

impl Default for LinkEndpoint {
    fn default() -> Self {
        Self::new(StreamRates::DEFAULT)
    }
}

impl LinkEndpoint {
    pub fn new(rates: StreamRates) -> Self {
        Self {
            decoder: FrameDecoder::new(),
            encoder: Encoder::new(),
            rates,
            next_due_us: [None; STREAMS],
            latest: LatestSamples::default(),
            pending_hello: true,
            pending_pong: None,
            acks: [None; ACK_QUEUE],
            param_acks: [None; ACK_QUEUE],
            peer: PeerState::Unknown,
            stats: LinkStats::default(),
            seq_before: SeqCounters::default(),
            seq_forgiven: SeqCounters::default(),
            loop_max_us: 0,
            loop_sum_us: 0,
            loop_n: 0,
            home_sent: None,
        }
    }

    pub fn rates(&self) -> &StreamRates {
        &self.rates
    }
    /// Change the telemetry rates; the streams restart their schedule.
    pub fn set_rates(&mut self, rates: StreamRates) {
        self.rates = rates;
        self.next_due_us = [None; STREAMS];
    }
    pub fn stats(&self) -> &LinkStats {
        &self.stats
    }
    /// Receive-side counters (CRC errors, resyncs, lost frames, …) of the Linux → MCU direction.
    ///
    /// A sequence jump onto a `HelloRequest` (the peer's new session, e.g. a restarted bridge
    /// whose sequence starts at 0 again) counts as one `seq_resets`, not as a gap with lost
    /// frames.
    pub fn rx_counters(&self) -> LinkCounters {
        let mut c = *self.decoder.counters();
        let f = &self.seq_forgiven;
        c.seq_gaps = c.seq_gaps.wrapping_sub(f.seq_gaps);
        c.frames_lost = c.frames_lost.wrapping_sub(f.frames_lost);
        c.seq_resets = c.seq_resets.wrapping_add(f.seq_resets);
        c
    }
    pub fn peer(&self) -> PeerState {
        self.peer
    }

    /// Record one control-loop execution time (µs), measured by the board; reported as max and
    /// mean in the next `Status`.
    pub fn record_loop_time_us(&mut self, us: u32) {
        self.loop_max_us = self.loop_max_us.max(us);
        self.loop_sum_us += us as u64;
        self.loop_n += 1;
    }

    /// Decode received bytes (any chunking) and apply what they carry to `core`.
    pub fn on_bytes(&mut self, now_us: u64, bytes: &[u8], core: &mut FlightCore) {
        let mut rest = bytes;
        while let Some((&b, tail)) = rest.split_first() {
            rest = tail;
            // Errors are counted by the decoder and reported in `Status`.
            let Some(r) = self.decoder.push(b) else {
                continue;
            };
            let after = SeqCounters::of(self.decoder.counters());
            if let Ok(frame) = r {
                if matches!(frame.message, Message::HelloRequest(_)) {
                    self.seq_forgiven.new_session(&self.seq_before, &after);
                }
                self.handle(now_us, frame.message, core);
            }
            self.seq_before = after;
        }
    }

    fn handle(&mut self, now_us: u64, msg: Message, core: &mut FlightCore) {
        match msg {
            Message::HelloRequest(r) => {
                self.peer = match r.check() {
                    Ok(()) => PeerState::Compatible,
                    Err(e) => PeerState::Incompatible(e),
                };
                self.pending_hello = true;
                self.home_sent = None;
            }
            Message::TimeSyncPing(p) => self.pending_pong = Some((p.linux_time_ns, now_us)),
            Message::VelocitySetpoint(sp) => {
                let r = if matches!(self.peer, PeerState::Incompatible(_)) {
                    CommandResult::Incompatible
                } else {
                    let core_sp = CoreSetpoint {
                        vel_ned_mps: sp.vel_ned_mps,
                        yaw: sp.yaw,
                        ttl_ms: sp.ttl_ms,
                    };
                    to_result(core.setpoint(now_us, core_sp))
                };
                if r == CommandResult::Accepted {
                    self.stats.setpoints_applied = self.stats.setpoints_applied.wrapping_add(1);
                } else {
                    self.stats.setpoint_rejects = self.stats.setpoint_rejects.wrapping_add(1);
                    self.stats.last_reject = r;
                }
            }
            Message::Command(c) => {
                let r = if matches!(self.peer, PeerState::Incompatible(_)) {
                    CommandResult::Incompatible
                } else {
                    to_result(core.command(now_us, to_core_command(c.command, c.confirm)))
                };
                if r == CommandResult::Accepted {
                    self.stats.commands_applied = self.stats.commands_applied.wrapping_add(1);
                } else {
                    self.stats.command_rejects = self.stats.command_rejects.wrapping_add(1);
                    self.stats.last_reject = r;
                }
                self.queue_ack(CommandAck {
                    command: c.command,
                    result: r,
                });
            }
            Message::ParamSet(ps) => {
                let result = if matches!(self.peer, PeerState::Incompatible(_)) {
                    ParamResult::Incompatible
                } else if core.param(ps.id).is_none() {
                    ParamResult::UnknownId
                } else if !ps.value.is_finite() {
                    // NaN: a read of the current value.
                    ParamResult::NotFinite
                } else {
                    match core.set_param(ps.id, ps.value) {
                        Ok(()) => {
                            // A `rates.*` parameter: the new schedule applies from now on.
                            if Stream::by_param_id(ps.id).is_some() {
                                self.set_rates(core.params().stream_rates());
                            }
                            ParamResult::Accepted
                        }
                        Err(e) if e.reason == ParamFault::NotFinite => ParamResult::NotFinite,
                        Err(_) => ParamResult::OutOfRange,
                    }
                };
                let ack = ParamAck {
                    id: ps.id,
                    value: core.param(ps.id).unwrap_or(f32::NAN),
                    result,
                };
                if let Some(slot) = self.param_acks.iter_mut().find(|a| a.is_none()) {
                    *slot = Some(ack);
                } else {
                    self.param_acks.rotate_left(1);
                    self.param_acks[ACK_QUEUE - 1] = Some(ack);
                    self.stats.tx_dropped = self.stats.tx_dropped.wrapping_add(1);
                }
            }
            _ => self.stats.unexpected = self.stats.unexpected.wrapping_add(1),
        }
    }

    fn queue_ack(&mut self, ack: CommandAck) {
        if let Some(slot) = self.acks.iter_mut().find(|a| a.is_none()) {
            *slot = Some(ack);
        } else {
            // Full: drop the oldest.
            self.acks.rotate_left(1);
            self.acks[ACK_QUEUE - 1] = Some(ack);
            self.stats.tx_dropped = self.stats.tx_dropped.wrapping_add(1);
        }
    }

    /// Write the frames due at `now_us` into `out`; returns the number of bytes written.
    ///
    /// Replies (`Hello`, `TimeSyncPong`, `CommandAck`) go first and wait for room if they do not
    /// fit; a telemetry frame that does not fit is dropped (counted) and its stream goes on at
    /// its next period. `sensors` are this tick's new samples (as given to
    /// [`FlightCore::step`]); the endpoint keeps the newest of each for the raw streams.
    pub fn poll_tx(
        &mut self,
        now_us: u64,
        core: &FlightCore,
        sensors: &SensorInputs,
        out: &mut [u8],
    ) -> usize {
        let l = &mut self.latest;
        l.imu.update(sensors.imu);
        l.mag.update(sensors.mag);
        l.baro.update(sensors.baro);
        l.gps.update(sensors.gps);
        l.laser.update(sensors.laser);
        l.sonar.update(sensors.sonar);
        l.battery.update(sensors.battery);

        let mut pos = 0;
        if self.pending_hello {
            let m = Message::Hello(Hello::ours(FIRMWARE_VERSION));
            if self.emit(&m, now_us, out, &mut pos).is_ok() {
                self.pending_hello = false;
            }
        }
        if let Some((linux_ns, rx_us)) = self.pending_pong {
            let m = Message::TimeSyncPong(TimeSyncPong {
                linux_time_ns: linux_ns,
                mcu_rx_time_us: rx_us,
                mcu_tx_time_us: now_us,
            });
            if self.emit(&m, now_us, out, &mut pos).is_ok() {
                self.pending_pong = None;
            }
        }
        while let Some(ack) = self.acks[0] {
            if self
                .emit(&Message::CommandAck(ack), now_us, out, &mut pos)
                .is_err()
            {
                break;
            }
            self.acks.rotate_left(1);
            self.acks[ACK_QUEUE - 1] = None;
        }
        while let Some(ack) = self.param_acks[0] {
            if self
                .emit(&Message::ParamAck(ack), now_us, out, &mut pos)
                .is_err()
            {
                break;
            }
            self.param_acks.rotate_left(1);
            self.param_acks[ACK_QUEUE - 1] = None;
        }

        for stream in Stream::ALL {
            let i = stream.index();
            let Some(period) = period_us(self.rates.hz(stream)) else {
                continue;
            };
            // `get`, not indexing: no panic path in the MCU image (STREAMS entries each).
            let Some(slot) = self.next_due_us.get_mut(i) else {
                continue;
            };
            let due = *slot.get_or_insert(now_us + phase_us(stream) % period);
            if now_us < due {
                continue;
            }
            let Some((msg, t_us)) = self.stream_message(stream, now_us, core) else {
                // Raw stream without a new sample: send as soon as one arrives.
                continue;
            };
            if self.emit(&msg, t_us, out, &mut pos).is_err() {
                self.stats.tx_dropped = self.stats.tx_dropped.wrapping_add(1);
            }
            let mut next = due + period;
            if next <= now_us {
                next = now_us + period;
            }
            if let Some(slot) = self.next_due_us.get_mut(i) {
                *slot = Some(next);
            }
        }
        pos
    }

    fn emit(
        &mut self,
        msg: &Message,
        t_us: u64,
        out: &mut [u8],
        pos: &mut usize,
    ) -> Result<(), EncodeError> {
        let rest = out.get_mut(*pos..).unwrap_or_default();
        let n = self.encoder.encode(msg, t_us, rest)?;
        *pos += n;
        self.stats.tx_frames = self.stats.tx_frames.wrapping_add(1);
        self.stats.tx_bytes = self.stats.tx_bytes.wrapping_add(n as u32);
        Ok(())
    }

    /// The message of a stream and its header time.
    fn stream_message(
        &mut self,
        stream: Stream,
        now_us: u64,
        core: &FlightCore,
    ) -> Option<(Message, u64)> {
        let nav = core.nav();
        let l = &mut self.latest;
        Some(match stream {
            Stream::Status => (Message::Status(core_status(core, self.status())), now_us),
            Stream::NavState => {
                let home = self.home_due(core, now_us);
                (Message::NavState(nav_state(core, home)), nav.t_us)
            }
            Stream::Altitude => {
                let range = |s: &Latest<RangeSample>| s.sample.map_or(f32::NAN, |r| r.range_m);
                let m = AltitudeFusion {
                    baro_alt_m: nav.baro_alt_m,
                    alt_m: -nav.pos_ned_m[2],
                    vel_down_mps: nav.vel_ned_mps[2],
                    ground_height_m: nav.ground.height_m,
                    ground_var_m2: nav.ground.variance_m2,
                    laser_m: range(&l.laser),
                    sonar_m: range(&l.sonar),
                    source: match nav.ground.source {
                        GroundSource::None => AltitudeSource::None,
                        GroundSource::Laser => AltitudeSource::Laser,
                        GroundSource::Sonar => AltitudeSource::Sonar,
                        GroundSource::Both => AltitudeSource::Both,
                        GroundSource::Predicted => AltitudeSource::Predicted,
                    },
                };
                (Message::AltitudeFusion(m), nav.t_us)
            }
            Stream::ImuRaw => {
                let s = l.imu.take_fresh()?;
                (
                    Message::ImuRaw(ImuRaw {
                        gyro_frd_radps: s.gyro_frd_radps,
                        accel_frd_mps2: s.accel_frd_mps2,
                    }),
                    s.t_us,
                )
            }
            Stream::MagRaw => {
                let s = l.mag.take_fresh()?;
                (
                    Message::MagRaw(MagRaw {
                        mag_frd_ut: s.mag_frd_ut,
                    }),
                    s.t_us,
                )
            }
            Stream::BaroRaw => {
                let s = l.baro.take_fresh()?;
                (
                    Message::BaroRaw(BaroRaw {
                        pressure_pa: s.pressure_pa,
                        temperature_c: s.temperature_c,
                    }),
                    s.t_us,
                )
            }
            Stream::GpsRaw => {
                let g = l.gps.take_fresh()?;
                let m = GpsRaw {
                    lat_deg: g.lat_deg,
                    lon_deg: g.lon_deg,
                    alt_m: g.alt_m,
                    vel_ned_mps: g.vel_ned_mps,
                    h_acc_m: g.h_acc_m,
                    num_sats: g.num_sats,
                    fix_ok: g.fix_ok,
                };
                (Message::GpsRaw(m), g.t_us)
            }
            Stream::LaserRaw => {
                let s = l.laser.take_fresh()?;
                (
                    Message::RangeRaw(RangeRaw {
                        sensor: RangeSensor::Laser,
                        range_m: s.range_m,
                    }),
                    s.t_us,
                )
            }
            Stream::SonarRaw => {
                let s = l.sonar.take_fresh()?;
                (
                    Message::RangeRaw(RangeRaw {
                        sensor: RangeSensor::Sonar,
                        range_m: s.range_m,
                    }),
                    s.t_us,
                )
            }
            Stream::Battery => {
                let s = l.battery.take_fresh()?;
                (
                    Message::Battery(Battery {
                        voltage_v: s.voltage_v,
                        current_a: s.current_a,
                    }),
                    s.t_us,
                )
            }
        })
    }

    /// The link's part of `Status`; restarts the loop-time statistics.
    fn status(&mut self) -> Status {
        let avg = if self.loop_n > 0 {
            (self.loop_sum_us / self.loop_n as u64) as u32
        } else {
            0
        };
        let s = Status {
            loop_time_max_us: self.loop_max_us,
            loop_time_avg_us: avg,
            link_rx: self.rx_counters(),
            tx_frames: self.stats.tx_frames,
            tx_dropped: self.stats.tx_dropped,
            setpoint_rejects: self.stats.setpoint_rejects,
            command_rejects: self.stats.command_rejects,
            last_reject: self.stats.last_reject,
            ..Status::default()
        };
        self.loop_max_us = 0;
        self.loop_sum_us = 0;
        self.loop_n = 0;
        s
    }
}

/// The core's part of `Status`.
fn core_status(core: &FlightCore, mut s: Status) -> Status {
    s.mode = core.mode();
    s.armed = core.armed();
    s.landed = core.landed();
    let n = core.nav();
    let (mag_disturbed, mag_rejects) = core.navigator().mag_disturbance();
    s.sensors = SensorHealth {
        gps_ok: n.gps_ok,
        mag_disturbed,
        mag_rejects,
        laser_ok: n.ground.laser_valid,
        sonar_ok: n.ground.sonar_valid,
        mag_disturbed_ds: (n.mag_disturbed_s * 10.0).min(u16::MAX as f32) as u16,
        nav_faults: n.nav_faults,
    };
    s.failsafe = core.failsafe();
    s
}

impl LinkEndpoint {
    /// The home to put in this `NavState`: when there is one and it was not sent within
    /// [`HOME_RESEND_US`] or has changed since.
    fn home_due(&mut self, core: &FlightCore, now_us: u64) -> Option<HomePosition> {
        let home = core.navigator().home().map(|h| HomePosition {
            lat_deg: h.lat_deg,
            lon_deg: h.lon_deg,
            alt_m: h.alt_m as f32,
        })?;
        // Changed: compared bit for bit (an f64 `==` is a soft-float call on the M4F).
        let bits = |h: &HomePosition| (h.lat_deg.to_bits(), h.lon_deg.to_bits(), h.alt_m.to_bits());
        let due = match self.home_sent {
            Some((sent, at)) => {
                bits(&sent) != bits(&home) || now_us.saturating_sub(at) >= HOME_RESEND_US
            }
            None => true,
        };
        if due {
            self.home_sent = Some((home, now_us));
        }
        due.then_some(home)
    }
}

fn nav_state(core: &FlightCore, home: Option<HomePosition>) -> NavState {
    let n = core.nav();
    NavState {
        q_body_to_ned: quat_from_euler(n.euler.roll_rad, n.euler.pitch_rad, n.euler.yaw_rad),
        rate_frd_radps: n.rate_frd_radps,
        pos_ned_m: n.pos_ned_m,
        vel_ned_mps: n.vel_ned_mps,
        accel_ned_mps2: n.accel_ned_mps2,
        accel_obs_ne_mps2: core.telemetry().accel_est_ne_mps2,
        home,
        gps_ok: n.gps_ok,
        home_set: n.home_set,
        calibrated: n.calibrated,
    }
}

/// The attitude quaternion on the link: `fcc_nav`'s, shared with the Linux side's fake MCU.
pub use fcc_nav::attitude::quat_from_euler;

fn to_result(r: Result<(), CommandError>) -> CommandResult {
    match r {
        Ok(()) => CommandResult::Accepted,
        Err(CommandError::NotCalibrated) => CommandResult::NotCalibrated,
        Err(CommandError::NoHome) => CommandResult::NoHome,
        Err(CommandError::NotLanded) => CommandResult::NotLanded,
        Err(CommandError::Disarmed) => CommandResult::Disarmed,
        Err(CommandError::InvalidSetpoint) => CommandResult::InvalidSetpoint,
        Err(CommandError::PilotOverride) => CommandResult::PilotOverride,
        Err(CommandError::KillNotConfirmed) => CommandResult::KillNotConfirmed,
    }
}

fn to_core_command(c: CommandKind, confirm: u32) -> commands::Command {
    match c {
        CommandKind::Kill => commands::Command::Kill { confirm },
        CommandKind::Arm => commands::Command::Arm,
        CommandKind::Disarm => commands::Command::Disarm,
        CommandKind::Hold => commands::Command::Hold,
        CommandKind::Land => commands::Command::Land,
        CommandKind::Velocity => commands::Command::Velocity,
    }
}
