//! Terrain for the rangefinder models (paper B): flat ground at NED down = 0, axis-aligned
//! boxes standing on it (so the ground under the vehicle can step), and surface darkness where
//! the laser altimeter gets no return — by area, by time window, or both.
//!
//! YAML (every field optional; `Terrain` deserialises with `#[serde(default)]`):
//! ```yaml
//! terrain:
//!   boxes:
//!     - { north_min_m: 5, north_max_m: 8, east_min_m: -2, east_max_m: 2, height_m: 0.5 }
//!   dark_patches:
//!     - { north_min_m: -1, north_max_m: 1, east_min_m: -1, east_max_m: 1 }   # rectangle
//!     - { center_north_m: 10, center_east_m: 0, radius_m: 2 }                 # circle
//!     - { from_s: 105, to_s: 184 }                       # everywhere, in a time window
//! ```
//! Paper B's ground test: "the laser diverged to 99 999 m from 105 s to 184 s over a dark
//! surface" — a patch with no bounds and `from_s: 105, to_s: 184`.
//!
//! Heights are **up positive** (a box of `height_m: 0.5` has its top at NED down = −0.5); a
//! negative height is a pit (floor at +|h| down; its walls are not modelled). Where boxes
//! overlap the highest top wins.

use nalgebra::{Unit, UnitQuaternion, Vector3};
use serde::Deserialize;

/// An axis-aligned box standing on the ground.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TerrainBox {
    pub north_min_m: f64,
    pub north_max_m: f64,
    pub east_min_m: f64,
    pub east_max_m: f64,
    /// Top of the box above the ground, m (up positive).
    pub height_m: f64,
}

impl TerrainBox {
    pub fn contains(&self, n: f64, e: f64) -> bool {
        n >= self.north_min_m
            && n <= self.north_max_m
            && e >= self.east_min_m
            && e <= self.east_max_m
    }
}

fn neg_inf() -> f64 {
    f64::NEG_INFINITY
}
fn pos_inf() -> f64 {
    f64::INFINITY
}

/// A dark area (no laser return): a rectangle (bounds default to ±∞, i.e. everywhere), a
/// circle (if `radius_m` is given; intersected with the rectangle), active in `[from_s, to_s)`
/// when given (default always).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DarkPatch {
    #[serde(default = "neg_inf")]
    pub north_min_m: f64,
    #[serde(default = "pos_inf")]
    pub north_max_m: f64,
    #[serde(default = "neg_inf")]
    pub east_min_m: f64,
    #[serde(default = "pos_inf")]
    pub east_max_m: f64,
    #[serde(default)]
    pub center_north_m: f64,
    #[serde(default)]
    pub center_east_m: f64,
    #[serde(default)]
    pub radius_m: Option<f64>,
    #[serde(default)]
    pub from_s: Option<f64>,
    #[serde(default)]
    pub to_s: Option<f64>,
}

impl Default for DarkPatch {
    fn default() -> Self {
        Self {
            north_min_m: f64::NEG_INFINITY,
            north_max_m: f64::INFINITY,
            east_min_m: f64::NEG_INFINITY,
            east_max_m: f64::INFINITY,
            center_north_m: 0.0,
            center_east_m: 0.0,
            radius_m: None,
            from_s: None,
            to_s: None,
        }
    }
}

impl DarkPatch {
    pub fn is_dark(&self, n: f64, e: f64, t_s: f64) -> bool {
        if let Some(f) = self.from_s {
            if t_s < f {
                return false;
            }
        }
        if let Some(to) = self.to_s {
            if t_s >= to {
                return false;
            }
        }
        if !(n >= self.north_min_m
            && n <= self.north_max_m
            && e >= self.east_min_m
            && e <= self.east_max_m)
        {
            return false;
        }
        match self.radius_m {
            Some(r) => {
                let (dn, de) = (n - self.center_north_m, e - self.center_east_m);
                dn * dn + de * de <= r * r
            }
            None => true,
        }
    }
}

/// Flat ground + boxes + darkness map.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct Terrain {
    pub boxes: Vec<TerrainBox>,
    pub dark_patches: Vec<DarkPatch>,
}

