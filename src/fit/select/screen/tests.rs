//! The linear model's algebra: combinations of columns, their charge, the bounds of a step.

use super::{EffectModel, Screen, charged, combine};

/// Two columns: the residual r = 2 a + 3 c is explained whole by the pair, by neither alone.
#[test]
fn the_best_combination_of_columns_explains_what_each_alone_does_not() {
    let a = [1.0, 0.0, 1.0, 0.5];
    let c = [0.0, 1.0, 1.0, -0.5];
    let r: Vec<f64> = a.iter().zip(&c).map(|(x, y)| 2.0 * x + 3.0 * y).collect();
    let d = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    let b = [d(&a, &r), d(&c, &r)];
    let g = vec![vec![d(&a, &a), d(&a, &c)], vec![d(&c, &a), d(&c, &c)]];
    let (e, x) = combine(&b, &g);
    let ss = d(&r, &r);
    assert!((e - ss).abs() < 1e-12 * ss, "{e} of {ss}");
    assert!((x[0] - 2.0).abs() < 1e-12 && (x[1] - 3.0).abs() < 1e-12, "{x:?}");
    assert!(b[0] * b[0] / g[0][0] < 0.9 * ss && b[1] * b[1] / g[1][1] < 0.9 * ss);
    // A repeated column adds nothing and is left at 0.
    let (e2, x2) = combine(&[b[0], b[0]], &[vec![g[0][0]; 2], vec![g[0][0]; 2]]);
    assert!((e2 - b[0] * b[0] / g[0][0]).abs() < 1e-12 * ss && x2[1] == 0.0, "{x2:?}");
    // A zero column (a parameter without a probe) too.
    let (e3, _) = combine(&[b[0], 0.0], &[vec![g[0][0], 0.0], vec![0.0, 0.0]]);
    assert!((e3 - b[0] * b[0] / g[0][0]).abs() < 1e-12 * ss);
}

/// The charge: nothing for one column; for a second, what is left grows by m^(1/m).
#[test]
fn a_second_column_is_charged_by_the_information_criterion() {
    assert_eq!(charged(10.0, 4.0, 1, 100), 4.0);
    let m = 100.0_f64;
    let want = 10.0 - 6.0 * m.powf(1.0 / m);
    assert!((charged(10.0, 4.0, 2, 100) - want).abs() < 1e-12);
    assert!(charged(10.0, 4.0, 2, 100) < 4.0 && charged(10.0, 4.0, 3, 100) < want);
    assert_eq!(charged(10.0, 0.0, 2, 100), 0.0);
}

/// A one-parameter prediction stays inside the parameter's bounds: a residual that asks for
/// a step below the lower bound (negative friction) is explained only as far as the bound
/// allows; a group's shared value keeps inside every member's bounds.
#[test]
fn a_one_parameter_prediction_respects_the_bounds() {
    let c = [1.0, -0.5, 0.25, 2.0];
    let d = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    let screen = |step: f64, room: (f64, f64)| {
        let r: Vec<f64> = c.iter().map(|x| step * x).collect();
        let m = EffectModel {
            joints: vec!["a".into(), "b".into()],
            room: vec![room, (room.0, room.1 * 0.5)],
            k: 1,
            b: vec![vec![d(&c, &r)], vec![0.0]],
            g: vec![vec![d(&c, &c), 0.0], vec![0.0, d(&c, &c)]],
        };
        let ss = d(&r, &r);
        let screen_rmse = (ss / r.len() as f64).sqrt();
        (
            Screen {
                models: [("e", m)].into(),
                train_ss: ss,
                train_n: r.len(),
                screen_rmse,
                pieces: 1,
            },
            ss,
        )
    };
    let rmse = |ss: f64| (ss / c.len() as f64).sqrt();
    // Inside the bounds: the residual explained whole, the step the one asked for.
    let (s, _) = screen(2.0, (-1.0, 10.0));
    let p = s.predict("e", &["a".into()]).expect("modelled");
    assert!(p.train_rmse < 1e-9 && (p.step - 2.0).abs() < 1e-12, "{p:?}");
    // Asking for −2 where the parameter cannot go below its start: nothing explained.
    let (s, ss) = screen(-2.0, (0.0, 10.0));
    let p = s.predict("e", &["a".into()]).expect("modelled");
    assert!((p.train_rmse - rmse(ss)).abs() < 1e-12 && p.step == 0.0, "{p:?}");
    // Half-way room: the step stops at the bound and explains 2 s b − s² g = 3/4 of it.
    let (s, ss) = screen(-2.0, (-1.0, 10.0));
    let p = s.predict("e", &["a".into()]).expect("modelled");
    assert!((p.train_rmse - rmse(0.25 * ss)).abs() < 1e-12 && p.step == -1.0, "{p:?}");
    // A group: the shared step keeps inside the narrower member's room (b's upper bound 1).
    let (s, _) = screen(4.0, (-1.0, 2.0));
    let p = s.predict("e", &["a".into(), "b".into()]).expect("modelled");
    assert!(p.step == 1.0, "{p:?}");
    // Probes on stretches whose residual is twice the screen's: the prediction is the
    // screen's RMSE scaled by the relative change on the probes' data.
    let (mut s, ss) = screen(-2.0, (-1.0, 10.0));
    s.screen_rmse = 0.5 * rmse(ss);
    assert_eq!(s.base_rmse(), 0.5 * rmse(ss));
    let p = s.predict("e", &["a".into()]).expect("modelled");
    assert!((p.train_rmse - 0.5 * rmse(0.25 * ss)).abs() < 1e-12, "{p:?}");
}
