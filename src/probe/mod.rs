//! Probe simulations: short MuJoCo experiments that confirm or refute static findings. Each
//! probe is one file (what it drives, what it measures, what counts as confirmation, its step
//! budget); this module only dispatches findings to them and records the outcome.
//! A refuted finding is downgraded to info and says why. All probes are deterministic.

pub mod bench;
pub mod direction;
pub mod impulse;
pub mod limit;
pub mod penetration;
pub mod sanity;
pub mod settle;

use std::collections::BTreeMap;

use crate::finding::{Finding, ProbeOutcome, ProbeStatus, Severity, Subject};
use crate::lint::Loaded;
use crate::util::fmt_num;

fn outcome(
    name: &str,
    status: ProbeStatus,
    measured: BTreeMap<String, f64>,
    steps: usize,
    note: String,
) -> ProbeOutcome {
    ProbeOutcome { name: name.into(), status, measured, steps, note }
}

fn skipped(name: &str, why: &str) -> ProbeOutcome {
    outcome(name, ProbeStatus::Skipped, BTreeMap::new(), 0, why.into())
}

/// Results of the simulations the findings ask for, computed once each and in parallel.
#[derive(Default)]
struct Results {
    impulse: BTreeMap<usize, Option<impulse::StepResponse>>,
    settle: Option<Option<settle::Settle>>,
    sanity: Option<Finding>,
    direction: BTreeMap<usize, Option<direction::Direction>>,
    limit: BTreeMap<usize, Option<limit::LimitHit>>,
    penetration: BTreeMap<(usize, usize), Option<penetration::Penetration>>,
}

/// One simulation to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Job {
    Impulse(usize),
    Settle,
    Sanity,
    Direction(usize),
    Limit(usize),
    Penetration(usize, usize),
}

enum Done {
    Impulse(usize, Option<impulse::StepResponse>),
    Settle(Option<settle::Settle>),
    Sanity(Option<Finding>),
    Direction(usize, Option<direction::Direction>),
    Limit(usize, Option<limit::LimitHit>),
    Penetration(usize, usize, Option<penetration::Penetration>),
}

/// The simulations the findings need (deduplicated: one step response per joint, one stance
/// settle per model, ...).
fn jobs(l: &Loaded, findings: &[Finding]) -> Vec<Job> {
    let mut jobs = std::collections::BTreeSet::new();
    for f in findings {
        let Some(probe) = crate::rules::find_meta(f.rule).and_then(|m| m.probe) else { continue };
        match (probe, f.subject) {
            ("impulse-response", Subject::Joint(j)) => {
                jobs.insert(Job::Impulse(j));
            }
            ("stance-settle", _) => {
                jobs.insert(Job::Settle);
            }
            ("actuator-direction", Subject::Actuator(a)) => {
                jobs.insert(Job::Direction(a));
            }
            ("limit-approach", Subject::Actuator(a)) => {
                jobs.insert(Job::Limit(a));
            }
            ("limit-approach", Subject::Joint(j)) => {
                if let Some(a) = l.robot.actuators_on_joint(j).first() {
                    jobs.insert(Job::Limit(a.id));
                }
            }
            ("keyframe-penetration", Subject::Geom(a)) => {
                if let Some(b) = f.data.get("geom2") {
                    jobs.insert(Job::Penetration(a, *b as usize));
                }
            }
            _ => {}
        }
    }
    if l.config.enabled(sanity::meta()) {
        jobs.insert(Job::Sanity);
    }
    // Longest first (whole-model runs with contacts), so that two cores finish together.
    let mut v: Vec<Job> = jobs.into_iter().collect();
    v.sort_by_key(|j| match j {
        Job::Sanity | Job::Settle => 0,
        _ => 1,
    });
    v
}

fn run_job(l: &Loaded, job: Job) -> Done {
    let robot = &l.robot;
    match job {
        Job::Impulse(j) => Done::Impulse(j, impulse::step_response(robot, j, spec_gains(l, j))),
        Job::Settle => Done::Settle(settle::run(robot)),
        Job::Sanity => Done::Sanity(sanity::run(robot, l.config.level(sanity::meta()))),
        Job::Direction(a) => Done::Direction(a, direction::run(robot, a)),
        Job::Limit(a) => Done::Limit(a, limit::run(robot, a)),
        Job::Penetration(a, b) => Done::Penetration(a, b, penetration::run(robot, a, b)),
    }
}

