//! The bridge's link-side state machine, without IO: decoded frames in → ROS messages out,
//! ROS setpoints/commands in → link messages out, plus every counter. The IO layer
//! ([`crate::bridge`]) only moves bytes and publishes what this returns.

use crate::bounded;
use crate::convert::{self, Config, SetpointLimits};
use crate::timesync::TimeSync;
use fcc_msgs as link;
use fcc_msgs::ros::*;
use std::collections::BTreeMap;

/// How message stamps are made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClockSource {
    /// MCU µs mapped to the Linux clock by the ping/pong time sync (arrival time until synced).
    Sync,
    /// MCU µs since boot used directly as ROS time, and `/clock` published (SITL with
    /// `use_sim_time`).
    Mcu,
}

/// A ROS message to publish, by topic.
#[derive(Clone, Debug)]
pub enum Out {
    ImuRaw(Imu),
    Mag(MagneticField),
    Baro(FluidPressure),
    GpsFix(NavSatFix),
    Laser(Range),
    Sonar(Range),
    Battery(BatteryState),
    Odom(Odometry),
    StateImu(Imu),
    Tf(TFMessage),
    /// `/tf_static` stamped with the MCU clock (`clock_source:=mcu`; with `sync` the IO layer
    /// publishes it at start-up on the Linux clock).
    TfStatic(TFMessage),
    Altitude(Altitude),
    Ground(Range),
    Status(Status),
    Clock(Clock),
    /// `accel/observer`: the Luenberger observer's horizontal acceleration (ENU, map).
    AccelObserver(AccelStamped),
    /// `accel/measured`: the gravity-compensated accelerometer (ENU, map).
    AccelMeasured(AccelStamped),
    /// `home`: the MCU's home (the origin of `map`), when it is set or moves.
    Home(NavSatFix),
}

/// Handshake progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Handshake {
    Waiting,
    Ok { firmware: [u8; 3] },
}

/// Bridge-side counters (all since start; link counters accumulate across reconnects).
#[derive(Clone, Debug, Default)]
pub struct Counters {
    /// Frames decoded, by message name.
    pub rx_by_type: BTreeMap<&'static str, u64>,
    /// Decoder counters of previous connections (added to the current decoder's).
    pub link_prev: LinkTotals,
    /// Decoded frames not published: before the handshake, unexpected direction.
    pub dropped: u64,
    /// DDS writes that failed.
    pub publish_errors: u64,
    /// Valid setpoints handed to the uplink (sent, or coalesced/superseded: see [`Uplink`]).
    pub setpoints_forwarded: u64,
    pub setpoint_rejects: u64,
    pub last_setpoint_reject: String,
    /// Forwarded setpoints that carried a yaw rate (`twist.angular.z` ≠ 0).
    pub yaw_rate_setpoints: u64,
    /// Forwarded setpoints that carried the latest `setpoint/heading`.
    pub heading_setpoints: u64,
    /// Valid `setpoint/heading` messages (refused ones count in `setpoint_rejects`).
    pub headings_received: u64,
    pub commands_forwarded: u64,
    pub command_rejects: u64,
    pub stamped_by_arrival: u64,
    pub reconnects: u64,
    pub command_acks: BTreeMap<String, u64>,
}

/// Sum of [`link::LinkCounters`] in u64.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkTotals {
    pub rx_bytes: u64,
    pub rx_frames: u64,
    pub crc_errors: u64,
    pub framing_errors: u64,
    pub overruns: u64,
    pub resyncs: u64,
    pub decode_errors: u64,
    pub unknown_ids: u64,
    pub version_errors: u64,
    pub seq_gaps: u64,
    pub frames_lost: u64,
    pub seq_resets: u64,
}

impl LinkTotals {
    pub fn add(&self, c: &link::LinkCounters) -> LinkTotals {
        LinkTotals {
            rx_bytes: self.rx_bytes + c.rx_bytes as u64,
            rx_frames: self.rx_frames + c.rx_frames as u64,
            crc_errors: self.crc_errors + c.crc_errors as u64,
            framing_errors: self.framing_errors + c.framing_errors as u64,
            overruns: self.overruns + c.overruns as u64,
            resyncs: self.resyncs + c.resyncs as u64,
            decode_errors: self.decode_errors + c.decode_errors as u64,
            unknown_ids: self.unknown_ids + c.unknown_ids as u64,
            version_errors: self.version_errors + c.version_errors as u64,
            seq_gaps: self.seq_gaps + c.seq_gaps as u64,
            frames_lost: self.frames_lost + c.frames_lost as u64,
            seq_resets: self.seq_resets + c.seq_resets as u64,
        }
    }
}

/// Why the session must stop.
#[derive(Clone, Debug, PartialEq)]
pub enum Fatal {
    Handshake(link::HandshakeError),
}

