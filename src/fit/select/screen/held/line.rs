//! The linear model of a group's one shared value when its members start it apart.
//!
//! A candidate on a joint group fits one parameter vector shared by every member
//! ([`crate::fit::effects::Applied`]): an armature group on a leg whose model holds 0.04, 0.03
//! and 0.012 kg·m² on hip, knee and ankle sets all three to one value v. Its columns are
//! probed per member at the member's own start a_i, so to first order v moves the residual by
//! Σ_i (v − a_i) c_i — not by the sum of the columns times one step, which is what
//! [`Screen::predict`] models (each member moved from its own start by the same amount: a
//! direction no shared value takes when the starts differ, and through the round's base, which
//! no shared value replays). This model uses the same columns and costs no replay.

use super::super::{Prediction, Screen};
use crate::fit::effects::{Applied, Effect};
use crate::fit::select::Engine;
use crate::fit::select::trust::starts_apart;

impl Screen {
    /// The relative RMSE gain on the probes' data (1 − √(left / before), negative where the
    /// value makes the residual worse) that `effect`'s one shared value on `group` makes to
    /// first order, each member moved from its own start `starts[i]` (see the module docs), and
    /// that value: at `at` when given, else the least-squares value inside every member's
    /// bounds (the residual's explained sum of squares is a concave quadratic in it). `None`
    /// when the effect's model has more than one parameter, a joint of `group` has no column,
    /// `starts` does not match `group`, the members' bounds do not overlap, or the probes'
    /// data has no residual.
    pub(in crate::fit::select) fn line_gain(
        &self,
        effect: &str,
        group: &[String],
        starts: &[f64],
        at: Option<f64>,
    ) -> Option<(f64, f64)> {
        let m = self.models.get(effect)?;
        if m.k != 1 || starts.len() != group.len() || self.train_n == 0 || !(self.train_ss > 0.0) {
            return None;
        }
        let ix: Vec<usize> = group
            .iter()
            .map(|j| m.joints.iter().position(|x| x == j))
            .collect::<Option<Vec<_>>>()?;
        let pairs = || (0..ix.len()).flat_map(|p| (0..ix.len()).map(move |q| (p, q)));
        let g = |p: usize, q: usize| m.g[ix[p]][ix[q]];
        // explained(v) = 2 Σ s_i b_i − Σ s_i s_j G_ij with s_i = v − a_i.
        let explained = |v: f64| {
            let s: Vec<f64> = starts.iter().map(|a| v - a).collect();
            let lin: f64 = ix.iter().zip(&s).map(|(&i, si)| si * m.b[i][0]).sum();
            2.0 * lin - pairs().map(|(p, q)| s[p] * s[q] * g(p, q)).sum::<f64>()
        };
        let lo = ix.iter().zip(starts).map(|(&i, a)| a + m.room[i].0).fold(f64::MIN, f64::max);
        let hi = ix.iter().zip(starts).map(|(&i, a)| a + m.room[i].1).fold(f64::MAX, f64::min);
        if !(lo <= hi) {
            return None;
        }
        let v = match at {
            Some(v) => v,
            None => {
                // d explained / dv = 2 (Σ b_i + Σ_ij a_j G_ij − v Σ_ij G_ij) (G symmetric).
                let a: f64 = pairs().map(|(p, q)| g(p, q)).sum();
                let lin: f64 = ix.iter().map(|&i| m.b[i][0]).sum::<f64>()
                    + pairs().map(|(p, q)| starts[q] * g(p, q)).sum::<f64>();
                if !(a > 0.0) {
                    return None;
                }
                (lin / a).clamp(lo, hi)
            }
        };
        let left = (self.train_ss - explained(v)).max(0.0);
        let gain = 1.0 - (left / self.train_ss).sqrt();
        (gain.is_finite() && v.is_finite()).then_some((gain, v))
    }
}

impl Screen {
    /// The linear prediction of `effect` on `group` whose members start its one parameter at
    /// `apart` when they differ: the linear model of the group's one shared value at its
    /// least-squares value inside every member's bounds ([`Screen::line_gain`]; the RMSE on
    /// the screen's data's scale, the step from the first member's start, where the group's
    /// value starts) — the summed columns of [`Screen::predict`] model each member moved by one
    /// step from its own start, a direction no shared value takes —; [`Screen::predict`]'s
    /// when `apart` is `None`. `None` when the model cannot be made.
    pub(in crate::fit::select) fn predict_from(
        &self,
        effect: &str,
        group: &[String],
        apart: Option<&[f64]>,
    ) -> Option<Prediction> {
        let Some(a) = apart else { return self.predict(effect, group) };
        let (gain, v) = self.line_gain(effect, group, a, None)?;
        Some(Prediction { train_rmse: self.base_rmse() * (1.0 - gain), step: v - a.first()? })
    }

