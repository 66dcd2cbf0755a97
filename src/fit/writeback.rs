//! Writing fitted effects back: MJCF text edits (attribute values spliced in place, attributes
//! added to the element when absent; the rest of the file byte for byte) and a TOML file for
//! the effects MuJoCo cannot express.

use std::collections::BTreeMap;

use crate::fit::effects::{self, WriteBack};
use crate::fit::select::Selected;
use crate::model::{ActuatorKind, Robot};

fn num(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    if s.is_empty() || s == "-0" { "0".into() } else { s }
}

/// Edits `xml` (the model's MJCF text) with the MuJoCo-expressible fitted values. Returns the new
/// text and warnings (joints or actuators not found in this file, effects left to the TOML).
pub fn edit_mjcf(xml: &str, robot: &Robot, selected: &[Selected]) -> Result<(String, Vec<String>), String> {
    let doc = roxmltree::Document::parse(xml).map_err(|e| format!("cannot parse the MJCF: {e}"))?;
    let mut warnings = Vec::new();
    // element start offset → (tag name end offset, attributes to set)
    let mut sets: BTreeMap<usize, (roxmltree::NodeId, Vec<(String, String)>)> = BTreeMap::new();
    let mut add = |node: roxmltree::Node, attr: &str, val: String| {
        let e = sets.entry(node.range().start).or_insert((node.id(), vec![]));
        if let Some(x) = e.1.iter_mut().find(|(a, _)| a == attr) {
            x.1 = val;
        } else {
            e.1.push((attr.to_string(), val));
        }
    };
    let in_actuator = |n: &roxmltree::Node| n.parent_element().is_some_and(|p| p.has_tag_name("actuator"));
    for s in selected {
        let Some(e) = effects::by_id(&s.effect) else { continue };
        match e.write_back(&s.values) {
            WriteBack::Joint(attrs) => {
                for j in &s.joints {
                    let Some(node) = doc.descendants().find(|n| n.has_tag_name("joint") && n.attribute("name") == Some(j.as_str()) && !in_actuator(n)) else {
                        warnings.push(format!("{}: <joint name=\"{j}\"> not found in this file; not written", s.effect));
                        continue;
                    };
                    for (a, v) in &attrs {
                        add(node, a, num(*v));
                    }
                }
            }
            WriteBack::Actuator(attrs) => {
                for j in &s.joints {
                    let acts: Vec<roxmltree::Node> = doc.descendants().filter(|n| in_actuator(n) && n.attribute("joint") == Some(j.as_str())).collect();
                    if acts.is_empty() {
                        warnings.push(format!("{}: no <actuator> element with joint=\"{j}\" in this file; not written", s.effect));
                    }
                    for node in acts {
                        let compiled = robot.actuators.iter().find(|a| Some(a.name.as_str()) == node.attribute("name")).or_else(|| {
                            robot.joint(j).and_then(|jj| robot.actuators_on_joint(jj.id).first().copied())
                        });
                        for (a, v) in &attrs {
                            match *a {
                                "delay" => {
                                    let n = (v / robot.opt.timestep).round().max(1.0) as i64;
                                    add(node, "delay", num(*v));
                                    add(node, "nsample", n.to_string());
                                }
                                "forcerange" => {
                                    add(node, "forcelimited", "true".into());
                                    add(node, "forcerange", format!("{} {}", num(-v), num(*v)));
                                }
                                "kp_scale" | "kv_scale" => {
                                    let Some(ActuatorKind::Position { kp, kv }) = compiled.map(|c| c.kind) else {
                                        warnings.push(format!("gain_error on {j}: actuator is not a position servo; not written"));
                                        continue;
                                    };
                                    if node.has_tag_name("position") {
                                        if *a == "kp_scale" {
                                            add(node, "kp", num(kp * v));
                                        } else {
                                            add(node, "kv", num(kv * v));
                                        }
                                    } else {
                                        warnings.push(format!("gain_error on {j}: <{}> is not <position>; not written", node.tag_name().name()));
                                    }
                                }
                                _ => add(node, a, num(*v)),
                            }
                        }
                    }
                }
            }
            WriteBack::TomlOnly => warnings.push(format!("{} on {}: not expressible in MJCF; see --write-actuators", s.effect, s.joints.join(","))),
        }
    }
    // Text edits (start, end, replacement), applied back to front.
    let mut edits: Vec<(usize, usize, String)> = Vec::new();
    for (start, (id, attrs)) in &sets {
        let node = doc.get_node(*id).expect("node");
        let mut insert = String::new();
        for (a, v) in attrs {
            match node.attributes().find(|x| x.name() == a) {
                Some(x) => {
                    let r = x.range_value();
                    edits.push((r.start, r.end, v.clone()));
                }
                None => insert.push_str(&format!(" {a}=\"{v}\"")),
            }
        }
        if !insert.is_empty() {
            // After the last attribute (or the tag name): new attributes are appended.
            let at = node.attributes().next_back().map_or(start + 1 + node.tag_name().name().len(), |x| x.range().end);
            edits.push((at, at, insert));
        }
    }
    edits.sort_by_key(|e| std::cmp::Reverse(e.0));
    let mut out = xml.to_string();
    for (s, e, r) in edits {
        out.replace_range(s..e, &r);
    }
    Ok((out, warnings))
}