pub struct LinkState {
    pub cfg: Config,
    pub limits: SetpointLimits,
    pub clock: ClockSource,
    pub decoder: link::FrameDecoder,
    pub encoder: link::Encoder,
    pub handshake: Handshake,
    pub timesync: TimeSync,
    pub counters: Counters,
    /// Latest MCU status (for diagnostics).
    pub mcu_status: Option<link::Status>,
    /// NED yaw of the latest navigation state.
    pub yaw_ned: Option<f64>,
    /// The latest valid `setpoint/heading` (NED yaw, rad) and when it arrived (bridge clock,
    /// ns): attached to the velocity setpoints that follow (see [`LinkState::on_heading`]).
    pub heading: Option<(f64, i64)>,
    /// MCU time of the latest frame.
    pub last_mcu_us: Option<u64>,
    /// `use_sim_time` with `clock_source:=sync`: `/clock` minus the Linux clock at the latest
    /// `/clock` (added to every stamp and to "now").
    pub sim_offset_ns: Option<i64>,
    /// `use_sim_time` in effect (start-up value, then as set at run time): with
    /// `clock_source:=sync`, `/clock` sets [`LinkState::sim_offset_ns`] only while true.
    pub sim_time: bool,
    /// `CommandAck`s and `ParamAck`s received, for the IO layer to answer services with.
    pub acks: Vec<link::Message>,
    /// Height above ground of the latest altitude fusion (for the sensor-health rules).
    pub ground_height_m: Option<f32>,
    /// Sensor-health transitions (WARN / INFO on `/rosout`).
    pub sensors: crate::health::SensorWatch,
    /// The current decoder's (seq_gaps, frames_lost, seq_resets) before the frame being decoded.
    seq_before: [u32; 3],
    /// The frames of one read, before their conversion (kept: no allocation per read).
    frames: Vec<link::Frame>,
    /// Gaps and lost frames the current decoder counted on `Hello` frames (the MCU's new
    /// session: a rebooted MCU counts from 0 again), taken out of [`LinkState::link_totals`],
    /// and the resets counted for them instead.
    seq_forgiven: [u32; 3],
    /// Rate limit of the warnings about input (per kind, 1 s).
    pub warn: bounded::WarnLimiter,
    /// The uplink shaper: setpoints coalesced to the newest at a bounded rate, commands first.
    pub uplink: Uplink,
    /// `clock_source:=mcu`: `/tf_static` still to be published, stamped with the first MCU time
    /// of this connection (one clock on every stamp).
    pub tf_static_due: bool,
    /// The home last published on `home` (latitude, longitude, altitude), if any.
    pub home_published: Option<link::HomePosition>,
}

fn seq_counters(c: &link::LinkCounters) -> [u32; 3] {
    [c.seq_gaps, c.frames_lost, c.seq_resets]
}

impl LinkState {
    pub fn new(cfg: Config, limits: SetpointLimits, clock: ClockSource) -> Self {
        LinkState {
            cfg,
            limits,
            clock,
            decoder: link::FrameDecoder::new(),
            encoder: link::Encoder::new(),
            handshake: Handshake::Waiting,
            timesync: TimeSync::new(),
            counters: Counters::default(),
            mcu_status: None,
            yaw_ned: None,
            heading: None,
            last_mcu_us: None,
            sim_offset_ns: None,
            sim_time: false,
            acks: Vec::new(),
            ground_height_m: None,
            sensors: Default::default(),
            seq_before: [0; 3],
            frames: Vec::new(),
            seq_forgiven: [0; 3],
            warn: bounded::WarnLimiter::default(),
            uplink: Uplink::new(SETPOINT_MIN_INTERVAL_NS),
            tf_static_due: clock == ClockSource::Mcu,
            home_published: None,
        }
    }

    /// A new connection: fold the decoder's counters into the totals and start afresh.
    pub fn reconnect(&mut self) {
        self.counters.link_prev = self.link_totals();
        self.decoder = link::FrameDecoder::new();
        self.seq_before = [0; 3];
        self.seq_forgiven = [0; 3];
        self.handshake = Handshake::Waiting;
        self.timesync.reset();
        self.uplink.reconnect();
        self.counters.reconnects += 1;
        // A restarted MCU counts its time from 0 again: restamp the static transforms.
        self.tf_static_due = self.clock == ClockSource::Mcu;
    }

    /// Link receive totals over all connections. A sequence jump onto the MCU's `Hello` (a new
    /// session) counts as one sequence reset, not as lost frames.
    pub fn link_totals(&self) -> LinkTotals {
        let mut c = *self.decoder.counters();
        let [gaps, lost, resets] = self.seq_forgiven;
        c.seq_gaps = c.seq_gaps.wrapping_sub(gaps);
        c.frames_lost = c.frames_lost.wrapping_sub(lost);
        c.seq_resets = c.seq_resets.wrapping_add(resets);
        self.counters.link_prev.add(&c)
    }

    /// ROS stamp (ns) for an MCU time, given the Linux clock now.
    pub fn stamp_ns(&mut self, mcu_us: u64, now_ns: i64) -> i64 {
        let off = self.sim_offset_ns.unwrap_or(0);
        off + match self.clock {
            ClockSource::Mcu => mcu_us as i64 * 1000,
            ClockSource::Sync => match self.timesync.to_ros_ns(mcu_us) {
                Some(t) => t,
                None => {
                    self.counters.stamped_by_arrival += 1;
                    now_ns
                }
            },
        }
    }

