//! Probe simulations: short MuJoCo experiments that confirm or refute static findings.
//!
//! A probe is a type implementing [`Probe`], one per file: what one run is about (`Key`: a joint,
//! an actuator, a geom pair, the whole model), what it measures (`Output`, a typed payload), how
//! to run it. A rule that can be confirmed names its probe by type (`declare_rule!`'s `probe:`)
//! and attaches to each finding a [`Claim`] for that probe: the claim says which run it needs and
//! owns the interpretation of the result (confirmed / refuted / inconclusive, measured values, a
//! one-sentence note). This module only plans the runs (deduplicated: one step response per
//! joint, one stance settle per model), runs them in parallel, and hands each finding's claim its
//! result. A refuted finding is downgraded to info and says why. All probes are deterministic.

pub mod bench;
pub mod direction;
pub mod impulse;
pub mod limit;
pub mod penetration;
pub mod sanity;
pub mod settle;

use std::any::{Any, TypeId};
use std::collections::BTreeMap;
use std::fmt::Debug;

use crate::finding::{Finding, ProbeOutcome, ProbeStatus, Severity};
use crate::lint::Loaded;

pub use direction::ActuatorDirection;
pub use impulse::ImpulseResponse;
pub use limit::LimitApproach;
pub use penetration::KeyframePenetration;
pub use sanity::WholeModelSanity;
pub use settle::StanceSettle;

/// One kind of probe simulation.
pub trait Probe: 'static {
    /// The probe's name in the output (`confirmed by probe `…``) and the rule pages.
    const NAME: &'static str;
    /// Runs with contacts on the whole model go first, so that two cores finish together.
    const WHOLE_MODEL: bool = false;
    /// Why [`Probe::run`] returned nothing (shown as "not probed: …").
    const UNAVAILABLE: &'static str;
    /// What one run is about.
    type Key: Ord + Copy + Debug + Send + Sync + 'static;
    /// What one run measures.
    type Output: Clone + Debug + Send + Sync + 'static;
    /// One run; `None` when the bench cannot be set up for this key.
    fn run(l: &Loaded, key: Self::Key) -> Option<Self::Output>;
    /// Number of simulation steps the run took (shown with the verdict).
    fn steps(out: &Self::Output) -> usize;
}

/// What a probe's verdict on one finding says.
#[derive(Debug, Clone)]
pub struct Verdict {
    pub status: ProbeStatus,
    /// Measured values, for the JSON/SARIF output.
    pub measured: BTreeMap<String, f64>,
    /// One sentence for the human output ("measured ζ = 0.31 (predicted 0.29)").
    pub note: String,
}

impl Verdict {
    pub fn new(
        status: ProbeStatus,
        measured: BTreeMap<String, f64>,
        note: impl Into<String>,
    ) -> Self {
        Verdict { status, measured, note: note.into() }
    }
}

/// What a finding claims that its rule's probe can check. Implemented in the rule's file: the
/// rule, not this module, interprets the probe's typed result.
pub trait Claim: Debug + Send + Sync + 'static {
    type Probe: Probe;
    /// The run this claim needs, or why the finding cannot be probed.
    fn key(&self, l: &Loaded) -> Result<<Self::Probe as Probe>::Key, &'static str>;
    /// The verdict on the run's result.
    fn judge(&self, l: &Loaded, out: &<Self::Probe as Probe>::Output) -> Verdict;
}