/// Runs the probe of every finding whose rule declares one, then the whole-model sanity probe.
/// The simulations are independent (each on its own copy of the model) and run in parallel;
/// results are gathered in a fixed order, so the output does not depend on scheduling.
pub fn confirm_all(l: &Loaded, findings: &mut Vec<Finding>) {
    use rayon::prelude::*;
    let done: Vec<Done> = jobs(l, findings).into_par_iter().map(|j| run_job(l, j)).collect();
    let mut res = Results::default();
    for d in done {
        match d {
            Done::Impulse(j, r) => {
                res.impulse.insert(j, r);
            }
            Done::Settle(s) => res.settle = Some(s),
            Done::Sanity(f) => res.sanity = f,
            Done::Direction(a, r) => {
                res.direction.insert(a, r);
            }
            Done::Limit(a, r) => {
                res.limit.insert(a, r);
            }
            Done::Penetration(a, b, r) => {
                res.penetration.insert((a, b), r);
            }
        }
    }
    let mut steps_cache = std::mem::take(&mut res.impulse);
    let mut settle_cache = res.settle.take();
    for f in findings.iter_mut() {
        let Some(meta) = crate::rules::find_meta(f.rule) else { continue };
        let Some(probe) = meta.probe else { continue };
        let p = match probe {
            "impulse-response" => impulse_probe(l, f, &mut steps_cache),
            "actuator-direction" => direction_probe(l, f, &mut res.direction),
            "limit-approach" => limit_probe(l, f, &mut res.limit),
            "stance-settle" => settle_probe(l, f, &mut settle_cache),
            "keyframe-penetration" => penetration_probe(l, f, &mut res.penetration),
            _ => skipped(probe, "no probe of this name"),
        };
        if p.status == ProbeStatus::Refuted && f.severity > Severity::Info {
            f.severity = Severity::Info;
            f.message = format!("{} (refuted by simulation)", f.message);
        }
        f.probe = Some(p);
    }
    if let Some(f) = res.sanity.take() {
        findings.push(f);
    }
    crate::lint::sort_findings(findings);
}

fn spec_gains(l: &Loaded, joint: usize) -> Option<(f64, f64)> {
    let spec = l.spec.as_ref()?;
    let facts = spec.joint(&l.robot.joints[joint].name)?;
    let m = spec.motor(facts.motor.as_deref()?)?;
    Some((crate::spec::v(&m.kp)?, crate::spec::v(&m.kd)?))
}

fn impulse_probe(
    l: &Loaded,
    f: &Finding,
    cache: &mut BTreeMap<usize, Option<impulse::StepResponse>>,
) -> ProbeOutcome {
    const NAME: &str = "impulse-response";
    let Subject::Joint(j) = f.subject else {
        return skipped(NAME, "finding is not about one joint");
    };
    let r = cache
        .entry(j)
        .or_insert_with(|| impulse::step_response(&l.robot, j, spec_gains(l, j)))
        .clone();
    let Some(r) = r else {
        return skipped(
            NAME,
            "joint has no PD servo to step (no position actuator, no spec kp/kd)",
        );
    };
    let mut m = impulse::measured_map(&r);
    if r.diverged {
        m.insert("diverged".into(), 1.0);
        let st = if f.rule == "gains-unstable-for-timestep" || f.rule == "underdamped-pd-gains" {
            ProbeStatus::Confirmed
        } else {
            ProbeStatus::Inconclusive
        };
        return outcome(
            NAME,
            st,
            m,
            r.steps,
            "the step response diverged (NaN, MuJoCo warning or unbounded growth)".into(),
        );
    }
    let z = r.zeta;
    let zs = z.map(|z| fmt_num(z, 3)).unwrap_or_else(|| "≥ 1 (no overshoot)".into());
    match f.rule {
        "underdamped-pd-gains" => {
            let threshold = f.data.get("threshold").copied().unwrap_or(0.7);
            let predicted = f.data.get("zeta").copied();
            let pred =
                predicted.map(|p| format!(" (predicted {})", fmt_num(p, 3))).unwrap_or_default();
            match z {
                Some(z) if z < threshold => outcome(
                    NAME,
                    ProbeStatus::Confirmed,
                    m,
                    r.steps,
                    format!(
                        "measured ζ = {zs}{pred}, overshoot {:.1} % on a 0.05 rad step",
                        100.0 * r.overshoot
                    ),
                ),
                _ => outcome(
                    NAME,
                    ProbeStatus::Refuted,
                    m,
                    r.steps,
                    format!("measured ζ = {zs}{pred} is not below {threshold}"),
                ),
            }
        }
        "armature-mismatch" | "parallel-ankle-armature" => {
            let (Some(arm), Some(exp)) = (f.data.get("armature"), f.data.get("expected_armature"))
            else {
                return outcome(
                    NAME,
                    ProbeStatus::Inconclusive,
                    m,
                    r.steps,
                    format!("measured ζ = {zs}; finding carries no armature figures"),
                );
            };
            let dof = l.robot.joints[j].dofadr;
            let m_model = l.robot.key.m_diag.get(dof).copied().unwrap_or(f64::NAN);
            let hw = m_model - arm + exp;
            match r.inertia {
                Some(i) => {
                    let rel = (i - hw) / hw;
                    m.insert("hardware_inertia".into(), hw);
                    let note = format!(
                        "simulated joint inertia {} kg·m² vs {} kg·m² with the hardware armature ({:+.0} %); ζ = {zs}",
                        fmt_num(i, 3),
                        fmt_num(hw, 3),
                        100.0 * rel
                    );
                    let st = if rel.abs() > 0.05 {
                        ProbeStatus::Confirmed
                    } else {
                        ProbeStatus::Refuted
                    };
                    outcome(NAME, st, m, r.steps, note)
                }
                None => outcome(
                    NAME,
                    ProbeStatus::Inconclusive,
                    m,
                    r.steps,
                    format!("response does not ring (ζ {zs}); inertia not identifiable from it"),
                ),
            }
        }
        "gains-unstable-for-timestep" => {
            let predicted = f.data.get("omega_n").copied();
            match (r.omega_n, predicted) {
                (Some(w), Some(p)) if ((w - p) / p).abs() > 0.1 => outcome(
                    NAME,
                    ProbeStatus::Confirmed,
                    m,
                    r.steps,
                    format!(
                        "integration distorts the response: measured ω_n = {} rad/s vs {} rad/s analytic",
                        fmt_num(w, 3),
                        fmt_num(p, 3)
                    ),
                ),
                _ => outcome(
                    NAME,
                    ProbeStatus::Refuted,
                    m,
                    r.steps,
                    format!("stable and accurate step response (ζ = {zs})"),
                ),
            }
        }
        _ => outcome(NAME, ProbeStatus::Inconclusive, m, r.steps, format!("measured ζ = {zs}")),
    }
}

