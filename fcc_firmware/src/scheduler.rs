//! The 500 Hz task: one tick of the flight computer — the link's received bytes in, the sensors
//! → the flight core → the ESCs, the link's frames out. The board's timer interrupt, the
//! simulator's lockstep loop and the QEMU replay image all call [`FlightComputer::tick`] every
//! 2 ms; none of them wires the link and the core by hand.

use crate::flight::FlightCore;
use crate::link::LinkEndpoint;
use crate::params::{ParamError, Params, RateParams};
use crate::sensors::{MotorOutputs, SensorBoard};
use fcc_msgs::StreamRates;

/// Control period (µs) — paper A runs navigation and control at 500 Hz.
pub const TICK_US: u64 = 2_000;

/// The MCU program: the flight core and the MCU end of the link to the Linux computer.
pub struct FlightComputer {
    pub core: FlightCore,
    pub link: LinkEndpoint,
}

impl FlightComputer {
    /// A core with `params`, a link sending telemetry at their rates (`params.rates`).
    pub fn new(params: Params) -> Self {
        Self {
            core: FlightCore::new(params),
            link: LinkEndpoint::new(params.stream_rates()),
        }
    }

    /// Change the telemetry rates: the core's `rates.*` parameters (so a parameter read
    /// reports them) and the link's schedule. Refused as a parameter set would be.
    pub fn set_stream_rates(&mut self, rates: StreamRates) -> Result<(), ParamError> {
        let mut p = *self.core.params();
        p.rates = RateParams::from_stream_rates(&rates);
        self.core.set_params(p)?;
        self.link.set_rates(p.stream_rates());
        Ok(())
    }

    /// One tick at `now_us`; returns the number of bytes written to `tx`.
    ///
    /// 1. `rx`: every byte the link received since the last tick (any chunking; empty when
    ///    none) → setpoints, commands, parameters, time sync applied to the core.
    /// 2. The board's new samples → [`FlightCore::step`] → the motor commands to `motors`.
    /// 3. The frames due now (replies first, then telemetry, with this tick's samples for the
    ///    raw streams) into `tx`: give it the room the UART can take now; telemetry that does
    ///    not fit is dropped and counted ([`LinkEndpoint::poll_tx`]).
    ///
    /// R/C receiver frames go to [`FlightCore::pilot`] before the tick (they take effect in
    /// its step).
    pub fn tick<B: SensorBoard, M: MotorOutputs>(
        &mut self,
        now_us: u64,
        rx: &[u8],
        board: &mut B,
        motors: &mut M,
        tx: &mut [u8],
    ) -> usize {
        self.link.on_bytes(now_us, rx, &mut self.core);
        let inputs = board.poll(now_us);
        let cmd = self.core.step(now_us, &inputs);
        motors.write(now_us, &cmd);
        self.link.poll_tx(now_us, &self.core, &inputs, tx)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::geometry::MOTOR_COUNT;
    use crate::sensors::{ImuSample, SensorInputs};
    use fcc_msgs::{
        Command, CommandKind, CommandResult, Encoder, FrameDecoder, Message, MAX_FRAME_LEN,
    };
    use std::vec::Vec;

    /// A level, still IMU every tick; counts its polls.
    struct Board {
        polls: u32,
    }
    impl SensorBoard for Board {
        fn poll(&mut self, now_us: u64) -> SensorInputs {
            self.polls += 1;
            SensorInputs {
                imu: Some(ImuSample {
                    t_us: now_us,
                    gyro_frd_radps: [0.0; 3],
                    accel_frd_mps2: [0.0, 0.0, -9.80665],
                }),
                ..Default::default()
            }
        }
    }

    /// Latches the last command and when it came.
    struct Escs(Option<(u64, [f32; MOTOR_COUNT])>);
    impl MotorOutputs for Escs {
        fn write(&mut self, now_us: u64, cmd: &[f32; MOTOR_COUNT]) {
            self.0 = Some((now_us, *cmd));
        }
    }

    fn acks(dec: &mut FrameDecoder, bytes: &[u8]) -> Vec<(CommandKind, CommandResult)> {
        dec.push_slice(bytes)
            .filter_map(|r| match r.expect("MCU frames decode").message {
                Message::CommandAck(a) => Some((a.command, a.result)),
                _ => None,
            })
            .collect()
    }

    /// One tick applies the bytes received (in any chunking) before its step, steps once on the
    /// board's samples, writes the ESCs, and answers in its own transmit bytes.
    #[test]
    fn tick_receives_steps_and_answers() {
        let mut fc = FlightComputer::new(Params {
            rates: RateParams::off(),
            ..Params::default()
        });
        let (mut board, mut escs) = (Board { polls: 0 }, Escs(None));
        let mut frame = [0u8; MAX_FRAME_LEN];
        let hold = Message::Command(Command {
            command: CommandKind::Hold,
            confirm: 0,
        });
        let n = Encoder::new().encode(&hold, 7, &mut frame).unwrap();
        let (first, second) = frame[..n].split_at(n / 2);
        let mut linux = FrameDecoder::new();
        let mut tx = [0u8; 256];

        // The frame's first half: nothing to answer yet (the pending Hello goes out).
        let sent = fc.tick(TICK_US, first, &mut board, &mut escs, &mut tx);
        assert!(sent > 0);
        assert_eq!(acks(&mut linux, &tx[..sent]), []);
        // Its second half: refused (disarmed), answered in the same tick's bytes.
        let sent = fc.tick(2 * TICK_US, second, &mut board, &mut escs, &mut tx);
        assert_eq!(
            acks(&mut linux, &tx[..sent]),
            [(CommandKind::Hold, CommandResult::Disarmed)]
        );
        assert_eq!(board.polls, 2);
        assert_eq!(escs.0, Some((2 * TICK_US, [0.0; MOTOR_COUNT])));
        assert_eq!(fc.core.nav().t_us, 2 * TICK_US);

        // No room to send: the reply waits for the next tick with room.
        assert_eq!(
            fc.tick(3 * TICK_US, &frame[..n], &mut board, &mut escs, &mut []),
            0
        );
        let sent = fc.tick(4 * TICK_US, &[], &mut board, &mut escs, &mut tx);
        assert_eq!(
            acks(&mut linux, &tx[..sent]),
            [(CommandKind::Hold, CommandResult::Disarmed)]
        );
    }
}