/// A [`Claim`] with its probe type erased, as a finding carries it.
pub trait ProbeCheck: Debug + Send + Sync {
    /// The name of the probe the claim is for.
    fn probe_name(&self) -> &'static str;
    /// Adds the run the claim needs to the plan (once per key).
    fn plan(&self, plan: &mut Plan<'_>);
    /// The outcome of the planned run for this claim.
    fn outcome(&self, l: &Loaded, runs: &Runs) -> ProbeOutcome;
}

impl<C: Claim> ProbeCheck for C {
    fn probe_name(&self) -> &'static str {
        C::Probe::NAME
    }
    fn plan(&self, plan: &mut Plan<'_>) {
        if let Ok(key) = self.key(plan.l) {
            plan.add::<C::Probe>(key);
        }
    }
    fn outcome(&self, l: &Loaded, runs: &Runs) -> ProbeOutcome {
        let name = C::Probe::NAME;
        let skipped = |why: &str| ProbeOutcome {
            name: name.into(),
            status: ProbeStatus::Skipped,
            measured: BTreeMap::new(),
            steps: 0,
            note: why.into(),
        };
        let key = match self.key(l) {
            Ok(k) => k,
            Err(why) => return skipped(why),
        };
        match runs.get::<C::Probe>(key) {
            Some(out) => {
                let v = self.judge(l, out);
                ProbeOutcome {
                    name: name.into(),
                    status: v.status,
                    measured: v.measured,
                    steps: C::Probe::steps(out),
                    note: v.note,
                }
            }
            None => skipped(C::Probe::UNAVAILABLE),
        }
    }
}

type Table<P> = BTreeMap<<P as Probe>::Key, Option<<P as Probe>::Output>>;

/// The results of the runs, by probe type and key.
#[derive(Default)]
pub struct Runs {
    tables: BTreeMap<TypeId, Box<dyn Any + Send + Sync>>,
}

impl Runs {
    fn table<P: Probe>(&self) -> Option<&Table<P>> {
        self.tables.get(&TypeId::of::<P>())?.downcast_ref::<Table<P>>()
    }
    fn contains<P: Probe>(&self, key: P::Key) -> bool {
        self.table::<P>().is_some_and(|t| t.contains_key(&key))
    }
    fn insert<P: Probe>(&mut self, key: P::Key, out: Option<P::Output>) {
        let t = self.tables.entry(TypeId::of::<P>()).or_insert_with(|| Box::new(Table::<P>::new()));
        if let Some(t) = t.downcast_mut::<Table<P>>() {
            t.insert(key, out);
        }
    }
    /// The result of probe `P` on `key`: `None` when it was not run or could not be set up.
    pub fn get<P: Probe>(&self, key: P::Key) -> Option<&P::Output> {
        self.table::<P>()?.get(&key)?.as_ref()
    }
}

/// A run to do: computes its result, then stores it.
type Job<'a> = Box<dyn FnOnce() -> Box<dyn FnOnce(&mut Runs) + Send + 'a> + Send + 'a>;

/// The runs to do, each once.
pub struct Plan<'a> {
    l: &'a Loaded,
    planned: Runs,
    jobs: Vec<(bool, Job<'a>)>,
}

impl<'a> Plan<'a> {
    pub fn new(l: &'a Loaded) -> Self {
        Plan { l, planned: Runs::default(), jobs: Vec::new() }
    }
    /// Plans one run of probe `P` (nothing when it is already planned).
    pub fn add<P: Probe>(&mut self, key: P::Key) {
        if self.planned.contains::<P>(key) {
            return;
        }
        self.planned.insert::<P>(key, None);
        let l = self.l;
        let job: Job<'a> = Box::new(move || {
            let out = P::run(l, key);
            Box::new(move |runs: &mut Runs| runs.insert::<P>(key, out))
        });
        self.jobs.push((P::WHOLE_MODEL, job));
    }
    /// Runs every planned simulation. They are independent (each on its own copy of the model)
    /// and run in parallel; results are keyed, so nothing depends on scheduling.
    pub fn run(self) -> Runs {
        use rayon::prelude::*;
        let mut jobs = self.jobs;
        // Longest first (whole-model runs with contacts), so that two cores finish together.
        jobs.sort_by_key(|(whole, _)| !*whole);
        let stores: Vec<_> = jobs.into_par_iter().map(|(_, job)| job()).collect();
        let mut runs = Runs::default();
        for store in stores {
            store(&mut runs);
        }
        runs
    }
}

