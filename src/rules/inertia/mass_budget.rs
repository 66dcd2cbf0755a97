use crate::declare_rule;
use crate::finding::{Finding, Severity, Subject};
use crate::rules::{Context, Rule, RuleMeta};
use crate::util::fmt_num;

declare_rule! {
    /// ## What it does
    /// Compares the robot's mass (the compiled mass of every body that moves or carries one
    /// that moves: a fixed arm's base counts, a scene's table or walls do not) with the mass
    /// budget the hardware spec states (`robot.mass_kg = [min, max]`, kg). Runs only with a
    /// spec that sets it.
    ///
    /// ## Why is this bad?
    /// A model lighter or heavier than the robot (a battery, cables, a payload left out; a CAD
    /// export in the wrong unit; a placeholder mass) gets the wrong gravity load on every joint,
    /// the wrong contact forces and the wrong base dynamics: a policy trained on it pushes too
    /// hard or too little on hardware. The spec's budget is the weighed robot's.
    ///
    /// ## How it is confirmed
    /// Static: the compiled `body_mass`; no simulation measures a mass budget.
    ///
    /// ## How to fix
    /// Correct the bodies' `mass` (or their geoms' density) so the model weighs what the robot
    /// weighs, or correct the spec's budget if the robot changed.
    pub MassBudget {
        id: "mass-budget",
        group: "inertia",
        level: Severity::Warning,
        probe: None,
        options: [],
    }
}

impl Rule for MassBudget {
    fn meta(&self) -> &'static RuleMeta {
        &Self::META
    }
    fn check(&self, cx: &Context, out: &mut Vec<Finding>) {
        let Some(spec) = cx.spec else { return };
        let Some(budget) = &spec.robot.mass_kg else { return };
        let [lo, hi] = *budget.get_ref();
        let (m, scenery) = cx.robot.mass_split();
        if (lo..=hi).contains(&m) {
            return;
        }
        let side = if m < lo { "below" } else { "above" };
        let f = cx
            .finding(
                format!(
                    "the robot weighs {} kg, {side} the spec's mass budget [{}, {}] kg",
                    fmt_num(m, 4),
                    fmt_num(lo, 4),
                    fmt_num(hi, 4)
                ),
                spec.loc(budget.span()),
            )
            .label(format!("robot: {} kg", fmt_num(m, 4)))
            .element("model", cx.robot.root_loc())
            .note(format!("every joint's gravity load, the contact forces and the base's dynamics scale with the mass; a policy trained on the wrong mass pushes too hard or too little on hardware{}", scenery_note(scenery)))
            .help("correct the bodies' masses (or their geoms' density) to the weighed robot's, or the budget if the robot changed")
            .subject(Subject::Model)
            .with("mass_kg", m);
        out.push(f);
    }
}

/// What the robot's mass leaves out, for the note ("" when the model has no static scenery).
fn scenery_note(scenery: f64) -> String {
    if scenery > 0.0 {
        format!(
            " (the robot: every body that moves or carries one that moves; the {} kg of static scenery is not counted)",
            fmt_num(scenery, 4)
        )
    } else {
        String::new()
    }
}
