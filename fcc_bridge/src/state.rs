//! The bridge's link-side state machine, without IO: decoded frames in → ROS messages out,
//! ROS setpoints/commands in → link messages out, plus every counter. The IO layer
//! ([`crate::bridge`]) only moves bytes and publishes what this returns.

use crate::bounded;
use crate::convert::{self, Config, SetpointLimits};
use crate::ros_types::*;
use crate::timesync::TimeSync;
use fcc_msgs as link;
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
    Altitude(Altitude),
    Ground(Range),
    Status(Status),
    Clock(Clock),
    /// `accel/observer`: the Luenberger observer's horizontal acceleration (ENU, map).
    AccelObserver(AccelStamped),
    /// `accel/measured`: the gravity-compensated accelerometer (ENU, map).
    AccelMeasured(AccelStamped),
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
    pub setpoints_forwarded: u64,
    pub setpoint_rejects: u64,
    pub last_setpoint_reject: String,
    pub yaw_rate_ignored: u64,
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
    /// MCU time of the latest frame.
    pub last_mcu_us: Option<u64>,
    /// `use_sim_time` with `clock_source:=sync`: `/clock` minus the Linux clock at the latest
    /// `/clock` (added to every stamp and to "now").
    pub sim_offset_ns: Option<i64>,
    /// `CommandAck`s and `ParamAck`s received, for the IO layer to answer services with.
    pub acks: Vec<link::Message>,
    /// Height above ground of the latest altitude fusion (for the sensor-health rules).
    pub ground_height_m: Option<f32>,
    /// Sensor-health transitions (WARN / INFO on `/rosout`).
    pub sensors: crate::diag::SensorWatch,
    /// The current decoder's (seq_gaps, frames_lost, seq_resets) before the frame being decoded.
    seq_before: [u32; 3],
    /// Gaps and lost frames the current decoder counted on `Hello` frames (the MCU's new
    /// session: a rebooted MCU counts from 0 again), taken out of [`LinkState::link_totals`],
    /// and the resets counted for them instead.
    seq_forgiven: [u32; 3],
    /// Rate limit of the warnings about input (per kind, 1 s).
    pub warn: bounded::WarnLimiter,
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
            last_mcu_us: None,
            sim_offset_ns: None,
            acks: Vec::new(),
            ground_height_m: None,
            sensors: Default::default(),
            seq_before: [0; 3],
            seq_forgiven: [0; 3],
            warn: bounded::WarnLimiter::default(),
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
        self.counters.reconnects += 1;
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
        let mut frames = Vec::new();
        for &b in bytes {
            let Some(r) = self.decoder.push(b) else {
                continue;
            };
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
        for f in frames {
            self.on_frame(&f, now_ns, &mut out)?;
        }
        Ok(out)
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
            _ => {
                let st = Time::from_nanos(self.stamp_ns(t_us, now_ns));
                let cfg = &self.cfg;
                match f.message {
                    link::Message::ImuRaw(m) => {
                        out.push(Out::ImuRaw(convert::imu_raw(&m, st, cfg)))
                    }
                    link::Message::MagRaw(m) => out.push(Out::Mag(convert::mag(&m, st, cfg))),
                    link::Message::BaroRaw(m) => out.push(Out::Baro(convert::baro(&m, st, cfg))),
                    link::Message::GpsRaw(m) => {
                        out.push(Out::GpsFix(convert::gps_fix(&m, st, cfg)))
                    }
                    link::Message::RangeRaw(m) => {
                        let (r, laser) = convert::range(&m, st, cfg);
                        out.push(if laser { Out::Laser(r) } else { Out::Sonar(r) });
                    }
                    link::Message::Battery(m) => {
                        out.push(Out::Battery(convert::battery(&m, st, cfg)))
                    }
                    link::Message::NavState(m) => {
                        self.yaw_ned = Some(crate::frames::yaw_ned(crate::frames::quat_f64(
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
                    }
                    link::Message::AltitudeFusion(m) => {
                        self.ground_height_m = Some(m.ground_height_m);
                        let (a, g) = convert::altitude(&m, st, cfg);
                        out.push(Out::Altitude(a));
                        out.push(Out::Ground(g));
                    }
                    link::Message::Status(m) => {
                        self.mcu_status = Some(m);
                        for (warn, text) in
                            self.sensors
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
        }
        Ok(())
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
        match convert::setpoint(m, now, self.yaw_ned, &self.cfg, &self.limits) {
            Ok((sp, yaw_rate)) => {
                if yaw_rate {
                    if self.counters.yaw_rate_ignored == 0 {
                        tracing::warn!("setpoint twist.angular.z (yaw rate) is not supported by the MCU link: ignored, heading is kept");
                    }
                    self.counters.yaw_rate_ignored += 1;
                }
                self.counters.setpoints_forwarded += 1;
                Some(link::Message::VelocitySetpoint(sp))
            }
            Err(e) => {
                self.refuse_setpoint(e, now_ns);
                None
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
        let now = crate::now_ns();
        let what = || bounded::log_value(what, bounded::LOG_CHARS);
        match c {
            Some(c) if self.handshake != Handshake::Waiting => {
                self.counters.commands_forwarded += 1;
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
