//! What the kept effects leave unexplained: a joint whose training residual with the final
//! model is still above its floor (noise, command reconstruction and start state, the model's
//! timestep; [`crate::fit::select::Floor`]) by more than the ratio that stops the search carries
//! structure no kept effect accounts for. `fit` says so — where and how large — instead of
//! presenting the kept set as the whole answer (issue 48).

use crate::fit::select::Floor;

/// One joint with an unexplained residual.
#[derive(Debug, Clone, PartialEq)]
pub struct Unexplained {
    pub joint: String,
    /// Training residual RMS of the final model [rad].
    pub residual_rms: f64,
    /// RMS of the floor it is compared with [rad].
    pub floor_rms: f64,
}

impl Unexplained {
    /// The warning line: where, how large, against what.
    pub fn message(&self) -> String {
        format!(
            "unexplained residual on {}: {:.3} mrad RMS ({:.4}°) with the fitted model, {:.1}× the {:.3} mrad its noise, command reconstruction and timestep explain — the kept effects are not the whole answer there",
            self.joint,
            1e3 * self.residual_rms,
            self.residual_rms.to_degrees(),
            self.residual_rms / self.floor_rms.max(1e-300),
            1e3 * self.floor_rms
        )
    }
}

/// The joints whose residual mean square exceeds `ratio` × their floor (the search's
/// `white_ratio`), in the floors' order.
pub fn unexplained(floors: &[Floor], ratio: f64) -> Vec<Unexplained> {
    floors
        .iter()
        .filter(|f| !f.reached(ratio))
        .map(|f| Unexplained {
            joint: f.joint.clone(),
            residual_rms: f.ms.sqrt(),
            floor_rms: (f.white + f.reconstruction + f.discretisation).sqrt(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn floor(joint: &str, ms: f64, white: f64) -> Floor {
        Floor { joint: joint.into(), ms, white, reconstruction: 0.0, discretisation: 0.0 }
    }

    /// A joint at 1.2× its floor is explained (the search stops at 1.5×); one at 4× is not,
    /// and the message gives its RMS (2 mrad) and the ratio (2.0× in RMS).
    #[test]
    fn a_residual_above_its_floor_is_named_with_its_size() {
        let f = [floor("hip", 1.2e-6, 1e-6), floor("knee", 4e-6, 1e-6)];
        let u = unexplained(&f, 1.5);
        assert_eq!(u.len(), 1);
        assert_eq!(u[0].joint, "knee");
        let m = u[0].message();
        assert!(m.starts_with("unexplained residual on knee: 2.000 mrad RMS"), "{m}");
        assert!(m.contains("2.0× the 1.000 mrad"), "{m}");
    }
}
