use crate::declare_rule;
use crate::finding::{Finding, Severity};
use crate::rules::{Context, Rule, RuleMeta};

declare_rule! {
    /// ## What it does
    /// PLACEHOLDER — not implemented yet.
    pub GainsUnstableForTimestep { id: "gains-unstable-for-timestep", group: "control", level: Severity::Warning, probe: None, options: [] }
}

impl Rule for GainsUnstableForTimestep {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, _cx: &Context, _out: &mut Vec<Finding>) {}
}
