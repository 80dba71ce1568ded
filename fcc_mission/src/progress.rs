//! The mission's progress as the node reports it: the phase's name (logged when it changes,
//! sent on `mission/status`), the distance to the current leg's end, and the cross-track
//! statistics of the estimated position on the legs (as the node sees it on `state/odom`).
//!
//! Pure logic on the follower's [`Guidance`] and the position estimate (NED, m).

use crate::{Guidance, Phase};

/// A phase as named in the log and on `mission/status`: (name, waypoint index).
pub type PhaseName = (&'static str, Option<usize>);

/// The name of a follower phase: `idle`, `takeoff`, `leg i`, `hold i`, `landing`, `done`.
pub fn phase_name(p: Phase) -> PhaseName {
    match p {
        Phase::Idle => ("idle", None),
        Phase::Takeoff => ("takeoff", None),
        Phase::Leg(i) => ("leg", Some(i)),
        Phase::Hold(i) => ("hold", Some(i)),
        Phase::Landing => ("landing", None),
        Phase::Done => ("done", None),
    }
}

/// Straight-line distance from `pos_ned_m` to the end of the current leg, m (None without one).
pub fn dist_to_go_m(g: &Guidance, pos_ned_m: [f32; 3]) -> Option<f32> {
    g.leg.map(|l| {
        let d = [
            l.to_ned_m[0] - pos_ned_m[0],
            l.to_ned_m[1] - pos_ned_m[1],
            l.to_ned_m[2] - pos_ned_m[2],
        ];
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    })
}

/// Cross-track statistics of positions on legs (horizontal distance to the leg line; only
/// positions between the leg's ends, on legs of 1 m or more).
#[derive(Debug, Clone, Default)]
pub struct CrossTrack {
    n: usize,
    sum_sq: f64,
    max_m: f64,
}

impl CrossTrack {
    /// Adds the position `pos` (NED, m) on the leg `from` → `to` (NED, m).
    pub fn add(&mut self, from: [f32; 3], to: [f32; 3], pos: [f32; 3]) {
        let (dn, de) = ((to[0] - from[0]) as f64, (to[1] - from[1]) as f64);
        let len = (dn * dn + de * de).sqrt();
        if len < 1.0 {
            return;
        }
        let (pn, pe) = ((pos[0] - from[0]) as f64, (pos[1] - from[1]) as f64);
        let along = (pn * dn + pe * de) / len;
        if along < 0.0 || along > len {
            return;
        }
        let xt = (pn * de - pe * dn).abs() / len;
        self.n += 1;
        self.sum_sq += xt * xt;
        self.max_m = self.max_m.max(xt);
    }

    /// Samples counted.
    pub fn samples(&self) -> usize {
        self.n
    }

    /// RMS cross-track, m (0 without samples).
    pub fn rms_m(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            (self.sum_sq / self.n as f64).sqrt()
        }
    }

    /// Largest cross-track, m.
    pub fn max_m(&self) -> f64 {
        self.max_m
    }
}

/// The phase last reported and the cross-track on the legs, updated with each guidance.
#[derive(Debug, Clone, Default)]
pub struct Progress {
    last_phase: Option<PhaseName>,
    track: CrossTrack,
}

impl Progress {
    pub fn new() -> Self {
        Self::default()
    }

    /// The phase of the latest guidance (None before the first).
    pub fn last_phase(&self) -> Option<PhaseName> {
        self.last_phase
    }

    /// Cross-track on the legs so far.
    pub fn track(&self) -> &CrossTrack {
        &self.track
    }

    /// Takes one guidance and the position it was computed for; returns the phase's name when
    /// it differs from the previous one (worth a log line).
    pub fn update(&mut self, g: &Guidance, pos_ned_m: [f32; 3]) -> Option<PhaseName> {
        let name = phase_name(g.phase);
        if let (Phase::Leg(_), Some(leg)) = (g.phase, g.leg) {
            self.track.add(leg.from_ned_m, leg.to_ned_m, pos_ned_m);
        }
        if self.last_phase == Some(name) {
            return None;
        }
        self.last_phase = Some(name);
        Some(name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LegInfo;

    fn guidance(phase: Phase, leg: Option<([f32; 3], [f32; 3])>) -> Guidance {
        Guidance {
            vel_ned_mps: [0.0; 3],
            yaw_rad: None,
            phase,
            leg: leg.map(|(from_ned_m, to_ned_m)| LegInfo {
                from_ned_m,
                to_ned_m,
            }),
            request: None,
        }
    }

    #[test]
    fn names() {
        assert_eq!(phase_name(Phase::Idle), ("idle", None));
        assert_eq!(phase_name(Phase::Takeoff), ("takeoff", None));
        assert_eq!(phase_name(Phase::Leg(2)), ("leg", Some(2)));
        assert_eq!(phase_name(Phase::Hold(3)), ("hold", Some(3)));
        assert_eq!(phase_name(Phase::Landing), ("landing", None));
        assert_eq!(phase_name(Phase::Done), ("done", None));
    }

    #[test]
    fn cross_track_counts_only_between_the_ends_of_long_enough_legs() {
        let mut t = CrossTrack::default();
        let (from, to) = ([0.0, 0.0, -5.0], [20.0, 0.0, -5.0]);
        t.add(from, to, [5.0, 0.3, -5.0]);
        t.add(from, to, [10.0, -0.4, -4.0]);
        t.add(from, to, [-1.0, 3.0, -5.0]); // behind the start
        t.add(from, to, [21.0, 3.0, -5.0]); // past the end
        t.add([0.0; 3], [0.5, 0.5, 0.0], [0.2, 0.0, 0.0]); // a leg under 1 m
        assert_eq!(t.samples(), 2);
        assert!(
            (t.rms_m() - (0.125f64).sqrt()).abs() < 1e-6,
            "{}",
            t.rms_m()
        );
        assert!((t.max_m() - 0.4).abs() < 1e-6);
        assert_eq!(CrossTrack::default().rms_m(), 0.0);
    }

    #[test]
    fn dist_to_go_is_to_the_legs_end() {
        let g = guidance(Phase::Leg(0), Some(([0.0; 3], [3.0, 4.0, 0.0])));
        assert_eq!(dist_to_go_m(&g, [0.0; 3]), Some(5.0));
        assert_eq!(
            dist_to_go_m(&guidance(Phase::Landing, None), [0.0; 3]),
            None
        );
    }

    #[test]
    fn phase_changes_are_reported_once_and_only_legs_count_for_cross_track() {
        let mut p = Progress::new();
        let leg = Some(([0.0, 0.0, -5.0], [20.0, 0.0, -5.0]));
        let off = [10.0, 1.0, -5.0];
        assert_eq!(
            p.update(&guidance(Phase::Takeoff, leg), off),
            Some(("takeoff", None))
        );
        assert_eq!(p.update(&guidance(Phase::Takeoff, leg), off), None);
        assert_eq!(p.track().samples(), 0);
        assert_eq!(
            p.update(&guidance(Phase::Leg(0), leg), off),
            Some(("leg", Some(0)))
        );
        assert_eq!(p.update(&guidance(Phase::Leg(0), leg), off), None);
        assert_eq!(
            p.update(&guidance(Phase::Hold(0), leg), off),
            Some(("hold", Some(0)))
        );
        assert_eq!(
            p.update(&guidance(Phase::Leg(1), leg), off),
            Some(("leg", Some(1)))
        );
        assert_eq!(p.track().samples(), 3);
        assert!((p.track().max_m() - 1.0).abs() < 1e-6);
        assert_eq!(p.last_phase(), Some(("leg", Some(1))));
    }
}
