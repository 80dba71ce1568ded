//! A scripted R/C pilot and receiver for the simulator (`pilot:` in a scenario file).
//!
//! The receiver is modelled the way an S.BUS receiver behaves on the board:
//! - a frame every [`FRAME_PERIOD_US`] (the core is fed at 50 Hz; S.BUS itself sends every
//!   14 ms, 7 ms in high-speed mode), each carrying the pilot's hand as it was
//!   [`LATENCY_US`] earlier (≈ one S.BUS frame period of transmission and decoding);
//! - sticks quantised to the 11-bit S.BUS value, 172..1811 ↔ −100..+100 % with 992 at centre
//!   (the FrSky/OpenTX convention, also used by PX4's `sbus.cpp` and Betaflight's
//!   `rx/sbus_channels.c` scaling; Futaba transmitters use 368..1680 around 1024), and read back
//!   the way the board does it (`fcc_firmware/board/src/drivers/sbus.rs::to_unit`);
//! - `receiver: failsafe`: the receiver has lost the transmitter and says so in its flags byte
//!   (S.BUS failsafe bit), still sending frames; `receiver: silent`: no frames at all (wire cut,
//!   receiver unpowered) — the core's 0.5 s timeout must notice.

use fcc_firmware::pilot::PilotInput;
use serde::Deserialize;

/// Interval between receiver frames handed to the core, µs (50 Hz).
pub const FRAME_PERIOD_US: u64 = 20_000;
/// Age of the stick positions a frame carries, µs.
pub const LATENCY_US: u64 = 10_000;
/// S.BUS raw values at −100 %, 0, +100 % (FrSky/OpenTX).
pub const RAW_MIN: u16 = 172;
pub const RAW_MID: u16 = 992;
pub const RAW_MAX: u16 = 1811;

/// What the receiver does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReceiverState {
    /// Frames with the pilot's sticks and switch.
    #[default]
    Ok,
    /// Frames flagged failsafe (transmitter lost): the channels are not the pilot's.
    Failsafe,
    /// No frames.
    Silent,
}

/// From `at_s` on (simulated s), the pilot holds these sticks and switch.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PilotEvent {
    pub at_s: f64,
    #[serde(default)]
    pub override_on: bool,
    /// `[roll, pitch, throttle, yaw]`, −1..1, 0 = centre (see [`fcc_firmware::pilot::PilotInput`]).
    #[serde(default)]
    pub sticks: [f32; 4],
    #[serde(default)]
    pub receiver: ReceiverState,
}

/// Stick → raw S.BUS value (what the transmitter sends).
pub fn to_raw(x: f32) -> u16 {
    let x = if x.is_finite() {
        x.clamp(-1.0, 1.0)
    } else {
        0.0
    };
    // 820 counts below centre, 819 above (172..992..1811).
    let span = if x < 0.0 {
        RAW_MID - RAW_MIN
    } else {
        RAW_MAX - RAW_MID
    };
    let r = (RAW_MID as f32 + x * span as f32).round();
    (r as u16).clamp(RAW_MIN, RAW_MAX)
}

/// Raw S.BUS value → stick, as the board reads it.
pub fn from_raw(raw: u16) -> f32 {
    ((raw as f32 - RAW_MID as f32) / (RAW_MAX - RAW_MID) as f32).clamp(-1.0, 1.0)
}

/// The simulated receiver.
#[derive(Clone, Debug, Default)]
pub struct SimReceiver {
    events: Vec<PilotEvent>,
    next_frame_us: u64,
}

impl SimReceiver {
    /// `events` sorted by `at_s` (the scenario validation checks it). No events → no receiver.
    pub fn new(events: &[PilotEvent]) -> Self {
        Self {
            events: events.to_vec(),
            next_frame_us: 0,
        }
    }

    /// The pilot's state at `t_s` (before the first event: switch off, sticks centred).
    fn state_at(&self, t_s: f64) -> PilotEvent {
        self.events
            .iter()
            .rev()
            .find(|e| e.at_s <= t_s)
            .copied()
            .unwrap_or(PilotEvent {
                at_s: 0.0,
                override_on: false,
                sticks: [0.0; 4],
                receiver: ReceiverState::Ok,
            })
    }