/// Runs the probe of every finding that carries a claim, with the extra runs already in `plan`
/// (e.g. the whole-model sanity run), and records each finding's outcome. Returns the results
/// (for the extra runs).
pub fn confirm(findings: &mut [Finding], mut plan: Plan<'_>) -> Runs {
    let l = plan.l;
    for f in findings.iter() {
        if let Some(c) = &f.claim {
            c.plan(&mut plan);
        }
    }
    let runs = plan.run();
    for f in findings.iter_mut() {
        let Some(c) = f.claim.clone() else { continue };
        let p = c.outcome(l, &runs);
        if p.status == ProbeStatus::Refuted && f.severity > Severity::Info {
            f.severity = Severity::Info;
            f.message = format!("{} (refuted by simulation)", f.message);
        }
        f.probe = Some(p);
    }
    runs
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;
    use crate::lint::{LintInput, load};
    use crate::model::source::Loc;

    static RUNS: AtomicUsize = AtomicUsize::new(0);

    /// A probe that counts its runs and echoes its key (no run for key 0).
    struct Echo;
    impl Probe for Echo {
        const NAME: &'static str = "echo";
        const UNAVAILABLE: &'static str = "nothing to echo";
        type Key = usize;
        type Output = usize;
        fn run(_: &Loaded, key: usize) -> Option<usize> {
            RUNS.fetch_add(1, Ordering::SeqCst);
            (key != 0).then_some(key)
        }
        fn steps(out: &usize) -> usize {
            *out * 10
        }
    }

    /// Claims the echo is above a bound; `key: None` cannot be probed.
    #[derive(Debug)]
    struct Above {
        key: Option<usize>,
        bound: usize,
    }
    impl Claim for Above {
        type Probe = Echo;
        fn key(&self, _: &Loaded) -> Result<usize, &'static str> {
            self.key.ok_or("no key")
        }
        fn judge(&self, _: &Loaded, out: &usize) -> Verdict {
            let st = if *out > self.bound { ProbeStatus::Confirmed } else { ProbeStatus::Refuted };
            Verdict::new(st, BTreeMap::from([("echo".to_string(), *out as f64)]), format!("{out}"))
        }
    }

    #[test]
    fn each_run_once_and_each_claim_judged() {
        let input = LintInput {
            model: "fixtures/rules/underdamped-pd-gains/invalid.xml".into(),
            spec: None,
            config: None,
            select: vec![],
            ignore: vec![],
        };
        let l = load(&input).unwrap();
        let at = Loc { file: 0, start: 0, end: 1 };
        let finding =
            |key, bound| Finding::new("x", Severity::Error, "m", at).claim(Above { key, bound });
        let mut fs = vec![
            finding(Some(3), 1),
            finding(Some(3), 5),
            finding(Some(7), 1),
            finding(Some(0), 1),
            finding(None, 1),
            Finding::new("x", Severity::Warning, "no claim", at),
        ];
        RUNS.store(0, Ordering::SeqCst);
        confirm(&mut fs, Plan::new(&l));
        // Keys 3, 7 and 0 once each; the claim without a key plans nothing.
        assert_eq!(RUNS.load(Ordering::SeqCst), 3);
        let status = |i: usize| fs[i].probe.as_ref().map(|p| (p.status, p.steps, p.note.clone()));
        assert_eq!(status(0), Some((ProbeStatus::Confirmed, 30, "3".into())));
        // Refuted: downgraded to info, and says so.
        assert_eq!(status(1), Some((ProbeStatus::Refuted, 30, "3".into())));
        assert_eq!(fs[1].severity, Severity::Info);
        assert!(fs[1].message.ends_with("(refuted by simulation)"));
        assert_eq!(status(2), Some((ProbeStatus::Confirmed, 70, "7".into())));
        assert_eq!(status(3), Some((ProbeStatus::Skipped, 0, "nothing to echo".into())));
        assert_eq!(status(4), Some((ProbeStatus::Skipped, 0, "no key".into())));
        assert!(fs[5].probe.is_none());
        assert!(fs.iter().take(5).all(|f| f.probe.as_ref().is_some_and(|p| p.name == "echo")));
    }
}
