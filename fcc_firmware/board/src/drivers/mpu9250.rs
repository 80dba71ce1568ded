//! InvenSense MPU-9250 (accelerometer + gyroscope) with its AK8963 magnetometer, over SPI.
//!
//! Sources (register addresses and bit fields are quoted with their section):
//! - **RM-MPU-9250A-00** rev. 1.6, "MPU-9250 Register Map and Descriptions" (RM below).
//! - **PS-MPU-9250A-01** rev. 1.1, "MPU-9250 Product Specification" (PS below): SPI protocol
//!   (§7.5: first byte = register address, MSB 1 = read, 0 = write; up to 1 MHz for all
//!   registers, 20 MHz for sensor and interrupt registers), axis orientation (§9.1: the AK8963
//!   axes inside the package are X_mag = Y_accel, Y_mag = X_accel, Z_mag = −Z_accel).
//! - **AKM AK8963** datasheet (MS1356-E-02): registers WIA (0x00 = 0x48), ST1 (0x02, DRDY bit 0,
//!   DOR bit 1), HXL..HZH (0x03–0x08, little-endian two's complement), ST2 (0x09, HOFL bit 3 =
//!   magnetic sensor overflow, BITM bit 4), CNTL1 (0x0A: MODE[3:0], BIT bit 4 = 16-bit),
//!   CNTL2 (0x0B, SRST bit 0), ASAX..ASAZ (0x10–0x12, fuse ROM, read in MODE 0b1111);
//!   sensitivity adjustment §8.3.11: `Hadj = H · ((ASA − 128) · 0.5 / 128 + 1)`;
//!   0.15 µT/LSB in 16-bit output.
//!
//! Configuration (see [`Mpu9250Config`]): ±16 g (ACCEL_FS_SEL = 3, 2048 LSB/g, RM reg 28),
//! ±2000 °/s (GYRO_FS_SEL = 3, 16.4 LSB/(°/s), RM reg 27), DLPF (RM reg 26 DLPF_CFG, reg 29
//! A_DLPFCFG), sample rate = 1 kHz / (1 + SMPLRT_DIV) (RM reg 25, valid with the DLPF on).
//! The AK8963 hangs on the MPU's auxiliary I²C bus: the driver sets it up through the I²C
//! master's slave 4 (one register at a time, RM regs 49–54), then lets slave 0 copy ST1..ST2
//! (8 bytes) into EXT_SENS_DATA_00.. (RM reg 73) every sample, so a single 22-byte SPI burst from
//! ACCEL_XOUT_H (0x3B) returns accel, temperature, gyro and magnetometer together.
//!
//! Frames: the chip's axes (PS §9.1) are mapped to the body FRD frame by
//! [`Mpu9250Config::body_from_chip`], a rotation matrix; the default is the chip mounted
//! component side up with its X axis forward (FRD = (x, −y, −z)), so at rest and level the
//! accelerometer gives `[0, 0, −9.81]` m/s² as `fcc_firmware::sensors::ImuSample` expects.

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{Operation, SpiDevice};
use fcc_firmware::sensors::{ImuSample, MagSample};

/// Register addresses (RM-MPU-9250A-00 §3, decimal in the RM's table).
pub mod reg {
    pub const SMPLRT_DIV: u8 = 0x19; // 25
    pub const CONFIG: u8 = 0x1A; // 26
    pub const GYRO_CONFIG: u8 = 0x1B; // 27
    pub const ACCEL_CONFIG: u8 = 0x1C; // 28
    pub const ACCEL_CONFIG2: u8 = 0x1D; // 29
    pub const I2C_MST_CTRL: u8 = 0x24; // 36
    pub const I2C_SLV0_ADDR: u8 = 0x25; // 37
    pub const I2C_SLV0_REG: u8 = 0x26; // 38
    pub const I2C_SLV0_CTRL: u8 = 0x27; // 39
    pub const I2C_SLV4_ADDR: u8 = 0x31; // 49
    pub const I2C_SLV4_REG: u8 = 0x32; // 50
    pub const I2C_SLV4_DO: u8 = 0x33; // 51
    pub const I2C_SLV4_CTRL: u8 = 0x34; // 52
    pub const I2C_SLV4_DI: u8 = 0x35; // 53
    pub const I2C_MST_STATUS: u8 = 0x36; // 54
    pub const INT_PIN_CFG: u8 = 0x37; // 55
    pub const INT_ENABLE: u8 = 0x38; // 56
    pub const ACCEL_XOUT_H: u8 = 0x3B; // 59
    pub const TEMP_OUT_H: u8 = 0x41; // 65
    pub const GYRO_XOUT_H: u8 = 0x43; // 67
    pub const GYRO_ZOUT_L: u8 = 0x48; // 72
    pub const EXT_SENS_DATA_00: u8 = 0x49; // 73
    pub const I2C_MST_DELAY_CTRL: u8 = 0x67; // 103
    pub const USER_CTRL: u8 = 0x6A; // 106
    pub const PWR_MGMT_1: u8 = 0x6B; // 107
    pub const PWR_MGMT_2: u8 = 0x6C; // 108
    pub const WHO_AM_I: u8 = 0x75; // 117
}