    /// The frame due at `now_us`, if one is.
    pub fn poll(&mut self, now_us: u64) -> Option<PilotInput> {
        if self.events.is_empty() || now_us < self.next_frame_us {
            return None;
        }
        self.next_frame_us = now_us + FRAME_PERIOD_US;
        let e = self.state_at(now_us.saturating_sub(LATENCY_US) as f64 * 1e-6);
        match e.receiver {
            ReceiverState::Silent => None,
            ReceiverState::Failsafe => Some(PilotInput {
                // A receiver's failsafe preset: the switch channel at whatever the pilot had.
                override_on: e.override_on,
                failsafe: true,
                sticks: [0.0; 4],
                t_us: now_us,
            }),
            ReceiverState::Ok => Some(PilotInput {
                override_on: e.override_on,
                failsafe: false,
                sticks: e.sticks.map(|x| from_raw(to_raw(x))),
                t_us: now_us,
            }),
        }
    }
}

/// Validate the `pilot:` list; the error names the field.
pub fn validate(events: &[PilotEvent]) -> Result<(), (String, String)> {
    let mut prev = 0.0f64;
    for (i, e) in events.iter().enumerate() {
        if !(e.at_s.is_finite() && e.at_s >= prev) {
            return Err((
                format!("pilot[{i}].at_s"),
                "must be finite, ≥ 0 and not before the previous event".into(),
            ));
        }
        prev = e.at_s;
        if let Some(k) = e
            .sticks
            .iter()
            .position(|x| !(x.is_finite() && x.abs() <= 1.0))
        {
            return Err((
                format!("pilot[{i}].sticks[{k}]"),
                "must be within ±1".into(),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantisation_matches_sbus_scaling() {
        assert_eq!(to_raw(-1.0), RAW_MIN);
        assert_eq!(to_raw(0.0), RAW_MID);
        assert_eq!(to_raw(1.0), RAW_MAX);
        assert_eq!(from_raw(RAW_MID), 0.0);
        assert_eq!(from_raw(RAW_MAX), 1.0);
        assert_eq!(from_raw(RAW_MIN), -1.0);
        // One count is ≈ 0.12 % of full travel.
        let x = 0.3337;
        assert!((from_raw(to_raw(x)) - x).abs() <= 0.5 / 819.0 + 1e-6);
        assert_ne!(from_raw(to_raw(x)), x);
    }

    #[test]
    fn frames_latency_and_failsafe() {
        let ev = [
            PilotEvent {
                at_s: 1.0,
                override_on: true,
                sticks: [0.0, 0.5, 0.0, 0.0],
                receiver: ReceiverState::Ok,
            },
            PilotEvent {
                at_s: 2.0,
                override_on: true,
                sticks: [0.0, 0.5, 0.0, 0.0],
                receiver: ReceiverState::Failsafe,
            },
            PilotEvent {
                at_s: 3.0,
                override_on: true,
                sticks: [0.0; 4],
                receiver: ReceiverState::Silent,
            },
        ];
        let mut r = SimReceiver::new(&ev);
        assert!(!r.poll(0).unwrap().override_on);
        assert!(r.poll(10_000).is_none(), "50 Hz");
        // At 1.000 s the frame still carries the hand of 0.990 s.
        assert!(!r.poll(1_000_000).unwrap().override_on);
        let f = r.poll(1_020_000).unwrap();
        assert!(f.override_on && !f.failsafe && (f.sticks[1] - 0.5).abs() < 1e-3);
        assert!(r.poll(2_020_000).unwrap().failsafe);
        assert!(r.poll(3_020_000).is_none());
        assert!(SimReceiver::new(&[]).poll(0).is_none());
    }

    #[test]
    fn validation_names_the_field() {
        let mut ev = [PilotEvent {
            at_s: 1.0,
            override_on: true,
            sticks: [0.0, 1.5, 0.0, 0.0],
            receiver: ReceiverState::Ok,
        }];
        assert_eq!(validate(&ev).unwrap_err().0, "pilot[0].sticks[1]");
        ev[0].sticks[1] = 0.0;
        ev[0].at_s = f64::NAN;
        assert_eq!(validate(&ev).unwrap_err().0, "pilot[0].at_s");
    }
}
