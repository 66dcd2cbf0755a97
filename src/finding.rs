//! Findings: what a rule (and its probe) says about a model. One type feeds every output format.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::model::source::Loc;

#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Info,
    Warning,
    Error,
}

impl Severity {
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Info => "info",
            Severity::Warning => "warning",
            Severity::Error => "error",
        }
    }
    pub fn parse(s: &str) -> Option<Severity> {
        match s {
            "info" => Some(Severity::Info),
            "warning" | "warn" => Some(Severity::Warning),
            "error" => Some(Severity::Error),
            _ => None,
        }
    }
}

/// A number with its unit, for `measured` / `expected`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Quantity {
    pub value: f64,
    pub unit: String,
}

pub fn q(value: f64, unit: &str) -> Quantity {
    Quantity { value, unit: unit.to_string() }
}

/// A secondary place related to a finding (the default class a value came from, the spec line).
#[derive(Debug, Clone)]
pub struct Label {
    pub loc: Loc,
    pub text: String,
}

/// What a finding is about, so that a probe can run an experiment on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "id")]
pub enum Subject {
    Model,
    Joint(usize),
    Actuator(usize),
    Geom(usize),
    Body(usize),
    /// Both feet / a side: body id of the foot.
    Foot(usize),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ProbeStatus {
    /// The experiment reproduced the consequence the finding predicts.
    Confirmed,
    /// Numbers about the consequence, no verdict (a fact of the file gets no other result).
    Measured,
    /// The experiment could not test the claim (`reason` says why).
    Inconclusive,
    /// The claim's recorded preconditions were all met and the consequence did not occur.
    Refuted,
    /// The probe was not run for this finding (`reason` says why).
    Skipped,
}

/// The result of a probe simulation on one finding.
#[derive(Debug, Clone, Serialize)]
pub struct ProbeOutcome {
    pub name: String,
    pub status: ProbeStatus,
    /// Why the run could not test the claim (inconclusive) or was not run (skipped).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// What the experiment had to reach before its result could speak about the claim.
    pub preconditions: Vec<crate::probe::Precondition>,
    pub measured: BTreeMap<String, f64>,
    pub steps: usize,
    /// One sentence: "confirmed by …: measured ζ = 0.31 (predicted 0.29)".
    pub note: String,
    /// The level the measurement sets (applied to the finding by `probe::confirm`, then cleared).
    #[serde(skip)]
    pub level: Option<crate::probe::MeasuredLevel>,
}

#[derive(Debug, Clone)]
pub struct Finding {
    pub rule: &'static str,
    pub severity: Severity,
    /// What is wrong.
    pub message: String,
    /// Why it matters.
    pub note: Option<String>,
    /// What to do.
    pub help: Option<String>,
    /// The tightest span (the attribute value when there is one).
    pub primary: Loc,
    pub primary_label: String,
    /// The element the finding is about (suppression comments on it apply).
    pub element_loc: Option<Loc>,
    pub labels: Vec<Label>,
    /// e.g. "joint left_knee".
    pub element: String,
    pub subject: Subject,
    pub measured: Option<Quantity>,
    pub expected: Option<Quantity>,
    /// Extra numbers a probe can compare against (e.g. predicted damping ratio).
    pub data: BTreeMap<String, f64>,
    /// What the rule's probe can check about this finding (the rule's typed claim).
    pub claim: Option<std::sync::Arc<dyn crate::probe::ProbeCheck>>,
    pub probe: Option<ProbeOutcome>,
    /// A fact of the file (no range, no damping, ctrlrange equal to the hard range, zero
    /// armature, no actuator): simulation never refutes or downgrades it; its probe, if any, is
    /// a [`crate::probe::Measure`] of the consequence.
    pub fact: bool,
}

impl Finding {
    pub fn new(
        rule: &'static str,
        severity: Severity,
        message: impl Into<String>,
        primary: Loc,
    ) -> Self {
        Finding {
            rule,
            severity,
            message: message.into(),
            note: None,
            help: None,
            primary,
            primary_label: String::new(),
            element_loc: None,
            labels: Vec::new(),
            element: String::new(),
            subject: Subject::Model,
            measured: None,
            expected: None,
            data: BTreeMap::new(),
            claim: None,
            probe: None,
            fact: false,
        }
    }
    pub fn note(mut self, s: impl Into<String>) -> Self {
        self.note = Some(s.into());
        self
    }
    pub fn help(mut self, s: impl Into<String>) -> Self {
        self.help = Some(s.into());
        self
    }
    pub fn label(mut self, s: impl Into<String>) -> Self {
        self.primary_label = s.into();
        self
    }
    pub fn element(mut self, s: impl Into<String>, loc: Loc) -> Self {
        self.element = s.into();
        self.element_loc = Some(loc);
        self
    }
    pub fn subject(mut self, s: Subject) -> Self {
        self.subject = s;
        self
    }
    pub fn measured(mut self, v: f64, unit: &str) -> Self {
        self.measured = Some(q(v, unit));
        self
    }
    pub fn expected(mut self, v: f64, unit: &str) -> Self {
        self.expected = Some(q(v, unit));
        self
    }
    pub fn with(mut self, key: &str, v: f64) -> Self {
        self.data.insert(key.to_string(), v);
        self
    }
    /// The claim the rule's probe checks (`--no-probe` leaves it unchecked).
    pub fn claim(mut self, c: impl crate::probe::Claim) -> Self {
        self.claim = Some(std::sync::Arc::new(crate::probe::AsClaim(c)));
        self
    }
    /// Marks the finding a fact of the file: no probe can refute or downgrade it.
    pub fn fact(mut self) -> Self {
        self.fact = true;
        self
    }
    /// A fact of the file whose probe measures the consequence (implies [`Finding::fact`]).
    pub fn measure(mut self, m: impl crate::probe::Measure) -> Self {
        self.set_measure(m);
        self
    }
    /// In place: [`Finding::measure`].
    pub fn set_measure(&mut self, m: impl crate::probe::Measure) {
        self.fact = true;
        self.claim = Some(std::sync::Arc::new(crate::probe::AsMeasure(m)));
    }
    pub fn secondary(mut self, loc: Loc, text: impl Into<String>) -> Self {
        self.labels.push(Label { loc, text: text.into() });
        self
    }
}
