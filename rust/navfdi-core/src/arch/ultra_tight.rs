//! Ultra-tight (vector-tracking) GNSS/INS with channel prefilters and AIME (paper 004,
//! METHODS §11).
//!
//! * **Navigation filter**: the tight filter's 17 states (INS error, receiver clock bias and
//!   drift), propagated and updated at the navigation rate `dt` (1 Hz in the paper).
//! * **Vector tracking**: every tracked channel's code and carrier replica follow the
//!   navigation solution. Its tracking errors are the truth minus the replica,
//!   `e_ρ = h_ρ(x − x̂) + f_ρ` (m) and `e_ρ̇ = h_ρ̇(x − x̂) + f_ρ̇` (m/s), with `h` the satellite's
//!   rows of the tight `H`, `x` the true error state, `x̂` the filter's estimate (the
//!   posterior of the previous epoch moving linearly to this epoch's prediction: the replica
//!   is driven by the predicted solution) and `f` the injected fault. In chips and Hz:
//!   `τ = e_ρ/λ_code`, `δf = e_ρ̇/λ_L1`. Within an epoch the truth error state and the fault
//!   are interpolated linearly between epochs (exact for a ramp; a step is spread over one
//!   epoch).
//! * **Prefilters**: per channel a [`Prefilter`] (τ, δf, δḟ) stepped every coherent
//!   integration `T` (20 ms) by the code and frequency discriminator outputs
//!   `z = [τ + v_τ, δf + v_f]`, their noise σ from the channel's C/N0 ([`dll_variance`],
//!   [`fll_variance`]: Kaplan & Hegarty 2006, eq. 5.71 and 5.64) drawn from the run's own
//!   random stream, so every variant sees the same discriminator noise.
//! * **Navigation measurement** ([`NavInput`]): per channel, averaged over the epoch's steps
//!   (averaging, not resampling: paper eq. 1–2), as pseudorange and rate residuals of the
//!   replica (m, m/s), i.e. the innovation of the navigation filter:
//!   - `discriminator` (default, the paper's): the discriminator outputs `λ_code·mean z_τ`,
//!     `λ_L1·mean z_f`, variances `λ²σ²/N` — exact, and independent from epoch to epoch
//!     because the discriminator noise is white. The average refers to the middle of the
//!     epoch; it is used as the residual at its end (a lag of half an epoch: a few cm of
//!     range for the range-rate errors here, against 0.58 m of noise at 48 dB-Hz).
//!   - `prefilter`: the prefilter's posteriors `λ_code·mean τ̂`, `λ_L1·mean δf̂`, variances
//!     `λ²·mean P` — correlated from epoch to epoch through the prefilter's memory, which
//!     the navigation filter and M1 take as independent (docs/liu2022.md).
//!
//!   After the update the replicas move from `x̂⁻` to `x̂⁺`, and each prefilter's state is
//!   shifted by `−h(x̂⁺ − x̂⁻)`: an error absorbed by the navigation solution reaches every
//!   channel (the paper's fault propagation).
//! * **Detection** per channel ([`AimeMethod`]): `m1` AIME on the navigation filter's
//!   innovation of the satellite (2 components, window `nav_window`; an excluded channel
//!   keeps being tested on its innovation, which no longer updates the filter), `m2` AIME on the
//!   prefilter innovations (window `prefilter_window`), `m3` two-stage AIME on them
//!   (`stage1_window` + `stage2_window`). With `exclude`, a channel in alarm stops feeding the
//!   navigation filter for the rest of the run (it keeps being tracked and tested).
//!
//! Statistics before `arm_after` (default 30 s: acquisition and convergence) are recorded but
//! never alarm.
//!
//! Records: one channel (sub-record) per tracked satellite with the method's detector; per
//! epoch its statistic is the largest of the epoch's tests (prefilter methods run 1/T tests
//! per second) and its alarm whether any of them alarmed; `isolated` = excluded, `fused` =
//! fed the navigation update. The satellite record holds in-view and excluded flags per
//! tracked satellite, so the satellite-FDE metrics apply.

