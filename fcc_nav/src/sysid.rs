//! "3D curve fitting" (paper A, Fig. 12): streaming least-squares fits of paper A's horizontal
//! model to flight samples (tilt, velocity, acceleration).
//!
//! * [`PlaneFit`]: the plane `a = k1·θ − k2·v` (no intercept) on samples of one axis, as
//!   paper A fits it. Right in calm air only: the drag term is about the **air-relative**
//!   velocity, so in a wind `w` the model is `a = k1·θ − k2·(v − w)`, and a hover against the
//!   wind (`v = 0`, `a = 0`, `θ = −k2·w/k1 ≠ 0`) pulls the fitted k1 towards 0.
//! * [`WindPlaneFit`]: the model with the wind, estimated from the log itself. Per horizontal
//!   axis `j` (N, E) of a fixed frame and per time window `m` in which the wind is taken as
//!   constant,
//!
//!   ```text
//!   a_j(t) = k1·θ_j(t) − k2·v_j(t) + c_jm,      c_jm = k2·w_jm     (t in window m)
//!   ```
//!
//!   with `θ_j` the tilt that accelerates along axis j (the heading-frame tilt
//!   `[−pitch, roll]` rotated by the yaw into N, E). Fitting in N, E with a per-window wind
//!   is the same as paper A's heading-frame model `a_fr = k1·θ_fr − k2·(v_fr − R(ψ)·w_ne)`:
//!   the rotation is orthogonal and k1, k2 are shared by both axes, so every sum of squares is
//!   unchanged. The per-window intercepts are eliminated exactly (Frisch–Waugh–Lovell): the
//!   least-squares k1, k2 of the model with intercepts are those of the plane without intercept
//!   fitted to the samples centred on their window means, and the 2×2 block of `(XᵀX)⁻¹` that
//!   gives their covariance is the inverse of the centred normal matrix. So only per-window
//!   and pooled centred sums are kept: heap-free and O(1) per sample.
//!
//! * [`WindIvFit`]: the same model and windows, estimated with instrumental variables. In
//!   closed loop the controller tilts against every gust, so the tilt is correlated with the
//!   part of the wind a window's constant does not hold (`k2·(w(t) − w_m)`, which stays in
//!   the residual), and least squares reads "tilt without acceleration" again: k1 and k2 come
//!   out low by the gusts' share. Instruments `z` that move tilt and velocity but not the
//!   wind — the velocity setpoints of the mission, now and delayed — give
//!   `[k1, −k2] = (ZᵀX)⁻¹·Zᵀa` (X = [θ, v], all centred per window and axis), consistent
//!   because `E[z·(residual)] = 0`, with covariance `σ²·(ZᵀX)⁻¹·ZᵀZ·(XᵀZ)⁻¹`.
//!
//! Sums are kept in `f64` (host tools and tests; the flight core does not link this module).

use libm::sqrt;

/// Result of a plane fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneFitResult {
    /// Tilt-to-acceleration gain k1 \[m/s² per rad].
    pub k1_mps2_per_rad: f32,
    /// Linear drag coefficient k2 \[1/s].
    pub k2_per_s: f32,
    /// RMS of the residuals \[m/s²].
    pub rms_residual_mps2: f32,
    /// Coefficient of determination (vs the mean of `a`), 1 = perfect.
    pub r_squared: f32,
}

/// Streaming least-squares accumulator.
#[derive(Clone, Copy, Debug, Default)]
pub struct PlaneFit {
    n: u32,
    s_tt: f64,
    s_tv: f64,
    s_vv: f64,
    s_ta: f64,
    s_va: f64,
    s_aa: f64,
    s_a: f64,
}

impl PlaneFit {
    /// Empty accumulator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add one sample: tilt \[rad], velocity \[m/s], acceleration \[m/s²].
    pub fn add(&mut self, tilt_rad: f32, vel_mps: f32, accel_mps2: f32) {
        let (t, v, a) = (tilt_rad as f64, vel_mps as f64, accel_mps2 as f64);
        self.n = self.n.saturating_add(1);
        self.s_tt += t * t;
        self.s_tv += t * v;
        self.s_vv += v * v;
        self.s_ta += t * a;
        self.s_va += v * a;
        self.s_aa += a * a;
        self.s_a += a;
    }

    /// Number of samples added.
    pub fn count(&self) -> u32 {
        self.n
    }

    /// Solve the normal equations. `None` with fewer than 3 samples or when tilt and velocity
    /// are (nearly) collinear or constant zero (normalised determinant < 1e−6).
    pub fn solve(&self) -> Option<PlaneFitResult> {
        if self.n < 3 {
            return None;
        }
        let det = self.s_tt * self.s_vv - self.s_tv * self.s_tv;
        let scale = self.s_tt * self.s_vv;
        if scale.is_nan() || scale <= 0.0 || det <= 1e-6 * scale {
            return None;
        }
        // [s_tt s_tv; s_tv s_vv]·[k1; c] = [s_ta; s_va], c = −k2
        let k1 = (self.s_ta * self.s_vv - self.s_tv * self.s_va) / det;
        let c = (self.s_tt * self.s_va - self.s_tv * self.s_ta) / det;
        let n = self.n as f64;
        let ssr = (self.s_aa - k1 * self.s_ta - c * self.s_va).max(0.0);
        let sst = self.s_aa - self.s_a * self.s_a / n;
        let r2 = if sst > 0.0 { 1.0 - ssr / sst } else { 1.0 };
        Some(PlaneFitResult {
            k1_mps2_per_rad: k1 as f32,
            k2_per_s: -c as f32,
            rms_residual_mps2: sqrt(ssr / n) as f32,
            r_squared: r2 as f32,
        })
    }
}

/// Two-sided 95 % quantile of Student's t with `dof` degrees of freedom (Cornish–Fisher
/// expansion about the normal quantile 1.959964 to 1/dof²: within 2 % of the exact value for
/// `dof ≥ 4`, 0.2 % for `dof ≥ 10`, exact in the limit). `f32::INFINITY` for `dof == 0`.
pub fn t95(dof: u32) -> f32 {
    if dof == 0 {
        return f32::INFINITY;
    }
    let z = 1.959_964_f64;
    let n = dof as f64;
    let z3 = z * z * z;
    let z5 = z3 * z * z;
    (z + (z3 + z) / (4.0 * n) + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * n * n)) as f32
}

