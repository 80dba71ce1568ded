//! MCU clock (µs since boot) → ROS time (ns), NTP-style from `TimeSyncPing`/`TimeSyncPong`.
//!
//! With t1 = ping sent (Linux), t2 = ping received (MCU), t3 = pong sent (MCU), t4 = pong
//! received (Linux): round trip `rtt = (t4 − t1) − (t3 − t2)`, and the MCU clock minus the Linux
//! clock is `θ = ((t2 − t1) + (t3 − t4)) / 2`, exact when both legs take equally long. The
//! estimate in use is the sample with the smallest RTT among the last [`WINDOW`] (the least
//! delayed exchange bounds the error best: |error| ≤ rtt / 2).

/// Samples kept for the min-RTT filter.
pub const WINDOW: usize = 16;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SyncSample {
    /// ROS time minus MCU time, ns.
    pub offset_ns: i64,
    pub rtt_ns: i64,
}

#[derive(Clone, Debug, Default)]
pub struct TimeSync {
    samples: Vec<SyncSample>,
    next: usize,
    /// Pongs refused (negative RTT, answer to no ping of ours).
    pub rejected: u64,
    pub accepted: u64,
}

impl TimeSync {
    pub fn new() -> Self {
        Self::default()
    }

    /// Add one exchange; all times in ns (MCU µs × 1000). Returns the sample if plausible.
    pub fn add(&mut self, t1: i64, t2: i64, t3: i64, t4: i64) -> Option<SyncSample> {
        let rtt = (t4 - t1) - (t3 - t2);
        if rtt < 0 || t4 < t1 || t3 < t2 || rtt > 5_000_000_000 {
            self.rejected += 1;
            return None;
        }
        let theta = ((t2 - t1) + (t3 - t4)) / 2;
        let s = SyncSample {
            offset_ns: -theta,
            rtt_ns: rtt,
        };
        if self.samples.len() < WINDOW {
            self.samples.push(s);
        } else {
            self.samples[self.next] = s;
            self.next = (self.next + 1) % WINDOW;
        }
        self.accepted += 1;
        Some(s)
    }

    /// Add a pong (`linux_time_ns` echoed, MCU µs) received at `t4_ns` (Linux clock).
    pub fn add_pong(&mut self, pong: &fcc_msgs::TimeSyncPong, t4_ns: i64) -> Option<SyncSample> {
        self.add(
            pong.linux_time_ns as i64,
            pong.mcu_rx_time_us as i64 * 1000,
            pong.mcu_tx_time_us as i64 * 1000,
            t4_ns,
        )
    }

    /// The estimate in use (min RTT in the window), if any.
    pub fn best(&self) -> Option<SyncSample> {
        self.samples.iter().copied().min_by_key(|s| s.rtt_ns)
    }

    pub fn is_synced(&self) -> bool {
        !self.samples.is_empty()
    }

    /// Forget everything (the MCU restarted or the port was reopened).
    pub fn reset(&mut self) {
        self.samples.clear();
        self.next = 0;
    }

    /// MCU µs → ROS ns, if synced.
    pub fn to_ros_ns(&self, mcu_us: u64) -> Option<i64> {
        self.best().map(|s| mcu_us as i64 * 1000 + s.offset_ns)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symmetric_delay_is_exact() {
        // MCU clock = Linux − 1 s. Legs 100 µs each, MCU turnaround 50 µs.
        let off = 1_000_000_000i64;
        let t1 = 5_000_000_000;
        let t2 = t1 + 100_000 - off;
        let t3 = t2 + 50_000;
        let t4 = t3 + off + 100_000;
        let mut ts = TimeSync::new();
        let s = ts.add(t1, t2, t3, t4).unwrap();
        assert_eq!(s.rtt_ns, 200_000);
        assert_eq!(s.offset_ns, off);
        assert_eq!(ts.to_ros_ns(1000), Some(1_000_000 + off));
    }

    #[test]
    fn min_rtt_wins() {
        let off = 7_000i64;
        let mut ts = TimeSync::new();
        // Slow, asymmetric exchange (3 ms out, 0.1 ms back): biased by 1.45 ms.
        let (t1, d_out, d_back) = (1_000_000i64, 3_000_000i64, 100_000i64);
        ts.add(t1, t1 + d_out - off, t1 + d_out - off, t1 + d_out + d_back);
        // Fast, symmetric.
        let t1 = 9_000_000;
        ts.add(t1, t1 + 50_000 - off, t1 + 50_000 - off, t1 + 100_000);
        assert_eq!(ts.best().unwrap().offset_ns, off);
        // Negative RTT refused.
        assert!(ts.add(10, 0, 100, 20).is_none());
        assert_eq!(ts.rejected, 1);
    }
}
