//! WGS-84 geodesy in `f64`: geodetic LLA ↔ ECEF ↔ local NED tangent plane.
//!
//! Latitude/longitude in degrees (north/east positive), altitude in metres above the
//! ellipsoid (up positive). Local NED is the tangent frame at a reference origin, so
//! `ned[2] = −(alt − alt_origin)` for points above the origin.

use libm::{atan2, cos, sin, sqrt};

/// WGS-84 semi-major axis \[m].
pub const WGS84_A_M: f64 = 6_378_137.0;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// WGS-84 first eccentricity squared.
pub const WGS84_E2: f64 = WGS84_F * (2.0 - WGS84_F);
/// WGS-84 semi-minor axis \[m].
pub const WGS84_B_M: f64 = WGS84_A_M * (1.0 - WGS84_F);

/// Geodetic position.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Lla {
    /// Latitude \[deg], north positive.
    pub lat_deg: f64,
    /// Longitude \[deg], east positive.
    pub lon_deg: f64,
    /// Height above the WGS-84 ellipsoid \[m], up positive.
    pub alt_m: f64,
}

/// Geodetic → ECEF \[m].
pub fn lla_to_ecef(l: &Lla) -> [f64; 3] {
    let lat = l.lat_deg.to_radians();
    let lon = l.lon_deg.to_radians();
    let (sl, cl) = (sin(lat), cos(lat));
    let n = WGS84_A_M / sqrt(1.0 - WGS84_E2 * sl * sl);
    [
        (n + l.alt_m) * cl * cos(lon),
        (n + l.alt_m) * cl * sin(lon),
        (n * (1.0 - WGS84_E2) + l.alt_m) * sl,
    ]
}

/// ECEF \[m] → geodetic. Bowring's closed form followed by two fixed-point refinements of
/// `tan φ = (z + e²·N·sin φ)/p`; sub-millimetre for terrestrial and aviation heights, valid at
/// the poles.
pub fn ecef_to_lla(x: [f64; 3]) -> Lla {
    let [x, y, z] = x;
    let p = sqrt(x * x + y * y);
    let lon = atan2(y, x);
    let ep2 = (WGS84_A_M * WGS84_A_M - WGS84_B_M * WGS84_B_M) / (WGS84_B_M * WGS84_B_M);
    let th = atan2(z * WGS84_A_M, p * WGS84_B_M);
    let (st, ct) = (sin(th), cos(th));
    let mut lat = atan2(
        z + ep2 * WGS84_B_M * st * st * st,
        p - WGS84_E2 * WGS84_A_M * ct * ct * ct,
    );
    for _ in 0..2 {
        let sl = sin(lat);
        let n = WGS84_A_M / sqrt(1.0 - WGS84_E2 * sl * sl);
        lat = atan2(z + WGS84_E2 * n * sl, p);
    }
    let (sl, cl) = (sin(lat), cos(lat));
    let alt = p * cl + z * sl - WGS84_A_M * sqrt(1.0 - WGS84_E2 * sl * sl);
    Lla {
        lat_deg: lat.to_degrees(),
        lon_deg: lon.to_degrees(),
        alt_m: alt,
    }
}

/// Local NED tangent frame at a fixed origin.
#[derive(Clone, Copy, Debug)]
pub struct LocalNed {
    origin: Lla,
    origin_ecef: [f64; 3],
    /// Rows: N, E, D unit vectors expressed in ECEF (ECEF → NED rotation).
    rot: [[f64; 3]; 3],
}

impl LocalNed {
    /// Frame with origin `origin`.
    pub fn new(origin: Lla) -> Self {
        let lat = origin.lat_deg.to_radians();
        let lon = origin.lon_deg.to_radians();
        let (sl, cl) = (sin(lat), cos(lat));
        let (so, co) = (sin(lon), cos(lon));
        Self {
            origin,
            origin_ecef: lla_to_ecef(&origin),
            rot: [
                [-sl * co, -sl * so, cl],
                [-so, co, 0.0],
                [-cl * co, -cl * so, -sl],
            ],
        }
    }

    /// The origin.
    pub fn origin(&self) -> Lla {
        self.origin
    }

    /// Geodetic → local NED \[m].
    pub fn lla_to_ned(&self, l: &Lla) -> [f64; 3] {
        let p = lla_to_ecef(l);
        let d = [
            p[0] - self.origin_ecef[0],
            p[1] - self.origin_ecef[1],
            p[2] - self.origin_ecef[2],
        ];
        self.rot.map(|r| r[0] * d[0] + r[1] * d[1] + r[2] * d[2])
    }