fn direction_probe(
    l: &Loaded,
    f: &Finding,
    cache: &mut BTreeMap<usize, Option<direction::Direction>>,
) -> ProbeOutcome {
    const NAME: &str = "actuator-direction";
    let Subject::Actuator(a) = f.subject else {
        return skipped(NAME, "finding is not about one actuator");
    };
    let Some(d) = cache.entry(a).or_insert_with(|| direction::run(&l.robot, a)).clone() else {
        return skipped(NAME, "could not set up the bench");
    };
    let act = &l.robot.actuators[a];
    let mut m = BTreeMap::new();
    for (j, dq) in &d.moved {
        m.insert(format!("dq.{}", l.robot.joints[*j].name), *dq);
    }
    if d.moved.is_empty() {
        return outcome(
            NAME,
            ProbeStatus::Confirmed,
            m,
            d.steps,
            "a positive command moved no joint".into(),
        );
    }
    let target = (act.target >= 0).then_some(act.target as usize);
    let on_target = target.and_then(|t| d.moved.iter().find(|(j, _)| *j == t)).map(|(_, dq)| *dq);
    let biggest = d.moved.iter().max_by(|a, b| a.1.abs().total_cmp(&b.1.abs())).map(|x| x.0);
    if let Some(expected) = f.data.get("expected_direction") {
        return match on_target {
            Some(dq) if dq.signum() != expected.signum() => outcome(
                NAME,
                ProbeStatus::Confirmed,
                m,
                d.steps,
                format!(
                    "a positive command moved the joint by {} rad: opposite to the spec's direction {expected:+}",
                    fmt_num(dq, 3)
                ),
            ),
            Some(dq) => outcome(
                NAME,
                ProbeStatus::Refuted,
                m,
                d.steps,
                format!(
                    "a positive command moved the joint by {} rad, as the spec says",
                    fmt_num(dq, 3)
                ),
            ),
            None => outcome(
                NAME,
                ProbeStatus::Inconclusive,
                m,
                d.steps,
                "the targeted joint did not move".into(),
            ),
        };
    }
    let names: Vec<String> =
        d.moved.iter().map(|(j, dq)| format!("{} {:+.4}", l.robot.joints[*j].name, dq)).collect();
    let st = if biggest != target { ProbeStatus::Confirmed } else { ProbeStatus::Inconclusive };
    outcome(NAME, st, m, d.steps, format!("a positive command moved: {}", names.join(", ")))
}