/// Factor by which the standard error of a regression coefficient grows when the residuals are
/// a first-order autoregressive process with lag-1 correlation `rho` instead of white noise:
/// `√((1 + ρ)/(1 − ρ))` (the variance of a mean of AR(1) samples; it bounds the coefficient's
/// inflation `√((1 + ρ·ρₓ)/(1 − ρ·ρₓ))` for any regressor correlation `ρₓ ≤ 1`, so it is the
/// conservative choice for slowly varying tilt and velocity). `rho` is clamped to [0, 0.9999]
/// (a negative correlation would shrink the interval; it is not trusted to).
pub fn ar1_inflation(rho: f32) -> f32 {
    let r = if rho.is_nan() {
        0.9999
    } else {
        rho.clamp(0.0, 0.9999) as f64
    };
    sqrt((1.0 + r) / (1.0 - r)) as f32
}

/// Sums of one axis's samples (tilt `t`, velocity `v`, acceleration `a`).
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    n: u32,
    s_t: f64,
    s_v: f64,
    s_a: f64,
    s_tt: f64,
    s_tv: f64,
    s_vv: f64,
    s_ta: f64,
    s_va: f64,
    s_aa: f64,
}

impl Moments {
    fn add(&mut self, t: f64, v: f64, a: f64) {
        self.n = self.n.saturating_add(1);
        self.s_t += t;
        self.s_v += v;
        self.s_a += a;
        self.s_tt += t * t;
        self.s_tv += t * v;
        self.s_vv += v * v;
        self.s_ta += t * a;
        self.s_va += v * a;
        self.s_aa += a * a;
    }

    /// Adds `o`'s products centred on `o`'s means (`Σxy − Σx·Σy/n`).
    fn add_centred(&mut self, o: &Moments) {
        if o.n == 0 {
            return;
        }
        let n = o.n as f64;
        self.n = self.n.saturating_add(o.n);
        self.s_tt += o.s_tt - o.s_t * o.s_t / n;
        self.s_tv += o.s_tv - o.s_t * o.s_v / n;
        self.s_vv += o.s_vv - o.s_v * o.s_v / n;
        self.s_ta += o.s_ta - o.s_t * o.s_a / n;
        self.s_va += o.s_va - o.s_v * o.s_a / n;
        self.s_aa += o.s_aa - o.s_a * o.s_a / n;
    }
}

/// Means of one closed window of a [`WindPlaneFit`] (per axis N, E), enough to recover the
/// window's wind once k1 and k2 are known ([`WindowMeans::wind_ne_mps`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WindowMeans {
    /// Samples in the window.
    pub samples: u32,
    /// Mean tilt N, E \[rad].
    pub tilt_ne_rad: [f32; 2],
    /// Mean ground velocity N, E \[m/s].
    pub vel_ne_mps: [f32; 2],
    /// Mean acceleration N, E \[m/s²].
    pub accel_ne_mps2: [f32; 2],
}

impl WindowMeans {
    /// The window's intercept `c = ā − k1·θ̄ + k2·v̄` \[m/s²] per axis (the least-squares
    /// intercept for given k1, k2).
    pub fn intercept_ne_mps2(&self, k1_mps2_per_rad: f32, k2_per_s: f32) -> [f32; 2] {
        let c = |j: usize| {
            self.accel_ne_mps2[j] - k1_mps2_per_rad * self.tilt_ne_rad[j]
                + k2_per_s * self.vel_ne_mps[j]
        };
        [c(0), c(1)]
    }

    /// The window's wind `w = c / k2` \[m/s] N, E (velocity of the air, NED; NaN when
    /// `k2 ≤ 0`).
    pub fn wind_ne_mps(&self, k1_mps2_per_rad: f32, k2_per_s: f32) -> [f32; 2] {
        if k2_per_s.is_nan() || k2_per_s <= 0.0 {
            return [f32::NAN; 2];
        }
        let c = self.intercept_ne_mps2(k1_mps2_per_rad, k2_per_s);
        [c[0] / k2_per_s, c[1] / k2_per_s]
    }
}

/// Result of a [`WindPlaneFit`]. Spreads are within-window (about each window's means): the
/// part of the signal that identifies k1 and k2 once the wind is free.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindFitResult {
    /// Tilt-to-acceleration gain k1 \[m/s² per rad].
    pub k1_mps2_per_rad: f32,
    /// Linear drag coefficient k2 \[1/s] (on air-relative velocity).
    pub k2_per_s: f32,
    /// Standard error of k1 from `σ²·(XᵀX)⁻¹` (white residuals assumed; scale by
    /// [`ar1_inflation`] for correlated ones) \[m/s² per rad].
    pub k1_se_mps2_per_rad: f32,
    /// Standard error of k2, likewise \[1/s].
    pub k2_se_per_s: f32,
    /// RMS of the residuals \[m/s²] (`√(SSR / n)`).
    pub rms_residual_mps2: f32,
    /// Residual variance `σ² = SSR / dof` \[m²/s⁴].
    pub residual_var_mps2_sq: f32,
    /// Within-window R²: `1 − SSR / Σ(a − ā_window)²`, the share of the acceleration that is
    /// not wind which k1·θ − k2·v explains (1 = perfect, ≤ 0 = no better than the wind alone).
    pub r_squared: f32,
    /// Scalar equations (2 per sample).
    pub equations: u32,
    /// Intercepts estimated (one per axis per window with samples).
    pub intercepts: u32,
    /// Degrees of freedom of the residual: `equations − 2 − intercepts`.
    pub dof: u32,
    /// Within-window standard deviation of the tilt \[rad] (both axes pooled).
    pub tilt_std_rad: f32,
    /// Within-window standard deviation of the velocity \[m/s].
    pub vel_std_mps: f32,
    /// Within-window standard deviation of the acceleration \[m/s²].
    pub accel_std_mps2: f32,
    /// Correlation of tilt and velocity (within windows).
    pub tilt_vel_corr: f32,
    /// Condition number of the normal matrix scaled to unit diagonal (the correlation matrix
    /// of tilt and velocity): `(1 + |r|)/(1 − |r|)`; independent of units, 1 = orthogonal,
    /// large = tilt and velocity move together and k1, k2 trade off.
    pub condition_number: f32,
    /// [`WindIvFit`] only (NaN for least squares): the smaller singular value of the
    /// correlation matrix between the instruments and (tilt, velocity), within windows. 1 =
    /// the instruments span the regressors, → 0 = weak instruments (the estimate is then
    /// biased towards least squares and its interval unreliable).
    pub instrument_strength: f32,
    /// Cluster-robust standard error of k1 (clusters = windows) \[m/s² per rad]: from the
    /// spread of the windows' score sums, valid for any correlation of the residuals within a
    /// window (gusts, filtering), see [`ClusterMeat`].
    pub k1_se_cluster_mps2_per_rad: f32,
    /// Cluster-robust standard error of k2 \[1/s].
    pub k2_se_cluster_per_s: f32,
    /// Windows (clusters).
    pub clusters: u32,
}

