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
pub mod float;
pub mod impulse;
pub mod limit;
pub mod penetration;
pub mod ringdown;
pub mod sanity;
pub mod settle;
pub mod slide;
pub mod stance;

use std::any::{Any, TypeId};
use std::collections::BTreeMap;
use std::fmt::Debug;

use crate::finding::{Finding, ProbeOutcome, ProbeStatus, Severity};
use crate::lint::Loaded;

pub use direction::ActuatorDirection;
pub use impulse::ImpulseResponse;
pub use limit::LimitApproach;
pub use penetration::KeyframePenetration;
pub use ringdown::RingDown;
pub use sanity::WholeModelSanity;
pub use settle::StanceSettle;
pub use slide::FootSlide;

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

/// One condition the experiment had to reach before its result can speak about the claim
/// ("the model has a floor", "the feet carry ≥ 50 % of the weight", "the joint reached the
/// commanded extreme"). Every verdict records the ones its probe checked, met or not, in the
/// JSON output.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Precondition {
    /// Stable snake_case name (`floor`, `feet_loaded`, `upright`, `stop_exists`, …).
    pub name: &'static str,
    pub met: bool,
    /// What was measured, in one phrase ("the feet carry 3 % of the weight, need ≥ 50 %").
    pub detail: String,
}

/// The preconditions of one run, checked in order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Preconditions(Vec<Precondition>);

/// Proof that every recorded precondition of a run was met. Its field is private: the only way
/// to get one is [`Preconditions::all_met`], and a refutation ([`Verdict::refuted`]) cannot be
/// built without it.
#[derive(Debug, Clone, PartialEq)]
pub struct Met(Vec<Precondition>);

impl Preconditions {
    pub fn new() -> Self {
        Preconditions(Vec::new())
    }
    /// Records one precondition.
    pub fn check(mut self, name: &'static str, met: bool, detail: impl Into<String>) -> Self {
        self.0.push(Precondition { name, met, detail: detail.into() });
        self
    }
    pub fn list(&self) -> &[Precondition] {
        &self.0
    }
    /// The first unmet precondition's detail, if any.
    pub fn unmet(&self) -> Option<&Precondition> {
        self.0.iter().find(|p| !p.met)
    }
    /// Every precondition met: the proof a refutation needs. Otherwise the reason.
    pub fn all_met(&self) -> Result<Met, String> {
        match self.unmet() {
            Some(p) => Err(p.detail.clone()),
            None => Ok(Met(self.0.clone())),
        }
    }
}

/// What a probe's run says about a finding.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    /// The experiment reproduced the consequence the finding predicts.
    Confirmed,
    /// Numbers about the consequence, no verdict (the only result a fact of the file can get).
    Measured,
    /// The experiment could not test the claim; why.
    Inconclusive(String),
    /// The claim's preconditions were met and its predicted consequence did not occur.
    Refuted(Met),
}

/// A probe's verdict on one finding.
#[derive(Debug, Clone)]
pub struct Verdict {
    pub status: Status,
    /// The preconditions the run checked (met or not).
    pub preconditions: Vec<Precondition>,
    /// Measured values, for the JSON/SARIF output.
    pub measured: BTreeMap<String, f64>,
    /// One sentence for the human output ("measured ζ = 0.31 (predicted 0.29)").
    pub note: String,
    /// The level the measurement gives the finding, and its message with the reason, when the
    /// rule grades the finding by how far the measured consequence is past its threshold. Only a
    /// confirmed verdict carries one ([`Verdict::with_level`]).
    pub level: Option<MeasuredLevel>,
}

/// A finding's level set from what the probe measured (see [`Verdict::level`]).
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredLevel {
    pub severity: crate::finding::Severity,
    /// The finding's message, rewritten to say why it has this level.
    pub message: String,
}

