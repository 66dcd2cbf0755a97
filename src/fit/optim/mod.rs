//! Bounded, derivative-free / least-squares optimisers for fitting physical
//! model parameters to recordings.
//!
//! Conventions shared by every method:
//! * Objectives are expensive and may be non-smooth. A NaN (or −∞) value is
//!   treated as `+∞`, i.e. a failed evaluation that is avoided, never
//!   propagated.
//! * Parameters are optimised in a normalised `[0,1]` space derived from
//!   [`Bounds`]; the objective is only ever called with points inside
//!   `[lo, hi]`. Parameters with `lo == hi` are held fixed.
//! * Everything is deterministic (own splitmix64 RNG). Parallel evaluation
//!   (rayon) always gathers results in a fixed order, so results do not
//!   depend on the thread count.
//! * Invalid input (empty `x0`, length mismatch with bounds, non-finite
//!   bounds, `hi < lo`) never panics: the result has `converged == false`.

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rayon::prelude::*;
use serde::Serialize;

/// Box bounds, one entry per parameter. `lo[i] <= hi[i]`, both finite.
#[derive(Debug, Clone, Serialize)]
pub struct Bounds {
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
}

/// Result of a scalar-objective minimisation.
#[derive(Debug, Clone, Serialize)]
pub struct OptResult {
    /// Best point found (always inside the bounds when input is valid).
    pub x: Vec<f64>,
    /// Objective at `x` (`+∞` if no finite value was ever seen).
    pub f: f64,
    /// Number of objective evaluations performed.
    pub evals: usize,
    /// Whether a tolerance criterion (rather than the budget) ended the search.
    pub converged: bool,
}

// ---------------------------------------------------------------------------
// Shared helpers
// ---------------------------------------------------------------------------

/// Deterministic splitmix64 generator.
#[derive(Debug, Clone)]
pub(crate) struct Rng {
    state: u64,
}

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Rng { state: seed ^ 0x5DEE_CE66_D1CE_4E5B }
    }
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub(crate) fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Standard normal (Box–Muller).
    pub(crate) fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // (0, 1]
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// Failed evaluations (NaN, −∞) become +∞.
#[inline]
fn sanitize(v: f64) -> f64 {
    if v.is_nan() || v == f64::NEG_INFINITY { f64::INFINITY } else { v }
}

/// Mapping between the user's parameter space and the normalised unit cube of
/// the free (non-fixed) parameters.
#[derive(Debug, Clone)]
struct Space {
    lo: Vec<f64>,
    span: Vec<f64>,
    free: Vec<usize>,
}

impl Space {
    fn new(b: &Bounds, n: usize) -> Option<Space> {
        if n == 0 || b.lo.len() != n || b.hi.len() != n {
            return None;
        }
        let mut span = Vec::with_capacity(n);
        let mut free = Vec::new();
        for i in 0..n {
            let (lo, hi) = (b.lo[i], b.hi[i]);
            let s = hi - lo;
            if !lo.is_finite() || !hi.is_finite() || !s.is_finite() || s < 0.0 {
                return None;
            }
            if s > 0.0 {
                free.push(i);
            }
            span.push(s);
        }
        Some(Space { lo: b.lo.clone(), span, free })
    }
    fn dim(&self) -> usize {
        self.free.len()
    }
    fn to_unit(&self, x: &[f64]) -> Vec<f64> {
        self.free
            .iter()
            .map(|&i| {
                let u = (x[i] - self.lo[i]) / self.span[i];
                if u.is_nan() { 0.5 } else { u.clamp(0.0, 1.0) }
            })
            .collect()
    }
    fn params_of(&self, u: &[f64]) -> Vec<f64> {
        let mut x = self.lo.clone();
        for (k, &i) in self.free.iter().enumerate() {
            let uk = if u[k].is_nan() { 0.5 } else { u[k].clamp(0.0, 1.0) };
            x[i] = (self.lo[i] + uk * self.span[i]).min(self.lo[i] + self.span[i]);
        }
        x
    }
    /// `x0` clamped into the bounds (used for results of trivial problems).
    fn clamp_x(&self, x0: &[f64]) -> Vec<f64> {
        let u = self.to_unit(x0);
        self.params_of(&u)
    }
}

fn invalid_result(x0: &[f64]) -> OptResult {
    OptResult { x: x0.to_vec(), f: f64::INFINITY, evals: 0, converged: false }
}

/// Reflect a coordinate into [0, 1] (period-2 mirror).
#[inline]
fn reflect01(u: f64) -> f64 {
    if !u.is_finite() {
        return 0.5;
    }
    if (0.0..=1.0).contains(&u) {
        return u;
    }
    let r = u.rem_euclid(2.0);
    if r > 1.0 { 2.0 - r } else { r }
}

#[inline]
fn clamp01(u: f64) -> f64 {
    if u.is_nan() { 0.5 } else { u.clamp(0.0, 1.0) }
}

// ---------------------------------------------------------------------------
// Nelder–Mead
// ---------------------------------------------------------------------------

/// Options for [`nelder_mead`].
#[derive(Debug, Clone, Serialize)]
pub struct NelderMeadOpts {
    /// Evaluation budget.
    pub max_evals: usize,
    /// Simplex size tolerance in normalised units (max ∞-distance of any
    /// vertex from the best one).
    pub xtol: f64,
    /// Absolute tolerance on the spread of objective values in the simplex.
    pub ftol: f64,
    /// Initial simplex edge, normalised (fraction of each bounds range).
    pub initial_step: f64,
}

impl Default for NelderMeadOpts {
    fn default() -> Self {
        NelderMeadOpts { max_evals: 1000, xtol: 1e-6, ftol: 1e-10, initial_step: 0.15 }
    }
}