impl WindFitResult {
    /// Half-widths of the cluster-robust 95 % intervals of (k1, k2): `t₀.₉₇₅(clusters − 1) ·
    /// SE_cluster`.
    pub fn ci95_cluster(&self) -> (f32, f32) {
        let t = t95(self.clusters.saturating_sub(1));
        (
            t * self.k1_se_cluster_mps2_per_rad,
            t * self.k2_se_cluster_per_s,
        )
    }

    /// Half-widths of the 95 % confidence intervals of (k1 \[m/s²/rad], k2 \[1/s]):
    /// `t₀.₉₇₅(dof) · inflation · SE`, with `inflation` = [`ar1_inflation`] of the residuals'
    /// lag-1 correlation (1 for white residuals).
    pub fn ci95(&self, inflation: f32) -> (f32, f32) {
        let t = t95(self.dof) * inflation;
        (t * self.k1_se_mps2_per_rad, t * self.k2_se_per_s)
    }
}

/// Cluster-robust ("sandwich") covariance with the windows as clusters. The estimate is
/// `β = B·Σ_m Z_mᵀa_m` with the bread `B` = `(XᵀX)⁻¹` (least squares, Z = X) or `(ZᵀX)⁻¹` (IV),
/// so `β − β_true = B·Σ_m g_m` with the window's score `g_m = Z_mᵀe_m` (both axes summed, all
/// centred in the window), and
///
/// ```text
/// Cov(β) = G/(G − 1) · B·(Σ_m g_m·g_mᵀ)·Bᵀ        (G windows)
/// ```
///
/// holds whatever the correlation of the residuals inside a window, as long as windows are
/// roughly independent (Liang & Zeger 1986). `g_m = za_m − zx_m·β` is linear in β, so the
/// windows' `u_m = [za₀, za₁, zx₀₀, zx₁₀, zx₀₁, zx₁₁]` are summed as `Σ u_m·u_mᵀ` (6×6) in one
/// pass, before β is known. Heap-free.
#[derive(Clone, Copy, Debug, Default)]
pub struct ClusterMeat {
    clusters: u32,
    uu: [[f64; 6]; 6],
}

impl ClusterMeat {
    /// Add one window's centred sums: `za[p] = Σ z_p·a`, `zx[p][q] = Σ z_p·x_q`.
    fn add(&mut self, za: [f64; 2], zx: [[f64; 2]; 2]) {
        let u = [za[0], za[1], zx[0][0], zx[1][0], zx[0][1], zx[1][1]];
        for i in 0..6 {
            for j in 0..6 {
                self.uu[i][j] += u[i] * u[j];
            }
        }
        self.clusters = self.clusters.saturating_add(1);
    }

    /// `Σ_m g_m·g_mᵀ` for the coefficients `beta` (= [k1, −k2]).
    fn meat(&self, beta: [f64; 2]) -> [[f64; 2]; 2] {
        let a = [
            [1.0, 0.0, -beta[0], 0.0, -beta[1], 0.0],
            [0.0, 1.0, 0.0, -beta[0], 0.0, -beta[1]],
        ];
        let mut m = [[0.0; 2]; 2];
        for p in 0..2 {
            for q in 0..2 {
                let mut x = 0.0;
                for i in 0..6 {
                    for j in 0..6 {
                        x += a[p][i] * self.uu[i][j] * a[q][j];
                    }
                }
                m[p][q] = x;
            }
        }
        m
    }

    /// Standard errors of β's two components with the bread `b`; NaN with < 2 clusters.
    fn se(&self, b: [[f64; 2]; 2], beta: [f64; 2]) -> [f64; 2] {
        if self.clusters < 2 {
            return [f64::NAN; 2];
        }
        let g = self.clusters as f64;
        let cov = mul2(mul2(b, self.meat(beta)), transpose2(b));
        let f = g / (g - 1.0);
        [
            sqrt((f * cov[0][0]).max(0.0)),
            sqrt((f * cov[1][1]).max(0.0)),
        ]
    }
}

/// Streaming least-squares fit of `a = k1·θ − k2·v + c` per N/E axis with the intercept
/// `c = k2·w` (the wind) constant within windows that the caller closes with
/// [`WindPlaneFit::end_window`] (see the module doc for the equations).
#[derive(Clone, Copy, Debug, Default)]
pub struct WindPlaneFit {
    /// Current window, per axis.
    win: [Moments; 2],
    /// Centred sums of all closed windows and both axes (first moments unused).
    within: Moments,
    meat: ClusterMeat,
    intercepts: u32,
    windows: u32,
}

impl WindPlaneFit {
    /// Empty fit.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add one sample: tilt N, E \[rad] (the tilt that accelerates north, east), ground
    /// velocity N, E \[m/s], acceleration N, E \[m/s²]. Non-finite samples are skipped.
    pub fn add(&mut self, tilt_ne_rad: [f32; 2], vel_ne_mps: [f32; 2], accel_ne_mps2: [f32; 2]) {
        let ok = tilt_ne_rad
            .iter()
            .chain(&vel_ne_mps)
            .chain(&accel_ne_mps2)
            .all(|x| x.is_finite());
        if !ok {
            return;
        }
        for j in 0..2 {
            self.win[j].add(
                tilt_ne_rad[j] as f64,
                vel_ne_mps[j] as f64,
                accel_ne_mps2[j] as f64,
            );
        }
    }

    /// Close the current window (the next sample starts a new wind); returns its means, or
    /// `None` if it had no sample.
    pub fn end_window(&mut self) -> Option<WindowMeans> {
        let n = self.win[0].n;
        if n == 0 {
            return None;
        }
        let nf = n as f64;
        let m =
            |f: fn(&Moments) -> f64| [(f(&self.win[0]) / nf) as f32, (f(&self.win[1]) / nf) as f32];
        let means = WindowMeans {
            samples: n,
            tilt_ne_rad: m(|x| x.s_t),
            vel_ne_mps: m(|x| x.s_v),
            accel_ne_mps2: m(|x| x.s_a),
        };
        let mut c = Moments::default();
        for j in 0..2 {
            self.within.add_centred(&self.win[j]);
            c.add_centred(&self.win[j]);
        }
        // Instruments = regressors (θ, v).
        self.meat
            .add([c.s_ta, c.s_va], [[c.s_tt, c.s_tv], [c.s_tv, c.s_vv]]);
        self.win = [Moments::default(); 2];
        self.intercepts = self.intercepts.saturating_add(2);
        self.windows = self.windows.saturating_add(1);
        Some(means)
    }