/// Bits (RM-MPU-9250A-00).
pub mod bits {
    /// SPI read flag on the address byte (PS §7.5).
    pub const READ: u8 = 0x80;
    /// PWR_MGMT_1: H_RESET (bit 7); CLKSEL = 1 (auto-select the gyro PLL when ready).
    pub const H_RESET: u8 = 0x80;
    pub const CLKSEL_AUTO: u8 = 0x01;
    /// USER_CTRL: I2C_MST_EN (bit 5), I2C_IF_DIS (bit 4: SPI only, PS §7.5), I2C_MST_RST (bit 1).
    pub const I2C_MST_EN: u8 = 0x20;
    pub const I2C_IF_DIS: u8 = 0x10;
    pub const I2C_MST_RST: u8 = 0x02;
    /// I2C_MST_CTRL: I2C_MST_CLK = 13 → 400 kHz (RM reg 36 table).
    pub const I2C_MST_CLK_400K: u8 = 13;
    /// I2C_SLVx_ADDR bit 7: read transfer.
    pub const I2C_SLV_RNW: u8 = 0x80;
    /// I2C_SLVx_CTRL bit 7: enable.
    pub const I2C_SLV_EN: u8 = 0x80;
    /// I2C_MST_STATUS: I2C_SLV4_DONE (bit 6), I2C_SLV4_NACK (bit 4).
    pub const I2C_SLV4_DONE: u8 = 0x40;
    pub const I2C_SLV4_NACK: u8 = 0x10;
    /// GYRO_CONFIG / ACCEL_CONFIG full scale = 3 in bits [4:3]: ±2000 °/s, ±16 g.
    pub const FS_SEL_3: u8 = 0x18;
    /// WHO_AM_I: MPU-9250 0x71 (RM reg 117); the MPU-9255 reads 0x73.
    pub const WHO_AM_I_9250: u8 = 0x71;
    pub const WHO_AM_I_9255: u8 = 0x73;
}

/// AK8963 (MS1356-E-02 §8).
pub mod ak8963 {
    pub const I2C_ADDR: u8 = 0x0C;
    pub const WIA: u8 = 0x00;
    pub const WIA_VALUE: u8 = 0x48;
    pub const ST1: u8 = 0x02;
    pub const ST2: u8 = 0x09;
    pub const CNTL1: u8 = 0x0A;
    pub const CNTL2: u8 = 0x0B;
    pub const ASAX: u8 = 0x10;
    /// ST1 bit 0: data ready.
    pub const ST1_DRDY: u8 = 0x01;
    /// ST2 bit 3: magnetic sensor overflow (|Hx|+|Hy|+|Hz| ≥ 4912 µT): the data are invalid.
    pub const ST2_HOFL: u8 = 0x08;
    /// CNTL1 modes.
    pub const MODE_POWER_DOWN: u8 = 0x00;
    pub const MODE_FUSE_ROM: u8 = 0x0F;
    pub const MODE_CONT_100HZ: u8 = 0x06;
    pub const MODE_CONT_8HZ: u8 = 0x02;
    /// CNTL1 bit 4: 16-bit output.
    pub const BIT_16: u8 = 0x10;
    /// CNTL2 bit 0: soft reset.
    pub const SRST: u8 = 0x01;
    /// 16-bit output sensitivity, µT per LSB.
    pub const UT_PER_LSB_16: f32 = 0.15;
}

/// Length of the burst: ACCEL_XOUT_H..GYRO_ZOUT_L (14) + EXT_SENS_DATA_00..07 (ST1..ST2, 8).
pub const BURST_LEN: usize = 22;

/// Standard gravity used for scaling, m/s².
pub const G: f32 = 9.806_65;
/// ±16 g: 2048 LSB/g (PS §3.2 table, AFS_SEL = 3).
pub const ACCEL_LSB_PER_G: f32 = 2048.0;
/// ±2000 °/s: 16.4 LSB/(°/s) (PS §3.1 table, FS_SEL = 3).
pub const GYRO_LSB_PER_DPS: f32 = 16.4;
/// Temperature: 333.87 LSB/°C, 0 LSB at 21 °C (PS temperature-sensor table; RM reg 65
/// formula `TEMP_degC = TEMP_OUT / 333.87 + 21`).
pub const TEMP_LSB_PER_C: f32 = 333.87;
pub const TEMP_OFFSET_C: f32 = 21.0;