/// Bounded Nelder–Mead simplex minimisation.
///
/// Works in the normalised box; trial points are clamped onto the box (so
/// bound-active optima are reached exactly). Uses the dimension-adaptive
/// coefficients of Gao & Han for `n > 2`. When the simplex collapses the
/// search is restarted around the best point (a collapsed simplex on a bound
/// face can otherwise stall); it is declared converged when a restart no
/// longer improves the best value by more than `ftol`.
pub fn nelder_mead(
    f: &dyn Fn(&[f64]) -> f64,
    x0: &[f64],
    b: &Bounds,
    o: &NelderMeadOpts,
) -> OptResult {
    let Some(sp) = Space::new(b, x0.len()) else {
        return invalid_result(x0);
    };
    let n = sp.dim();
    let mut evals = 0usize;
    let feval = |u: &[f64], evals: &mut usize| -> f64 {
        *evals += 1;
        sanitize(f(&sp.params_of(u)))
    };
    if o.max_evals == 0 {
        return OptResult { x: sp.clamp_x(x0), f: f64::INFINITY, evals: 0, converged: false };
    }
    let u0 = sp.to_unit(x0);
    if n == 0 {
        let fx = feval(&u0, &mut evals);
        return OptResult { x: sp.params_of(&u0), f: fx, evals, converged: true };
    }
    let nf = n as f64;
    let (alpha, gamma, rho, delta) = if n > 2 {
        (1.0, 1.0 + 2.0 / nf, 0.75 - 1.0 / (2.0 * nf), 1.0 - 1.0 / nf)
    } else {
        (1.0, 2.0, 0.5, 0.5)
    };
    let step0 = if o.initial_step.is_finite() && o.initial_step > 0.0 {
        o.initial_step.min(0.5)
    } else {
        0.15
    };
    let xtol = if o.xtol.is_finite() { o.xtol.max(0.0) } else { 1e-6 };
    let ftol = if o.ftol.is_finite() { o.ftol.max(0.0) } else { 1e-10 };

    let mut best_u = u0.clone();
    let mut best_f = feval(&u0, &mut evals);
    let mut converged = false;
    let mut prev_restart_best: Option<f64> = None;
    const MAX_RESTARTS: usize = 6;

    'restarts: for restart in 0..=MAX_RESTARTS {
        // Build simplex around the best point, stepping inward at the bounds.
        let step = if restart == 0 {
            step0
        } else {
            (step0 * 0.5f64.powi(restart as i32)).max(10.0 * xtol).min(step0)
        };
        let mut pts: Vec<Vec<f64>> = vec![best_u.clone()];
        let mut fs: Vec<f64> = vec![best_f];
        for i in 0..n {
            if evals >= o.max_evals {
                break 'restarts;
            }
            let mut p = best_u.clone();
            p[i] = if p[i] + step <= 1.0 { p[i] + step } else { p[i] - step };
            p[i] = clamp01(p[i]);
            let fp = feval(&p, &mut evals);
            pts.push(p);
            fs.push(fp);
        }

        loop {
            // Order vertices (stable on ties so the run is deterministic).
            let mut idx: Vec<usize> = (0..=n).collect();
            idx.sort_by(|&a, &b| fs[a].total_cmp(&fs[b]));
            pts = idx.iter().map(|&i| pts[i].clone()).collect();
            fs = idx.iter().map(|&i| fs[i]).collect();
            if fs[0] < best_f || (fs[0] == best_f && best_u != pts[0]) {
                best_f = fs[0];
                best_u = pts[0].clone();
            }

            let size = pts[1..]
                .iter()
                .map(|p| p.iter().zip(&pts[0]).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max))
                .fold(0.0, f64::max);
            let spread = fs[n] - fs[0];
            if size <= xtol && spread <= ftol {
                break; // this run converged
            }
            if size <= xtol * 1e-3 {
                break; // collapsed (e.g. all-infinite simplex); restart
            }
            if evals >= o.max_evals {
                break 'restarts;
            }

            // Centroid of all but the worst.
            let mut c = vec![0.0; n];
            for p in &pts[..n] {
                for (ci, pi) in c.iter_mut().zip(p) {
                    *ci += pi / nf;
                }
            }
            let worst = pts[n].clone();
            let along = |t: f64| -> Vec<f64> {
                c.iter().zip(&worst).map(|(ci, wi)| clamp01(ci + t * (ci - wi))).collect()
            };

            let xr = along(alpha);
            let fr = feval(&xr, &mut evals);
            if fr < fs[0] {
                if evals >= o.max_evals {
                    pts[n] = xr;
                    fs[n] = fr;
                    continue;
                }
                let xe = along(gamma);
                let fe = feval(&xe, &mut evals);
                if fe < fr {
                    pts[n] = xe;
                    fs[n] = fe;
                } else {
                    pts[n] = xr;
                    fs[n] = fr;
                }
                continue;
            }
            if fr < fs[n - 1] {
                pts[n] = xr;
                fs[n] = fr;
                continue;
            }
            if evals >= o.max_evals {
                continue; // loop head records best and exits on budget
            }
            // Contraction (outside if the reflection improved on the worst).
            let (xc, fc_ref) = if fr < fs[n] { (along(rho), fr) } else { (along(-rho), fs[n]) };
            let fc = feval(&xc, &mut evals);
            if fc <= fc_ref && fc.is_finite() || fc < fc_ref {
                pts[n] = xc;
                fs[n] = fc;
                continue;
            }
            // Shrink towards the best vertex.
            for i in 1..=n {
                if evals >= o.max_evals {
                    break;
                }
                let p: Vec<f64> = pts[i]
                    .iter()
                    .zip(&pts[0])
                    .map(|(pi, bi)| clamp01(bi + delta * (pi - bi)))
                    .collect();
                fs[i] = feval(&p, &mut evals);
                pts[i] = p;
            }
        }

        if let Some(prev) = prev_restart_best
            && prev - best_f <= ftol
        {
            converged = best_f.is_finite();
            break;
        }
        prev_restart_best = Some(best_f);
        if restart == MAX_RESTARTS {
            converged = best_f.is_finite();
        }
    }

    OptResult { x: sp.params_of(&best_u), f: best_f, evals, converged }
}

// ---------------------------------------------------------------------------
// CMA-ES
// ---------------------------------------------------------------------------

/// Options for [`cmaes`].
#[derive(Debug, Clone, Serialize)]
pub struct CmaesOpts {
    /// Evaluation budget (shared by all restarts; no generation is started
    /// that would exceed it).
    pub max_evals: usize,
    /// Initial step size, normalised (fraction of each bounds range).
    pub sigma0: f64,
    /// Population size of the first run (default `4 + ⌊3 ln n⌋`); doubled at
    /// every restart.
    pub popsize: Option<usize>,
    /// RNG seed; identical seeds give bit-identical results.
    pub seed: u64,
    /// Absolute tolerance on objective stagnation (ends a run).
    pub ftol: f64,
}

impl Default for CmaesOpts {
    fn default() -> Self {
        CmaesOpts { max_evals: 5000, sigma0: 0.3, popsize: None, seed: 0x00C0_FFEE, ftol: 1e-11 }
    }
}

struct CmaRun {
    best_u: Vec<f64>,
    best_f: f64,
    by_tol: bool,
}