    /// ROS "now" (ns) for stamp checks: the Linux clock, or the MCU clock in `Mcu` mode.
    pub fn ros_now_ns(&self, now_ns: i64) -> i64 {
        match self.clock {
            ClockSource::Sync => now_ns + self.sim_offset_ns.unwrap_or(0),
            ClockSource::Mcu => self.last_mcu_us.map_or(now_ns, |t| t as i64 * 1000),
        }
    }

    /// Feed received bytes; returns the ROS messages to publish, or a fatal error.
    pub fn on_bytes(&mut self, bytes: &[u8], now_ns: i64) -> Result<Vec<Out>, Fatal> {
        let mut out = Vec::new();
        self.on_bytes_into(bytes, now_ns, &mut out)?;
        Ok(out)
    }

    /// [`Self::on_bytes`] appending to `out` (the caller keeps the vector: the session's hot
    /// path allocates nothing per read for it).
    pub fn on_bytes_into(
        &mut self,
        bytes: &[u8],
        now_ns: i64,
        out: &mut Vec<Out>,
    ) -> Result<(), Fatal> {
        let mut frames = std::mem::take(&mut self.frames);
        frames.clear();
        let mut rest = bytes;
        while let Some(r) = self.decoder.next_from(&mut rest) {
            let after = seq_counters(self.decoder.counters());
            // Errors are counted by the decoder.
            if let Ok(f) = r {
                if matches!(f.message, link::Message::Hello(_)) {
                    let gaps = after[0].wrapping_sub(self.seq_before[0]);
                    if gaps != 0 {
                        let lost = after[1].wrapping_sub(self.seq_before[1]);
                        let fg = &mut self.seq_forgiven;
                        fg[0] = fg[0].wrapping_add(gaps);
                        fg[1] = fg[1].wrapping_add(lost);
                        fg[2] = fg[2].wrapping_add(1);
                    }
                }
                frames.push(f);
            }
            self.seq_before = after;
        }
        let r = frames
            .drain(..)
            .try_for_each(|f| self.on_frame(&f, now_ns, out));
        self.frames = frames;
        r
    }

    pub fn on_frame(
        &mut self,
        f: &link::Frame,
        now_ns: i64,
        out: &mut Vec<Out>,
    ) -> Result<(), Fatal> {
        *self
            .counters
            .rx_by_type
            .entry(f.message.name())
            .or_default() += 1;
        if let link::Message::Hello(h) = &f.message {
            h.check().map_err(Fatal::Handshake)?;
            if self.handshake == Handshake::Waiting {
                tracing::info!(
                    "link handshake ok: protocol v{}, schema 0x{:08x}, firmware {}.{}.{}",
                    h.protocol_version,
                    h.schema_hash,
                    h.firmware_version[0],
                    h.firmware_version[1],
                    h.firmware_version[2]
                );
            }
            self.handshake = Handshake::Ok {
                firmware: h.firmware_version,
            };
            return Ok(());
        }
        if self.handshake == Handshake::Waiting
            || f.message.direction() != link::Direction::McuToLinux
        {
            self.counters.dropped += 1;
            return Ok(());
        }
        let t_us = f.header.t_us;
        if !matches!(f.message, link::Message::TimeSyncPong(_)) {
            self.last_mcu_us = Some(self.last_mcu_us.map_or(t_us, |t| t.max(t_us)));
        }
        match f.message {
            link::Message::TimeSyncPong(p) => {
                if let Some(s) = self.timesync.add_pong(&p, now_ns) {
                    tracing::debug!(
                        "time sync: offset {} ns, rtt {} µs",
                        s.offset_ns,
                        s.rtt_ns / 1000
                    );
                }
            }
            link::Message::ParamAck(_) => self.acks.push(f.message),
            link::Message::CommandAck(a) => {
                self.acks.push(f.message);
                let key = format!("{:?}:{}", a.command, convert::reject_name(a.result));
                *self.counters.command_acks.entry(key).or_default() += 1;
                if a.result != link::CommandResult::Accepted {
                    crate::warn_limited!(
                        self.warn,
                        "mcu_refused",
                        now_ns,
                        "MCU refused {:?}: {}",
                        a.command,
                        convert::reject_name(a.result)
                    );
                }
            }
            m => self.on_telemetry(m, t_us, now_ns, out),
        }
        Ok(())
    }

