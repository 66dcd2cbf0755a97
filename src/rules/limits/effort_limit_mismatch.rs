use crate::declare_rule;
use crate::finding::{Finding, Severity};
use crate::rules::{Context, Rule, RuleMeta};

declare_rule! {
    /// ## What it does
    /// PLACEHOLDER — not implemented yet.
    pub EffortLimitMismatch { id: "effort-limit-mismatch", group: "limits", level: Severity::Warning, probe: None, options: [] }
}

impl Rule for EffortLimitMismatch {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, _cx: &Context, _out: &mut Vec<Finding>) {}
}