impl Verdict {
    /// Gives a confirmed verdict the level its measurement sets; any other verdict is left as it
    /// is (an inconclusive run measured nothing to grade, a refuted one drops to info anyway).
    pub fn with_level(mut self, severity: crate::finding::Severity, message: String) -> Self {
        if self.status == Status::Confirmed {
            self.level = Some(MeasuredLevel { severity, message });
        }
        self
    }
    /// Confirmed: only when every recorded precondition was met; otherwise inconclusive with
    /// the unmet one's detail (a run that could not test the claim confirms nothing either).
    pub fn confirmed(
        pre: &Preconditions,
        measured: BTreeMap<String, f64>,
        note: impl Into<String>,
    ) -> Self {
        if let Some(p) = pre.unmet() {
            return Verdict::inconclusive(pre, measured, p.detail.clone());
        }
        Verdict {
            status: Status::Confirmed,
            preconditions: pre.0.clone(),
            measured,
            note: note.into(),
            level: None,
        }
    }
    pub fn measured(
        pre: &Preconditions,
        measured: BTreeMap<String, f64>,
        note: impl Into<String>,
    ) -> Self {
        Verdict {
            status: Status::Measured,
            preconditions: pre.0.clone(),
            measured,
            note: note.into(),
            level: None,
        }
    }
    /// The experiment could not test the claim: `reason` is the note.
    pub fn inconclusive(
        pre: &Preconditions,
        measured: BTreeMap<String, f64>,
        reason: impl Into<String>,
    ) -> Self {
        let reason = reason.into();
        Verdict {
            status: Status::Inconclusive(reason.clone()),
            preconditions: pre.0.clone(),
            measured,
            note: reason,
            level: None,
        }
    }
    /// Refuted: needs the proof that every precondition was met.
    pub fn refuted(met: Met, measured: BTreeMap<String, f64>, note: impl Into<String>) -> Self {
        let preconditions = met.0.clone();
        Verdict {
            status: Status::Refuted(met),
            preconditions,
            measured,
            note: note.into(),
            level: None,
        }
    }
    /// Refuted when every precondition was met, else inconclusive with the unmet one's detail.
    pub fn refuted_or_inconclusive(
        pre: &Preconditions,
        measured: BTreeMap<String, f64>,
        note: impl Into<String>,
    ) -> Self {
        match pre.all_met() {
            Ok(met) => Verdict::refuted(met, measured, note),
            Err(why) => Verdict::inconclusive(pre, measured, why),
        }
    }
    pub fn probe_status(&self) -> ProbeStatus {
        match self.status {
            Status::Confirmed => ProbeStatus::Confirmed,
            Status::Measured => ProbeStatus::Measured,
            Status::Inconclusive(_) => ProbeStatus::Inconclusive,
            Status::Refuted(_) => ProbeStatus::Refuted,
        }
    }
}

/// What a probe's run says about a fact of the file (no range, no damping, ctrlrange equal to
/// the hard range, zero armature, no actuator): numbers about its consequence, or why the run
/// could not measure it. There is no refuted (and no confirmed) variant: simulation does not
/// decide a fact.
#[derive(Debug, Clone)]
pub struct Measurement {
    /// `None`: measured; `Some(reason)`: the run could not measure the consequence.
    pub inconclusive: Option<String>,
    pub preconditions: Vec<Precondition>,
    pub measured: BTreeMap<String, f64>,
    pub note: String,
}