/// Bounded CMA-ES with IPOP restarts.
///
/// The first run starts at `x0`; if budget remains after it stops, the search
/// is restarted from a uniformly random point with a doubled population (at
/// most 9 restarts). Samples are reflected into the box. Each generation's
/// population is evaluated in parallel with rayon; samples are drawn
/// sequentially from the seeded RNG and fitnesses collected in sample order, so
/// the result is independent of the thread count. `converged` reports whether
/// the run that produced the best point stopped on a tolerance criterion.
pub fn cmaes(
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    x0: &[f64],
    b: &Bounds,
    o: &CmaesOpts,
) -> OptResult {
    let Some(sp) = Space::new(b, x0.len()) else {
        return invalid_result(x0);
    };
    if o.max_evals == 0 {
        return OptResult { x: sp.clamp_x(x0), f: f64::INFINITY, evals: 0, converged: false };
    }
    let n = sp.dim();
    let u0 = sp.to_unit(x0);
    let mut evals = 1usize;
    let f0 = sanitize(f(&sp.params_of(&u0)));
    if n == 0 {
        return OptResult { x: sp.params_of(&u0), f: f0, evals, converged: true };
    }
    let mut rng = Rng::new(o.seed);
    let sigma0 = if o.sigma0.is_finite() && o.sigma0 > 0.0 { o.sigma0.min(1.0) } else { 0.3 };
    let ftol = if o.ftol.is_finite() { o.ftol.max(0.0) } else { 1e-11 };
    let default_lambda = 4 + (3.0 * (n as f64).ln()).floor() as usize;
    let mut lambda = o.popsize.unwrap_or(default_lambda).max(2);

    let mut best_u = u0.clone();
    let mut best_f = f0;
    let mut converged = false;
    const MAX_RESTARTS: usize = 9;
    for restart in 0..=MAX_RESTARTS {
        if evals + lambda > o.max_evals {
            break;
        }
        let start: Vec<f64> =
            if restart == 0 { u0.clone() } else { (0..n).map(|_| rng.uniform()).collect() };
        let run = cma_run(f, &sp, &start, sigma0, lambda, ftol, o.max_evals, &mut evals, &mut rng);
        if run.best_f < best_f {
            best_f = run.best_f;
            best_u = run.best_u;
            converged = run.by_tol;
        } else if run.best_f == best_f && best_f.is_finite() {
            converged |= run.by_tol;
        }
        lambda = lambda.saturating_mul(2);
    }
    OptResult { x: sp.params_of(&best_u), f: best_f, evals, converged }
}

#[allow(clippy::too_many_arguments)]
fn cma_run(
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    sp: &Space,
    start: &[f64],
    sigma0: f64,
    lambda: usize,
    ftol: f64,
    max_evals: usize,
    evals: &mut usize,
    rng: &mut Rng,
) -> CmaRun {
    let n = start.len();
    let nf = n as f64;
    let mu = (lambda / 2).max(1);
    let raw_w: Vec<f64> =
        (0..mu).map(|i| ((mu as f64) + 0.5).ln() - ((i + 1) as f64).ln()).collect();
    let wsum: f64 = raw_w.iter().sum();
    let w: Vec<f64> = raw_w.iter().map(|v| v / wsum).collect();
    let mueff = 1.0 / w.iter().map(|v| v * v).sum::<f64>();
    let cs = (mueff + 2.0) / (nf + mueff + 5.0);
    let ds = 1.0 + 2.0 * (((mueff - 1.0) / (nf + 1.0)).sqrt() - 1.0).max(0.0) + cs;
    let cc = (4.0 + mueff / nf) / (nf + 4.0 + 2.0 * mueff / nf);
    let c1 = 2.0 / ((nf + 1.3).powi(2) + mueff);
    let cmu =
        (1.0 - c1).min(2.0 * (mueff - 2.0 + 1.0 / mueff) / ((nf + 2.0).powi(2) + mueff)).max(0.0);
    let chin = nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf));
    let hist_len = 10 + (30.0 * nf / lambda as f64).ceil() as usize;
    let max_gens = 100 + (150.0 * (nf + 3.0).powi(2) / (lambda as f64).sqrt()) as usize;

    let mut m = DVector::from_column_slice(start);
    let mut sigma = sigma0;
    let mut c = DMatrix::<f64>::identity(n, n);
    let mut ps = DVector::<f64>::zeros(n);
    let mut pc = DVector::<f64>::zeros(n);
    let mut bmat = DMatrix::<f64>::identity(n, n);
    let mut dvec = DVector::<f64>::from_element(n, 1.0);
    let mut hist: std::collections::VecDeque<f64> = std::collections::VecDeque::new();
    let mut all_inf_gens = 0usize;

    let mut run = CmaRun { best_u: start.to_vec(), best_f: f64::INFINITY, by_tol: false };

    for generation in 0..max_gens {
        if *evals + lambda > max_evals {
            break;
        }
        // Sample (sequentially: deterministic).
        let mut us: Vec<Vec<f64>> = Vec::with_capacity(lambda);
        let mut ys: Vec<DVector<f64>> = Vec::with_capacity(lambda);
        for _ in 0..lambda {
            let z = DVector::from_fn(n, |_, _| rng.normal());
            let y = &bmat * z.component_mul(&dvec);
            let x = &m + &y * sigma;
            let u: Vec<f64> = x.iter().map(|&v| reflect01(v)).collect();
            // Step actually taken (after reflection) is what the update learns from.
            let yr = DVector::from_fn(n, |i, _| (u[i] - m[i]) / sigma);
            us.push(u);
            ys.push(yr);
        }
        // Evaluate in parallel, results in sample order.
        let fs: Vec<f64> = us.par_iter().map(|u| sanitize(f(&sp.params_of(u)))).collect();
        *evals += lambda;

        let mut idx: Vec<usize> = (0..lambda).collect();
        idx.sort_by(|&a, &b| fs[a].total_cmp(&fs[b]));
        let gen_best = fs[idx[0]];
        if gen_best < run.best_f {
            run.best_f = gen_best;
            run.best_u = us[idx[0]].clone();
        }
        if gen_best.is_infinite() {
            all_inf_gens += 1;
            if all_inf_gens >= 20 {
                break;
            }
        } else {
            all_inf_gens = 0;
        }

        // Recombination.
        let mut yw = DVector::<f64>::zeros(n);
        for (k, &i) in idx.iter().take(mu).enumerate() {
            yw += &ys[i] * w[k];
        }
        m += &yw * sigma;
        for v in m.iter_mut() {
            *v = clamp01(*v);
        }
        // C^{-1/2} y_w
        let dinv = dvec.map(|d| 1.0 / d);
        let cinv_half_yw = &bmat * (bmat.transpose() * &yw).component_mul(&dinv);
        ps = &ps * (1.0 - cs) + cinv_half_yw * (cs * (2.0 - cs) * mueff).sqrt();
        let ps_norm = ps.norm();
        let denom = (1.0 - (1.0 - cs).powi(2 * (generation as i32 + 1))).sqrt().max(1e-300);
        let hsig = ps_norm / denom < (1.4 + 2.0 / (nf + 1.0)) * chin;
        let hs = if hsig { 1.0 } else { 0.0 };
        pc = &pc * (1.0 - cc) + &yw * (hs * (cc * (2.0 - cc) * mueff).sqrt());

        let mut rank_mu = DMatrix::<f64>::zeros(n, n);
        for (k, &i) in idx.iter().take(mu).enumerate() {
            rank_mu += &ys[i] * ys[i].transpose() * w[k];
        }
        let c_old_scale = 1.0 - c1 - cmu + c1 * (1.0 - hs) * cc * (2.0 - cc);
        c = &c * c_old_scale + &pc * pc.transpose() * c1 + rank_mu * cmu;
        c = (&c + c.transpose()) * 0.5;

        sigma *= ((cs / ds) * (ps_norm / chin - 1.0)).min(1.0).exp();
        // Flat fitness: escape plateaus (e.g. quantised parameters).
        let k07 = ((0.7 * lambda as f64).ceil() as usize).min(lambda - 1);
        if fs[idx[0]] == fs[idx[k07]] && fs[idx[0]].is_finite() {
            sigma *= (0.2 + cs / ds).exp();
        }
        sigma = sigma.min(2.0);

        // Eigendecomposition for the next generation.
        let eig = SymmetricEigen::new(c.clone());
        let maxev = eig.eigenvalues.iter().cloned().fold(0.0_f64, f64::max);
        if !(maxev.is_finite() && maxev > 0.0) {
            break;
        }
        let floor = maxev * 1e-20;
        bmat = eig.eigenvectors;
        dvec = eig.eigenvalues.map(|e| e.max(floor).sqrt());
        let dmax = dvec.max();
        let dmin = dvec.min();
        if !sigma.is_finite() || sigma <= 0.0 {
            break;
        }

        // Termination.
        hist.push_back(gen_best);
        if hist.len() > hist_len {
            hist.pop_front();
        }
        if hist.len() == hist_len {
            let pop_hi =
                fs.iter().cloned().filter(|v| v.is_finite()).fold(f64::NEG_INFINITY, f64::max);
            let hi = hist.iter().cloned().fold(pop_hi, f64::max);
            let lo = hist.iter().cloned().fold(f64::INFINITY, f64::min);
            if hi - lo <= ftol && fs[idx[0]].is_finite() {
                run.by_tol = true;
                break;
            }
        }
        if sigma * dmax < 1e-12 {
            run.by_tol = true;
            break;
        }
        if (dmax / dmin).powi(2) > 1e14 {
            break;
        }
    }
    run
}