    /// A telemetry frame (MCU time `t_us`) → the ROS messages it gives; the navigation state,
    /// altitude and status also update the state the bridge keeps (yaw, ground height, the
    /// MCU's status and sensor-health transitions).
    fn on_telemetry(&mut self, message: link::Message, t_us: u64, now_ns: i64, out: &mut Vec<Out>) {
        let st = Time::from_nanos(self.stamp_ns(t_us, now_ns));
        let cfg = &self.cfg;
        if self.tf_static_due {
            self.tf_static_due = false;
            out.push(Out::TfStatic(convert::static_transforms(st, cfg)));
        }
        match message {
            link::Message::ImuRaw(m) => out.push(Out::ImuRaw(convert::imu_raw(&m, st, cfg))),
            link::Message::MagRaw(m) => out.push(Out::Mag(convert::mag(&m, st, cfg))),
            link::Message::BaroRaw(m) => out.push(Out::Baro(convert::baro(&m, st, cfg))),
            link::Message::GpsRaw(m) => out.push(Out::GpsFix(convert::gps_fix(&m, st, cfg))),
            link::Message::RangeRaw(m) => {
                let (r, laser) = convert::range(&m, st, cfg);
                out.push(if laser { Out::Laser(r) } else { Out::Sonar(r) });
            }
            link::Message::Battery(m) => out.push(Out::Battery(convert::battery(&m, st, cfg))),
            link::Message::NavState(m) => {
                self.yaw_ned = Some(fcc_ros::frames::yaw_ned(fcc_ros::frames::quat_f64(
                    m.q_body_to_ned,
                )));
                let (odom, imu, tf) = convert::nav_state(&m, st, cfg);
                out.push(Out::Odom(odom));
                out.push(Out::StateImu(imu));
                out.push(Out::Tf(tf));
                let (obs, meas) = convert::accels(&m, st, cfg);
                out.push(Out::AccelObserver(obs));
                out.push(Out::AccelMeasured(meas));
                if self.clock == ClockSource::Mcu {
                    out.push(Out::Clock(Clock { clock: st }));
                }
                if let Some(home) = m.home.filter(|_| m.home_set) {
                    if self.home_published != Some(home) {
                        self.home_published = Some(home);
                        out.push(Out::Home(convert::home(&home, st, cfg)));
                    }
                }
            }
            link::Message::AltitudeFusion(m) => {
                self.ground_height_m = Some(m.ground_height_m);
                let (a, g) = convert::altitude(&m, st, cfg);
                out.push(Out::Altitude(a));
                out.push(Out::Ground(g));
            }
            link::Message::Status(m) => {
                self.mcu_status = Some(m);
                for (warn, text) in self
                    .sensors
                    .update(&m, self.ground_height_m, &self.cfg, t_us)
                {
                    if warn {
                        tracing::warn!("{text}");
                    } else {
                        tracing::info!("{text}");
                    }
                }
                let s = self.fill_status(convert::status(&m, st, cfg));
                out.push(Out::Status(s));
            }
            _ => self.counters.dropped += 1,
        }
    }

    /// Add the bridge's counters to a status message.
    pub fn fill_status(&self, mut s: Status) -> Status {
        let t = self.link_totals();
        let c = &self.counters;
        s.rx_bytes = t.rx_bytes;
        s.rx_frames = t.rx_frames;
        s.crc_errors = t.crc_errors;
        s.framing_errors = t.framing_errors;
        s.resyncs = t.resyncs;
        s.decode_errors = t.decode_errors + t.unknown_ids + t.version_errors;
        s.frames_lost = t.frames_lost;
        s.dropped = c.dropped + c.publish_errors;
        s.setpoints_forwarded = c.setpoints_forwarded;
        s.setpoint_rejects_bridge = c.setpoint_rejects;
        s.commands_forwarded = c.commands_forwarded;
        if let Some(b) = self.timesync.best() {
            s.time_synced = true;
            s.time_sync_offset_ns = b.offset_ns;
            s.time_sync_rtt_us = (b.rtt_ns / 1000).clamp(0, u32::MAX as i64) as u32;
        }
        s
    }

    /// A velocity setpoint from ROS: the link message to send, or `None` (refused, counted;
    /// the warning is rate-limited per kind of refusal).
    pub fn on_setpoint(&mut self, m: &TwistStamped, now_ns: i64) -> Option<link::Message> {
        if self.handshake == Handshake::Waiting {
            self.counters.setpoint_rejects += 1;
            self.counters.last_setpoint_reject = "link not connected".into();
            crate::warn_limited!(
                self.warn,
                "setpoint_not_connected",
                now_ns,
                "setpoint refused: link not connected"
            );
            return None;
        }
        let now = self.ros_now_ns(now_ns);
        // The latest heading, unless older than HEADING_MAX_AGE_NS (then dropped).
        if matches!(self.heading, Some((_, at)) if now_ns - at > convert::HEADING_MAX_AGE_NS) {
            self.heading = None;
        }
        let heading = self.heading.map(|(h, _)| h);
        match convert::setpoint(m, now, self.yaw_ned, heading, &self.cfg, &self.limits) {
            Ok(sp) => {
                match sp.yaw {
                    // A turn clears the heading: when it stops, the vehicle keeps the heading
                    // where the turn ended instead of swinging back.
                    link::YawSetpoint::Rate { .. } => {
                        self.heading = None;
                        self.counters.yaw_rate_setpoints += 1;
                    }
                    link::YawSetpoint::Heading { .. } => self.counters.heading_setpoints += 1,
                    link::YawSetpoint::Keep => {}
                }
                self.counters.setpoints_forwarded += 1;
                self.uplink
                    .setpoint(sp, now_ns)
                    .map(link::Message::VelocitySetpoint)
            }
            Err(e) => {
                self.refuse_setpoint(e, now_ns);
                None
            }
        }
    }