    /// Local NED \[m] → geodetic.
    pub fn ned_to_lla(&self, ned: [f64; 3]) -> Lla {
        let r = &self.rot;
        let mut p = self.origin_ecef;
        for (j, pj) in p.iter_mut().enumerate() {
            *pj += r[0][j] * ned[0] + r[1][j] * ned[1] + r[2][j] * ned[2];
        }
        ecef_to_lla(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lla(lat_deg: f64, lon_deg: f64, alt_m: f64) -> Lla {
        Lla {
            lat_deg,
            lon_deg,
            alt_m,
        }
    }

    fn close3(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < tol)
    }

    #[test]
    fn known_ecef_points() {
        assert!(close3(
            lla_to_ecef(&lla(0.0, 0.0, 0.0)),
            [WGS84_A_M, 0.0, 0.0],
            1e-6
        ));
        assert!(close3(
            lla_to_ecef(&lla(0.0, 90.0, 100.0)),
            [0.0, WGS84_A_M + 100.0, 0.0],
            1e-6
        ));
        assert!(close3(
            lla_to_ecef(&lla(90.0, 0.0, 0.0)),
            [0.0, 0.0, 6_356_752.314_245],
            1e-3
        ));
        assert!(close3(
            lla_to_ecef(&lla(-90.0, 0.0, 0.0)),
            [0.0, 0.0, -6_356_752.314_245],
            1e-3
        ));
        // 45°N 0°E: N = a/sqrt(1 − e²/2), x = N·cos45, z = N(1−e²)·sin45
        let n = WGS84_A_M / (1.0 - WGS84_E2 / 2.0).sqrt();
        let s = core::f64::consts::FRAC_1_SQRT_2;
        assert!(close3(
            lla_to_ecef(&lla(45.0, 0.0, 0.0)),
            [n * s, 0.0, n * (1.0 - WGS84_E2) * s],
            1e-6
        ));
        // GPS-textbook value: 4_510_731 / 4_510_731 / 4_487_348 m ≈ 45°N 45°E 0 m (rounded)
        let e = lla_to_ecef(&lla(45.0, 45.0, 0.0));
        assert!(
            close3(e, [3_194_419.145, 3_194_419.145, 4_487_348.409], 1.0),
            "{e:?}"
        );
    }

    #[test]
    fn ecef_round_trip_mm() {
        for &(la, lo, h) in &[
            (37.5665, 126.978, 38.0),
            (-33.86, 151.21, 5000.0),
            (89.9999, 10.0, 100.0),
            (90.0, 0.0, 0.0),
            (-90.0, 0.0, 1234.0),
            (0.0, -180.0, -50.0),
            (60.0, -45.0, 12_000.0),
        ] {
            let l = lla(la, lo, h);
            let b = ecef_to_lla(lla_to_ecef(&l));
            let back = lla_to_ecef(&b);
            assert!(close3(back, lla_to_ecef(&l), 1e-3), "{l:?} -> {b:?}");
            assert!((b.alt_m - h).abs() < 1e-3, "{l:?} -> {b:?}");
            assert!((b.lat_deg - la).abs() < 1e-8, "{l:?} -> {b:?}");
        }
    }

    #[test]
    fn ned_signs_and_scale() {
        let o = lla(37.5, 127.0, 50.0);
        let f = LocalNed::new(o);
        assert_eq!(f.origin(), o);
        assert!(close3(f.lla_to_ned(&o), [0.0; 3], 1e-6));
        // 1e-5° latitude ≈ 1.11 m north
        let n = f.lla_to_ned(&lla(37.50001, 127.0, 50.0));
        assert!(
            n[0] > 1.10 && n[0] < 1.12 && n[1].abs() < 1e-6 && n[2].abs() < 1e-3,
            "{n:?}"
        );
        // 1e-5° longitude ≈ 1.11·cos(lat) m east
        let e = f.lla_to_ned(&lla(37.5, 127.00001, 50.0));
        assert!(e[1] > 0.87 && e[1] < 0.89 && e[0].abs() < 1e-3, "{e:?}");
        // up 10 m = down −10 m
        let u = f.lla_to_ned(&lla(37.5, 127.0, 60.0));
        assert!((u[2] + 10.0).abs() < 1e-6 && u[0].abs() < 1e-6, "{u:?}");
    }

    #[test]
    fn ned_round_trip_mm() {
        let f = LocalNed::new(lla(37.5, 127.0, 50.0));
        for &ned in &[
            [100.0, -250.0, -30.0],
            [5000.0, 3000.0, 10.0],
            [-1.0, 0.5, 0.0],
        ] {
            let l = f.ned_to_lla(ned);
            assert!(close3(f.lla_to_ned(&l), ned, 1e-3), "{ned:?}");
        }
        let l = lla(37.51, 126.99, 80.0);
        let b = f.ned_to_lla(f.lla_to_ned(&l));
        assert!(close3(lla_to_ecef(&b), lla_to_ecef(&l), 1e-3));
    }
}
