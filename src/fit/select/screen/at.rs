//! The linear model of a [`Screen`] at a given step: what it predicts for a parameter step that
//! is not its own least-squares optimum (the training linear step, judged on the held-out
//! set's columns by [`super::super::trust::heldout_confirmed`]).

use super::Screen;

impl Screen {
    /// The relative gain on the probes' data (1 − RMSE after / before) that the linear model of
    /// `effect` on `group` predicts for the step `x` of its probed parameters from the
    /// effect's start ([`Screen::steps`]' parameters, in their order; missing ones at 0):
    /// `2 xᵀb − xᵀGx` of the residual's sum of squares explained (negative where the step
    /// makes the residual worse). `None` when a joint of `group` has no column or the probes'
    /// data has no residual.
    pub(in crate::fit::select) fn gain_at(
        &self,
        effect: &str,
        group: &[String],
        x: &[f64],
    ) -> Option<f64> {
        let m = self.models.get(effect)?;
        let ix: Vec<usize> = group
            .iter()
            .map(|j| m.joints.iter().position(|x| x == j))
            .collect::<Option<Vec<_>>>()?;
        let s = m.k;
        if self.train_n == 0 || !(self.train_ss > 0.0) {
            return None;
        }
        let at = |p: usize| x.get(p).copied().filter(|v| v.is_finite()).unwrap_or(0.0);
        let mut explained = 0.0;
        for p in 0..s {
            let b: f64 = ix.iter().map(|&i| m.b[i][p]).sum();
            explained += 2.0 * at(p) * b;
            for q in 0..s {
                let g: f64 = ix
                    .iter()
                    .flat_map(|&i| ix.iter().map(move |&j| (i, j)))
                    .map(|(i, j)| m.g[i * s + p][j * s + q])
                    .sum();
                explained -= at(p) * at(q) * g;
            }
        }
        let left = (self.train_ss - explained).max(0.0);
        Some(1.0 - (left / self.train_ss).sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::super::{EffectModel, Screen};

    /// Two parameters on two joints, columns built by hand: at the least-squares step the
    /// gain is the one `steps` predicts; at no step it is 0; at a step the residual does not
    /// ask for, the residual grows (a negative gain) by exactly the squared change.
    #[test]
    fn the_gain_at_a_step_is_the_linear_model_there() {
        let d = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
        // Columns per joint and parameter: joint a's (a0, a1), joint b's (b0, b1).
        let cols = [
            [1.0, 0.0, 1.0, 0.5, 0.0, 0.0],
            [0.0, 1.0, 1.0, -0.5, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 1.0, 2.0],
            [0.0, 0.0, 0.0, 0.0, -1.0, 1.0],
        ];
        // The residual the shared step (2, 3) explains on both joints, and some more.
        let r: Vec<f64> = (0..6)
            .map(|i| {
                2.0 * (cols[0][i] + cols[2][i]) + 3.0 * (cols[1][i] + cols[3][i]) + 0.1 * i as f64
            })
            .collect();
        let b =
            vec![vec![d(&cols[0], &r), d(&cols[1], &r)], vec![d(&cols[2], &r), d(&cols[3], &r)]];
        let g: Vec<Vec<f64>> =
            (0..4).map(|i| (0..4).map(|j| d(&cols[i], &cols[j])).collect()).collect();
        let m = EffectModel {
            joints: vec!["a".into(), "b".into()],
            room: vec![(-10.0, 10.0); 2],
            k: 2,
            ranked: 2,
            b,
            g,
            held: vec![0, 0],
        };
        let ss = d(&r, &r);
        let s = Screen {
            models: [("e", m)].into(),
            train_ss: ss,
            train_n: r.len(),
            screen_rmse: 1.0,
            pieces: 1,
        };
        let group = ["a".to_string(), "b".to_string()];
        let (p, x) = s.steps("e", &group).expect("modelled");
        let at = s.gain_at("e", &group, &x).expect("modelled");
        assert!((at - (1.0 - p.train_rmse / s.base_rmse())).abs() < 1e-12, "{at} {p:?}");
        assert!(at > 0.5, "{at}");
        assert_eq!(s.gain_at("e", &group, &[0.0, 0.0]), Some(0.0));
        // The opposite step: the residual r + (moved) has r's sum of squares plus 4 xᵀb.
        let back: Vec<f64> = x.iter().map(|v| -v).collect();
        let worse = s.gain_at("e", &group, &back).expect("modelled");
        let direct: Vec<f64> = (0..6)
            .map(|i| {
                let moved =
                    back[0] * (cols[0][i] + cols[2][i]) + back[1] * (cols[1][i] + cols[3][i]);
                r[i] - moved
            })
            .collect();
        assert!((worse - (1.0 - (d(&direct, &direct) / ss).sqrt())).abs() < 1e-12, "{worse}");
        assert!(worse < 0.0);
        // A joint without a column: no prediction.
        assert_eq!(s.gain_at("e", &["c".to_string()], &x), None);
    }
}