    /// A `setpoint/heading` from ROS: kept (replacing the previous one) for the velocity
    /// setpoints that follow — nothing goes to the MCU by itself. A heading is dropped
    /// [`convert::HEADING_MAX_AGE_NS`] after it arrived and by a yaw-rate setpoint. Refused
    /// (counted as a setpoint refusal, reason prefixed `heading:`) when invalid
    /// ([`convert::heading`]); a refused heading also drops the one kept: the sender's intent
    /// is no longer that heading.
    pub fn on_heading(&mut self, m: &QuaternionStamped, now_ns: i64) {
        let now = self.ros_now_ns(now_ns);
        match convert::heading(m, now, &self.cfg, &self.limits) {
            Ok(yaw_ned) => {
                self.heading = Some((yaw_ned, now_ns));
                self.counters.headings_received += 1;
            }
            Err(e) => {
                self.heading = None;
                self.counters.setpoint_rejects += 1;
                self.counters.last_setpoint_reject = format!("heading: {e}");
                crate::warn_limited!(self.warn, e.kind(), now_ns, "setpoint/heading refused: {e}");
            }
        }
    }

    /// Count a refused setpoint and warn (rate-limited per kind; the text is bounded: see
    /// [`crate::bounded`]).
    pub fn refuse_setpoint(&mut self, e: convert::SetpointReject, now_ns: i64) {
        self.counters.setpoint_rejects += 1;
        self.counters.last_setpoint_reject = e.to_string();
        crate::warn_limited!(self.warn, e.kind(), now_ns, "setpoint refused: {e}");
    }

    /// A `cmd/mode` text over [`bounded::MAX_MODE`] bytes: refused, counted, warned (bounded).
    pub fn refuse_oversize_mode(&mut self, o: bounded::Oversize, now_ns: i64) {
        self.counters.command_rejects += 1;
        crate::warn_limited!(self.warn, "mode_oversize", now_ns, "cmd/mode refused: {o}");
    }

    /// A command from ROS (`what`: the text it came from, shown escaped and cut). Logs are
    /// rate-limited per kind.
    /// `cmd/kill`: the emergency motor stop. Logged at ERROR with its source whether it is
    /// forwarded or refused (a text other than `KILL`, counted as a command refusal).
    pub fn on_kill(&mut self, m: &StringMsg) -> Option<link::Message> {
        match crate::convert::kill_command(m) {
            Some(c) => {
                tracing::error!("EMERGENCY KILL requested on cmd/kill: stopping the motors");
                self.on_command(Some(c), "kill")
            }
            None => {
                self.counters.command_rejects += 1;
                tracing::error!(
                    "cmd/kill refused: the text must be exactly '{}', got '{}'",
                    crate::convert::KILL_TEXT,
                    bounded::log_value(&m.data, bounded::LOG_CHARS)
                );
                None
            }
        }
    }

    pub fn on_command(&mut self, c: Option<link::Command>, what: &str) -> Option<link::Message> {
        let now = fcc_ros::now_ns();
        let what = || bounded::log_value(what, bounded::LOG_CHARS);
        match c {
            Some(c) if self.handshake != Handshake::Waiting => {
                self.counters.commands_forwarded += 1;
                self.uplink.command(c.command);
                if let Some(n) = self.warn.check("command", now) {
                    tracing::info!("command {:?}{}", c.command, bounded::suppressed_note(n));
                }
                Some(link::Message::Command(c))
            }
            Some(_) => {
                self.counters.command_rejects += 1;
                crate::warn_limited!(
                    self.warn,
                    "command_not_connected",
                    now,
                    "command '{}' refused: link not connected",
                    what()
                );
                None
            }
            None => {
                self.counters.command_rejects += 1;
                crate::warn_limited!(
                    self.warn,
                    "unknown_mode",
                    now,
                    "unknown mode '{}' (hold, land, velocity)",
                    what()
                );
                None
            }
        }
    }

    /// The held setpoint, if its turn on the uplink has come (see [`Uplink::poll`]).
    pub fn uplink_due(&mut self, now_ns: i64) -> Option<link::Message> {
        self.uplink
            .poll(now_ns)
            .map(link::Message::VelocitySetpoint)
    }

    /// Encode a message for the MCU.
    pub fn encode(&mut self, m: &link::Message, now_ns: i64) -> Vec<u8> {
        let mut buf = [0u8; link::MAX_FRAME_LEN];
        let t_us = (now_ns / 1000).max(0) as u64;
        match self.encoder.encode(m, t_us, &mut buf) {
            Ok(n) => buf[..n].to_vec(),
            Err(e) => {
                tracing::error!("encode {}: {e}", m.name());
                Vec::new()
            }
        }
    }
}

