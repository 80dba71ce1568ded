//! Mutation fuzzing of the link decoder (every message type), run as a test.
//!
//! Valid frames of every message are mutated (bit flips, byte overwrites, insertions, deletions,
//! truncations, splices of two frames, runs of garbage) and fed to a [`FrameDecoder`] in random
//! chunk sizes. Oracle: no panic, and every frame the decoder accepts is byte-for-byte one of the
//! frames that went in unmodified (re-encoding it gives bytes present intact in the input) — so
//! no frame with a wrong CRC or length is ever accepted.
//!
//! The test command runs `FCC_FUZZ_ITERS` inputs (default 2·10⁶, about 2 s). The long run
//! (10⁷ inputs, ~10 s on one core; 10⁸ for a thorough one):
//!
//! ```text
//! FCC_FUZZ_ITERS=10000000 cargo test --release -p fcc_msgs fuzz -- --nocapture
//! ```

extern crate std;

use crate::tests::{enc, samples};
use crate::{encode, FrameDecoder, MAX_FRAME_LEN};
use std::vec::Vec;

/// xorshift64*: small, seeded, dependency-free generator for the mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn mutate(rng: &mut Rng, frames: &[Vec<u8>]) -> Vec<u8> {
    let mut v = frames[rng.below(frames.len())].clone();
    let rounds = 1 + rng.below(4);
    for _ in 0..rounds {
        if v.is_empty() {
            v.push(rng.next() as u8);
        }
        match rng.below(7) {
            0 => {
                let i = rng.below(v.len());
                v[i] ^= 1 << rng.below(8);
            }
            1 => {
                let i = rng.below(v.len());
                v[i] = rng.next() as u8;
            }
            2 => {
                let i = rng.below(v.len() + 1);
                v.insert(i, rng.next() as u8);
            }
            3 if v.len() > 1 => {
                let i = rng.below(v.len());
                v.remove(i);
            }
            4 => {
                let n = rng.below(v.len() + 1);
                v.truncate(n);
            }
            5 => {
                let other = &frames[rng.below(frames.len())];
                let cut = rng.below(v.len() + 1);
                let from = rng.below(other.len() + 1);
                v.truncate(cut);
                v.extend_from_slice(&other[from..]);
            }
            _ => {
                let n = rng.below(40);
                for _ in 0..n {
                    v.push(rng.next() as u8);
                }
            }
        }
    }
    v
}

fn contains(hay: &[u8], needle: &[u8]) -> bool {
    hay.windows(needle.len()).any(|w| w == needle)
}

#[test]
fn mutated_frames_never_panic_and_corrupt_frames_are_never_accepted() {
    let iters: u64 = std::env::var("FCC_FUZZ_ITERS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2_000_000);
    let msgs = samples();
    let frames: Vec<Vec<u8>> = msgs
        .iter()
        .enumerate()
        .map(|(i, m)| enc(m, i as u16, 7_000 + i as u64))
        .collect();
    let mut rng = Rng(0x5EED_F022_1234_5678);
    let mut dec = FrameDecoder::new();
    let (mut accepted, mut rejected) = (0u64, 0u64);
    let mut out = [0u8; MAX_FRAME_LEN];
    for _ in 0..iters {
        // A mutated frame, sometimes between intact ones, delimited so each input stands alone.
        let mut input = Vec::new();
        if rng.below(4) == 0 {
            input.extend_from_slice(&frames[rng.below(frames.len())]);
        }
        input.extend(mutate(&mut rng, &frames));
        input.push(0);
        let mut pos = 0;
        while pos < input.len() {
            let n = (1 + rng.below(64)).min(input.len() - pos);
            for r in dec.push_slice(&input[pos..pos + n]) {
                match r {
                    Ok(f) => {
                        accepted += 1;
                        let len =
                            encode(&f.message, f.header.seq, f.header.t_us, &mut out).unwrap();
                        assert!(
                            contains(&input, &out[..len]),
                            "accepted a frame that was not in the input intact: {f:?}"
                        );
                    }
                    Err(_) => rejected += 1,
                }
            }
            pos += n;
        }
    }
    let c = dec.counters();
    std::println!(
        "fuzz: {iters} inputs, {accepted} intact frames accepted, {rejected} rejected (CRC errors {}, framing {}, decode {}, overruns {})",
        c.crc_errors, c.framing_errors, c.decode_errors, c.overruns
    );
    assert!(accepted > 0 && rejected > 0);
}
