//! Time to fit one effect: on the one-joint pendulum rig (fixtures/bam_xl330/rig.xml) and on the
//! 12 leg joints of models/asimov.xml (base pinned). Synthetic data from the same effect
//! machinery; run with `cargo run --release --example fit_bench`.

use std::path::PathBuf;
use std::time::Instant;

use modellint::fit::effects::{self, Applied};
use modellint::fit::select::{FitOptions, fit};
use modellint::fit::synth::{SynthOptions, generate};
use modellint::model::source::SourceMap;

fn bench(
    model: &str,
    joints: Vec<String>,
    effect: &str,
    on: Vec<String>,
    truth: Vec<f64>,
    episodes: usize,
    synth: SynthOptions,
) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut map = SourceMap::default();
    let robot = modellint::model::load(&mut map, &root.join(model), None).expect("model");
    let e = effects::by_id(effect).unwrap();
    let hidden = vec![Applied { effect: e, joints: on.clone(), params: truth.clone() }];
    let t0 = Instant::now();
    let recs = generate(&robot, &joints, &hidden, episodes, &synth, 5).expect("generate");
    let t_gen = t0.elapsed().as_secs_f64();
    let opts = FitOptions { effects: vec![effect.into()], max_rounds: 1, ..Default::default() };
    let t1 = Instant::now();
    let out = fit(&robot, &recs, &opts);
    let t_fit = t1.elapsed().as_secs_f64();
    let got =
        out.selected.first().map(|s| (s.joints.clone(), s.values.clone(), s.heldout_improvement));
    println!(
        "{model}: {} joints, {episodes} × {:.0} s episodes: generate {t_gen:.2} s, fit {effect} {t_fit:.2} s; truth {truth:?} on {on:?}; fitted {got:?}",
        joints.len(),
        synth.duration_s
    );
}

fn main() {
    bench(
        "fixtures/bam_xl330/rig.xml",
        vec!["servo".into()],
        "armature",
        vec!["servo".into()],
        vec![0.005],
        8,
        SynthOptions { amplitude: 0.8, ..Default::default() },
    );
    let legs: Vec<String> =
        ["hip_pitch", "hip_roll", "hip_yaw", "knee", "ankle_pitch", "ankle_roll"]
            .iter()
            .flat_map(|j| [format!("left_{j}"), format!("right_{j}")])
            .collect();
    bench(
        "models/asimov.xml",
        legs,
        "viscous_damping",
        vec!["left_knee".into(), "right_knee".into()],
        vec![3.0],
        8,
        SynthOptions { amplitude: 0.15, duration_s: 4.0, ..Default::default() },
    );
}