/// Highest rate at which setpoints go to the MCU: 100 Hz. The flight core runs at 500 Hz but
/// its velocity loop needs no more than this (the mission node sends 20–50 Hz; the setpoint TTL
/// is hundreds of ms), and at 921600 baud 100 largest `VelocitySetpoint` frames a second are
/// `100 × max_frame_len(VELOCITY_SETPOINT)` ≈ 3.5 KB/s, ≈ 4 % of the 92,160 B/s the UART carries
/// (test `setpoint_rate_fits_the_uplink_budget`), leaving the rest for commands, parameters and
/// pings. Without a bound, a peer publishing at 10 kHz offered 4× what the UART carries.
pub const SETPOINT_MAX_HZ: i64 = 100;
/// [`SETPOINT_MAX_HZ`] as the minimum spacing of two setpoints on the uplink.
pub const SETPOINT_MIN_INTERVAL_NS: i64 = 1_000_000_000 / SETPOINT_MAX_HZ;
/// Share of the uplink's bytes/s that setpoints may use at most (at [`SETPOINT_MAX_HZ`] and
/// 921600 baud they use ≈ 4 %; a slower UART lowers the rate: [`Uplink::for_baud`]).
pub const SETPOINT_BUDGET_SHARE: f64 = 0.125;

/// The uplink shaper (sans-IO; time is passed in, in ns of any clock that does not jump; a
/// clock that goes back releases the held setpoint rather than holding it).
///
/// * Commands (arm, disarm, land, hold, velocity, kill) are never held or dropped: the IO layer
///   writes them at once, ahead of any held setpoint ([`Uplink::command`] is told of each).
/// * Setpoints go out at most one per `interval_ns`: one that arrives when the last went out
///   longer ago goes at once; otherwise it is held, and a newer one replaces it (counted in
///   `coalesced`), so the MCU always gets the newest and never a backlog.
/// * The turns keep their grid under a flood: a setpoint sent less than one interval after its
///   turn came counts as sent on its turn, so the IO layer's wake-up delay is not added to every
///   spacing (measured in CI on a loaded machine: 88–94 setpoints/s instead of 100). Over any
///   span the count stays ≤ span/interval + 1; after a pause the grid restarts at the send.
/// * A held setpoint older than a `hold`, `land`, `disarm` or `kill` command is dropped
///   (counted in `superseded`): sent after the command it would take the MCU out of HOLD
///   (a fresh setpoint resumes velocity mode), which its sender never asked for.
#[derive(Clone, Debug)]
pub struct Uplink {
    interval_ns: i64,
    held: Option<link::VelocitySetpoint>,
    last_sent_ns: Option<i64>,
    /// Setpoints written to the link.
    pub sent: u64,
    /// Setpoints replaced by a newer one before their turn.
    pub coalesced: u64,
    /// Held setpoints dropped because a hold/land/disarm/kill command went out after them.
    pub superseded: u64,
}

impl Uplink {
    pub fn new(interval_ns: i64) -> Self {
        Uplink {
            interval_ns: interval_ns.max(0),
            held: None,
            last_sent_ns: None,
            sent: 0,
            coalesced: 0,
            superseded: 0,
        }
    }

    /// The shaper for a UART of `baud` (8N1): [`SETPOINT_MAX_HZ`], or slower if setpoints at
    /// that rate would take more than [`SETPOINT_BUDGET_SHARE`] of the link.
    pub fn for_baud(baud: u32) -> Self {
        Uplink::new(setpoint_interval_ns(baud))
    }

    pub fn interval_ns(&self) -> i64 {
        self.interval_ns
    }

    fn may_send(&self, now_ns: i64) -> bool {
        match self.last_sent_ns {
            None => true,
            Some(t) => now_ns < t || now_ns - t >= self.interval_ns,
        }
    }

    /// A setpoint goes out at `now_ns`: on its turn's grid point when at most one interval
    /// late, else (a pause, or a clock that went back) the grid restarts now.
    fn mark_sent(&mut self, now_ns: i64) {
        let turn = self
            .last_sent_ns
            .map(|t| t.saturating_add(self.interval_ns));
        self.last_sent_ns = Some(match turn {
            Some(due) if now_ns >= due && now_ns - due < self.interval_ns => due,
            _ => now_ns,
        });
        self.sent += 1;
    }

    /// A valid setpoint: returned if it may go now (replacing a held one, counted), else held
    /// (replacing, and counting, a setpoint held before it).
    pub fn setpoint(
        &mut self,
        sp: link::VelocitySetpoint,
        now_ns: i64,
    ) -> Option<link::VelocitySetpoint> {
        if self.may_send(now_ns) {
            if self.held.take().is_some() {
                self.coalesced += 1;
            }
            self.mark_sent(now_ns);
            return Some(sp);
        }
        if self.held.replace(sp).is_some() {
            self.coalesced += 1;
        }
        None
    }

    /// The held setpoint, if its turn has come.
    pub fn poll(&mut self, now_ns: i64) -> Option<link::VelocitySetpoint> {
        if self.held.is_some() && self.may_send(now_ns) {
            self.mark_sent(now_ns);
            return self.held.take();
        }
        None
    }