impl Measurement {
    /// Measured when every precondition was met, else inconclusive with the unmet one's detail.
    pub fn new(
        pre: &Preconditions,
        measured: BTreeMap<String, f64>,
        note: impl Into<String>,
    ) -> Self {
        let note = note.into();
        match pre.unmet() {
            None => {
                Measurement { inconclusive: None, preconditions: pre.0.clone(), measured, note }
            }
            Some(p) => Measurement {
                inconclusive: Some(p.detail.clone()),
                preconditions: pre.0.clone(),
                measured,
                note: p.detail.clone(),
            },
        }
    }
    fn into_verdict(self) -> Verdict {
        Verdict {
            status: match self.inconclusive {
                None => Status::Measured,
                Some(r) => Status::Inconclusive(r),
            },
            preconditions: self.preconditions,
            measured: self.measured,
            note: self.note,
            level: None,
        }
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

/// What a probe measures about a fact of the file (the finding is marked `fact`): the
/// consequence, never a verdict on the fact itself.
pub trait Measure: Debug + Send + Sync + 'static {
    type Probe: Probe;
    /// The run this measurement needs, or why the finding cannot be probed.
    fn key(&self, l: &Loaded) -> Result<<Self::Probe as Probe>::Key, &'static str>;
    fn measure(&self, l: &Loaded, out: &<Self::Probe as Probe>::Output) -> Measurement;
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

fn not_run(name: &str, why: &str) -> ProbeOutcome {
    ProbeOutcome {
        name: name.into(),
        status: ProbeStatus::Skipped,
        reason: Some(why.into()),
        preconditions: Vec::new(),
        measured: BTreeMap::new(),
        steps: 0,
        note: why.into(),
        level: None,
    }
}

fn outcome_of(name: &str, v: Verdict, steps: usize) -> ProbeOutcome {
    ProbeOutcome {
        name: name.into(),
        status: v.probe_status(),
        reason: match &v.status {
            Status::Inconclusive(r) => Some(r.clone()),
            _ => None,
        },
        preconditions: v.preconditions,
        measured: v.measured,
        steps,
        note: v.note,
        level: v.level,
    }
}

/// A [`Claim`] as a finding carries it.
#[derive(Debug)]
pub struct AsClaim<C>(pub C);

/// A [`Measure`] as a finding carries it.
#[derive(Debug)]
pub struct AsMeasure<M>(pub M);

impl<C: Claim> ProbeCheck for AsClaim<C> {
    fn probe_name(&self) -> &'static str {
        C::Probe::NAME
    }
    fn plan(&self, plan: &mut Plan<'_>) {
        if let Ok(key) = self.0.key(plan.l) {
            plan.add::<C::Probe>(key);
        }
    }
    fn outcome(&self, l: &Loaded, runs: &Runs) -> ProbeOutcome {
        let name = C::Probe::NAME;
        let key = match self.0.key(l) {
            Ok(k) => k,
            Err(why) => return not_run(name, why),
        };
        match runs.get::<C::Probe>(key) {
            Some(out) => outcome_of(name, self.0.judge(l, out), C::Probe::steps(out)),
            None => not_run(name, C::Probe::UNAVAILABLE),
        }
    }
}

impl<M: Measure> ProbeCheck for AsMeasure<M> {
    fn probe_name(&self) -> &'static str {
        M::Probe::NAME
    }
    fn plan(&self, plan: &mut Plan<'_>) {
        if let Ok(key) = self.0.key(plan.l) {
            plan.add::<M::Probe>(key);
        }
    }
    fn outcome(&self, l: &Loaded, runs: &Runs) -> ProbeOutcome {
        let name = M::Probe::NAME;
        let key = match self.0.key(l) {
            Ok(k) => k,
            Err(why) => return not_run(name, why),
        };
        match runs.get::<M::Probe>(key) {
            Some(out) => {
                outcome_of(name, self.0.measure(l, out).into_verdict(), M::Probe::steps(out))
            }
            None => not_run(name, M::Probe::UNAVAILABLE),
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
        let mut p = c.outcome(l, &runs);
        if f.fact && p.status == ProbeStatus::Refuted {
            // Unreachable through `Finding::measure` (a `Measurement` has no refuted variant);
            // kept so that no path downgrades a fact of the file.
            p.status = ProbeStatus::Measured;
        }
        if let Some(lv) = p.level.take().filter(|_| p.status == ProbeStatus::Confirmed) {
            f.severity = lv.severity;
            f.message = lv.message;
        }
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
    /// The tests that run `Echo` hold this, so the run counter sees one test's runs.
    static ECHO: std::sync::Mutex<()> = std::sync::Mutex::new(());

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
            let m = BTreeMap::from([("echo".to_string(), *out as f64)]);
            // Precondition: the echo is odd (an even echo cannot test the bound).
            let pre = Preconditions::new().check("odd", out % 2 == 1, "the echo is even");
            if *out > self.bound {
                Verdict::confirmed(&pre, m, format!("{out}"))
            } else {
                Verdict::refuted_or_inconclusive(&pre, m, format!("{out}"))
            }
        }
    }