// ---------------------------------------------------------------------------
// Golden section (1-D)
// ---------------------------------------------------------------------------

/// 1-D bounded minimisation on `[lo, hi]` returning `(x, f(x))`.
///
/// A 9-point uniform grid (endpoints included) is scanned first so a
/// multimodal objective is refined around the globally best grid point; the
/// bracket between its neighbours is then refined by golden-section search
/// until it is narrower than `tol` or `max_evals` evaluations have been spent.
/// The best point ever evaluated is returned. `lo > hi` is swapped;
/// non-finite bounds or `max_evals == 0` return `f = +∞` without evaluating.
pub fn golden_section(
    f: &dyn Fn(f64) -> f64,
    lo: f64,
    hi: f64,
    tol: f64,
    max_evals: usize,
) -> (f64, f64) {
    if !lo.is_finite() || !hi.is_finite() || max_evals == 0 {
        let x = if lo.is_finite() {
            lo
        } else if hi.is_finite() {
            hi
        } else {
            0.0
        };
        return (x, f64::INFINITY);
    }
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
    let mut evals = 0usize;
    let mut best = (lo, f64::INFINITY);
    let ev = |x: f64, evals: &mut usize, best: &mut (f64, f64)| -> f64 {
        *evals += 1;
        let v = sanitize(f(x));
        if v < best.1 || best.1 == f64::INFINITY && *evals == 1 {
            *best = (x, v);
        }
        v
    };
    if hi == lo {
        let v = ev(lo, &mut evals, &mut best);
        return (lo, v);
    }
    let tol = if tol.is_finite() && tol > 0.0 { tol } else { (hi - lo) * 1e-9 };
    let n_grid = max_evals.min(9);
    if n_grid == 1 {
        let x = 0.5 * (lo + hi);
        let v = ev(x, &mut evals, &mut best);
        return (x, v);
    }
    let grid: Vec<f64> =
        (0..n_grid).map(|i| lo + (hi - lo) * i as f64 / (n_grid - 1) as f64).collect();
    let gf: Vec<f64> = grid.iter().map(|&x| ev(x, &mut evals, &mut best)).collect();
    // First index of the minimum (deterministic on ties).
    let ib = (0..n_grid).fold(0, |b, i| if gf[i] < gf[b] { i } else { b });
    let mut a = grid[ib.saturating_sub(1)];
    let mut bb = grid[(ib + 1).min(n_grid - 1)];

    let invphi = (5f64.sqrt() - 1.0) / 2.0; // 0.618...
    if evals + 2 > max_evals {
        return best;
    }
    let mut x1 = bb - invphi * (bb - a);
    let mut x2 = a + invphi * (bb - a);
    let mut f1 = ev(x1, &mut evals, &mut best);
    let mut f2 = ev(x2, &mut evals, &mut best);
    while (bb - a) > tol && evals < max_evals {
        if f1 <= f2 {
            bb = x2;
            x2 = x1;
            f2 = f1;
            x1 = bb - invphi * (bb - a);
            f1 = ev(x1, &mut evals, &mut best);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + invphi * (bb - a);
            f2 = ev(x2, &mut evals, &mut best);
        }
    }
    best
}

// ---------------------------------------------------------------------------
// Levenberg–Marquardt
// ---------------------------------------------------------------------------

/// Options for [`levenberg_marquardt`].
#[derive(Debug, Clone, Serialize)]
pub struct LmOpts {
    /// Maximum number of Jacobian evaluations (outer iterations).
    pub max_iters: usize,
    /// Forward finite-difference step in normalised units.
    pub rel_step: f64,
    /// Convergence tolerance: relative cost decrease, normalised step size
    /// and projected-gradient size (relative to the cost).
    pub tol: f64,
}

impl Default for LmOpts {
    fn default() -> Self {
        LmOpts { max_iters: 100, rel_step: 1e-3, tol: 1e-8 }
    }
}

/// Result of [`levenberg_marquardt`].
#[derive(Debug, Clone, Serialize)]
pub struct LmResult {
    pub x: Vec<f64>,
    /// `0.5 * Σ r²` at `x` (`+∞` if the residuals could never be evaluated).
    pub cost: f64,
    /// Finite-difference Jacobian at `x`, `n_resid x n_param`, in the user's
    /// parameter units (columns of fixed parameters are zero).
    pub jacobian: Vec<Vec<f64>>,
    pub iters: usize,
    pub converged: bool,
}