    /// When the held setpoint may go (`None`: nothing held).
    pub fn due_ns(&self) -> Option<i64> {
        self.held?;
        Some(
            self.last_sent_ns
                .map_or(i64::MIN, |t| t.saturating_add(self.interval_ns)),
        )
    }

    /// A command is going out now (never held): drop a held setpoint it supersedes.
    pub fn command(&mut self, kind: link::CommandKind) {
        use link::CommandKind as K;
        if matches!(kind, K::Hold | K::Land | K::Disarm | K::Kill) && self.held.take().is_some() {
            self.superseded += 1;
        }
    }

    /// A new connection: nothing held over from the old one.
    pub fn reconnect(&mut self) {
        if self.held.take().is_some() {
            self.superseded += 1;
        }
        self.last_sent_ns = None;
    }
}

/// Spacing of setpoints on a UART of `baud` (8N1): the [`SETPOINT_MAX_HZ`] spacing, or longer
/// if the largest setpoint frame at that rate would exceed [`SETPOINT_BUDGET_SHARE`] of it.
pub fn setpoint_interval_ns(baud: u32) -> i64 {
    let frame = link::max_frame_len(link::id::VELOCITY_SETPOINT) as f64;
    let bytes_per_s = (baud.max(1) as f64 / 10.0) * SETPOINT_BUDGET_SHARE;
    let by_budget = (frame / bytes_per_s * 1e9).ceil() as i64;
    SETPOINT_MIN_INTERVAL_NS.max(by_budget)
}

#[cfg(test)]
mod uplink_tests {
    use super::*;
    const MS: i64 = 1_000_000;

    fn sp(vx: f32) -> link::VelocitySetpoint {
        link::VelocitySetpoint {
            vel_ned_mps: [vx, 0.0, 0.0],
            ..Default::default()
        }
    }

    #[test]
    fn setpoint_rate_fits_the_uplink_budget() {
        let frame = link::max_frame_len(link::id::VELOCITY_SETPOINT) as i64;
        let bytes_per_s = SETPOINT_MAX_HZ * frame;
        let budget = link::BAUD_921600_BYTES_PER_S as i64;
        assert!(
            (bytes_per_s as f64) <= SETPOINT_BUDGET_SHARE * budget as f64,
            "{bytes_per_s} B/s of {budget}"
        );
        assert_eq!(setpoint_interval_ns(921_600), 10 * MS);
        // 57600 baud: 5760 B/s, 1/8 of it = 720 B/s → one frame every frame/720 s.
        let slow = setpoint_interval_ns(57_600);
        assert_eq!(slow, (frame as f64 / 720.0 * 1e9).ceil() as i64);
        assert!(slow > 10 * MS);
    }

    /// The IO layer wakes 0–3 ms late for every turn (a loaded machine): the flood still gets
    /// 100 setpoints a second, never more than one per interval on average and never two
    /// closer than the interval minus the largest delay.
    #[test]
    fn late_wake_ups_keep_the_rate() {
        let mut u = Uplink::new(10 * MS);
        let t0 = 5_000 * MS;
        assert!(u.setpoint(sp(0.0), t0).is_some());
        let mut sends = vec![t0];
        let mut t = t0;
        let mut k = 0i64;
        while t < t0 + 10_000 * MS {
            let _ = u.setpoint(sp(1.0), t);
            let due = u.due_ns().expect("held");
            // Wake up 0, 1, 2 or 3 ms after the turn.
            k += 1;
            t = due + (k % 4) * MS;
            if u.poll(t).is_some() {
                sends.push(t);
            }
        }
        let in_s = |a: i64| {
            sends
                .iter()
                .filter(|&&x| x >= a && x < a + 1000 * MS)
                .count()
        };
        for s in 0..9 {
            let n = in_s(t0 + s * 1000 * MS);
            assert!((100..=101).contains(&n), "second {s}: {n}");
        }
        let min_gap = sends.windows(2).map(|w| w[1] - w[0]).min().unwrap();
        assert!(min_gap >= 7 * MS, "{min_gap}");
        // Before: each spacing was the interval plus the delay, 1.5 ms on average → 87/s.
    }