    /// Samples added (closed windows and the open one).
    pub fn count(&self) -> u32 {
        self.within.n / 2 + self.win[0].n
    }

    /// Windows closed.
    pub fn windows(&self) -> u32 {
        self.windows
    }

    /// Solve over the closed windows and the open one. `None` when the residual has no degree
    /// of freedom, or tilt and velocity are (nearly) collinear or constant within the windows
    /// (normalised determinant < 1e−6).
    pub fn solve(&self) -> Option<WindFitResult> {
        let mut all = *self;
        all.end_window();
        let w = &all.within;
        let eq = w.n;
        let dof = eq.checked_sub(2 + all.intercepts).filter(|&d| d > 0)?;
        let det = w.s_tt * w.s_vv - w.s_tv * w.s_tv;
        let scale = w.s_tt * w.s_vv;
        if scale.is_nan() || scale <= 0.0 || det <= 1e-6 * scale {
            return None;
        }
        // [s_tt s_tv; s_tv s_vv]·[k1; −k2] = [s_ta; s_va]
        let k1 = (w.s_ta * w.s_vv - w.s_tv * w.s_va) / det;
        let c = (w.s_tt * w.s_va - w.s_tv * w.s_ta) / det;
        let ssr = (w.s_aa - k1 * w.s_ta - c * w.s_va).max(0.0);
        let var = ssr / dof as f64;
        let r2 = if w.s_aa > 0.0 {
            1.0 - ssr / w.s_aa
        } else {
            1.0
        };
        let r = w.s_tv / sqrt(scale);
        let n = eq as f64;
        let bread = [[w.s_vv / det, -w.s_tv / det], [-w.s_tv / det, w.s_tt / det]];
        let se_c = all.meat.se(bread, [k1, c]);
        Some(WindFitResult {
            k1_mps2_per_rad: k1 as f32,
            k2_per_s: -c as f32,
            k1_se_mps2_per_rad: sqrt(var * w.s_vv / det) as f32,
            k2_se_per_s: sqrt(var * w.s_tt / det) as f32,
            rms_residual_mps2: sqrt(ssr / n) as f32,
            residual_var_mps2_sq: var as f32,
            r_squared: r2 as f32,
            equations: eq,
            intercepts: all.intercepts,
            dof,
            tilt_std_rad: sqrt(w.s_tt / n) as f32,
            vel_std_mps: sqrt(w.s_vv / n) as f32,
            accel_std_mps2: sqrt(w.s_aa / n) as f32,
            tilt_vel_corr: r as f32,
            condition_number: ((1.0 + r.abs()) / (1.0 - r.abs()).max(1e-12)) as f32,
            instrument_strength: f32::NAN,
            k1_se_cluster_mps2_per_rad: se_c[0] as f32,
            k2_se_cluster_per_s: se_c[1] as f32,
            clusters: all.meat.clusters,
        })
    }
}

/// Sums of one axis's samples for [`WindIvFit`]: instruments `z` (2), regressors `x` =
/// (tilt, velocity), acceleration `a`.
#[derive(Clone, Copy, Debug, Default)]
struct IvMoments {
    n: u32,
    s_z: [f64; 2],
    s_x: [f64; 2],
    s_a: f64,
    /// Σ z_p·z_q, Σ z_p·x_q, Σ x_p·x_q, Σ z_p·a, Σ x_p·a, Σ a².
    zz: [[f64; 2]; 2],
    zx: [[f64; 2]; 2],
    xx: [[f64; 2]; 2],
    za: [f64; 2],
    xa: [f64; 2],
    aa: f64,
}

impl IvMoments {
    fn add(&mut self, z: [f64; 2], x: [f64; 2], a: f64) {
        self.n = self.n.saturating_add(1);
        for p in 0..2 {
            self.s_z[p] += z[p];
            self.s_x[p] += x[p];
            self.za[p] += z[p] * a;
            self.xa[p] += x[p] * a;
            for q in 0..2 {
                self.zz[p][q] += z[p] * z[q];
                self.zx[p][q] += z[p] * x[q];
                self.xx[p][q] += x[p] * x[q];
            }
        }
        self.s_a += a;
        self.aa += a * a;
    }

    /// Adds `o`'s products centred on `o`'s means.
    fn add_centred(&mut self, o: &IvMoments) {
        if o.n == 0 {
            return;
        }
        let n = o.n as f64;
        self.n = self.n.saturating_add(o.n);
        for p in 0..2 {
            self.za[p] += o.za[p] - o.s_z[p] * o.s_a / n;
            self.xa[p] += o.xa[p] - o.s_x[p] * o.s_a / n;
            for q in 0..2 {
                self.zz[p][q] += o.zz[p][q] - o.s_z[p] * o.s_z[q] / n;
                self.zx[p][q] += o.zx[p][q] - o.s_z[p] * o.s_x[q] / n;
                self.xx[p][q] += o.xx[p][q] - o.s_x[p] * o.s_x[q] / n;
            }
        }
        self.aa += o.aa - o.s_a * o.s_a / n;
    }
}

/// 2×2 inverse; `None` when singular.
fn inv2(m: [[f64; 2]; 2]) -> Option<[[f64; 2]; 2]> {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let scale = libm::fabs(m[0][0] * m[1][1]) + libm::fabs(m[0][1] * m[1][0]);
    if !det.is_finite() || scale <= 0.0 || libm::fabs(det) <= 1e-9 * scale {
        return None;
    }
    Some([
        [m[1][1] / det, -m[0][1] / det],
        [-m[1][0] / det, m[0][0] / det],
    ])
}

fn mul2(a: [[f64; 2]; 2], b: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    let mut c = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j];
        }
    }
    c
}

fn transpose2(a: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    [[a[0][0], a[1][0]], [a[0][1], a[1][1]]]
}

/// Streaming instrumental-variable fit of `a = k1·θ − k2·v + c` per N/E axis, `c` constant
/// within windows closed with [`WindIvFit::end_window`], with two instruments per axis (see
/// the module doc). Heap-free.
#[derive(Clone, Copy, Debug, Default)]
pub struct WindIvFit {
    win: [IvMoments; 2],
    within: IvMoments,
    meat: ClusterMeat,
    intercepts: u32,
    windows: u32,
}