/// TOML with every selected effect (parameters, standard errors), and an Isaac Lab / mjlab
/// actuator snippet as comments.
pub fn actuators_toml(selected: &[Selected]) -> String {
    let mut s = String::from("# Written by `modellint fit`: effects found missing in the model, with fitted parameters.\n# Effects MuJoCo cannot express (hook-only) are applied by a per-step torque/command hook.\n\n");
    for x in selected {
        let hook = effects::by_id(&x.effect).map(|e| matches!(e.write_back(&x.values), WriteBack::TomlOnly)).unwrap_or(true);
        s.push_str("[[effect]]\n");
        s.push_str(&format!("id = \"{}\"\njoints = [{}]\nhook_only = {hook}\nheldout_improvement = {}\n", x.effect, x.joints.iter().map(|j| format!("\"{j}\"")).collect::<Vec<_>>().join(", "), num(x.heldout_improvement)));
        s.push_str("[effect.params]\n");
        for (k, v) in &x.params {
            s.push_str(&format!("{k} = {}\n", num(*v)));
        }
        s.push_str("[effect.stderr]\n");
        for (k, v) in &x.stderr {
            s.push_str(&format!("{k} = {}\n", if v.is_finite() { num(*v) } else { "inf".into() }));
        }
        s.push('\n');
    }
    // Isaac Lab-style snippet.
    let mut per_joint: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for x in selected {
        for j in &x.joints {
            let e = per_joint.entry(j.clone()).or_default();
            let p = |k: &str| x.params.get(k).copied().unwrap_or(f64::NAN);
            match x.effect.as_str() {
                "torque_limit" => e.push(format!("effort_limit={}", num(p("effort_limit")))),
                "armature" => e.push(format!("armature={}", num(p("armature")))),
                "coulomb_friction" => e.push(format!("friction={}", num(p("frictionloss")))),
                "viscous_damping" => e.push(format!("# joint damping {}", num(p("damping")))),
                "action_delay" => e.push(format!("# DelayedPDActuatorCfg: min_delay=max_delay={} physics steps", num(p("delay_s")))),
                _ => {}
            }
        }
    }
    if !per_joint.is_empty() {
        s.push_str("# Isaac Lab / mjlab actuator snippet (edit to taste):\n");
        for (j, items) in per_joint {
            s.push_str(&format!("#   \"{j}\": ImplicitActuatorCfg(joint_names_expr=[\"{j}\"], {})\n", items.join(", ")));
        }
    }
    s
}