/// Where a ray met the terrain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance from the ray origin, m.
    pub range_m: f64,
    /// The point hit, NED m.
    pub point_ned_m: Vector3<f64>,
    /// Outward surface normal, NED (up = `[0, 0, −1]`).
    pub normal_ned: Vector3<f64>,
    /// Angle between the ray and the surface normal (0 = perpendicular incidence), rad.
    pub incidence_rad: f64,
}

const EPS: f64 = 1e-9;

impl Terrain {
    /// Flat ground, always bright.
    pub fn flat() -> Self {
        Self::default()
    }

    /// Ground height (up positive, m) under `(north, east)`: the highest box containing the
    /// point, else 0.
    pub fn height_at(&self, n: f64, e: f64) -> f64 {
        self.boxes
            .iter()
            .filter(|b| b.contains(n, e))
            .map(|b| b.height_m)
            .fold(None, |acc: Option<f64>, h| {
                Some(acc.map_or(h, |a| a.max(h)))
            })
            .unwrap_or(0.0)
    }

    /// Ground surface as NED down (= −height).
    pub fn ground_down_at(&self, n: f64, e: f64) -> f64 {
        -self.height_at(n, e)
    }

    /// Is the surface at `(north, east)` dark (no laser return) at time `t_s`?
    pub fn is_dark(&self, n: f64, e: f64, t_s: f64) -> bool {
        self.dark_patches.iter().any(|p| p.is_dark(n, e, t_s))
    }

