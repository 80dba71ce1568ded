//! Test helpers: a hand-written `SpiDevice` around a behavioural model of a chip, a `DelayNs`
//! that only adds up, and a small PRNG for the "any bytes → no panic" tests.

use core::convert::Infallible;
use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{ErrorType, Operation, SpiDevice};

/// A chip behind chip-select: `select` when CS falls, then one call per clocked byte.
pub trait FakeChip {
    fn select(&mut self);
    fn xfer(&mut self, mosi: u8) -> u8;
    fn deselect(&mut self) {}
}

/// `SpiDevice` over a [`FakeChip`]; each `transaction` is one CS-low period.
pub struct FakeSpi<C: FakeChip> {
    pub chip: C,
    pub transactions: usize,
}

impl<C: FakeChip> FakeSpi<C> {
    pub fn new(chip: C) -> Self {
        Self {
            chip,
            transactions: 0,
        }
    }
}

impl<C: FakeChip> ErrorType for FakeSpi<C> {
    type Error = Infallible;
}

impl<C: FakeChip> SpiDevice for FakeSpi<C> {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Infallible> {
        self.transactions += 1;
        self.chip.select();
        for op in ops.iter_mut() {
            match op {
                Operation::Write(w) => {
                    for b in w.iter() {
                        self.chip.xfer(*b);
                    }
                }
                Operation::Read(r) => {
                    for b in r.iter_mut() {
                        *b = self.chip.xfer(0);
                    }
                }
                Operation::Transfer(r, w) => {
                    let n = r.len().max(w.len());
                    for i in 0..n {
                        let o = self.chip.xfer(w.get(i).copied().unwrap_or(0));
                        if let Some(x) = r.get_mut(i) {
                            *x = o;
                        }
                    }
                }
                Operation::TransferInPlace(b) => {
                    for x in b.iter_mut() {
                        *x = self.chip.xfer(*x);
                    }
                }
                Operation::DelayNs(_) => {}
            }
        }
        self.chip.deselect();
        Ok(())
    }
}

/// A delay that does not wait; it adds up what was asked.
#[derive(Default)]
pub struct FakeDelay {
    pub total_ns: u64,
}

impl DelayNs for FakeDelay {
    fn delay_ns(&mut self, ns: u32) {
        self.total_ns += ns as u64;
    }
}

/// xorshift64*: deterministic pseudo-random bytes for the no-panic tests.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    pub fn byte(&mut self) -> u8 {
        (self.next_u64() >> 32) as u8
    }
    /// A byte biased towards `interesting` (sync bytes, digits, CR/LF…) half of the time.
    pub fn biased(&mut self, interesting: &[u8]) -> u8 {
        let r = self.next_u64();
        if r & 1 == 0 && !interesting.is_empty() {
            interesting[((r >> 8) as usize) % interesting.len()]
        } else {
            (r >> 40) as u8
        }
    }
}