impl WindIvFit {
    /// Empty fit.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add one sample: instruments per axis `[[z1_n, z2_n], [z1_e, z2_e]]` (e.g. velocity
    /// setpoints \[m/s]), tilt N, E \[rad], ground velocity N, E \[m/s], acceleration N, E
    /// \[m/s²]. Non-finite samples are skipped.
    pub fn add(
        &mut self,
        instr_ne: [[f32; 2]; 2],
        tilt_ne_rad: [f32; 2],
        vel_ne_mps: [f32; 2],
        accel_ne_mps2: [f32; 2],
    ) {
        let ok = instr_ne
            .iter()
            .flatten()
            .chain(&tilt_ne_rad)
            .chain(&vel_ne_mps)
            .chain(&accel_ne_mps2)
            .all(|x| x.is_finite());
        if !ok {
            return;
        }
        for j in 0..2 {
            self.win[j].add(
                [instr_ne[j][0] as f64, instr_ne[j][1] as f64],
                [tilt_ne_rad[j] as f64, vel_ne_mps[j] as f64],
                accel_ne_mps2[j] as f64,
            );
        }
    }

    /// Close the current window (a new wind from the next sample on); `false` if it was empty.
    pub fn end_window(&mut self) -> bool {
        if self.win[0].n == 0 {
            return false;
        }
        let mut c = IvMoments::default();
        for j in 0..2 {
            self.within.add_centred(&self.win[j]);
            c.add_centred(&self.win[j]);
        }
        self.meat.add(c.za, c.zx);
        self.win = [IvMoments::default(); 2];
        self.intercepts = self.intercepts.saturating_add(2);
        self.windows = self.windows.saturating_add(1);
        true
    }

    /// Samples added.
    pub fn count(&self) -> u32 {
        self.within.n / 2 + self.win[0].n
    }