fn penetration_probe(
    l: &Loaded,
    f: &Finding,
    cache: &mut BTreeMap<(usize, usize), Option<penetration::Penetration>>,
) -> ProbeOutcome {
    const NAME: &str = "keyframe-penetration";
    let (Subject::Geom(a), Some(b)) = (f.subject, f.data.get("geom2")) else {
        return skipped(NAME, "finding does not name a geom pair");
    };
    let b = *b as usize;
    let Some(p) = cache.entry((a, b)).or_insert_with(|| penetration::run(&l.robot, a, b)).clone()
    else {
        return skipped(NAME, "could not set up the bench");
    };
    let mut m = BTreeMap::new();
    m.insert("depth_m".into(), -p.depth0);
    m.insert("contact_force_n".into(), p.contact_force);
    m.insert("separation_speed_m_s".into(), p.separation_speed);
    m.insert("distance_after_m".into(), p.dist_end);
    if let Some(t) = p.clear_time {
        m.insert("clear_time_s".into(), t);
    }
    let clears = p
        .clear_time
        .map(|t| format!(", clear of each other after {} ms", fmt_num(t * 1000.0, 3)))
        .unwrap_or_default();
    if p.contact_force > 0.0 {
        let motion = if p.separation_speed >= penetration::JOLT_SPEED {
            format!("the pair jumps apart at up to {} m/s{clears}", fmt_num(p.separation_speed, 3))
        } else {
            format!(
                "the joints cannot separate them (at most {} m/s over {} s): the force and its friction act on every motion of the two links",
                fmt_num(p.separation_speed, 3),
                fmt_num(penetration::DURATION, 3)
            )
        };
        outcome(
            NAME,
            ProbeStatus::Confirmed,
            m,
            p.steps,
            format!(
                "at the keyframe (base on a stand, commands held) MuJoCo pushes the pair apart with {} N; {motion}",
                fmt_num(p.contact_force, 4)
            ),
        )
    } else {
        outcome(
            NAME,
            ProbeStatus::Refuted,
            m,
            p.steps,
            "MuJoCo applies no force between the pair at the keyframe (the contact is inactive, e.g. its gap exceeds the overlap)".into(),
        )
    }
}

fn limit_probe(
    l: &Loaded,
    f: &Finding,
    cache: &mut BTreeMap<usize, Option<limit::LimitHit>>,
) -> ProbeOutcome {
    const NAME: &str = "limit-approach";
    let a = match f.subject {
        Subject::Actuator(a) => a,
        Subject::Joint(j) => match l.robot.actuators_on_joint(j).first() {
            Some(a) => a.id,
            None => return skipped(NAME, "joint has no actuator to drive"),
        },
        _ => return skipped(NAME, "finding is not about one actuator"),
    };
    let Some(h) = cache.entry(a).or_insert_with(|| limit::run(&l.robot, a)).clone() else {
        return skipped(NAME, "actuator does not drive a hinge or slide joint");
    };
    let mut m = BTreeMap::new();
    m.insert("hit".into(), if h.hit { 1.0 } else { 0.0 });
    m.insert("impact_velocity".into(), h.impact_velocity);
    m.insert("max_limit_force".into(), h.max_limit_force);
    if h.hit {
        outcome(
            NAME,
            ProbeStatus::Confirmed,
            m,
            h.steps,
            format!(
                "commanding the ctrlrange extreme drove the joint into its hard stop at {} rad/s (limit force up to {} N·m)",
                fmt_num(h.impact_velocity, 3),
                fmt_num(h.max_limit_force, 3)
            ),
        )
    } else {
        outcome(
            NAME,
            ProbeStatus::Refuted,
            m,
            h.steps,
            "the commanded extremes never reached the hard stop".into(),
        )
    }
}