    /// The lead's measure ([`Screen::lead_rmse`]) of `e` on `g` beside `applied`: of the
    /// shared value's model where the group's members start its parameter apart
    /// ([`starts_apart`], [`Screen::predict_from`]), else of the summed columns.
    pub(in crate::fit::select) fn lead_rmse_beside(
        &self,
        engine: &Engine,
        applied: &[Applied],
        (e, g): (&dyn Effect, &[String]),
    ) -> Option<f64> {
        let apart = starts_apart(engine, applied, (e, g));
        let p = self.predict_from(e.id(), g, apart.as_deref())?;
        Some(self.lead_rmse(e.id(), g, e.fitted(), p))
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::tests::two_member_screen;
    use super::super::super::{EffectModel, Screen};

    /// Three members with columns c_a, c_b, c_c (apart) and a residual made by moving them
    /// from their starts (0.04, 0.03, 0.012) to one shared value 0.06: the model finds that
    /// value and explains the residual whole; at the starts' first member (0.04 on all) it
    /// predicts what the columns give there, worked out by hand; where every member starts at
    /// the same value the model is the summed columns' ([`Screen::predict`]) exactly.
    #[test]
    fn a_shared_value_moves_each_member_from_its_own_start() {
        let cols = [
            vec![1.0, 0.5, -0.2, 0.0, 0.3],
            vec![0.0, 1.0, 0.4, -0.6, 0.1],
            vec![0.2, 0.0, 0.0, 1.0, -0.5],
        ];
        let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
        let model = |starts: &[f64], truth: f64| {
            let r: Vec<f64> = (0..5)
                .map(|t| cols.iter().zip(starts).map(|(c, a)| (truth - a) * c[t]).sum())
                .collect();
            let m = EffectModel {
                joints: vec!["a".into(), "b".into(), "c".into()],
                room: starts.iter().map(|a| (-a, 0.5 - a)).collect(),
                k: 1,
                ranked: 1,
                b: cols.iter().map(|c| vec![dot(c, &r)]).collect(),
                g: cols.iter().map(|x| cols.iter().map(|y| dot(x, y)).collect()).collect(),
                held: vec![0; 3],
            };
            let ss = dot(&r, &r);
            let s = Screen {
                models: [("e", m)].into(),
                train_ss: ss,
                train_n: r.len(),
                screen_rmse: (ss / r.len() as f64).sqrt(),
                pieces: 1,
            };
            (s, r)
        };
        let group: Vec<String> = ["a", "b", "c"].iter().map(|s| s.to_string()).collect();
        let starts = [0.04, 0.03, 0.012];
        let (s, r) = model(&starts, 0.06);
        let (gain, v) = s.line_gain("e", &group, &starts, None).expect("modelled");
        // (The residual left is rounding: its square root, 1e-8 of the base.)
        assert!((v - 0.06).abs() < 1e-12 && (gain - 1.0).abs() < 1e-6, "{v} {gain}");
        // At 0.04 on every member: the hip stays, knee and ankle move by 0.01 and 0.028.
        let left: Vec<f64> = (0..5)
            .map(|t| r[t] - (0.04 - 0.03) * cols[1][t] - (0.04 - 0.012) * cols[2][t])
            .collect();
        let want = 1.0 - (dot(&left, &left) / dot(&r, &r)).sqrt();
        let (got, at) = s.line_gain("e", &group, &starts, Some(0.04)).expect("modelled");
        assert!(at == 0.04 && (got - want).abs() < 1e-9, "{got} {want}");
        // The summed columns' prediction is for another direction: it does not find 0.06.
        let p = s.predict("e", &group).expect("modelled");
        assert!((p.step - 0.02).abs() > 1e-3 || p.train_rmse > 1e-6, "{p:?}");
        // Members that start together: the same model as the summed columns.
        let same = [0.03; 3];
        let (s, _) = model(&same, 0.045);
        let (gain, v) = s.line_gain("e", &group, &same, None).expect("modelled");
        let p = s.predict("e", &group).expect("modelled");
        let summed = 1.0 - p.train_rmse / s.base_rmse();
        assert!((v - 0.03 - p.step).abs() < 1e-12 && (gain - summed).abs() < 1e-6, "{v} {p:?}");
    }

    /// The shared value stays inside every member's bounds: a residual that asks for a value
    /// past the narrowest member's upper bound is explained only as far as that bound; and a
    /// model of two parameters, or starts that do not match the group, give none.
    #[test]
    fn a_shared_value_keeps_inside_every_members_bounds() {
        let c = [1.0, -0.5, 0.25, 2.0];
        let r: Vec<f64> = c.iter().map(|x| 3.0 * x).collect();
        // Member a from 1.0 within [0, 2]; b from 0.5 within [0, 1.5].
        let (mut s, _) = two_member_screen(&c, &r, [(-1.0, 1.0), (-0.5, 1.0)]);
        let g = vec!["a".to_string(), "b".to_string()];
        let (_, v) = s.line_gain("e", &g, &[1.0, 0.5], None).expect("modelled");
        assert_eq!(v, 1.5);
        assert!(s.line_gain("e", &g, &[1.0], None).is_none());
        s.models.get_mut("e").expect("model").k = 2;
        assert!(s.line_gain("e", &g, &[1.0, 0.5], None).is_none());
    }

    /// The lead's measure of a group whose members start apart is the shared value's. Members
    /// a, b, c (starts 0.04, 0.03, 0.012, as a leg's armature) and d (start 0), four columns
    /// apart; the residual asks each member to move by 0.01 from its own start — which the
    /// summed columns of a, b, c explain for the most part, and no one shared value does. By a
    /// scan of the shared value, each residual worked out from the columns themselves: the
    /// prediction from the starts is that scan's best, and leaves more than d alone does (its
    /// least-squares residual, also worked out from the columns); without starts it is the
    /// summed columns' ([`Screen::predict`]); and the lead (the least charged RMSE,
    /// [`Screen::lead_rmse`]) is d alone, where the summed columns would take the group.
    #[test]
    fn a_group_starting_apart_leads_by_its_shared_value() {
        let cols = [
            vec![1.0, 0.2, 0.0, -0.3, 0.1, 0.0],
            vec![0.0, 1.0, 0.5, 0.0, -0.2, 0.3],
            vec![0.3, 0.0, 1.0, 0.4, 0.0, -0.1],
            vec![0.0, 0.1, -0.2, 0.0, 1.0, 0.6],
        ];
        let starts = [0.04, 0.03, 0.012, 0.0];
        let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
        let r: Vec<f64> = (0..6).map(|t| cols.iter().map(|c| 0.01 * c[t]).sum()).collect();
        let names: Vec<String> = ["a", "b", "c", "d"].iter().map(|s| s.to_string()).collect();
        let m = EffectModel {
            joints: names.clone(),
            room: starts.iter().map(|a| (-1.0 - a, 1.0 - a)).collect(),
            k: 1,
            ranked: 1,
            b: cols.iter().map(|c| vec![dot(c, &r)]).collect(),
            g: cols.iter().map(|x| cols.iter().map(|y| dot(x, y)).collect()).collect(),
            held: vec![0; 4],
        };
        let ss = dot(&r, &r);
        let base = (ss / r.len() as f64).sqrt();
        let s = Screen {
            models: [("e", m)].into(),
            train_ss: ss,
            train_n: r.len(),
            screen_rmse: base,
            pieces: 1,
        };
        let group = names[..3].to_vec();
        // The scan: the residual left with a, b, c all at v, from each column and start.
        let left = |v: f64| {
            let l: Vec<f64> = (0..6)
                .map(|t| r[t] - (0..3).map(|i| (v - starts[i]) * cols[i][t]).sum::<f64>())
                .collect();
            dot(&l, &l)
        };
        let (v_best, l_best) = (0..=20_000)
            .map(|i| -0.1 + 0.2 * i as f64 / 20_000.0)
            .map(|v| (v, left(v)))
            .fold((f64::NAN, f64::INFINITY), |b, x| if x.1 < b.1 { x } else { b });
        let p = s.predict_from("e", &group, Some(&starts[..3])).expect("modelled");
        let want = base * (l_best / ss).sqrt();
        assert!((p.train_rmse - want).abs() < 1e-6 * base, "{p:?} vs {want}");
        // d alone: the residual less its projection on d's column.
        let d_left = ss - dot(&cols[3], &r).powi(2) / dot(&cols[3], &cols[3]);
        assert!(d_left < l_best, "{d_left} vs {l_best}");
        assert!((p.step - (v_best - starts[0])).abs() < 2e-5, "{p:?} vs {v_best}");
        // Without starts: the summed columns, which explain a, b, c's part whole.
        let q = s.predict_from("e", &group, None).expect("modelled");
        let summed = s.predict("e", &group).expect("modelled");
        assert!(q.train_rmse == summed.train_rmse && q.step == summed.step, "{q:?}");
        let d = s.predict_from("e", &names[3..], None).expect("modelled");
        assert!((d.train_rmse - base * (d_left / ss).sqrt()).abs() < 1e-9 * base, "{d:?}");
        assert!(summed.train_rmse < d.train_rmse, "{summed:?} {d:?}");
        // The lead: d alone by the shared value's measure; the group by the summed columns'.
        let lead = |g: &[String], p| s.lead_rmse("e", g, 1, p);
        assert!(lead(&names[3..], d) < lead(&group, p));
        assert!(lead(&group, summed) < lead(&names[3..], d));
    }
}