    #[test]
    fn first_setpoint_goes_at_once_then_at_most_one_per_interval() {
        let mut u = Uplink::new(10 * MS);
        let t0 = 5_000 * MS;
        assert_eq!(u.setpoint(sp(1.0), t0), Some(sp(1.0)));
        // 10 kHz flood for 1 s: every 0.1 ms a new setpoint; poll as the IO layer would.
        let mut out = Vec::new();
        for i in 1..=10_000i64 {
            let t = t0 + i * MS / 10;
            if let Some(s) = u.setpoint(sp(i as f32), t) {
                out.push((t, s));
            }
            if let Some(s) = u.poll(t) {
                out.push((t, s));
            }
        }
        // 100 more in the second (t0+10 ms … t0+1000 ms), each the newest at its time.
        assert_eq!(out.len(), 100, "{}", out.len());
        for (k, (t, s)) in out.iter().enumerate() {
            assert_eq!(*t, t0 + (k as i64 + 1) * 10 * MS);
            assert_eq!(s.vel_ned_mps[0], ((t - t0) / (MS / 10)) as f32);
        }
        assert_eq!(u.sent, 101);
        // Every setpoint offered was sent or replaced by a newer one (the last, at t0 + 1 s,
        // went out on its turn).
        assert_eq!(u.sent + u.coalesced, 10_001);
        assert_eq!(u.due_ns(), None);
        // One more, 0.05 ms later: held until t0 + 1010 ms.
        assert_eq!(u.setpoint(sp(-1.0), t0 + 1000 * MS + MS / 20), None);
        assert_eq!(u.due_ns(), Some(t0 + 1010 * MS));
        assert_eq!(u.poll(t0 + 1010 * MS - 1), None);
        assert_eq!(u.poll(t0 + 1010 * MS), Some(sp(-1.0)));
        assert_eq!(u.due_ns(), None);
    }

    #[test]
    fn slow_setpoints_pass_unchanged() {
        let mut u = Uplink::new(10 * MS);
        for i in 0..50 {
            // 50 Hz: never held.
            assert!(u.setpoint(sp(i as f32), i * 20 * MS).is_some());
            assert_eq!(u.due_ns(), None);
        }
        assert_eq!((u.sent, u.coalesced, u.superseded), (50, 0, 0));
    }

    #[test]
    fn hold_land_disarm_kill_drop_an_older_held_setpoint() {
        use link::CommandKind as K;
        for (kind, drops) in [
            (K::Hold, true),
            (K::Land, true),
            (K::Disarm, true),
            (K::Kill, true),
            (K::Arm, false),
            (K::Velocity, false),
        ] {
            let mut u = Uplink::new(10 * MS);
            assert!(u.setpoint(sp(1.0), 0).is_some());
            assert!(u.setpoint(sp(2.0), 2 * MS).is_none());
            u.command(kind);
            assert_eq!(u.poll(10 * MS).is_some(), !drops, "{kind:?}");
            assert_eq!(u.superseded, drops as u64, "{kind:?}");
            // A setpoint after the command goes as usual.
            assert!(u.setpoint(sp(3.0), 30 * MS).is_some());
        }
    }

    #[test]
    fn clock_going_back_releases_the_held_setpoint() {
        let mut u = Uplink::new(10 * MS);
        assert!(u.setpoint(sp(1.0), 1_000 * MS).is_some());
        assert!(u.setpoint(sp(2.0), 1_001 * MS).is_none());
        assert_eq!(u.poll(500 * MS), Some(sp(2.0)));
    }

    #[test]
    fn reconnect_forgets_the_held_setpoint() {
        let mut u = Uplink::new(10 * MS);
        assert!(u.setpoint(sp(1.0), 0).is_some());
        assert!(u.setpoint(sp(2.0), MS).is_none());
        u.reconnect();
        assert_eq!(u.due_ns(), None);
        assert_eq!(u.superseded, 1);
        assert!(u.setpoint(sp(3.0), 2 * MS).is_some());
    }

    /// Through the state machine: commands are never held, even in a setpoint flood.
    #[test]
    fn commands_pass_a_setpoint_flood() {
        use fcc_msgs::ros::{Header, Twist, TwistStamped, Vector3};
        let mut s = LinkState::new(
            Config::default(),
            SetpointLimits::default(),
            ClockSource::Sync,
        );
        s.handshake = Handshake::Ok {
            firmware: [0, 1, 0],
        };
        let t0 = fcc_ros::now_ns();
        let tw = |i: i64| TwistStamped {
            header: Header {
                stamp: Time::from_nanos(t0),
                frame_id: "map".into(),
            },
            twist: Twist {
                linear: Vector3 {
                    x: (i % 5) as f64,
                    y: 0.0,
                    z: 0.0,
                },
                angular: Vector3::default(),
            },
        };
        let mut sent = 0;
        for i in 0..1000i64 {
            let t = t0 + i * MS / 10;
            sent += s.on_setpoint(&tw(i), t).is_some() as u64;
            sent += s.uplink_due(t).is_some() as u64;
            // 0.5 ms after a setpoint went out: one is held when the land goes.
            if i == 505 {
                let land = link::Command {
                    command: link::CommandKind::Land,
                    confirm: 0,
                };
                assert!(matches!(
                    s.on_command(Some(land), "land"),
                    Some(link::Message::Command(c)) if c.command == link::CommandKind::Land
                ));
            }
        }
        assert_eq!(s.counters.setpoints_forwarded, 1000);
        assert_eq!(s.uplink.sent, sent);
        assert_eq!(sent, 10); // 0, 10, … 90 ms
        assert_eq!(
            s.uplink.sent
                + s.uplink.coalesced
                + s.uplink.superseded
                + s.uplink.due_ns().is_some() as u64,
            1000
        );
        assert_eq!(s.uplink.superseded, 1);
    }
}
