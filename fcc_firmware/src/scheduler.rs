//! The 500 Hz task as a board runs it: poll the sensors, step the core, write the ESCs.
//! A hardware timer interrupt (or the SITL's lockstep loop) calls [`tick`] every 2 ms.

use crate::flight::FlightCore;
use crate::sensors::{MotorOutputs, SensorBoard, SensorInputs};

/// Control period (µs) — paper A runs navigation and control at 500 Hz.
pub const TICK_US: u64 = 2_000;

/// One tick; returns the samples the core saw (the link's raw telemetry streams send them on).
pub fn tick<B: SensorBoard, M: MotorOutputs>(
    core: &mut FlightCore,
    board: &mut B,
    motors: &mut M,
    now_us: u64,
) -> SensorInputs {
    let inputs = board.poll(now_us);
    let cmd = core.step(now_us, &inputs);
    motors.write(now_us, &cmd);
    inputs
}