/// Driver configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mpu9250Config {
    /// CONFIG.DLPF_CFG (gyro low-pass): 0 = 250 Hz … 3 = 41 Hz (5.9 ms) … 6 = 5 Hz (RM reg 26).
    pub gyro_dlpf_cfg: u8,
    /// ACCEL_CONFIG2.A_DLPFCFG: 3 = 44.8 Hz (4.88 ms) (RM reg 29).
    pub accel_dlpf_cfg: u8,
    /// SMPLRT_DIV: sample rate = 1 kHz / (1 + div); 1 → 500 Hz (the core's tick).
    pub smplrt_div: u8,
    /// Read the AK8963 (continuous mode 2, 100 Hz, 16 bit).
    pub magnetometer: bool,
    /// Rotation from the chip's accel/gyro axes (PS §9.1) to the body FRD frame, row-major:
    /// `v_frd = body_from_chip · v_chip`. Any mounting: a proper rotation, not checked here.
    pub body_from_chip: [[f32; 3]; 3],
}

impl Default for Mpu9250Config {
    fn default() -> Self {
        Self {
            gyro_dlpf_cfg: 3,
            accel_dlpf_cfg: 3,
            smplrt_div: 1,
            magnetometer: true,
            body_from_chip: [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
        }
    }
}

/// What can go wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error<E> {
    Spi(E),
    /// WHO_AM_I was neither 0x71 nor 0x73 (wrong chip, bus fault, not powered).
    WrongId(u8),
    /// AK8963 WIA was not 0x48.
    MagWrongId(u8),
    /// The I²C master's slave-4 transfer did not finish, or was NACKed.
    MagTimeout,
    MagNack,
}

impl<E> From<E> for Error<E> {
    fn from(e: E) -> Self {
        Error::Spi(e)
    }
}

/// One decoded burst.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mpu9250Reading {
    pub imu: ImuSample,
    pub temperature_c: f32,
    /// New magnetometer data (ST1.DRDY), not overflowed; `None` otherwise.
    pub mag: Option<MagSample>,
}

/// Counted rejections and events.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Mpu9250Stats {
    pub bursts: u32,
    /// All 14 accel/temp/gyro bytes 0x00 or all 0xFF: a dead bus, not a measurement.
    pub stuck_bursts: u32,
    /// AK8963 ST2.HOFL set: magnetic overflow, sample rejected.
    pub mag_overflow: u32,
    /// ST1.DRDY clear: no new magnetometer data in this burst (normal: 100 Hz vs 500 Hz).
    pub mag_not_ready: u32,
    pub mag_samples: u32,
}

/// Decode a 22-byte burst (ACCEL_XOUT_H.. then EXT_SENS_DATA_00..07 = AK8963 ST1..ST2) into SI
/// units in the body frame. Pure; used by [`Mpu9250::read`]. `None` for a stuck bus.
pub fn decode_burst(
    b: &[u8; BURST_LEN],
    t_us: u64,
    cfg: &Mpu9250Config,
    mag_asa: &[f32; 3],
    stats: &mut Mpu9250Stats,
) -> Option<Mpu9250Reading> {
    stats.bursts = stats.bursts.wrapping_add(1);
    let core = &b[..14];
    if core.iter().all(|&x| x == 0) || core.iter().all(|&x| x == 0xFF) {
        stats.stuck_bursts = stats.stuck_bursts.wrapping_add(1);
        return None;
    }
    let be = |h: u8, l: u8| i16::from_be_bytes([h, l]) as f32;
    let accel_chip =
        [be(b[0], b[1]), be(b[2], b[3]), be(b[4], b[5])].map(|v| v / ACCEL_LSB_PER_G * G);
    let temp_raw = be(b[6], b[7]);
    let gyro_chip = [be(b[8], b[9]), be(b[10], b[11]), be(b[12], b[13])]
        .map(|v| (v / GYRO_LSB_PER_DPS).to_radians());
    let m = &cfg.body_from_chip;
    let imu = ImuSample {
        t_us,
        gyro_frd_radps: mat_vec(m, &gyro_chip),
        accel_frd_mps2: mat_vec(m, &accel_chip),
    };
    let temperature_c = temp_raw / TEMP_LSB_PER_C + TEMP_OFFSET_C;

    let mut mag = None;
    if cfg.magnetometer {
        let (st1, st2) = (b[14], b[21]);
        if st1 & ak8963::ST1_DRDY == 0 {
            stats.mag_not_ready = stats.mag_not_ready.wrapping_add(1);
        } else if st2 & ak8963::ST2_HOFL != 0 {
            stats.mag_overflow = stats.mag_overflow.wrapping_add(1);
        } else {
            let le = |l: u8, h: u8| i16::from_le_bytes([l, h]) as f32;
            let raw = [le(b[15], b[16]), le(b[17], b[18]), le(b[19], b[20])];
            let h = [
                raw[0] * mag_asa[0] * ak8963::UT_PER_LSB_16,
                raw[1] * mag_asa[1] * ak8963::UT_PER_LSB_16,
                raw[2] * mag_asa[2] * ak8963::UT_PER_LSB_16,
            ];
            // PS §9.1: AK8963 axes → accel/gyro axes: x = y_mag, y = x_mag, z = −z_mag.
            let in_chip = [h[1], h[0], -h[2]];
            mag = Some(MagSample {
                t_us,
                mag_frd_ut: mat_vec(m, &in_chip),
            });
            stats.mag_samples = stats.mag_samples.wrapping_add(1);
        }
    }
    Some(Mpu9250Reading {
        imu,
        temperature_c,
        mag,
    })
}