use crate::cancel::Cancel;
use crate::detect::{Aime, TwoStageAime};
use crate::error::{Error, Result};
use crate::gnss::prefilter::{
    dll_variance, fll_variance, Prefilter, PrefilterConfig, F_CARRIER_L1, F_CODE_L1CA,
};
use crate::gnss::snapshot::FdeStatus;
use crate::gnss::C;
use crate::kalman::{KalmanFilter, Sequential};
use crate::record::{RunRecord, SatRecord};
use crate::spec::{AimeMethod, NavInput, ScenarioSpec, UltraTightSpec};
use crate::stream::Streams;
use nalgebra::{DMatrix, DVector, Matrix3, Vector2, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// GPS L1 C/A chip length (m).
pub const LAMBDA_CODE: f64 = C / F_CODE_L1CA;
/// GPS L1 carrier wavelength (m).
pub const LAMBDA_L1: f64 = C / F_CARRIER_L1;
/// Stream offset of the discriminator noise.
const DISCRIMINATOR_STREAM: u64 = 0x0D15_C0DE_0050;

use crate::record::SAT_NO_MEASUREMENT as NO_MEASUREMENT;

/// A channel's detector.
enum ChannelTest {
    Aime(Box<Aime>),
    TwoStage(Box<TwoStageAime>),
}

impl ChannelTest {
    fn new(u: &UltraTightSpec, dt: f64) -> Result<Self> {
        let steps = |s: f64, step: f64| (s / step).round().max(1.0) as usize;
        Ok(match u.method {
            AimeMethod::M1 => {
                ChannelTest::Aime(Box::new(Aime::new(u.pf, steps(u.nav_window, dt))?))
            }
            AimeMethod::M2 => ChannelTest::Aime(Box::new(Aime::new(
                u.pf,
                steps(u.prefilter_window, u.integration),
            )?)),
            AimeMethod::M3 => {
                // The statistic filter and stage 2 take one stage-1 statistic per
                // `stage_period`; stage 2's window counts those samples.
                let every = steps(u.stage_period, u.integration);
                ChannelTest::TwoStage(Box::new(
                    TwoStageAime::new(
                        u.pf,
                        steps(u.stage1_window, u.integration),
                        steps(u.stage2_window, u.stage_period),
                        u.stage_q,
                        u.fading_b,
                    )?
                    .with_decimation(every, u.stage_r0)?,
                ))
            }
        })
    }

    /// Test a fully available residual `r` (m) with covariance `a` (m × m column-major).
    fn test(&mut self, r: &[f64], a: &[f64]) -> Result<crate::detect::Decision> {
        match self {
            ChannelTest::Aime(d) => Ok(d.test_trusted(r, a)),
            ChannelTest::TwoStage(d) => d.test_trusted(r, a),
        }
    }
}

/// One tracked channel's state over the run.
struct Channel {
    /// Index into the constellation's names.
    sat: usize,
    prefilter: Option<Prefilter>,
    test: ChannelTest,
    excluded: bool,
    /// Sums over the epoch's steps of the navigation input, code (chips) and frequency (Hz),
    /// and of a per-step variance term (chips², Hz²) whose mean is the variance of the
    /// input's mean: divided by the step count, the mean and its variance.
    sums: [f64; 4],
    steps: usize,
    /// The epoch's largest statistic, its threshold, any alarm.
    stat: f64,
    thr: f64,
    alarm: bool,
}

/// The rows (pseudorange, rate) of satellite `sat` at epoch `ep`, with the local index.
fn rows_of(ep: &crate::gnss::ranges::RangeEpoch, sat: usize) -> Option<usize> {
    ep.sats.iter().position(|&s| s == sat)
}

/// `h · x` for row `row` of `h`.
fn dot_row(h: &DMatrix<f64>, row: usize, x: &DVector<f64>) -> f64 {
    (0..h.ncols()).map(|j| h[(row, j)] * x[j]).sum()
}

/// `h P hᵀ` for row `row` of `h`.
fn quad_row(h: &DMatrix<f64>, row: usize, p: &DMatrix<f64>) -> f64 {
    quad_rows(h, row, row, p)
}

/// `h_a P h_bᵀ` for rows `a`, `b` of `h`.
fn quad_rows(h: &DMatrix<f64>, a: usize, b: usize, p: &DMatrix<f64>) -> f64 {
    let n = h.ncols();
    let mut s = 0.0;
    for i in 0..n {
        let hi = h[(a, i)];
        if hi == 0.0 {
            continue;
        }
        for j in 0..n {
            s += hi * p[(i, j)] * h[(b, j)];
        }
    }
    s
}

/// Run the ultra-tight architecture of scenario `spec` over one run's streams
/// (`isolation = false`: detectors report, channels are never excluded). `full` is accepted
/// for symmetry (everything is recorded either way). `cancel` is checked every epoch.
///
/// The tracking loops are simulated here: each channel's discriminators see the true tracking
/// error, so the streams must carry the reference error state (a simulated source); their
/// noise comes from the run's seed and stream.
pub fn run_ultra_tight(
    spec: &ScenarioSpec,
    src: &Streams,
    isolation: bool,
    _full: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    let models = src.models;
    let u = spec.ultra_tight()?;
    let x_true = &src
        .reference
        .ok_or_else(|| {
            Error::Invalid(
                "ultra_tight: the tracking loops need the signal's truth (the reference error state), which only a simulated source provides".into(),
            )
        })?
        .x_true;
    let rp = models.ranges.as_ref().ok_or_else(|| {
        Error::Invalid("ultra_tight: the scenario has no gnss_ranges sensor".into())
    })?;
    let si = rp.sensor;
    let n = spec.n_states();
    let dt = spec.dt;
    let steps = (dt / u.integration).round() as usize;
    let cfg = PrefilterConfig {
        t: u.integration,
        beta: F_CODE_L1CA / F_CARRIER_L1,
        jerk_psd: u.jerk_psd,
        code_psd: u.code_psd,
        spacing: u.spacing,
    };
    cfg.validate()?;
    let r_disc = Vector2::new(
        dll_variance(u.cn0, u.integration, u.spacing)?,
        fll_variance(u.cn0, u.integration, false)?,
    );
    let sd = Vector2::new(r_disc[0].sqrt(), r_disc[1].sqrt());
    let exclude = isolation && u.exclude;
    let mut chans: Vec<Channel> = Vec::with_capacity(u.satellites.len());
    for name in &u.satellites {
        let sat = rp
            .names
            .iter()
            .position(|x| x == name)
            .ok_or_else(|| Error::Invalid(format!("ultra_tight: no satellite {name:?}")))?;
        chans.push(Channel {
            sat,
            prefilter: None,
            test: ChannelTest::new(u, dt)?,
            excluded: false,
            sums: [0.0; 4],
            steps: 0,
            stat: f64::NAN,
            thr: f64::NAN,
            alarm: false,
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(src.seed);
    rng.set_stream(src.stream ^ DISCRIMINATOR_STREAM);
    let mut kf = KalmanFilter::new(DVector::zeros(n), models.p0.clone())?;
    let mut seq = Sequential::new(n);
    let epochs = src.epochs();
    let s_count = chans.len();
    let mut rec = RunRecord::empty(spec, models);
    let mut sat = SatRecord::new(u.satellites.clone(), epochs);
    let mut sig = DVector::zeros(crate::ins::N_STATES);
    let mut x_post = kf.x().clone();
    for k in 0..epochs {
        cancel.check()?;
        let ep = &rp.epochs[k];
        let m = ep.len();
        let measured = models.available[si][k] && m > 0;
        if k > 0 {
            kf.predict_trusted(&models.phi[k], &models.q[k], 1.0)
                .map_err(|e| crate::run::at_epoch(k, e))?;
        }
        // Fine steps over (t_{k−1}, t_k]: the replicas move from x̂⁺_{k−1} to x̂⁻_k.
        let prev = if k > 0 { Some(&rp.epochs[k - 1]) } else { None };
        for ch in chans.iter_mut() {
            ch.sums = [0.0; 4];
            ch.steps = 0;
            ch.stat = f64::NAN;
            ch.thr = f64::NAN;
            ch.alarm = false;
            let Some(j) = rows_of(ep, ch.sat).filter(|_| measured) else {
                // Not in view: the channel loses lock and is re-initialised when it returns.
                ch.prefilter = None;
                continue;
            };
            let (hr, hd) = (j, m + j);
            let Some(pf) = ch.prefilter.as_mut() else {
                // Acquisition: zero error estimate with the navigation solution's uncertainty.
                let p = kf.p();
                let p0 = Matrix3::from_diagonal(&Vector3::new(
                    quad_row(&ep.h, hr, p) / (LAMBDA_CODE * LAMBDA_CODE),
                    quad_row(&ep.h, hd, p) / (LAMBDA_L1 * LAMBDA_L1),
                    1.0,
                ));
                ch.prefilter = Some(Prefilter::new(cfg, Vector3::zeros(), p0)?);
                continue;
            };
            let Some(prev) = prev else { continue };
            let jp = rows_of(prev, ch.sat);
            let f_prev = jp.map_or((0.0, 0.0), |i| (prev.fault[i], prev.fault[prev.len() + i]));
            let (f_now_r, f_now_d) = (ep.fault[hr], ep.fault[hd]);
            // Tracking errors at the epoch boundaries (truth − replica), m and m/s.
            let e0r = dot_row(&ep.h, hr, &x_true[k - 1]) - dot_row(&ep.h, hr, &x_post);
            let e1r = dot_row(&ep.h, hr, &x_true[k]) - dot_row(&ep.h, hr, kf.x());
            let e0d = dot_row(&ep.h, hd, &x_true[k - 1]) - dot_row(&ep.h, hd, &x_post);
            let e1d = dot_row(&ep.h, hd, &x_true[k]) - dot_row(&ep.h, hd, kf.x());
            for l in 1..=steps {
                let a = l as f64 / steps as f64;
                let er = (1.0 - a) * (e0r + f_prev.0) + a * (e1r + f_now_r);
                let ed = (1.0 - a) * (e0d + f_prev.1) + a * (e1d + f_now_d);
                let v1: f64 = StandardNormal.sample(&mut rng);
                let v2: f64 = StandardNormal.sample(&mut rng);
                let z = Vector2::new(er / LAMBDA_CODE + sd[0] * v1, ed / LAMBDA_L1 + sd[1] * v2);
                let st = pf.step_with(z, r_disc);
                let (v, var) = match u.nav_input {
                    // White outputs: the mean's variance is σ²/N.
                    NavInput::Discriminator => {
                        let n = steps as f64;
                        ([z[0], z[1]], [r_disc[0] / n, r_disc[1] / n])
                    }
                    // Correlated estimates: the mean P, an upper bound.
                    NavInput::Prefilter => {
                        let (x, p) = (pf.x(), pf.p());
                        ([x[0], x[1]], [p[(0, 0)], p[(1, 1)]])
                    }
                };
                ch.sums[0] += v[0];
                ch.sums[1] += v[1];
                ch.sums[2] += var[0];
                ch.sums[3] += var[1];
                ch.steps += 1;
                if u.method != AimeMethod::M1 {
                    let d = ch
                        .test
                        .test(st.residual.as_slice(), st.covariance.as_slice())
                        .map_err(|e| crate::run::at_epoch(k, e))?;
                    if d.statistic.is_finite() && !(d.statistic <= ch.stat) {
                        ch.stat = d.statistic;
                    }
                    ch.thr = d.threshold;
                    ch.alarm |= d.alarm;
                }
            }
        }
        // Navigation update from the averaged channel outputs: per channel the averaged
        // residual of the replica (which follows x̂⁻) is the filter's innovation.
        let mut used = 0u32;
        let mut fused = vec![false; s_count];
        if k > 0 && measured {
            let mut z = DVector::from_element(2 * m, f64::NAN);
            let mut r_diag = vec![1.0; 2 * m];
            let pred = &ep.h * kf.x();
            for (c, ch) in chans.iter_mut().enumerate() {
                if ch.steps == 0 {
                    continue;
                }
                let Some(j) = rows_of(ep, ch.sat) else {
                    continue;
                };
                let n_steps = ch.steps as f64;
                let res = [
                    LAMBDA_CODE * ch.sums[0] / n_steps,
                    LAMBDA_L1 * ch.sums[1] / n_steps,
                ];
                let var = [
                    LAMBDA_CODE * LAMBDA_CODE * ch.sums[2] / n_steps,
                    LAMBDA_L1 * LAMBDA_L1 * ch.sums[3] / n_steps,
                ];
                if u.method == AimeMethod::M1 {
                    // M1: the satellite's innovation and its covariance H_c P⁻ H_cᵀ + R_c,
                    // also for an excluded channel (tested, not used).
                    let p = kf.p();
                    let cross = quad_rows(&ep.h, j, m + j, p);
                    let a = [
                        quad_row(&ep.h, j, p) + var[0],
                        cross,
                        cross,
                        quad_row(&ep.h, m + j, p) + var[1],
                    ];
                    let d = ch
                        .test
                        .test(&res, &a)
                        .map_err(|e| crate::run::at_epoch(k, e))?;
                    ch.stat = d.statistic;
                    ch.thr = d.threshold;
                    ch.alarm = d.alarm;
                }
                if ch.excluded && exclude {
                    continue;
                }
                z[j] = pred[j] + res[0];
                z[m + j] = pred[m + j] + res[1];
                r_diag[j] = var[0];
                r_diag[m + j] = var[1];
                fused[c] = true;
                used += 1;
            }
            if used > 0 {
                let x_prior = kf.x().clone();
                kf.sequential_pending(&z, &ep.h, &r_diag, &mut seq)
                    .map_err(|e| crate::run::at_epoch(k, e))?;
                kf.commit_sequential(&mut seq)
                    .map_err(|e| crate::run::at_epoch(k, e))?;
                // Vector tracking: the replicas jump with the solution.
                let dx = kf.x() - &x_prior;
                for ch in chans.iter_mut() {
                    let (Some(j), Some(pf)) = (rows_of(ep, ch.sat), ch.prefilter.as_mut()) else {
                        continue;
                    };
                    let shift = Vector3::new(
                        -dot_row(&ep.h, j, &dx) / LAMBDA_CODE,
                        -dot_row(&ep.h, m + j, &dx) / LAMBDA_L1,
                        0.0,
                    );
                    pf.shift(&shift).map_err(|e| crate::run::at_epoch(k, e))?;
                }
            }
        }
        x_post.copy_from(kf.x());
        // Decisions and records.
        let mut any_excluded = false;
        let armed = models.t[k] >= u.arm_after;
        for (c, ch) in chans.iter_mut().enumerate() {
            ch.alarm &= armed;
            if ch.alarm && exclude {
                ch.excluded = true;
            }
            let in_view = measured && rows_of(ep, ch.sat).is_some();
            sat.in_view[k * s_count + c] = in_view;
            sat.excluded[k * s_count + c] = in_view && ch.excluded && exclude;
            any_excluded |= sat.excluded[k * s_count + c];
            let sub = &mut rec.subs[c];
            let det = &mut sub.detectors[0];
            det.statistic.push(ch.stat);
            det.threshold.push(ch.thr);
            det.alarm.push(ch.alarm);
            sub.statistic.push(ch.stat);
            sub.dof.push(if ch.stat.is_finite() { 2 } else { 0 });
            sub.isolated.push(ch.excluded && exclude);
            sub.reinstated.push(false);
            sub.fused.push(fused[c]);
        }
        sat.status.push(if !measured {
            NO_MEASUREMENT
        } else if any_excluded {
            FdeStatus::Excluded.code()
        } else {
            FdeStatus::Passed.code()
        });
        sat.used.push(used);
        rec.sources.push(u32::from(used > 0));
        rec.push_navigation(src, k, kf.x(), kf.p(), &mut sig);
    }
    sat.score(&rec.t, &spec.faults, &spec.sensors[si].name);
    rec.sats = Some(sat);
    Ok(rec)
}
