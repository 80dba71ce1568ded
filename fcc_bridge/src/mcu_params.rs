//! The MCU parameters the bridge exposes as ROS 2 parameters: name (the firmware's
//! `section.field`), link id ([`fcc_msgs::param_id`]), the firmware's default and its valid
//! range (mirrors `fcc_firmware::params::Params::validate` and `FlightCore::set_param`; the MCU
//! checks again and has the last word).

use fcc_msgs::param_id as pid;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McuParam {
    pub name: &'static str,
    pub id: u16,
    pub default: f32,
    pub min: f32,
    pub max: f32,
}

pub const MCU_PARAMS: &[McuParam] = &[
    McuParam {
        name: "limits.max_horiz_speed_mps",
        id: pid::MAX_HORIZ_SPEED_MPS,
        default: 8.0,
        min: 0.1,
        max: 30.0,
    },
    McuParam {
        name: "limits.max_tilt_deg",
        id: pid::MAX_TILT_DEG,
        default: 25.0,
        min: 5.0,
        max: 60.0,
    },
    McuParam {
        name: "control.cross_track_k_per_s",
        id: pid::CROSS_TRACK_K_PER_S,
        default: 2.0,
        min: 0.0,
        max: 5.0,
    },
    McuParam {
        name: "control.vel_p_per_s",
        id: pid::VEL_P_PER_S,
        default: 3.0,
        min: 0.05,
        max: 10.0,
    },
    McuParam {
        name: "limits.max_climb_mps",
        id: pid::MAX_CLIMB_MPS,
        default: 2.5,
        min: 0.1,
        max: 10.0,
    },
    McuParam {
        name: "limits.max_descent_mps",
        id: pid::MAX_DESCENT_MPS,
        default: 1.5,
        min: 0.1,
        max: 10.0,
    },
];

pub fn by_name(name: &str) -> Option<&'static McuParam> {
    MCU_PARAMS.iter().find(|p| p.name == name)
}

pub fn by_id(id: u16) -> Option<&'static McuParam> {
    MCU_PARAMS.iter().find(|p| p.id == id)
}

impl McuParam {
    /// Range check with a ROS-style reason.
    pub fn check(&self, v: f64) -> Result<(), String> {
        if !v.is_finite() {
            return Err(format!("{}: not finite", self.name));
        }
        if v < self.min as f64 || v > self.max as f64 {
            return Err(format!(
                "{}: {v} out of range [{}, {}]",
                self.name, self.min, self.max
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn table_matches_the_link_ids() {
        assert_eq!(super::MCU_PARAMS.len(), fcc_msgs::param_id::ALL.len());
        for (id, name) in fcc_msgs::param_id::ALL {
            let p = super::by_id(*id).unwrap();
            assert_eq!(p.name, *name);
            assert!(p.check(p.default as f64).is_ok());
            assert!(p.check(p.max as f64 * 2.0 + 1.0).is_err());
        }
    }
}
