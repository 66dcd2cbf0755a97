//! Bounded CMA-ES with IPOP restarts (deterministic, population evaluated in parallel).

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rayon::prelude::*;
use serde::Serialize;

use super::{
    Bounds, OptResult, Rng, Space, clamp01, invalid_result, reflect01, sanitize, seeded_rng,
};

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
    let mut rng = seeded_rng(o.seed);
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
            let z = DVector::from_fn(n, |_, _| rng.normal_complement());
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

#[cfg(test)]
mod tests {
    use super::*;

    fn rastrigin(x: &[f64]) -> f64 {
        10.0 * x.len() as f64
            + x.iter().map(|v| v * v - 10.0 * (std::f64::consts::TAU * v).cos()).sum::<f64>()
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
}