fn mat_vec(m: &[[f32; 3]; 3], v: &[f32; 3]) -> [f32; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

/// AK8963 sensitivity adjustment factor from a fuse-ROM ASA byte (MS1356-E-02 §8.3.11).
pub fn asa_factor(asa: u8) -> f32 {
    (asa as f32 - 128.0) * 0.5 / 128.0 + 1.0
}

/// The driver. Owns the SPI device (its own chip select).
pub struct Mpu9250<SPI> {
    spi: SPI,
    cfg: Mpu9250Config,
    mag_asa: [f32; 3],
    mag_ok: bool,
    pub stats: Mpu9250Stats,
    who_am_i: u8,
}

impl<SPI: SpiDevice> Mpu9250<SPI> {
    pub fn new(spi: SPI, cfg: Mpu9250Config) -> Self {
        Self {
            spi,
            cfg,
            mag_asa: [1.0; 3],
            mag_ok: false,
            stats: Mpu9250Stats::default(),
            who_am_i: 0,
        }
    }

    pub fn release(self) -> SPI {
        self.spi
    }

    /// WHO_AM_I read at init (0x71 MPU-9250, 0x73 MPU-9255).
    pub fn who_am_i(&self) -> u8 {
        self.who_am_i
    }

    /// The AK8963's ASA factors (1.0 until read).
    pub fn mag_asa(&self) -> [f32; 3] {
        self.mag_asa
    }

    /// Whether the magnetometer was found and set up.
    pub fn mag_ok(&self) -> bool {
        self.mag_ok
    }

    pub fn write_reg(&mut self, reg: u8, val: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[reg & 0x7F, val])?;
        Ok(())
    }

    pub fn read_regs(&mut self, reg: u8, buf: &mut [u8]) -> Result<(), Error<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[reg | bits::READ]), Operation::Read(buf)])?;
        Ok(())
    }

    pub fn read_reg(&mut self, reg: u8) -> Result<u8, Error<SPI::Error>> {
        let mut b = [0u8; 1];
        self.read_regs(reg, &mut b)?;
        Ok(b[0])
    }

    /// Reset and configure (RM register descriptions; order as the PS §7.5 / RM notes ask:
    /// reset, wait 100 ms, clock source, SPI-only, filters and ranges, I²C master, AK8963).
    /// Returns an error if WHO_AM_I is wrong. A magnetometer failure is not fatal when
    /// `cfg.magnetometer` is false; otherwise it is returned (the IMU is configured by then).
    pub fn init<D: DelayNs>(&mut self, delay: &mut D) -> Result<(), Error<SPI::Error>> {
        self.write_reg(reg::PWR_MGMT_1, bits::H_RESET)?;
        delay.delay_ms(100);
        let id = self.read_reg(reg::WHO_AM_I)?;
        self.who_am_i = id;
        if id != bits::WHO_AM_I_9250 && id != bits::WHO_AM_I_9255 {
            return Err(Error::WrongId(id));
        }
        self.write_reg(reg::PWR_MGMT_1, bits::CLKSEL_AUTO)?;
        delay.delay_ms(1);
        self.write_reg(reg::PWR_MGMT_2, 0x00)?; // all accel and gyro axes on
        self.write_reg(reg::USER_CTRL, bits::I2C_IF_DIS | bits::I2C_MST_EN)?;
        self.write_reg(reg::CONFIG, self.cfg.gyro_dlpf_cfg & 0x07)?;
        self.write_reg(reg::SMPLRT_DIV, self.cfg.smplrt_div)?;
        self.write_reg(reg::GYRO_CONFIG, bits::FS_SEL_3)?; // FCHOICE_B = 00: DLPF used
        self.write_reg(reg::ACCEL_CONFIG, bits::FS_SEL_3)?;
        self.write_reg(reg::ACCEL_CONFIG2, self.cfg.accel_dlpf_cfg & 0x07)?; // ACCEL_FCHOICE_B = 0
        self.write_reg(reg::INT_PIN_CFG, 0x10)?; // INT_ANYRD_2CLEAR
        self.write_reg(reg::INT_ENABLE, 0x01)?; // RAW_RDY_EN: data-ready on INT
        if self.cfg.magnetometer {
            self.init_mag(delay)?;
        }
        Ok(())
    }

    fn init_mag<D: DelayNs>(&mut self, delay: &mut D) -> Result<(), Error<SPI::Error>> {
        self.mag_ok = false;
        self.write_reg(reg::I2C_MST_CTRL, bits::I2C_MST_CLK_400K)?;
        self.ak_write(ak8963::CNTL2, ak8963::SRST, delay)?;
        delay.delay_ms(10);
        let wia = self.ak_read(ak8963::WIA, delay)?;
        if wia != ak8963::WIA_VALUE {
            return Err(Error::MagWrongId(wia));
        }
        // Fuse ROM access for ASA; the AK8963 wants power-down mode (and ≥ 100 µs) between any two
        // other modes (MS1356-E-02, operating modes).
        self.ak_write(ak8963::CNTL1, ak8963::MODE_POWER_DOWN, delay)?;
        delay.delay_ms(1);
        self.ak_write(ak8963::CNTL1, ak8963::MODE_FUSE_ROM, delay)?;
        delay.delay_ms(1);
        for i in 0..3u8 {
            let asa = self.ak_read(ak8963::ASAX + i, delay)?;
            if let Some(f) = self.mag_asa.get_mut(i as usize) {
                *f = asa_factor(asa);
            }
        }
        self.ak_write(ak8963::CNTL1, ak8963::MODE_POWER_DOWN, delay)?;
        delay.delay_ms(1);
        self.ak_write(
            ak8963::CNTL1,
            ak8963::BIT_16 | ak8963::MODE_CONT_100HZ,
            delay,
        )?;
        delay.delay_ms(1);
        // Slave 0: read ST1..ST2 (8 bytes) into EXT_SENS_DATA_00.. every sample.
        self.write_reg(reg::I2C_SLV0_ADDR, bits::I2C_SLV_RNW | ak8963::I2C_ADDR)?;
        self.write_reg(reg::I2C_SLV0_REG, ak8963::ST1)?;
        self.write_reg(reg::I2C_SLV0_CTRL, bits::I2C_SLV_EN | 8)?;
        self.mag_ok = true;
        Ok(())
    }

    /// One AK8963 register write through the I²C master's slave 4 (RM regs 49–54).
    fn ak_write<D: DelayNs>(
        &mut self,
        r: u8,
        v: u8,
        delay: &mut D,
    ) -> Result<(), Error<SPI::Error>> {
        self.write_reg(reg::I2C_SLV4_ADDR, ak8963::I2C_ADDR)?;
        self.write_reg(reg::I2C_SLV4_REG, r)?;
        self.write_reg(reg::I2C_SLV4_DO, v)?;
        self.write_reg(reg::I2C_SLV4_CTRL, bits::I2C_SLV_EN)?;
        self.slv4_wait(delay)
    }

    /// One AK8963 register read through slave 4.
    fn ak_read<D: DelayNs>(&mut self, r: u8, delay: &mut D) -> Result<u8, Error<SPI::Error>> {
        self.write_reg(reg::I2C_SLV4_ADDR, bits::I2C_SLV_RNW | ak8963::I2C_ADDR)?;
        self.write_reg(reg::I2C_SLV4_REG, r)?;
        self.write_reg(reg::I2C_SLV4_CTRL, bits::I2C_SLV_EN)?;
        self.slv4_wait(delay)?;
        self.read_reg(reg::I2C_SLV4_DI)
    }

    fn slv4_wait<D: DelayNs>(&mut self, delay: &mut D) -> Result<(), Error<SPI::Error>> {
        // The master runs at the sample rate (≥ 4 Hz in the worst configuration); 50 × 1 ms is
        // ample at 500 Hz.
        for _ in 0..50 {
            let st = self.read_reg(reg::I2C_MST_STATUS)?;
            if st & bits::I2C_SLV4_NACK != 0 {
                return Err(Error::MagNack);
            }
            if st & bits::I2C_SLV4_DONE != 0 {
                return Ok(());
            }
            delay.delay_ms(1);
        }
        Err(Error::MagTimeout)
    }

    /// Burst-read and decode one sample (call on data-ready, or at the sample rate).
    /// `Ok(None)` for a stuck bus (counted in `stats`).
    pub fn read(&mut self, now_us: u64) -> Result<Option<Mpu9250Reading>, Error<SPI::Error>> {
        let mut b = [0u8; BURST_LEN];
        self.read_regs(reg::ACCEL_XOUT_H, &mut b)?;
        let mut cfg = self.cfg;
        cfg.magnetometer = self.mag_ok;
        Ok(decode_burst(
            &b,
            now_us,
            &cfg,
            &self.mag_asa,
            &mut self.stats,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::testutil::{FakeChip, FakeDelay, FakeSpi, Rng};

    /// Behavioural model of an MPU-9250 + AK8963 on SPI: a register file with auto-increment,
    /// H_RESET, the slave-4 single transfers and slave-0 copying into EXT_SENS_DATA.
    struct FakeMpu {
        regs: [u8; 128],
        ak: [u8; 32],
        addr: u8,
        read: bool,
        first: bool,
        writes: Vec<(u8, u8)>,
        ak_writes: Vec<(u8, u8)>,
    }

    impl FakeMpu {
        fn new(who: u8) -> Self {
            let mut regs = [0u8; 128];
            regs[reg::WHO_AM_I as usize] = who;
            regs[reg::PWR_MGMT_1 as usize] = 0x01;
            let mut ak = [0u8; 32];
            ak[ak8963::WIA as usize] = 0x48;
            ak[0x10] = 176; // ASAX: 1 + 48·0.5/128 = 1.1875
            ak[0x11] = 128; // ASAY: 1.0
            ak[0x12] = 64; // ASAZ: 0.75
            Self {
                regs,
                ak,
                addr: 0,
                read: false,
                first: true,
                writes: vec![],
                ak_writes: vec![],
            }
        }
        fn write(&mut self, r: u8, v: u8) {
            self.writes.push((r, v));
            if r == reg::PWR_MGMT_1 && v & 0x80 != 0 {
                let who = self.regs[reg::WHO_AM_I as usize];
                self.regs = [0; 128];
                self.regs[reg::WHO_AM_I as usize] = who;
                self.regs[reg::PWR_MGMT_1 as usize] = 0x01;
                return;
            }
            if r == reg::I2C_SLV4_CTRL && v & 0x80 != 0 {
                let a = self.regs[reg::I2C_SLV4_ADDR as usize];
                let ar = self.regs[reg::I2C_SLV4_REG as usize] as usize & 31;
                if a & 0x7F != 0x0C {
                    self.regs[reg::I2C_MST_STATUS as usize] = 0x10 | 0x40; // NACK
                } else if a & 0x80 != 0 {
                    let mut v = self.ak[ar];
                    // Fuse ROM is only readable in fuse-ROM mode.
                    if (0x10..=0x12).contains(&ar) && self.ak[0x0A] & 0x0F != 0x0F {
                        v = 0;
                    }
                    self.regs[reg::I2C_SLV4_DI as usize] = v;
                    self.regs[reg::I2C_MST_STATUS as usize] = 0x40;
                } else {
                    let d = self.regs[reg::I2C_SLV4_DO as usize];
                    self.ak_writes.push((ar as u8, d));
                    self.ak[ar] = d;
                    self.regs[reg::I2C_MST_STATUS as usize] = 0x40;
                }
                return; // SLV4_EN self-clears
            }
            self.regs[r as usize & 127] = v;
        }
        fn read(&mut self, r: u8) -> u8 {
            let r = r & 127;
            if r == reg::I2C_MST_STATUS {
                let v = self.regs[r as usize];
                self.regs[r as usize] = 0; // clear on read
                return v;
            }
            if (reg::EXT_SENS_DATA_00..reg::EXT_SENS_DATA_00 + 24).contains(&r)
                && self.regs[reg::I2C_SLV0_CTRL as usize] & 0x80 != 0
            {
                let off = (r - reg::EXT_SENS_DATA_00) as usize;
                let start = self.regs[reg::I2C_SLV0_REG as usize] as usize;
                return self.ak[(start + off) & 31];
            }
            self.regs[r as usize]
        }
        fn set_sample(&mut self, accel: [i16; 3], temp: i16, gyro: [i16; 3]) {
            let mut a = reg::ACCEL_XOUT_H as usize;
            for v in accel.iter().chain([temp].iter()).chain(gyro.iter()) {
                let [h, l] = v.to_be_bytes();
                self.regs[a] = h;
                self.regs[a + 1] = l;
                a += 2;
            }
        }
        fn set_mag(&mut self, st1: u8, h: [i16; 3], st2: u8) {
            self.ak[2] = st1;
            for (i, v) in h.iter().enumerate() {
                let [l, hh] = v.to_le_bytes();
                self.ak[3 + 2 * i] = l;
                self.ak[4 + 2 * i] = hh;
            }
            self.ak[9] = st2;
        }
    }

    impl FakeChip for FakeMpu {
        fn select(&mut self) {
            self.first = true;
        }
        fn xfer(&mut self, mosi: u8) -> u8 {
            if self.first {
                self.first = false;
                self.read = mosi & 0x80 != 0;
                self.addr = mosi & 0x7F;
                return 0;
            }
            let a = self.addr;
            self.addr = (self.addr + 1) & 0x7F;
            if self.read {
                self.read(a)
            } else {
                self.write(a, mosi);
                0
            }
        }
    }

    fn ready() -> Mpu9250<FakeSpi<FakeMpu>> {
        let mut m = Mpu9250::new(FakeSpi::new(FakeMpu::new(0x71)), Mpu9250Config::default());
        let mut d = FakeDelay::default();
        m.init(&mut d).unwrap();
        assert!(d.total_ns >= 100_000_000, "waits ≥ 100 ms after H_RESET");
        m
    }

    #[test]
    fn who_am_i_checked() {
        for (id, ok) in [
            (0x71, true),
            (0x73, true),
            (0x70, false),
            (0x00, false),
            (0xFF, false),
        ] {
            let mut m = Mpu9250::new(FakeSpi::new(FakeMpu::new(id)), Mpu9250Config::default());
            let r = m.init(&mut FakeDelay::default());
            assert_eq!(r.is_ok(), ok, "id {id:#x}");
            if !ok {
                assert_eq!(r, Err(Error::WrongId(id)));
            }
        }
    }

    #[test]
    fn config_sequence_per_register_map() {
        let m = ready();
        let chip = &m.spi.chip;
        let w = &chip.writes;
        // Reset first, then the configuration values of RM-MPU-9250A-00.
        assert_eq!(w[0], (reg::PWR_MGMT_1, 0x80));
        let last = |r: u8| w.iter().rev().find(|x| x.0 == r).map(|x| x.1);
        assert_eq!(last(reg::PWR_MGMT_1), Some(0x01));
        assert_eq!(last(reg::GYRO_CONFIG), Some(0x18)); // ±2000 dps
        assert_eq!(last(reg::ACCEL_CONFIG), Some(0x18)); // ±16 g
        assert_eq!(last(reg::CONFIG), Some(3)); // DLPF 41 Hz
        assert_eq!(last(reg::ACCEL_CONFIG2), Some(3));
        assert_eq!(last(reg::SMPLRT_DIV), Some(1)); // 500 Hz
        assert_eq!(last(reg::USER_CTRL), Some(0x30)); // I2C_MST_EN | I2C_IF_DIS
        assert_eq!(last(reg::I2C_SLV0_ADDR), Some(0x8C));
        assert_eq!(last(reg::I2C_SLV0_REG), Some(0x02));
        assert_eq!(last(reg::I2C_SLV0_CTRL), Some(0x88));
        // AK8963: soft reset, power-down, fuse ROM, power-down, 16-bit continuous 100 Hz.
        assert_eq!(
            chip.ak_writes,
            vec![
                (0x0B, 0x01),
                (0x0A, 0x00),
                (0x0A, 0x0F),
                (0x0A, 0x00),
                (0x0A, 0x16)
            ]
        );
        assert!(m.mag_ok());
        let asa = m.mag_asa();
        assert!((asa[0] - 1.1875).abs() < 1e-6 && asa[1] == 1.0 && (asa[2] - 0.75).abs() < 1e-6);
    }

    #[test]
    fn asa_formula() {
        // MS1356-E-02 §8.3.11: Hadj = H·((ASA−128)·0.5/128 + 1).
        assert_eq!(asa_factor(128), 1.0);
        assert_eq!(asa_factor(0), 0.5);
        assert!((asa_factor(255) - 1.496_093_8).abs() < 1e-6);
    }

    #[test]
    fn burst_scaling_and_frd_mapping() {
        let mut m = ready();
        // Level, at rest, component side up: +1 g on chip Z (2048 LSB). Gyro: +164 LSB = 10 °/s
        // about chip X, −328 = −20 °/s about chip Y, 1640 = 100 °/s about chip Z.
        // Temperature 333.87·4 ≈ 1335 LSB → 25 °C.
        m.spi
            .chip
            .set_sample([1024, -512, 2048], 1335, [164, -328, 1640]);
        // Magnetometer (AK8963 axes): 100, 200, −300 LSB, new data, no overflow.
        m.spi.chip.set_mag(0x01, [100, 200, -300], 0x10);
        let r = m.read(1234).unwrap().unwrap();
        assert_eq!(r.imu.t_us, 1234);
        let a = r.imu.accel_frd_mps2;
        assert!((a[0] - 0.5 * G).abs() < 1e-4); // +x chip → forward
        assert!((a[1] - 0.25 * G).abs() < 1e-4); // −y chip → right
        assert!((a[2] + G).abs() < 1e-4); // level at rest → −g on down
        let g = r.imu.gyro_frd_radps;
        assert!((g[0] - 10f32.to_radians()).abs() < 1e-5);
        assert!((g[1] - 20f32.to_radians()).abs() < 1e-5);
        assert!((g[2] + 100f32.to_radians()).abs() < 1e-4);
        assert!((r.temperature_c - 25.0).abs() < 0.01);
        // Mag: AK axes (x, y, z) = (100·1.1875, 200·1.0, −300·0.75)·0.15 µT
        //   → chip (y_ak, x_ak, −z_ak) = (30, 17.8125, 33.75) → FRD (30, −17.8125, −33.75).
        let mg = r.mag.unwrap().mag_frd_ut;
        assert!((mg[0] - 30.0).abs() < 1e-4, "{mg:?}");
        assert!((mg[1] + 17.8125).abs() < 1e-4);
        assert!((mg[2] + 33.75).abs() < 1e-4);
        assert_eq!(m.stats.mag_samples, 1);

        // Overflow (ST2.HOFL) → rejected and counted; not ready → None, counted.
        m.spi.chip.set_mag(0x01, [100, 200, -300], 0x18);
        assert!(m.read(2000).unwrap().unwrap().mag.is_none());
        assert_eq!(m.stats.mag_overflow, 1);
        m.spi.chip.set_mag(0x00, [100, 200, -300], 0x10);
        assert!(m.read(3000).unwrap().unwrap().mag.is_none());
        assert_eq!(m.stats.mag_not_ready, 1);
    }

    #[test]
    fn full_scale_extremes_and_stuck_bus() {
        let cfg = Mpu9250Config::default();
        let mut st = Mpu9250Stats::default();
        let mut b = [0u8; BURST_LEN];
        // −32768 on every axis = −16 g / −2000 °/s·(32768/32767.5) on the chip axes.
        for i in [0, 2, 4, 8, 10, 12] {
            b[i] = 0x80;
        }
        let r = decode_burst(&b, 0, &cfg, &[1.0; 3], &mut st).unwrap();
        assert!((r.imu.accel_frd_mps2[0] + 16.0 * G).abs() < 1e-3);
        assert!((r.imu.gyro_frd_radps[0] + (32768.0 / 16.4f32).to_radians()).abs() < 1e-4);
        assert_eq!(
            decode_burst(&[0; BURST_LEN], 0, &cfg, &[1.0; 3], &mut st),
            None
        );
        assert_eq!(
            decode_burst(&[0xFF; BURST_LEN], 0, &cfg, &[1.0; 3], &mut st),
            None
        );
        assert_eq!(st.stuck_bursts, 2);
    }

    #[test]
    fn any_burst_never_panics() {
        let mut rng = Rng(0x9250);
        let cfg = Mpu9250Config::default();
        let mut st = Mpu9250Stats::default();
        for _ in 0..20_000 {
            let mut b = [0u8; BURST_LEN];
            b.iter_mut().for_each(|x| *x = rng.byte());
            if let Some(r) = decode_burst(&b, 0, &cfg, &[asa_factor(rng.byte()); 3], &mut st) {
                assert!(r.imu.accel_frd_mps2.iter().all(|v| v.is_finite()));
                assert!(r
                    .mag
                    .is_none_or(|m| m.mag_frd_ut.iter().all(|v| v.is_finite())));
            }
        }
    }

    #[test]
    fn missing_magnetometer_is_reported() {
        let mut chip = FakeMpu::new(0x71);
        chip.ak[0] = 0x00;
        let mut m = Mpu9250::new(FakeSpi::new(chip), Mpu9250Config::default());
        assert_eq!(m.init(&mut FakeDelay::default()), Err(Error::MagWrongId(0)));
        assert!(!m.mag_ok());
        let mut m = Mpu9250::new(
            FakeSpi::new(FakeMpu::new(0x71)),
            Mpu9250Config {
                magnetometer: false,
                ..Default::default()
            },
        );
        m.init(&mut FakeDelay::default()).unwrap();
        m.spi.chip.set_sample([0, 0, 2048], 0, [0, 0, 0]);
        assert!(m.read(0).unwrap().unwrap().mag.is_none());
    }
}