    /// Solve over all windows. `None` without a degree of freedom, or when `ZᵀX` is singular
    /// (instruments constant within the windows or not moving the regressors).
    pub fn solve(&self) -> Option<WindFitResult> {
        let mut all = *self;
        all.end_window();
        let w = &all.within;
        let eq = w.n;
        let dof = eq.checked_sub(2 + all.intercepts).filter(|&d| d > 0)?;
        let zx_inv = inv2(w.zx)?;
        let b = [
            zx_inv[0][0] * w.za[0] + zx_inv[0][1] * w.za[1],
            zx_inv[1][0] * w.za[0] + zx_inv[1][1] * w.za[1],
        ];
        // SSR = aᵀa − 2·bᵀXᵀa + bᵀ·XᵀX·b
        let mut ssr = w.aa - 2.0 * (b[0] * w.xa[0] + b[1] * w.xa[1]);
        for p in 0..2 {
            for q in 0..2 {
                ssr += b[p] * w.xx[p][q] * b[q];
            }
        }
        let ssr = ssr.max(0.0);
        let var = ssr / dof as f64;
        let cov = mul2(mul2(zx_inv, w.zz), transpose2(zx_inv));
        let se_c = all.meat.se(zx_inv, b);
        let n = eq as f64;
        let (sxx, svv, stv) = (w.xx[0][0], w.xx[1][1], w.xx[0][1]);
        let r = if sxx > 0.0 && svv > 0.0 {
            stv / sqrt(sxx * svv)
        } else {
            f64::NAN
        };
        // Correlation matrix of instruments and regressors; its smaller singular value.
        let c = [0, 1].map(|p| [0, 1].map(|q| w.zx[p][q] / sqrt(w.zz[p][p] * w.xx[q][q])));
        let ctc = mul2(transpose2(c), c);
        let (tr, det) = (
            ctc[0][0] + ctc[1][1],
            ctc[0][0] * ctc[1][1] - ctc[0][1] * ctc[1][0],
        );
        let lmin = 0.5 * (tr - sqrt((tr * tr - 4.0 * det).max(0.0)));
        Some(WindFitResult {
            k1_mps2_per_rad: b[0] as f32,
            k2_per_s: -b[1] as f32,
            k1_se_mps2_per_rad: sqrt(var * cov[0][0].max(0.0)) as f32,
            k2_se_per_s: sqrt(var * cov[1][1].max(0.0)) as f32,
            rms_residual_mps2: sqrt(ssr / n) as f32,
            residual_var_mps2_sq: var as f32,
            r_squared: if w.aa > 0.0 { 1.0 - ssr / w.aa } else { 1.0 } as f32,
            equations: eq,
            intercepts: all.intercepts,
            dof,
            tilt_std_rad: sqrt(sxx / n) as f32,
            vel_std_mps: sqrt(svv / n) as f32,
            accel_std_mps2: sqrt(w.aa / n) as f32,
            tilt_vel_corr: r as f32,
            condition_number: ((1.0 + libm::fabs(r)) / (1.0 - libm::fabs(r)).max(1e-12)) as f32,
            instrument_strength: sqrt(lmin.max(0.0)) as f32,
            k1_se_cluster_mps2_per_rad: se_c[0] as f32,
            k2_se_cluster_per_s: se_c[1] as f32,
            clusters: all.meat.clusters,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::Rng;

    #[test]
    fn recovers_k1_k2_from_noisy_samples() {
        let mut rng = Rng::new(21);
        let mut fit = PlaneFit::new();
        let (k1, k2) = (9.5f32, 0.35f32);
        for _ in 0..5000 {
            let th = rng.normal(0.15);
            let v = rng.normal(4.0);
            fit.add(th, v, k1 * th - k2 * v + rng.normal(0.3));
        }
        assert_eq!(fit.count(), 5000);
        let r = fit.solve().unwrap();
        assert!((r.k1_mps2_per_rad - k1).abs() < 0.1, "{r:?}");
        assert!((r.k2_per_s - k2).abs() < 0.01, "{r:?}");
        assert!((r.rms_residual_mps2 - 0.3).abs() < 0.02, "{r:?}");
        assert!(r.r_squared > 0.9 && r.r_squared <= 1.0, "{r:?}");
    }

    #[test]
    fn exact_data_exact_fit() {
        let mut fit = PlaneFit::new();
        for i in 0..10 {
            let th = 0.01 * i as f32;
            let v = 0.5 * ((i * 7) % 5) as f32;
            fit.add(th, v, 8.0 * th - 0.2 * v);
        }
        let r = fit.solve().unwrap();
        assert!((r.k1_mps2_per_rad - 8.0).abs() < 1e-4);
        assert!((r.k2_per_s - 0.2).abs() < 1e-5);
        assert!(r.rms_residual_mps2 < 1e-4);
    }

    #[test]
    fn ill_conditioned_is_none() {
        let mut fit = PlaneFit::new();
        assert!(fit.solve().is_none());
        // v proportional to θ: collinear
        for i in 0..100 {
            let th = 0.01 * i as f32;
            fit.add(th, 3.0 * th, th);
        }
        assert!(fit.solve().is_none());
        // velocity always zero
        let mut fit = PlaneFit::new();
        for i in 0..100 {
            fit.add(0.01 * i as f32, 0.0, 0.1 * i as f32);
        }
        assert!(fit.solve().is_none());
    }

    /// Paper A's model in a wind: `a = k1·θ − k2·(v − w)` with the wind `w` N, E made of a
    /// constant and a slow sinusoid, the tilt = a hover tilt that holds against the wind plus
    /// manoeuvres, measurement noise on the acceleration. Samples at 50 Hz, windows of 5 s.
    fn windy(seed: u64, noise_mps2: f32) -> (PlaneFit, WindPlaneFit, [[f32; 2]; 2]) {
        let (k1, k2) = (9.2f32, 0.28f32);
        let mut rng = Rng::new(seed);
        let (mut plain, mut fit) = (PlaneFit::new(), WindPlaneFit::new());
        let mut first_wind = [[0.0f32; 2]; 2]; // true mean wind, window 0
        for i in 0..30_000 {
            let t = i as f32 * 0.02;
            let w = [
                3.0 + 0.8 * libm::sinf(0.05 * t),
                -1.0 + 0.5 * libm::cosf(0.03 * t),
            ];
            // Manoeuvres: velocity and tilt excursions, not collinear.
            let v = [
                2.0 * libm::sinf(0.31 * t) + rng.normal(0.3),
                1.5 * libm::cosf(0.23 * t) + rng.normal(0.3),
            ];
            let th = [
                -k2 * w[0] / k1 + 0.08 * libm::sinf(0.9 * t) + rng.normal(0.01),
                -k2 * w[1] / k1 + 0.06 * libm::cosf(1.3 * t) + rng.normal(0.01),
            ];
            let a = [
                k1 * th[0] - k2 * (v[0] - w[0]) + rng.normal(noise_mps2),
                k1 * th[1] - k2 * (v[1] - w[1]) + rng.normal(noise_mps2),
            ];
            if i < 250 {
                first_wind[0][0] += w[0] / 250.0;
                first_wind[0][1] += w[1] / 250.0;
            }
            plain.add(th[0], v[0], a[0]);
            plain.add(th[1], v[1], a[1]);
            fit.add(th, v, a);
            if i % 250 == 249 {
                let m = fit.end_window().expect("samples");
                if i == 249 {
                    first_wind[1] = m.wind_ne_mps(k1, k2);
                }
            }
        }
        (plain, fit, first_wind)
    }

    #[test]
    fn wind_term_removes_the_bias_of_the_plain_fit() {
        let (plain, fit, wind) = windy(5, 0.3);
        let p = plain.solve().unwrap();
        // Without the wind, the hover tilt against the wind is "tilt without acceleration".
        assert!(p.k1_mps2_per_rad < 0.8 * 9.2, "{p:?}");
        let r = fit.solve().unwrap();
        assert_eq!(fit.count(), 30_000);
        assert_eq!(fit.windows(), 120);
        assert_eq!(
            (r.equations, r.intercepts, r.dof),
            (60_000, 240, 60_000 - 242)
        );
        assert!((r.k1_mps2_per_rad - 9.2).abs() < 0.02 * 9.2, "{r:?}");
        assert!((r.k2_per_s - 0.28).abs() < 0.02 * 0.28, "{r:?}");
        // The truth lies inside the 95 % intervals (white noise here: no inflation).
        let (c1, c2) = r.ci95(1.0);
        assert!(
            (r.k1_mps2_per_rad - 9.2).abs() < c1 && c1 < 0.05,
            "{r:?} ±{c1}"
        );
        assert!((r.k2_per_s - 0.28).abs() < c2 && c2 < 0.01, "{r:?} ±{c2}");
        assert!((r.rms_residual_mps2 - 0.3).abs() < 0.01, "{r:?}");
        assert!(r.r_squared > 0.65 && r.r_squared < 0.8, "{r:?}"); // signal var ≈ 0.23, noise 0.09
                                                                   // The window's wind comes back (true mean wind vs estimate, m/s).
        for j in 0..2 {
            assert!((wind[0][j] - wind[1][j]).abs() < 0.3, "{wind:?}");
        }
        assert!(
            r.condition_number >= 1.0 && r.condition_number < 2.0,
            "{r:?}"
        );
        assert!((r.tilt_std_rad - 0.05).abs() < 0.01, "{r:?}");
    }

    #[test]
    fn standard_errors_match_the_spread_over_repeated_flights() {
        // 200 independent noisy data sets: the spread of k1 equals the reported standard
        // error, and the 95 % interval holds the truth about 95 % of the time.
        let (mut k1s, mut se, mut inside) = (std::vec::Vec::new(), 0.0f64, 0);
        for seed in 0..200 {
            let mut rng = Rng::new(1000 + seed);
            let mut fit = WindPlaneFit::new();
            for i in 0..400 {
                let th = [rng.normal(0.05), rng.normal(0.05)];
                let v = [rng.normal(1.0), rng.normal(1.0)];
                let w = [2.0 + (i / 100) as f32, -1.0];
                let a = [
                    9.0 * th[0] - 0.3 * (v[0] - w[0]) + rng.normal(0.5),
                    9.0 * th[1] - 0.3 * (v[1] - w[1]) + rng.normal(0.5),
                ];
                fit.add(th, v, a);
                if i % 100 == 99 {
                    fit.end_window();
                }
            }
            let r = fit.solve().unwrap();
            k1s.push(r.k1_mps2_per_rad as f64);
            se += r.k1_se_mps2_per_rad as f64 / 200.0;
            if (r.k1_mps2_per_rad - 9.0).abs() < r.ci95(1.0).0 {
                inside += 1;
            }
        }
        let m = k1s.iter().sum::<f64>() / 200.0;
        let sd = libm::sqrt(k1s.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / 199.0);
        assert!((m - 9.0).abs() < 0.05, "{m}");
        assert!((sd / se - 1.0).abs() < 0.15, "sd {sd} se {se}");
        assert!((180..=198).contains(&inside), "{inside}/200");
    }

    #[test]
    fn wind_fit_exact_and_degenerate_cases() {
        let mut fit = WindPlaneFit::new();
        assert!(fit.solve().is_none());
        assert!(fit.end_window().is_none());
        for i in 0..40 {
            let th = [0.01 * (i % 7) as f32, -0.02 * (i % 3) as f32];
            let v = [0.5 * ((i * 7) % 5) as f32, 0.3 * (i % 4) as f32];
            let w = if i < 20 { [3.0, 1.0] } else { [-2.0, 0.5] };
            fit.add(
                th,
                v,
                [
                    8.0 * th[0] - 0.2 * (v[0] - w[0]),
                    8.0 * th[1] - 0.2 * (v[1] - w[1]),
                ],
            );
            if i == 19 {
                let m = fit.end_window().unwrap();
                assert_eq!(m.samples, 20);
                let w = m.wind_ne_mps(8.0, 0.2);
                assert!(
                    (w[0] - 3.0).abs() < 1e-4 && (w[1] - 1.0).abs() < 1e-4,
                    "{w:?}"
                );
            }
        }
        fit.add([f32::NAN, 0.0], [0.0; 2], [0.0; 2]); // skipped
        assert_eq!(fit.count(), 40);
        let r = fit.solve().unwrap();
        assert!((r.k1_mps2_per_rad - 8.0).abs() < 1e-3, "{r:?}");
        assert!((r.k2_per_s - 0.2).abs() < 1e-4, "{r:?}");
        assert!(
            r.rms_residual_mps2 < 1e-4 && r.k1_se_mps2_per_rad < 1e-3,
            "{r:?}"
        );
        assert_eq!((r.intercepts, r.dof), (4, 80 - 6));
        // Velocity proportional to tilt within the windows: no fit.
        let mut fit = WindPlaneFit::new();
        for i in 0..100 {
            let th = 0.01 * i as f32;
            fit.add([th, -th], [3.0 * th + 1.0, -3.0 * th], [th, th]);
        }
        assert!(fit.solve().is_none());
        // A tilt that changes only between windows carries no information once the wind is
        // free: every window is absorbed by its intercept.
        let mut fit = WindPlaneFit::new();
        for i in 0..100 {
            let th = 0.01 * (i / 10) as f32;
            fit.add([th, th], [0.1 * (i % 10) as f32; 2], [th; 2]);
            if i % 10 == 9 {
                fit.end_window();
            }
        }
        assert!(fit.solve().is_none());
        // One sample per window: no degree of freedom left.
        let mut fit = WindPlaneFit::new();
        for i in 0..10 {
            fit.add([0.01 * i as f32; 2], [0.1; 2], [0.1; 2]);
            fit.end_window();
        }
        assert!(fit.solve().is_none());
    }

    #[test]
    fn t_quantile_and_ar1_inflation() {
        // Exact two-sided 95 % t quantiles.
        for (dof, t) in [
            (4, 2.776),
            (5, 2.571),
            (10, 2.228),
            (30, 2.042),
            (1000, 1.962),
        ] {
            let e = (t95(dof) - t) / t;
            assert!(
                e.abs() < if dof < 10 { 0.02 } else { 0.002 },
                "{dof}: {}",
                t95(dof)
            );
        }
        assert!(t95(0).is_infinite());
        assert_eq!(ar1_inflation(0.0), 1.0);
        assert!((ar1_inflation(0.5) - 3f32.sqrt()).abs() < 1e-6);
        assert_eq!(ar1_inflation(-0.5), 1.0);
        assert!(ar1_inflation(1.0) > 100.0 && ar1_inflation(f32::NAN) > 100.0);
        // The variance of the mean of AR(1) noise with ρ = 0.9 is inflated by (1+ρ)/(1−ρ).
        let (rho, n, runs) = (0.9f32, 2000, 300);
        let mut rng = Rng::new(77);
        let mut means = std::vec::Vec::new();
        for _ in 0..runs {
            let mut e = rng.normal(1.0) / libm::sqrtf(1.0 - rho * rho);
            let mut s = 0.0f64;
            for _ in 0..n {
                e = rho * e + rng.normal(1.0);
                s += e as f64;
            }
            means.push(s / n as f64);
        }
        let var = means.iter().map(|m| m * m).sum::<f64>() / runs as f64;
        let white = 1.0 / (1.0 - 0.81) / n as f64; // variance of the mean of white samples
        let got = libm::sqrt(var / white) as f32;
        assert!((got / ar1_inflation(rho) - 1.0).abs() < 0.15, "{got}");
    }

    /// Closed loop with gusts: a PI velocity controller tracks a setpoint square wave and
    /// leans into the wind; the gusts inside a window stay in the residual and the tilt
    /// answers them. Returns (least squares, IV) fits.
    fn closed_loop(seed: u64, gust_mps: f32) -> (WindPlaneFit, WindIvFit) {
        let (k1, k2, dt) = (9.2f32, 0.28f32, 0.01f32);
        let mut rng = Rng::new(seed);
        let (mut ls, mut iv) = (WindPlaneFit::new(), WindIvFit::new());
        let (mut v, mut th, mut integ, mut gust) =
            ([0.0f32; 2], [0.0f32; 2], [0.0f32; 2], [0.0f32; 2]);
        let mut hist = [[0.0f32; 2]; 100]; // setpoints of the last 1 s
        for i in 0..60_000 {
            let t = i as f32 * dt;
            let vc = [
                if (t / 8.0) as i32 % 2 == 0 { 3.0 } else { 0.0 },
                if (t / 11.0) as i32 % 2 == 0 {
                    -2.0
                } else {
                    1.0
                },
            ];
            let delayed = hist[i % 100];
            hist[i % 100] = vc;
            let mut a = [0.0f32; 2];
            for j in 0..2 {
                gust[j] +=
                    -gust[j] * dt / 1.5 + gust_mps * libm::sqrtf(2.0 * dt / 1.5) * rng.normal(1.0);
                let w = [3.0, -1.0][j] + gust[j];
                let e = vc[j] - v[j];
                integ[j] = (integ[j] + 0.5 * e * dt).clamp(-2.0, 2.0);
                let th_cmd = ((1.5 * e + integ[j] + 0.25 * v[j]) / 9.0).clamp(-0.35, 0.35);
                th[j] += (th_cmd - th[j]) * dt / 0.1;
                a[j] = k1 * th[j] - k2 * (v[j] - w);
                v[j] += a[j] * dt;
            }
            let am = [a[0] + rng.normal(0.2), a[1] + rng.normal(0.2)];
            ls.add(th, v, am);
            iv.add([[vc[0], delayed[0]], [vc[1], delayed[1]]], th, v, am);
            if i % 500 == 499 {
                ls.end_window();
                iv.end_window();
            }
        }
        (ls, iv)
    }

    #[test]
    fn instruments_remove_the_gust_bias_of_least_squares() {
        let (ls, iv) = closed_loop(9, 0.8);
        let l = ls.solve().unwrap();
        let r = iv.solve().unwrap();
        assert_eq!(iv.count(), 60_000);
        assert_eq!((r.intercepts, r.dof), (240, 120_000 - 242));
        // Least squares is biased low by the gusts the controller answers, beyond its interval.
        assert!(9.2 - l.k1_mps2_per_rad > 3.0 * l.ci95(1.0).0, "{l:?}");
        assert!(l.k1_mps2_per_rad < 0.985 * 9.2, "{l:?}");
        // IV: the truth within 2 %, a fraction of least squares' error.
        assert!((r.k1_mps2_per_rad - 9.2).abs() < 0.02 * 9.2, "{r:?}");
        assert!(
            (r.k2_per_s - 0.28).abs() < 0.02 * 0.28 + r.ci95(1.0).1,
            "{r:?}"
        );
        // (Not inside the white-noise interval: the gusts make the residual correlated.)
        assert!(
            (r.k1_mps2_per_rad - 9.2).abs() < 0.25 * (l.k1_mps2_per_rad - 9.2).abs(),
            "{r:?}"
        );
        assert!(
            r.instrument_strength > 0.1 && r.instrument_strength <= 1.0,
            "{r:?}"
        );
        assert!(l.instrument_strength.is_nan());
        // Without gusts both agree with the truth.
        let (ls, iv) = closed_loop(10, 0.0);
        let (l, r) = (ls.solve().unwrap(), iv.solve().unwrap());
        assert!((l.k1_mps2_per_rad - 9.2).abs() < 0.01 * 9.2, "{l:?}");
        assert!((r.k1_mps2_per_rad - 9.2).abs() < 0.01 * 9.2, "{r:?}");
    }

    #[test]
    fn iv_with_the_regressors_as_instruments_is_least_squares() {
        let mut rng = Rng::new(4);
        let (mut ls, mut iv) = (WindPlaneFit::new(), WindIvFit::new());
        for i in 0..3000 {
            let th = [rng.normal(0.05), rng.normal(0.05)];
            let v = [rng.normal(1.0), rng.normal(1.0)];
            let a = [
                9.0 * th[0] - 0.3 * v[0] + 0.5 + rng.normal(0.3),
                9.0 * th[1] - 0.3 * v[1] + rng.normal(0.3),
            ];
            ls.add(th, v, a);
            iv.add([[th[0], v[0]], [th[1], v[1]]], th, v, a);
            if i % 300 == 299 {
                ls.end_window();
                iv.end_window();
            }
        }
        let (l, r) = (ls.solve().unwrap(), iv.solve().unwrap());
        for (x, y) in [
            (l.k1_mps2_per_rad, r.k1_mps2_per_rad),
            (l.k2_per_s, r.k2_per_s),
            (l.k1_se_mps2_per_rad, r.k1_se_mps2_per_rad),
            (l.k2_se_per_s, r.k2_se_per_s),
            (l.r_squared, r.r_squared),
        ] {
            assert!((x - y).abs() <= 1e-4 * x.abs().max(1e-3), "{l:?}\n{r:?}");
        }
        // Instruments = regressors: the correlation matrix of (θ, v), smaller singular value 1 − |r|.
        assert!(
            (r.instrument_strength - (1.0 - r.tilt_vel_corr.abs())).abs() < 1e-4,
            "{r:?}"
        );
        // Instruments constant within every window: no fit.
        let mut iv = WindIvFit::new();
        for i in 0..100 {
            let z = (i / 10) as f32;
            iv.add(
                [[z, z], [z, z]],
                [0.01 * (i % 7) as f32; 2],
                [0.1 * (i % 3) as f32; 2],
                [0.0; 2],
            );
            if i % 10 == 9 {
                iv.end_window();
            }
        }
        assert!(iv.solve().is_none());
    }

    #[test]
    fn cluster_standard_errors_hold_with_correlated_residuals() {
        // Residuals and regressors that vary slowly (AR(1), ρ 0.97 and 0.95 per sample):
        // white-noise standard errors are far too small, the window-clustered ones match the
        // spread over 300 data sets; for IV (instruments = a noisy copy of the regressors) too.
        let runs = 300;
        let (mut k1s, mut k1s_iv) = (std::vec::Vec::new(), std::vec::Vec::new());
        let (mut se_w, mut se_c, mut se_c_iv) = (0.0f64, 0.0f64, 0.0f64);
        for seed in 0..runs {
            let mut rng = Rng::new(5000 + seed);
            let (mut ls, mut iv) = (WindPlaneFit::new(), WindIvFit::new());
            let (mut e, mut th, mut v) = ([0.0f32; 2], [0.0f32; 2], [0.0f32; 2]);
            for i in 0..4000 {
                let (mut a, mut z) = ([0.0f32; 2], [[0.0f32; 2]; 2]);
                for j in 0..2 {
                    e[j] = 0.97 * e[j] + rng.normal(0.1);
                    th[j] = 0.95 * th[j] + rng.normal(0.02);
                    v[j] = 0.95 * v[j] + rng.normal(0.3);
                    a[j] = 9.0 * th[j] - 0.3 * v[j] + e[j];
                    z[j] = [th[j] + rng.normal(0.02), v[j] + rng.normal(0.3)];
                }
                ls.add(th, v, a);
                iv.add(z, th, v, a);
                if i % 100 == 99 {
                    ls.end_window();
                    iv.end_window();
                }
            }
            let (l, r) = (ls.solve().unwrap(), iv.solve().unwrap());
            assert_eq!((l.clusters, r.clusters), (40, 40));
            k1s.push(l.k1_mps2_per_rad as f64);
            k1s_iv.push(r.k1_mps2_per_rad as f64);
            se_w += l.k1_se_mps2_per_rad as f64 / runs as f64;
            se_c += l.k1_se_cluster_mps2_per_rad as f64 / runs as f64;
            se_c_iv += r.k1_se_cluster_mps2_per_rad as f64 / runs as f64;
        }
        let sd = |x: &[f64]| {
            let m = x.iter().sum::<f64>() / x.len() as f64;
            libm::sqrt(x.iter().map(|y| (y - m) * (y - m)).sum::<f64>() / (x.len() - 1) as f64)
        };
        let (s, s_iv) = (sd(&k1s), sd(&k1s_iv));
        std::println!("sd {s} white {se_w} cluster {se_c}; iv sd {s_iv} cluster {se_c_iv}");
        assert!(s / se_w > 2.0, "sd {s} white se {se_w}");
        assert!((s / se_c - 1.0).abs() < 0.2, "sd {s} cluster se {se_c}");
        assert!(
            (s_iv / se_c_iv - 1.0).abs() < 0.2,
            "sd {s_iv} cluster se {se_c_iv}"
        );
    }
}