fn settle_probe(
    l: &Loaded,
    f: &Finding,
    cache: &mut Option<Option<settle::Settle>>,
) -> ProbeOutcome {
    const NAME: &str = "stance-settle";
    let robot = &l.robot;
    let s = cache.get_or_insert_with(|| settle::run(robot)).clone();
    let Some(s) = s else { return skipped(NAME, "could not set up the bench") };
    if s.diverged {
        return outcome(
            NAME,
            ProbeStatus::Confirmed,
            BTreeMap::new(),
            s.steps,
            "the standing simulation diverged".into(),
        );
    }
    // The foot: the body of the subject geom / the subject body, plus its parent and children.
    let body = match f.subject {
        Subject::Geom(g) => robot.geoms.get(g).map(|g| g.body),
        Subject::Foot(b) | Subject::Body(b) => Some(b),
        Subject::Joint(j) => robot.joints.get(j).map(|j| j.body),
        _ => None,
    };
    let Some(body) = body else {
        return skipped(NAME, "finding is not about a foot, geom or joint");
    };
    let foot: Vec<usize> = robot
        .bodies
        .iter()
        .filter(|b| {
            b.id == body || b.parent == body || (robot.bodies[body].parent == b.id && b.id != 0)
        })
        .map(|b| b.id)
        .collect();
    let geoms: Vec<usize> = robot
        .geoms
        .iter()
        .filter(|g| g.collides() && foot.contains(&g.body))
        .map(|g| g.id)
        .collect();
    let total: f64 = geoms.iter().map(|g| s.geom_load.get(g).copied().unwrap_or(0.0)).sum();
    let mut m = BTreeMap::new();
    m.insert("foot_load_n".into(), total);
    for g in &geoms {
        let gname = &robot.geoms[*g].name;
        m.insert(
            format!("load.{}", if gname.is_empty() { format!("geom{g}") } else { gname.clone() }),
            s.geom_load.get(g).copied().unwrap_or(0.0),
        );
    }
    let chatter =
        foot.iter().map(|b| s.chatter_per_s.get(b).copied().unwrap_or(0.0)).fold(0.0, f64::max);
    let pen = foot.iter().map(|b| s.penetration.get(b).copied().unwrap_or(0.0)).fold(0.0, f64::max);
    let tilt = s.body_tilt_deg.get(&body).copied().unwrap_or(0.0);
    m.insert("chatter_per_s".into(), chatter);
    m.insert("penetration_m".into(), pen);
    m.insert("tilt_deg".into(), tilt);
    m.insert("base_drop_m".into(), s.base_drop);
    match f.rule {
        "toe-tilt" => {
            let unloaded: Vec<String> = geoms
                .iter()
                .filter(|g| s.geom_load.get(g).copied().unwrap_or(0.0) < 0.02 * total)
                .map(|g| crate::rules::display_name(&robot.geoms[*g].name, *g))
                .collect();
            if total <= 1e-6 {
                outcome(
                    NAME,
                    ProbeStatus::Inconclusive,
                    m,
                    s.steps,
                    "the foot carries no load at all after settling".into(),
                )
            } else if !unloaded.is_empty() {
                outcome(
                    NAME,
                    ProbeStatus::Confirmed,
                    m,
                    s.steps,
                    format!(
                        "after 1 s standing, {} carr{} < 2 % of the foot's {} N",
                        unloaded.join(", "),
                        if unloaded.len() == 1 { "ies" } else { "y" },
                        fmt_num(total, 3)
                    ),
                )
            } else {
                outcome(
                    NAME,
                    ProbeStatus::Refuted,
                    m,
                    s.steps,
                    format!(
                        "every contact geom of the foot carries load ({} N in all)",
                        fmt_num(total, 3)
                    ),
                )
            }
        }
        "foot-collision-geometry" => {
            let touching = geoms
                .iter()
                .filter(|g| s.geom_load.get(g).copied().unwrap_or(0.0) > 0.02 * total.max(1e-9))
                .count();
            let note = format!(
                "{} contact changes/s, {} mm deepest penetration, {} loaded contact geom(s)",
                fmt_num(chatter, 3),
                fmt_num(pen * 1000.0, 3),
                touching
            );
            let st = if chatter > 5.0 || pen > 0.005 {
                ProbeStatus::Confirmed
            } else {
                ProbeStatus::Inconclusive
            };
            outcome(NAME, st, m, s.steps, note)
        }
        "passive-joint-spring" => {
            let Subject::Joint(j) = f.subject else {
                return outcome(NAME, ProbeStatus::Inconclusive, m, s.steps, "no joint".into());
            };
            let defl = s.joint_deflection.get(&j).copied().unwrap_or(0.0);
            m.insert("deflection_rad".into(), defl);
            let jt = &robot.joints[j];
            let q = robot.key.qpos.get(jt.qposadr).copied().unwrap_or(0.0) + defl;
            let at_limit = jt.limited && (q <= jt.range[0] + 1e-3 || q >= jt.range[1] - 1e-3);
            let note = format!(
                "passive joint deflected {} rad under the standing load{}",
                fmt_num(defl, 3),
                if at_limit { ", onto its limit" } else { "" }
            );
            let st = if defl.abs() > 0.2 || at_limit {
                ProbeStatus::Confirmed
            } else {
                ProbeStatus::Refuted
            };
            outcome(NAME, st, m, s.steps, note)
        }
        _ => outcome(
            NAME,
            ProbeStatus::Inconclusive,
            m,
            s.steps,
            format!("foot tilt {tilt:.2}°, chatter {chatter:.1}/s"),
        ),
    }
}
