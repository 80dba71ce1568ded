//! `mission/status`: one JSON object per message, at most every [`REPORT_PERIOD_S`] of wall
//! time: `{"t_s":…,"phase":"leg","waypoint":1,"of":4,"dist_to_go_m":12.3,"armed":true,
//! "mode":"velocity"}`; after the mission one `{"phase":"finished",…}`.
//!
//! Pure: the JSON text and the rate limit, time passed in (the node's wall clock, s).

/// Shortest time between two reports, s (wall clock): 2 Hz.
pub const REPORT_PERIOD_S: f64 = 0.5;

/// What one report says.
#[derive(Debug, Clone, PartialEq)]
pub struct StatusReport<'a> {
    /// ROS time, s.
    pub t_s: f64,
    /// `arming`, `pilot`, `hover`, `landing` or the follower's phase name.
    pub phase: &'a str,
    /// The waypoint index of the phase, if any.
    pub waypoint: Option<usize>,
    /// Waypoints in the mission.
    pub of: usize,
    /// Distance to the current leg's end, m.
    pub dist_to_go_m: Option<f32>,
    /// The MCU is armed.
    pub armed: bool,
    /// The MCU's mode name (as on `status`).
    pub mode: &'a str,
}

impl StatusReport<'_> {
    /// The JSON text (`null` for a missing waypoint or distance).
    pub fn json(&self) -> String {
        let wp = self
            .waypoint
            .map(|i| i.to_string())
            .unwrap_or_else(|| "null".into());
        let d = self
            .dist_to_go_m
            .map(|d| format!("{d:.2}"))
            .unwrap_or_else(|| "null".into());
        format!(
            "{{\"t_s\":{:.2},\"phase\":\"{}\",\"waypoint\":{wp},\"of\":{},\"dist_to_go_m\":{d},\"armed\":{},\"mode\":\"{}\"}}",
            self.t_s, self.phase, self.of, self.armed, self.mode
        )
    }
}

/// The last report: every waypoint done, landed and disarmed.
pub fn finished_json(n_waypoints: usize) -> String {
    let n = n_waypoints;
    format!("{{\"phase\":\"finished\",\"waypoint\":{n},\"of\":{n},\"dist_to_go_m\":0.0,\"armed\":false,\"landed\":true}}")
}

/// The rate limit of the reports.
#[derive(Debug, Clone, Default)]
pub struct ReportClock {
    last_s: Option<f64>,
}

impl ReportClock {
    pub fn new() -> Self {
        Self::default()
    }

    /// True when a report is due at `wall_s` (s, monotonic); then the next is due
    /// [`REPORT_PERIOD_S`] later.
    pub fn due(&mut self, wall_s: f64) -> bool {
        if self.last_s.is_some_and(|t| wall_s - t < REPORT_PERIOD_S) {
            return false;
        }
        self.last_s = Some(wall_s);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_text() {
        let r = StatusReport {
            t_s: 12.345,
            phase: "leg",
            waypoint: Some(1),
            of: 4,
            dist_to_go_m: Some(12.304),
            armed: true,
            mode: "velocity",
        };
        assert_eq!(
            r.json(),
            r#"{"t_s":12.35,"phase":"leg","waypoint":1,"of":4,"dist_to_go_m":12.30,"armed":true,"mode":"velocity"}"#
        );
        let r = StatusReport {
            phase: "arming",
            waypoint: None,
            dist_to_go_m: None,
            armed: false,
            mode: "disarmed",
            ..r
        };
        assert_eq!(
            r.json(),
            r#"{"t_s":12.35,"phase":"arming","waypoint":null,"of":4,"dist_to_go_m":null,"armed":false,"mode":"disarmed"}"#
        );
        assert_eq!(
            finished_json(4),
            r#"{"phase":"finished","waypoint":4,"of":4,"dist_to_go_m":0.0,"armed":false,"landed":true}"#
        );
    }

    #[test]
    fn at_most_two_a_second() {
        let mut c = ReportClock::new();
        let due: Vec<f64> = (0..150)
            .map(|k| k as f64 * 0.02)
            .filter(|&t| c.due(t))
            .collect();
        assert_eq!(due.len(), 6, "{due:?}");
        for (k, t) in due.iter().enumerate() {
            assert!((t - 0.5 * k as f64).abs() < 0.02 + 1e-9, "{due:?}");
        }
    }
}