    #[test]
    fn each_run_once_and_each_claim_judged() {
        let _g = ECHO.lock().unwrap_or_else(|e| e.into_inner());
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
            finding(Some(3), 5), // odd echo: the precondition holds, so refuted
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

    /// Measures the echo of a fact: never a verdict; inconclusive when the echo is even.
    #[derive(Debug)]
    struct EchoFact(usize);
    impl Measure for EchoFact {
        type Probe = Echo;
        fn key(&self, _: &Loaded) -> Result<usize, &'static str> {
            Ok(self.0)
        }
        fn measure(&self, _: &Loaded, out: &usize) -> Measurement {
            let pre = Preconditions::new().check("odd", out % 2 == 1, "the echo is even");
            Measurement::new(&pre, BTreeMap::new(), format!("echo {out}"))
        }
    }

    #[test]
    fn unmet_precondition_is_inconclusive_and_facts_are_never_refuted() {
        let _g = ECHO.lock().unwrap_or_else(|e| e.into_inner());
        let input = LintInput {
            model: "fixtures/rules/underdamped-pd-gains/invalid.xml".into(),
            spec: None,
            config: None,
            select: vec![],
            ignore: vec![],
        };
        let l = load(&input).unwrap();
        let at = Loc { file: 0, start: 0, end: 1 };
        let mut fs = vec![
            // Even echo at or below the bound: the precondition fails, so not refuted.
            Finding::new("x", Severity::Error, "m", at).claim(Above { key: Some(4), bound: 5 }),
            Finding::new("x", Severity::Error, "fact", at).measure(EchoFact(3)),
            Finding::new("x", Severity::Error, "fact", at).measure(EchoFact(4)),
        ];
        confirm(&mut fs, Plan::new(&l));
        let p0 = fs[0].probe.clone().unwrap();
        assert_eq!(p0.status, ProbeStatus::Inconclusive);
        assert_eq!(p0.reason.as_deref(), Some("the echo is even"));
        assert_eq!(p0.preconditions.len(), 1);
        assert!(!p0.preconditions[0].met);
        assert_eq!(fs[0].severity, Severity::Error);
        assert!(fs[1].fact && fs[2].fact);
        assert_eq!(fs[1].probe.as_ref().unwrap().status, ProbeStatus::Measured);
        assert_eq!(fs[2].probe.as_ref().unwrap().status, ProbeStatus::Inconclusive);
        assert!(fs[1..].iter().all(|f| f.severity == Severity::Error && f.message == "fact"));
        // A fact never takes a claim that could refute it.
        let mut f = vec![Finding::new("x", Severity::Error, "fact", at).fact()];
        crate::rules::claim_each(&mut f, |_| Some(Above { key: Some(3), bound: 5 }));
        assert!(f[0].claim.is_none());
    }

    #[test]
    fn a_confirmation_needs_every_precondition_met() {
        let pre = Preconditions::new().check("a", true, "a ok").check("b", false, "b failed");
        let v = Verdict::confirmed(&pre, BTreeMap::new(), "the consequence occurred");
        assert_eq!(v.status, Status::Inconclusive("b failed".into()));
        assert_eq!(v.preconditions, pre.list());
        let ok = Preconditions::new().check("a", true, "a ok");
        let v = Verdict::confirmed(&ok, BTreeMap::new(), "the consequence occurred");
        assert_eq!(v.status, Status::Confirmed);
    }

    #[test]
    fn a_refutation_needs_every_precondition_met() {
        let pre = Preconditions::new().check("a", true, "a ok").check("b", false, "b failed");
        assert_eq!(pre.all_met(), Err("b failed".to_string()));
        let v = Verdict::refuted_or_inconclusive(&pre, BTreeMap::new(), "no effect");
        assert_eq!(v.status, Status::Inconclusive("b failed".into()));
        let ok = Preconditions::new().check("a", true, "a ok");
        let v = Verdict::refuted_or_inconclusive(&ok, BTreeMap::new(), "no effect");
        assert!(matches!(v.status, Status::Refuted(_)));
        assert_eq!(v.preconditions, ok.list());
    }
}