    /// First intersection of the ray `origin + t·dir` (t ≥ 0, `dir` normalised here) with the
    /// terrain, up to `max_range_m`: the ground plane, box tops and box walls (pit floors,
    /// not pit walls).
    pub fn ray_cast(
        &self,
        origin_ned_m: Vector3<f64>,
        dir_ned: Vector3<f64>,
        max_range_m: f64,
    ) -> Option<RayHit> {
        let d = dir_ned.try_normalize(EPS)?;
        let o = origin_ned_m;
        let mut best: Option<(f64, Vector3<f64>)> = None;
        let mut consider = |t: f64, normal: Vector3<f64>| {
            if t >= 0.0 && t <= max_range_m && best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, normal));
            }
        };
        let up = Vector3::new(0.0, 0.0, -1.0);
        // Ground plane (down = 0), or a pit floor, where no box stands.
        if d.z > EPS {
            let t = (0.0 - o.z) / d.z;
            let p = o + d * t;
            let h = self.height_at(p.x, p.y);
            if h == 0.0 {
                consider(t, up);
            } else if h < 0.0 {
                let tf = (-h - o.z) / d.z;
                let pf = o + d * tf;
                if self.height_at(pf.x, pf.y) == h {
                    consider(tf, up);
                }
            }
        }
        // Boxes standing on the ground: slab intersection with [n, e, down ∈ −h..0].
        for b in self.boxes.iter().filter(|b| b.height_m > 0.0) {
            let lo = Vector3::new(b.north_min_m, b.east_min_m, -b.height_m);
            let hi = Vector3::new(b.north_max_m, b.east_max_m, 0.0);
            let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
            let mut n0 = Vector3::zeros();
            let mut miss = false;
            for k in 0..3 {
                if d[k].abs() < EPS {
                    if o[k] < lo[k] || o[k] > hi[k] {
                        miss = true;
                        break;
                    }
                    continue;
                }
                let (ta, tb) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
                let (tn, tf) = if ta < tb { (ta, tb) } else { (tb, ta) };
                if tn > t0 {
                    t0 = tn;
                    n0 = Vector3::zeros();
                    n0[k] = -d[k].signum();
                }
                t1 = t1.min(tf);
            }
            if miss || t0 > t1 || t0 < 0.0 {
                // t0 < 0: origin inside or past the box; ignore (the vehicle is not inside one).
                continue;
            }
            // The top face of a box whose height is overridden by a taller overlapping box is
            // still a surface here; the highest-top rule only matters for height_at.
            consider(t0, n0);
        }
        let (t, normal) = best?;
        let cos_inc = (-d.dot(&normal)).clamp(-1.0, 1.0);
        Some(RayHit {
            range_m: t,
            point_ned_m: o + d * t,
            normal_ned: normal,
            incidence_rad: cos_inc.acos(),
        })
    }

    /// Range along the body-down axis (a narrow beam, e.g. the laser) from `pos_ned_m`.
    pub fn range_body_down(
        &self,
        pos_ned_m: Vector3<f64>,
        q_body_to_ned: &UnitQuaternion<f64>,
        max_range_m: f64,
    ) -> Option<RayHit> {
        self.ray_cast(pos_ned_m, q_body_to_ned * Vector3::z(), max_range_m)
    }

    /// Nearest surface within a cone of half-angle `half_angle_rad` around body-down (a sonar
    /// beam): the minimum over the axis, the ray in the cone closest to local vertical (which is
    /// exactly the nearest point of flat ground within the cone), and two rings of 6 and 12
    /// rays at half and full half-angle.
    pub fn range_cone(
        &self,
        pos_ned_m: Vector3<f64>,
        q_body_to_ned: &UnitQuaternion<f64>,
        half_angle_rad: f64,
        max_range_m: f64,
    ) -> Option<RayHit> {
        let axis = q_body_to_ned * Vector3::z();
        let half = half_angle_rad.max(0.0);
        let mut dirs: Vec<Vector3<f64>> = Vec::with_capacity(20);
        dirs.push(axis);
        let down = Vector3::z();
        let off = axis.dot(&down).clamp(-1.0, 1.0).acos();
        if off <= half {
            dirs.push(down);
        } else if let Some(rot_axis) = Unit::try_new(axis.cross(&down), EPS) {
            dirs.push(UnitQuaternion::from_axis_angle(&rot_axis, half) * axis);
        }
        if half > 0.0 {
            // Orthonormal u, v ⟂ axis.
            let helper = if axis.x.abs() < 0.9 {
                Vector3::x()
            } else {
                Vector3::y()
            };
            let u = axis.cross(&helper).normalize();
            let v = axis.cross(&u);
            for (beta, n) in [(half * 0.5, 6usize), (half, 12usize)] {
                for k in 0..n {
                    let psi = core::f64::consts::TAU * k as f64 / n as f64;
                    dirs.push(axis * beta.cos() + (u * psi.cos() + v * psi.sin()) * beta.sin());
                }
            }
        }
        dirs.iter()
            .filter_map(|d| self.ray_cast(pos_ned_m, *d, max_range_m))
            .min_by(|a, b| a.range_m.total_cmp(&b.range_m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxed() -> Terrain {
        Terrain {
            boxes: vec![TerrainBox {
                north_min_m: 5.0,
                north_max_m: 8.0,
                east_min_m: -2.0,
                east_max_m: 2.0,
                height_m: 0.5,
            }],
            dark_patches: vec![
                DarkPatch {
                    north_min_m: -1.0,
                    north_max_m: 1.0,
                    east_min_m: -1.0,
                    east_max_m: 1.0,
                    ..Default::default()
                },
                DarkPatch {
                    center_north_m: 20.0,
                    radius_m: Some(2.0),
                    ..Default::default()
                },
                DarkPatch {
                    north_min_m: 30.0,
                    from_s: Some(105.0),
                    to_s: Some(184.0),
                    ..Default::default()
                },
            ],
        }
    }

    #[test]
    fn heights_and_darkness() {
        let t = boxed();
        assert_eq!(t.height_at(0.0, 0.0), 0.0);
        assert_eq!(t.height_at(6.0, 0.0), 0.5);
        assert_eq!(t.ground_down_at(6.0, 0.0), -0.5);
        assert_eq!(t.height_at(6.0, 3.0), 0.0);
        assert!(t.is_dark(0.5, -0.5, 0.0));
        assert!(!t.is_dark(1.5, 0.0, 0.0));
        assert!(t.is_dark(21.9, 0.0, 0.0) && !t.is_dark(21.5, 1.5, 0.0));
        assert!(!t.is_dark(40.0, 0.0, 104.9));
        assert!(t.is_dark(40.0, 0.0, 105.0) && t.is_dark(40.0, 99.0, 183.9));
        assert!(!t.is_dark(40.0, 0.0, 184.0));
        assert!(!t.is_dark(29.0, 0.0, 150.0));
    }

    #[test]
    fn yaml() {
        let y = "boxes:\n  - { north_min_m: 5, north_max_m: 8, east_min_m: -2, east_max_m: 2, height_m: 0.5 }\n\
                 dark_patches:\n  - { north_min_m: -1, north_max_m: 1, east_min_m: -1, east_max_m: 1 }\n  \
                 - { center_north_m: 20, radius_m: 2 }\n  - { north_min_m: 30, from_s: 105, to_s: 184 }\n";
        let t: Terrain = serde_yaml::from_str(y).unwrap();
        assert_eq!(t, boxed());
        // The paper's ground test: dark everywhere from 105 s to 184 s.
        let g: Terrain =
            serde_yaml::from_str("dark_patches: [{ from_s: 105, to_s: 184 }]").unwrap();
        assert!(g.is_dark(1e6, -1e6, 150.0) && !g.is_dark(0.0, 0.0, 100.0));
        let e: Terrain = serde_yaml::from_str("{}").unwrap();
        assert_eq!(e, Terrain::flat());
        assert!(serde_yaml::from_str::<Terrain>("bxes: []").is_err());
    }

    #[test]
    fn ray_cast_flat_tilted_and_box() {
        let t = boxed();
        let level = UnitQuaternion::identity();
        let h = t
            .range_body_down(Vector3::new(0.0, 0.0, -2.0), &level, 150.0)
            .unwrap();
        assert!((h.range_m - 2.0).abs() < 1e-12 && h.incidence_rad.abs() < 1e-9);
        let roll = 20f64.to_radians();
        let q = UnitQuaternion::from_euler_angles(roll, 0.0, 0.3);
        let h = t
            .range_body_down(Vector3::new(0.0, 0.0, -2.0), &q, 150.0)
            .unwrap();
        assert!((h.range_m - 2.0 / roll.cos()).abs() < 1e-9);
        assert!((h.incidence_rad - roll).abs() < 1e-9);
        // Over the box top.
        let h = t
            .range_body_down(Vector3::new(6.0, 0.0, -2.0), &level, 150.0)
            .unwrap();
        assert!((h.range_m - 1.5).abs() < 1e-12);
        // Beyond max range: none.
        assert!(t
            .range_body_down(Vector3::new(0.0, 0.0, -2.0), &level, 1.9)
            .is_none());
        // A shallow ray from 4.5 m north, 0.3 m up, toward the box: hits its side wall at
        // north 5 (down −0.05), with the wall's horizontal normal.
        let h = t
            .ray_cast(
                Vector3::new(4.5, 0.0, -0.3),
                Vector3::new(1.0, 0.0, 0.5),
                10.0,
            )
            .unwrap();
        assert!((h.point_ned_m.x - 5.0).abs() < 1e-9, "{:?}", h.point_ned_m);
        assert_eq!(h.normal_ned, Vector3::new(-1.0, 0.0, 0.0));
        // Pointing up: nothing.
        let up = UnitQuaternion::from_euler_angles(std::f64::consts::PI, 0.0, 0.0);
        assert!(t
            .range_body_down(Vector3::new(0.0, 0.0, -2.0), &up, 150.0)
            .is_none());
    }

    #[test]
    fn cone_sees_nearest_surface() {
        let t = boxed();
        let p = Vector3::new(0.0, 0.0, -1.0);
        let half = 15f64.to_radians();
        // Tilt within the beam: straight down.
        let q = UnitQuaternion::from_euler_angles(10f64.to_radians(), 0.0, 0.0);
        let h = t.range_cone(p, &q, half, 10.68).unwrap();
        assert!((h.range_m - 1.0).abs() < 1e-9);
        // 30° and 45°: the cone edge nearest vertical.
        for deg in [30.0f64, 45.0] {
            let q = UnitQuaternion::from_euler_angles(deg.to_radians(), 0.0, 0.0);
            let h = t.range_cone(p, &q, half, 10.68).unwrap();
            let expect = 1.0 / (deg.to_radians() - half).cos();
            assert!((h.range_m - expect).abs() < 1e-9, "{deg}: {}", h.range_m);
        }
        // Next to the box edge (0.2 m short of it at 2 m up): the cone clips the box top.
        let p = Vector3::new(4.8, 0.0, -2.0);
        let level = UnitQuaternion::identity();
        let narrow = t.range_body_down(p, &level, 10.68).unwrap().range_m;
        let wide = t.range_cone(p, &level, half, 10.68).unwrap().range_m;
        assert!((narrow - 2.0).abs() < 1e-9);
        assert!((1.5..1.6).contains(&wide), "{wide}");
    }
}