/// Bounded Levenberg–Marquardt least squares (`min 0.5 Σ r(x)²`).
///
/// Works in the normalised box; steps are projected onto it. Damping is
/// Marquardt's diagonal scaling. The Jacobian is computed by forward
/// differences (stepping inward at an upper bound), its columns evaluated in
/// parallel. Residual vectors containing non-finite values, or whose length
/// differs from the one at `x0`, count as failures: such trial steps are
/// rejected (damping increased), such Jacobian columns fall back to the
/// opposite-side difference or zero.
pub fn levenberg_marquardt(
    r: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    x0: &[f64],
    b: &Bounds,
    o: &LmOpts,
) -> LmResult {
    let fail = |x: Vec<f64>| LmResult {
        x,
        cost: f64::INFINITY,
        jacobian: vec![],
        iters: 0,
        converged: false,
    };
    let Some(sp) = Space::new(b, x0.len()) else {
        return fail(x0.to_vec());
    };
    let np = x0.len();
    let n = sp.dim();
    let mut u = sp.to_unit(x0);
    let Some(mut res) =
        Some(r(&sp.params_of(&u))).filter(|v| !v.is_empty() && v.iter().all(|x| x.is_finite()))
    else {
        return fail(sp.params_of(&u));
    };
    let m = res.len();
    let eval = |u: &[f64]| -> Option<Vec<f64>> {
        let v = r(&sp.params_of(u));
        if v.len() == m && v.iter().all(|x| x.is_finite()) { Some(v) } else { None }
    };
    let cost_of = |v: &[f64]| 0.5 * v.iter().map(|x| x * x).sum::<f64>();
    let h = if o.rel_step.is_finite() && o.rel_step > 0.0 { o.rel_step.min(0.25) } else { 1e-3 };
    let tol = if o.tol.is_finite() && o.tol >= 0.0 { o.tol } else { 1e-8 };

    // Jacobian in unit space, m x n, columns in parallel (fixed order).
    let jac_unit = |u: &[f64], res: &[f64]| -> DMatrix<f64> {
        let cols: Vec<Vec<f64>> = (0..n)
            .into_par_iter()
            .map(|j| {
                let try_step = |s: f64| -> Option<Vec<f64>> {
                    let mut up = u.to_vec();
                    up[j] = clamp01(u[j] + s);
                    let ds = up[j] - u[j];
                    if ds == 0.0 {
                        return None;
                    }
                    eval(&up).map(|rp| rp.iter().zip(res).map(|(a, b)| (a - b) / ds).collect())
                };
                let first = if u[j] + h <= 1.0 { h } else { -h };
                try_step(first).or_else(|| try_step(-first)).unwrap_or_else(|| vec![0.0; m])
            })
            .collect();
        DMatrix::from_fn(m, n, |i, j| cols[j][i])
    };

    let mut cost = cost_of(&res);
    let mut lambda = 1e-3;
    let mut iters = 0usize;
    let mut converged = false;
    let mut jac: Option<DMatrix<f64>> = None;

    if n == 0 || cost == 0.0 {
        converged = true;
    }
    'outer: while !converged && iters < o.max_iters {
        let j = jac_unit(&u, &res);
        iters += 1;
        let jt = j.transpose();
        let a = &jt * &j;
        let g = &jt * DVector::from_column_slice(&res);
        jac = Some(j);

        // Projected gradient: components pushing out of the box don't count.
        let active: Vec<bool> =
            (0..n).map(|k| (u[k] <= 0.0 && g[k] > 0.0) || (u[k] >= 1.0 && g[k] < 0.0)).collect();
        let pg = (0..n).map(|k| if active[k] { 0.0 } else { g[k].abs() }).fold(0.0, f64::max);
        if pg <= tol * 1e-4 * cost.max(f64::MIN_POSITIVE) {
            converged = true;
            break;
        }
        let maxdiag = (0..n).map(|k| a[(k, k)]).fold(0.0, f64::max);
        let dfloor = (maxdiag * 1e-9).max(1e-300);
        loop {
            // Active-set reduction: variables held at a bound they are pushed
            // against are frozen (identity row/column, zero right-hand side).
            let mut damped = a.clone();
            let mut rhs = -&g;
            for k in 0..n {
                if active[k] {
                    damped.row_mut(k).fill(0.0);
                    damped.column_mut(k).fill(0.0);
                    damped[(k, k)] = 1.0;
                    rhs[k] = 0.0;
                } else {
                    damped[(k, k)] += lambda * a[(k, k)].max(dfloor);
                }
            }
            let step = damped.cholesky().map(|ch| ch.solve(&rhs));
            let Some(step) = step.filter(|s| s.iter().all(|v| v.is_finite())) else {
                lambda *= 10.0;
                if lambda > 1e16 {
                    break 'outer;
                }
                continue;
            };
            let un: Vec<f64> = (0..n).map(|k| clamp01(u[k] + step[k])).collect();
            let du = (0..n).map(|k| (un[k] - u[k]).abs()).fold(0.0, f64::max);
            if du == 0.0 {
                // Projected step vanished: stationary w.r.t. the active bounds.
                converged = true;
                break 'outer;
            }
            let trial = eval(&un);
            let cn = trial.as_deref().map(cost_of).unwrap_or(f64::INFINITY);
            if cn < cost {
                let rel_drop = (cost - cn) / cost;
                u = un;
                res = trial.unwrap();
                cost = cn;
                jac = None;
                lambda = (lambda / 3.0).max(1e-12);
                if rel_drop <= tol || du <= tol || cost == 0.0 {
                    converged = true;
                }
                break;
            }
            lambda *= 10.0;
            if lambda > 1e16 {
                // No descent even for tiny steps: local minimum up to FD accuracy.
                converged = du <= (tol * 1e3).max(1e-6);
                break 'outer;
            }
        }
    }

    let j = match jac {
        Some(j) => j,
        None => jac_unit(&u, &res),
    };
    let mut jacobian = vec![vec![0.0; np]; m];
    for (k, &i) in sp.free.iter().enumerate() {
        for row in 0..m {
            jacobian[row][i] = j[(row, k)] / sp.span[i];
        }
    }
    LmResult { x: sp.params_of(&u), cost, jacobian, iters, converged }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    fn rosenbrock(x: &[f64]) -> f64 {
        (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2)
    }

    fn rastrigin(x: &[f64]) -> f64 {
        10.0 * x.len() as f64
            + x.iter().map(|v| v * v - 10.0 * (std::f64::consts::TAU * v).cos()).sum::<f64>()
    }

    #[test]
    fn nm_rosenbrock_2d() {
        let b = Bounds { lo: vec![-2.0, -2.0], hi: vec![2.0, 2.0] };
        let o = NelderMeadOpts { max_evals: 2000, xtol: 1e-9, ftol: 1e-14, ..Default::default() };
        let count = AtomicUsize::new(0);
        let f = |x: &[f64]| {
            count.fetch_add(1, Ordering::Relaxed);
            assert!(x.iter().all(|v| (-2.0..=2.0).contains(v)));
            rosenbrock(x)
        };
        let r = nelder_mead(&f, &[-1.2, 1.0], &b, &o);
        assert!((r.x[0] - 1.0).abs() < 1e-4 && (r.x[1] - 1.0).abs() < 1e-4, "{r:?}");
        assert!(r.f < 1e-8);
        assert!(r.evals <= 2000);
        assert_eq!(r.evals, count.load(Ordering::Relaxed));
        assert!(r.converged);
        assert_eq!(r.f, rosenbrock(&r.x));
    }

    #[test]
    fn nm_bound_active() {
        // Unconstrained minimum (3, -0.5) lies outside x <= 2.
        let b = Bounds { lo: vec![-1.0, -1.0], hi: vec![2.0, 1.0] };
        let f = |x: &[f64]| (x[0] - 3.0).powi(2) + (x[1] + 0.5).powi(2);
        let r = nelder_mead(&f, &[0.0, 0.5], &b, &NelderMeadOpts::default());
        assert_eq!(r.x[0], 2.0, "{r:?}");
        assert!((r.x[1] + 0.5).abs() < 1e-5, "{r:?}");
        assert!((r.f - 1.0).abs() < 1e-9);
        assert!(r.converged);
        // Corner optimum, 3-D, with a fixed parameter (lo == hi) that must stay put.
        let b = Bounds { lo: vec![0.0, 0.0, 0.7, 0.0], hi: vec![1.0, 1.0, 0.7, 1.0] };
        let f =
            |x: &[f64]| (x[0] - 3.0).powi(2) + (x[1] + 2.0).powi(2) + (x[3] - 0.25).powi(2) + x[2];
        let r = nelder_mead(&f, &[0.5, 0.5, 123.0, 0.5], &b, &NelderMeadOpts::default());
        assert_eq!(r.x[0], 1.0);
        assert_eq!(r.x[1], 0.0);
        assert_eq!(r.x[2], 0.7);
        assert!((r.x[3] - 0.25).abs() < 1e-5, "{r:?}");
    }

    #[test]
    fn cmaes_rastrigin_3d_global() {
        let b = Bounds { lo: vec![-5.12; 3], hi: vec![5.12; 3] };
        let o = CmaesOpts { max_evals: 20000, seed: 42, ..Default::default() };
        let r = cmaes(&rastrigin, &[3.3, -2.2, 4.1], &b, &o);
        assert!(r.x.iter().all(|v| v.abs() < 1e-3), "{r:?}");
        assert!(r.f < 1e-3, "{r:?}");
        assert!(r.evals <= 20000);
        assert!(r.converged);
    }

    #[test]
    fn cmaes_deterministic() {
        let b = Bounds { lo: vec![-5.12; 3], hi: vec![5.12; 3] };
        let o = CmaesOpts { max_evals: 3000, seed: 7, ..Default::default() };
        let r1 = cmaes(&rastrigin, &[1.0, 2.0, 3.0], &b, &o);
        // Same seed in a single-threaded pool: bit-identical.
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let r2 = pool.install(|| cmaes(&rastrigin, &[1.0, 2.0, 3.0], &b, &o));
        assert_eq!(
            r1.x.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            r2.x.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(r1.f.to_bits(), r2.f.to_bits());
        assert_eq!(r1.evals, r2.evals);
        // A different seed explores differently.
        let r3 = cmaes(&rastrigin, &[1.0, 2.0, 3.0], &b, &CmaesOpts { seed: 8, ..o.clone() });
        assert_ne!(r1.x, r3.x);
    }

    #[test]
    fn cmaes_quantised_delay() {
        // Delay quantised to 2 ms physics steps (simulated delay = nearest whole
        // step) plus a smooth damping parameter; the best plateau is [0.021, 0.023).
        let q = 0.002;
        let true_delay = 0.0213;
        let f = |x: &[f64]| {
            let d = (x[0] / q).round() * q;
            ((d - true_delay) / 0.01).powi(2) + (x[1] - 0.37).powi(2)
        };
        let b = Bounds { lo: vec![0.0, 0.0], hi: vec![0.1, 1.0] };
        let o = CmaesOpts { max_evals: 1500, seed: 3, ..Default::default() };
        let r = cmaes(&f, &[0.08, 0.9], &b, &o);
        assert!((r.x[0] - true_delay).abs() < q, "{r:?}");
        assert!((r.x[1] - 0.37).abs() < 1e-3, "{r:?}");
        // On the best plateau: f = ((0.022 - 0.0213) / 0.01)^2 + tiny.
        assert!((r.f - 0.0049).abs() < 1e-6, "{r:?}");
        assert!(r.evals <= 1500);
    }

    #[test]
    fn golden_multimodal_picks_global() {
        // Broad local minimum at -1 (depth 1), narrow global at 2.1 (depth 2).
        let f =
            |x: f64| -2.0 * (-((x - 2.1) / 0.3).powi(2)).exp() - (-((x + 1.0) / 1.0).powi(2)).exp();
        let count = AtomicUsize::new(0);
        let fc = |x: f64| {
            count.fetch_add(1, Ordering::Relaxed);
            assert!((-4.0..=4.0).contains(&x));
            f(x)
        };
        let (x, fx) = golden_section(&fc, -4.0, 4.0, 1e-7, 100);
        assert!((x - 2.1).abs() < 1e-5, "x = {x}");
        assert!((fx - f(x)).abs() == 0.0 && fx < -1.99);
        assert!(count.load(Ordering::Relaxed) <= 100);
        // Budget respected when tiny.
        count.store(0, Ordering::Relaxed);
        let (x5, _) = golden_section(&fc, -4.0, 4.0, 1e-7, 5);
        assert!(count.load(Ordering::Relaxed) <= 5);
        assert_eq!(x5, 2.0);
        // Reversed bounds and a bound-active minimum.
        let (xb, fb) = golden_section(&|x: f64| x, 3.0, 1.0, 1e-9, 50);
        assert_eq!((xb, fb), (1.0, 1.0));
    }

    /// y = a exp(-b t) + c
    fn exp_model(p: &[f64], t: f64) -> f64 {
        p[0] * (-p[1] * t).exp() + p[2]
    }

    fn exp_data(seed: u64, truth: &[f64], sigma: f64) -> (Vec<f64>, Vec<f64>) {
        let mut rng = Rng::new(seed);
        let t: Vec<f64> = (0..60).map(|i| i as f64 * 0.1).collect();
        let y = t.iter().map(|&ti| exp_model(truth, ti) + sigma * rng.normal()).collect();
        (t, y)
    }

    #[test]
    fn lm_exp_fit_and_uncertainty_calibration() {
        use super::super::stats::uncertainty_from_jacobian;
        let truth = [2.0, 1.3, 0.5];
        let sigma = 0.05;
        let b = Bounds { lo: vec![0.0, 0.01, -2.0], hi: vec![5.0, 5.0, 2.0] };
        let ranges: Vec<f64> = b.lo.iter().zip(&b.hi).map(|(l, h)| h - l).collect();
        let o = LmOpts::default();
        let n_seeds = 50;
        let mut est: Vec<Vec<f64>> = vec![];
        let mut pred: Vec<Vec<f64>> = vec![];
        let mut within2 = 0;
        for seed in 0..n_seeds {
            let (t, y) = exp_data(seed, &truth, sigma);
            let r = |p: &[f64]| {
                t.iter().zip(&y).map(|(&ti, &yi)| exp_model(p, ti) - yi).collect::<Vec<f64>>()
            };
            let fit = levenberg_marquardt(&r, &[1.0, 0.5, 0.0], &b, &o);
            assert!(fit.converged, "seed {seed}: {fit:?}");
            let resid = r(&fit.x);
            assert!((fit.cost - 0.5 * resid.iter().map(|v| v * v).sum::<f64>()).abs() < 1e-15);
            assert_eq!(fit.jacobian.len(), 60);
            // Jacobian (user units) vs analytic at the solution.
            let (a_, b_) = (fit.x[0], fit.x[1]);
            for (i, &ti) in t.iter().enumerate() {
                let e = (-b_ * ti).exp();
                let an = [e, -a_ * ti * e, 1.0];
                for k in 0..3 {
                    assert!((fit.jacobian[i][k] - an[k]).abs() < 0.02, "J[{i}][{k}]");
                }
            }
            let u = uncertainty_from_jacobian(&fit.jacobian, &resid, 3, &ranges);
            assert!(u.identifiable.iter().all(|&v| v));
            if (0..3).all(|k| (fit.x[k] - truth[k]).abs() < 2.0 * u.stderr[k]) {
                within2 += 1;
            }
            if seed == 0 {
                for k in 0..3 {
                    assert!(
                        (fit.x[k] - truth[k]).abs() < 2.0 * u.stderr[k],
                        "param {k}: {:?} {:?}",
                        fit.x,
                        u.stderr
                    );
                }
            }
            est.push(fit.x.clone());
            pred.push(u.stderr.clone());
        }
        // Nominal joint coverage of three ±2σ intervals is ≳ 0.86.
        assert!(within2 >= 40, "only {within2}/50 within 2 stderr");
        for k in 0..3 {
            let mean = est.iter().map(|e| e[k]).sum::<f64>() / n_seeds as f64;
            let emp = (est.iter().map(|e| (e[k] - mean).powi(2)).sum::<f64>()
                / (n_seeds - 1) as f64)
                .sqrt();
            let p = pred.iter().map(|s| s[k]).sum::<f64>() / n_seeds as f64;
            let ratio = p / emp;
            assert!((1.0 / 1.5..=1.5).contains(&ratio), "param {k}: predicted {p} empirical {emp}");
            // Estimator is unbiased to well within its spread.
            assert!(
                (mean - truth[k]).abs() < 3.0 * emp / (n_seeds as f64).sqrt() + 1e-3,
                "param {k} mean {mean}"
            );
        }
    }

    #[test]
    fn lm_bound_active_and_exact() {
        // Noise-free: exact recovery.
        let truth = [2.0, 1.3, 0.5];
        let (t, y) = exp_data(1, &truth, 0.0);
        let b = Bounds { lo: vec![0.0, 0.01, -2.0], hi: vec![5.0, 5.0, 2.0] };
        let r = |p: &[f64]| {
            t.iter().zip(&y).map(|(&ti, &yi)| exp_model(p, ti) - yi).collect::<Vec<f64>>()
        };
        let fit = levenberg_marquardt(&r, &[1.0, 0.5, 0.0], &b, &LmOpts::default());
        for k in 0..3 {
            assert!((fit.x[k] - truth[k]).abs() < 1e-6, "{fit:?}");
        }
        assert!(fit.cost < 1e-12);
        // Offset c forced to be >= 0.8 while data has c = 0.5: c ends at the bound.
        let b2 = Bounds { lo: vec![0.0, 0.01, 0.8], hi: vec![5.0, 5.0, 2.0] };
        let fit2 = levenberg_marquardt(&r, &[1.0, 0.5, 1.5], &b2, &LmOpts::default());
        assert_eq!(fit2.x[2], 0.8, "{fit2:?}");
        assert!(fit2.converged);
        // Reference: Nelder–Mead on the same problem with c fixed at the bound.
        let b3 = Bounds { lo: vec![0.0, 0.01, 0.8], hi: vec![5.0, 5.0, 0.8] };
        let sse = |p: &[f64]| 0.5 * r(p).iter().map(|v| v * v).sum::<f64>();
        let nm = nelder_mead(
            &sse,
            &[1.0, 0.5, 0.8],
            &b3,
            &NelderMeadOpts { xtol: 1e-10, ftol: 1e-15, ..Default::default() },
        );
        assert!((fit2.cost - nm.f).abs() < 1e-9 * (1.0 + nm.f), "{fit2:?} {nm:?}");
        assert!(
            (fit2.x[0] - nm.x[0]).abs() < 1e-4 && (fit2.x[1] - nm.x[1]).abs() < 1e-4,
            "{fit2:?} {nm:?}"
        );
        // Linear case y = 3 + 2 t: stderr equals the OLS closed form.
        let ts: Vec<f64> = (0..20).map(|i| i as f64).collect();
        let mut rng = Rng::new(11);
        let ys: Vec<f64> = ts.iter().map(|&x| 3.0 + 2.0 * x + 0.3 * rng.normal()).collect();
        let rl = |p: &[f64]| {
            ts.iter().zip(&ys).map(|(&x, &y)| p[0] + p[1] * x - y).collect::<Vec<f64>>()
        };
        let bl = Bounds { lo: vec![-10.0, -10.0], hi: vec![10.0, 10.0] };
        let fl = levenberg_marquardt(&rl, &[0.0, 0.0], &bl, &LmOpts::default());
        let n = 20.0;
        let (sx, sy): (f64, f64) = (ts.iter().sum(), ys.iter().sum());
        let sxx: f64 = ts.iter().map(|x| x * x).sum();
        let sxy: f64 = ts.iter().zip(&ys).map(|(x, y)| x * y).sum();
        let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
        let icpt = (sy - slope * sx) / n;
        assert!(
            (fl.x[1] - slope).abs() < 1e-7 && (fl.x[0] - icpt).abs() < 1e-6,
            "{fl:?} {icpt} {slope}"
        );
        let u = super::super::stats::uncertainty_from_jacobian(
            &fl.jacobian,
            &rl(&fl.x),
            2,
            &[20.0, 20.0],
        );
        let s2 = 2.0 * fl.cost / (n - 2.0);
        let se_slope = (s2 * n / (n * sxx - sx * sx)).sqrt();
        assert!((u.stderr[1] / se_slope - 1.0).abs() < 1e-6);
    }

    #[test]
    fn nan_regions_avoided() {
        // Unconstrained optimum (1,1) sits in a region where the "simulation" fails.
        let f = |x: &[f64]| {
            if x[0] + x[1] > 1.5 { f64::NAN } else { (x[0] - 1.0).powi(2) + (x[1] - 1.0).powi(2) }
        };
        let b = Bounds { lo: vec![-2.0, -2.0], hi: vec![2.0, 2.0] };
        let nm = nelder_mead(&f, &[-1.0, 0.0], &b, &NelderMeadOpts::default());
        assert!(nm.f.is_finite() && nm.x[0] + nm.x[1] <= 1.5, "{nm:?}");
        // Constrained optimum on the failure boundary: (0.75, 0.75), f = 0.125.
        assert!(nm.f < 0.125 + 1e-6 && (nm.x[0] - 0.75).abs() < 1e-4, "{nm:?}");
        let cm = cmaes(&f, &[-1.0, 0.0], &b, &CmaesOpts { max_evals: 3000, ..Default::default() });
        assert!(cm.f.is_finite() && cm.x[0] + cm.x[1] <= 1.5, "{cm:?}");
        assert!(cm.f < 0.125 + 1e-3, "{cm:?}");
        let (gx, gf) = golden_section(&|x: f64| f(&[x, x]), -2.0, 2.0, 1e-9, 60);
        assert!(gf.is_finite() && (gx - 0.75).abs() < 1e-6, "{gx} {gf}");
        // Objective that is NaN everywhere: no panic, infinite f, not converged.
        let all_nan = |_: &[f64]| f64::NAN;
        let r = nelder_mead(
            &all_nan,
            &[0.0, 0.0],
            &b,
            &NelderMeadOpts { max_evals: 100, ..Default::default() },
        );
        assert!(r.f.is_infinite() && !r.converged && r.evals <= 100);
        let r =
            cmaes(&all_nan, &[0.0, 0.0], &b, &CmaesOpts { max_evals: 200, ..Default::default() });
        assert!(r.f.is_infinite() && !r.converged && r.evals <= 200);
        // LM: residuals NaN for b > 1.6; start at b = 1.5 so naive steps overshoot into it.
        let truth = [2.0, 1.3, 0.5];
        let (t, y) = exp_data(5, &truth, 0.02);
        let rr = |p: &[f64]| {
            if p[1] > 1.6 {
                return vec![f64::NAN; t.len()];
            }
            t.iter().zip(&y).map(|(&ti, &yi)| exp_model(p, ti) - yi).collect::<Vec<f64>>()
        };
        let bb = Bounds { lo: vec![0.0, 0.01, -2.0], hi: vec![5.0, 5.0, 2.0] };
        let fit = levenberg_marquardt(&rr, &[4.0, 1.55, -1.0], &bb, &LmOpts::default());
        assert!(fit.cost.is_finite() && fit.converged, "{fit:?}");
        assert!((fit.x[1] - 1.3).abs() < 0.1 && (fit.x[0] - 2.0).abs() < 0.1, "{fit:?}");
        assert!(fit.jacobian.iter().flatten().all(|v| v.is_finite()));
    }

    #[test]
    fn degenerate_inputs() {
        let f = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
        let rf = |x: &[f64]| x.to_vec();
        let empty = Bounds { lo: vec![], hi: vec![] };
        let b2 = Bounds { lo: vec![0.0, 0.0], hi: vec![1.0, 1.0] };
        let bad = Bounds { lo: vec![1.0, 0.0], hi: vec![0.0, f64::NAN] };
        for (x0, b) in [(&[][..], &empty), (&[0.5][..], &b2), (&[0.5, 0.5][..], &bad)] {
            let r = nelder_mead(&f, x0, b, &NelderMeadOpts::default());
            assert!(!r.converged && r.evals == 0);
            let r = cmaes(&f, x0, b, &CmaesOpts::default());
            assert!(!r.converged && r.evals == 0);
            let r = levenberg_marquardt(&rf, x0, b, &LmOpts::default());
            assert!(!r.converged && r.iters == 0);
        }
        // Zero budgets.
        assert!(
            !nelder_mead(
                &f,
                &[0.5, 0.5],
                &b2,
                &NelderMeadOpts { max_evals: 0, ..Default::default() }
            )
            .converged
        );
        assert!(
            !cmaes(&f, &[0.5, 0.5], &b2, &CmaesOpts { max_evals: 0, ..Default::default() })
                .converged
        );
        let r = cmaes(
            &f,
            &[0.5, 0.5],
            &b2,
            &CmaesOpts { max_evals: 3, popsize: Some(1), ..Default::default() },
        );
        assert!(r.evals <= 3 && r.f.is_finite());
        // Empty residual vector.
        let r = levenberg_marquardt(
            &|_: &[f64]| vec![],
            &[0.5],
            &Bounds { lo: vec![0.0], hi: vec![1.0] },
            &LmOpts::default(),
        );
        assert!(!r.converged);
        // x0 outside the box and all-fixed parameters.
        let fixed = Bounds { lo: vec![0.3, 0.4], hi: vec![0.3, 0.4] };
        let r = nelder_mead(&f, &[9.0, -9.0], &fixed, &NelderMeadOpts::default());
        assert_eq!(r.x, vec![0.3, 0.4]);
        assert_eq!(r.evals, 1);
        let r = cmaes(&f, &[9.0, 9.0], &b2, &CmaesOpts { max_evals: 500, ..Default::default() });
        assert!(r.x.iter().all(|v| (0.0..=1.0).contains(v)) && r.f < 1e-8, "{r:?}");
        let lr = levenberg_marquardt(&rf, &[9.0, 9.0], &fixed, &LmOpts::default());
        assert_eq!(lr.x, vec![0.3, 0.4]);
        assert!(lr.converged);
        // golden_section degenerate bounds.
        assert_eq!(golden_section(&|x| x * x, 2.0, 2.0, 1e-6, 10), (2.0, 4.0));
        assert!(golden_section(&|x| x, f64::NAN, 1.0, 1e-6, 10).1.is_infinite());
        assert!(golden_section(&|x| x, 0.0, 1.0, 1e-6, 0).1.is_infinite());
        let (x1, _) = golden_section(&|x: f64| (x - 0.3).abs(), 0.0, 1.0, 0.0, 1);
        assert_eq!(x1, 0.5);
    }
}
