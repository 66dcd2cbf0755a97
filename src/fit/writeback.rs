//! Writing fitted effects back: MJCF text edits (attribute values spliced in place, attributes
//! added to the element when absent; the rest of the file byte for byte) and a TOML file for
//! the effects MuJoCo cannot express.

use std::collections::{BTreeMap, BTreeSet};

use crate::fit::effects::{self, ActuatorSite, IsaacLab, WriteBack, num};
use crate::fit::select::Selected;
use crate::model::Robot;

/// Edits `xml` (the model's MJCF text) with the MuJoCo-expressible fitted values. Returns the new
/// text and warnings (joints or actuators not found in this file, effects left to the TOML).
pub fn edit_mjcf(
    xml: &str,
    robot: &Robot,
    selected: &[Selected],
) -> Result<(String, Vec<String>), String> {
    let mut found = BTreeSet::new();
    let (out, mut warnings) = edit_file(xml, robot, selected, &mut found)?;
    warnings.extend(unwritten(selected, &found, "in this file"));
    Ok((out, warnings))
}

/// What `edit_file` could not place: (effect, joint) pairs whose element was found in none of the
/// files searched, and the effects MJCF cannot express.
pub fn unwritten(
    selected: &[Selected],
    found: &BTreeSet<(usize, String)>,
    where_: &str,
) -> Vec<String> {
    let mut warnings = Vec::new();
    for (i, s) in selected.iter().enumerate() {
        let Some(e) = effects::by_id(&s.effect) else { continue };
        match e.write_back(&s.values) {
            WriteBack::Joint(_) | WriteBack::Inertial | WriteBack::Geoms => {
                for j in s.joints.iter().filter(|j| !found.contains(&(i, (*j).clone()))) {
                    warnings.push(format!(
                        "{}: <joint name=\"{j}\"> not found {where_}; not written",
                        s.effect
                    ));
                }
            }
            WriteBack::Actuator(_) => {
                for j in s.joints.iter().filter(|j| !found.contains(&(i, (*j).clone()))) {
                    warnings.push(format!(
                        "{}: no <actuator> element with joint=\"{j}\" {where_}; not written",
                        s.effect
                    ));
                }
            }
            WriteBack::TomlOnly => warnings.push(format!(
                "{} on {}: not expressible in MJCF; see --write-actuators",
                s.effect,
                s.joints.join(",")
            )),
        }
    }
    warnings
}

/// Edits one MJCF file's text; records in `found` the (selected index, joint) pairs whose element
/// is in this file. Warnings here are about elements found but not editable.
pub fn edit_file(
    xml: &str,
    robot: &Robot,
    selected: &[Selected],
    found: &mut BTreeSet<(usize, String)>,
) -> Result<(String, Vec<String>), String> {
    let opts = roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
    let doc = roxmltree::Document::parse_with_options(xml, opts)
        .map_err(|e| format!("cannot parse the MJCF: {e}"))?;
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
    let in_actuator =
        |n: &roxmltree::Node| n.parent_element().is_some_and(|p| p.has_tag_name("actuator"));
    let joint_node = |j: &str| {
        doc.descendants()
            .find(|n| n.has_tag_name("joint") && n.attribute("name") == Some(j) && !in_actuator(n))
    };
    // Whole-element edits (start, end, text): a body's `<inertial>`, once per body.
    let mut element_edits: Vec<(usize, usize, String)> = Vec::new();
    let mut bodies_done = BTreeSet::new();
    let mut with_all: Option<mujoco_rs::prelude::MjModel> = None;
    for (i, s) in selected.iter().enumerate() {
        let Some(e) = effects::by_id(&s.effect) else { continue };
        match e.write_back(&s.values) {
            WriteBack::Joint(attrs) => {
                for j in &s.joints {
                    let Some(node) = joint_node(j) else { continue };
                    found.insert((i, j.clone()));
                    for (a, v) in &attrs {
                        add(node, a, num(*v));
                    }
                    // A fitted stiffness pulls towards the pose it was fitted about (the
                    // keyframe's): MuJoCo's spring pulls towards `springref`, 0 unless set.
                    if attrs.iter().any(|(a, _)| *a == "stiffness")
                        && let Some(jt) = robot.joint(j)
                    {
                        let q = robot.key.qpos.get(jt.qposadr).copied().unwrap_or(0.0);
                        let hinge = jt.jtype == crate::model::JointType::Hinge;
                        let deg =
                            hinge && crate::rules::limits::ctrlrange_in_degrees::degree_mode(robot);
                        add(node, "springref", num(if deg { q.to_degrees() } else { q }));
                    }
                }
            }
            WriteBack::Actuator(attrs) => {
                for j in &s.joints {
                    let acts: Vec<roxmltree::Node> = doc
                        .descendants()
                        .filter(|n| in_actuator(n) && n.attribute("joint") == Some(j.as_str()))
                        .collect();
                    if !acts.is_empty() {
                        found.insert((i, j.clone()));
                    }
                    for node in acts {
                        let compiled = robot
                            .actuators
                            .iter()
                            .find(|a| Some(a.name.as_str()) == node.attribute("name"))
                            .or_else(|| {
                                robot
                                    .joint(j)
                                    .and_then(|jj| robot.actuators_on_joint(jj.id).first().copied())
                            });
                        let site = ActuatorSite {
                            tag: node.tag_name().name(),
                            kind: compiled.map(|c| c.kind),
                            timestep: robot.opt.timestep,
                            gear: compiled.map_or(1.0, |c| c.gear),
                            forcerange: compiled.filter(|c| c.forcelimited).map(|c| c.forcerange),
                        };
                        for (a, v) in &attrs {
                            match e.actuator_attr(a, *v, &site) {
                                Ok(set) => {
                                    for (name, text) in set {
                                        add(node, name, text);
                                    }
                                }
                                Err(why) => warnings
                                    .push(format!("{} on {j}: {why}; not written", s.effect)),
                            }
                        }
                    }
                }
            }
            WriteBack::Inertial => {
                for j in &s.joints {
                    let Some(node) = joint_node(j) else { continue };
                    found.insert((i, j.clone()));
                    let Some(body) = node.parent_element().filter(|b| b.has_tag_name("body"))
                    else {
                        warnings.push(format!(
                            "{} on {j}: the joint is not in a <body>; not written",
                            s.effect
                        ));
                        continue;
                    };
                    if !bodies_done.insert(body.range().start) {
                        continue;
                    }
                    if inertia_from_geoms(&doc) {
                        warnings.push(format!(
                            "{} on {j}: <compiler inertiafromgeom=\"true\"> ignores <inertial>; not written",
                            s.effect
                        ));
                        continue;
                    }
                    let m = with_all.get_or_insert_with(|| model_with_selected(robot, selected));
                    let Some(mut text) = robot.joint(j).and_then(|jj| inertial_text(m, jj.id))
                    else {
                        continue;
                    };
                    // Every body effect on this body: those with a component written at its
                    // nominal value say so, in a note and beside the element.
                    let body_joints: Vec<&str> = body
                        .children()
                        .filter(|c| c.has_tag_name("joint"))
                        .filter_map(|c| c.attribute("name"))
                        .collect();
                    let on_body = |x: &&Selected| {
                        x.joints.iter().any(|k| k == j || body_joints.contains(&k.as_str()))
                    };
                    for x in selected.iter().filter(on_body) {
                        let Some(ex) = effects::by_id(&x.effect) else { continue };
                        let (_, nominal) = written_values(x, ex);
                        if !nominal.is_empty() {
                            let note = nominal_note(x, ex, &nominal);
                            text.push_str(&format!(
                                " <!-- modellint fit: {} -->",
                                xml_comment(&note)
                            ));
                            warnings.push(note);
                        }
                    }
                    element_edits.push(inertial_edit(xml, body, text));
                }
            }
            WriteBack::Geoms => {
                for j in &s.joints {
                    let Some(node) = joint_node(j) else { continue };
                    found.insert((i, j.clone()));
                    let body = node.parent_element().filter(|b| b.has_tag_name("body"));
                    let (Some(body), Some(t)) = (body, effects::JointTarget::of(robot, j)) else {
                        continue;
                    };
                    let m = with_all.get_or_insert_with(|| model_with_selected(robot, selected));
                    match ground_geom_attrs(m, body, &t) {
                        Ok(list) => {
                            for (el, attrs) in list {
                                for (a, v) in attrs {
                                    add(el, a, v);
                                }
                            }
                        }
                        Err(why) => {
                            warnings.push(format!("{} on {j}: {why}; not written", s.effect))
                        }
                    }
                }
            }
            WriteBack::TomlOnly => {}
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
            let at = node
                .attributes()
                .next_back()
                .map_or(start + 1 + node.tag_name().name().len(), |x| x.range().end);
            edits.push((at, at, insert));
        }
    }
    edits.extend(element_edits);
    edits.sort_by_key(|e| std::cmp::Reverse(e.0));
    let mut out = xml.to_string();
    for (s, e, r) in edits {
        out.replace_range(s..e, &r);
    }
    Ok((out, warnings))
}

/// The attributes of `t`'s ground-touching geoms as the model `m` holds them, each with its
/// `<geom>` element: the body's own `<geom>` children, in the compiled order.
type GeomAttrs<'a, 'i> = Vec<(roxmltree::Node<'a, 'i>, Vec<(&'static str, String)>)>;
fn ground_geom_attrs<'a, 'i>(
    m: &mujoco_rs::prelude::MjModel,
    body: roxmltree::Node<'a, 'i>,
    t: &effects::JointTarget,
) -> Result<GeomAttrs<'a, 'i>, String> {
    let b = usize::try_from(*m.jnt_bodyid().get(t.jnt).ok_or("no such joint")?)
        .map_err(|_| "no body")?;
    let adr = usize::try_from(m.body_geomadr()[b]).unwrap_or(0);
    let n = usize::try_from(m.body_geomnum()[b]).unwrap_or(0);
    let elems: Vec<roxmltree::Node> = body.children().filter(|c| c.has_tag_name("geom")).collect();
    if elems.len() != n {
        return Err(format!(
            "the body's {} <geom> children are not its {n} compiled geoms (a frame, include or \
             replicate adds some)",
            elems.len()
        ));
    }
    let join = |v: &[f64]| v.iter().map(|x| sig(*x)).collect::<Vec<_>>().join(" ");
    let mut out = Vec::new();
    for g in &t.ground {
        let el = *elems.get(g.geom.wrapping_sub(adr)).ok_or("a geom outside its body")?;
        out.push((
            el,
            vec![
                ("solref", join(&m.geom_solref()[g.geom])),
                ("priority", m.geom_priority()[g.geom].to_string()),
                ("solimp", join(&m.geom_solimp()[g.geom])),
                ("friction", join(&m.geom_friction()[g.geom])),
                ("condim", m.geom_condim()[g.geom].to_string()),
            ],
        ));
    }
    Ok(out)
}

/// `true` when the document's `<compiler>` computes every body's inertia from its geoms.
fn inertia_from_geoms(doc: &roxmltree::Document) -> bool {
    doc.descendants()
        .any(|n| n.has_tag_name("compiler") && n.attribute("inertiafromgeom") == Some("true"))
}

/// The model with every selected effect applied (what the body effects' write-back reads), each
/// at [`written_values`].
fn model_with_selected(robot: &Robot, selected: &[Selected]) -> mujoco_rs::prelude::MjModel {
    let applied: Vec<effects::Applied> = selected
        .iter()
        .filter_map(|s| {
            let effect = effects::by_id(&s.effect)?;
            Some(effects::Applied {
                effect,
                joints: s.joints.clone(),
                params: written_values(s, effect).0,
            })
        })
        .collect();
    effects::model_with(robot, &applied)
}

/// The values written back for `s`: its fitted values, except that a body effect's (written as
/// an `<inertial>`) parameter the output reports as not identified is written at its nominal
/// value — [`effects::ParamDef::default`], the body as the model has it (no mass added, the
/// centre of mass not moved along that direction, the inertia not scaled) — not at the value
/// the fitted replay keeps; with the names of the parameters so written. (A joint effect's
/// default is not always the model's own value — a contact's MuJoCo defaults — so its values
/// are written as fitted.)
pub fn written_values(s: &Selected, effect: &dyn effects::Effect) -> (Vec<f64>, Vec<String>) {
    let mut v = s.values.clone();
    let mut nominal = Vec::new();
    if effect.write_back(&s.values) != WriteBack::Inertial {
        return (v, nominal);
    }
    for (k, d) in effect.params().iter().enumerate() {
        if s.unidentified.iter().any(|u| u == d.name)
            && let Some(x) = v.get_mut(k)
        {
            *x = d.default;
            nominal.push(d.name.to_string());
        }
    }
    (v, nominal)
}

/// The note (and the comment beside the written `<inertial>`) for a body effect some of whose
/// parameters `nominal` were written at their nominal values ([`written_values`]).
fn nominal_note(s: &Selected, effect: &dyn effects::Effect, nominal: &[String]) -> String {
    let parts: Vec<String> = nominal
        .iter()
        .filter_map(|n| {
            let d = effect.params().iter().find(|d| d.name == n.as_str())?;
            let unit = if d.unit.is_empty() { String::new() } else { format!(" {}", d.unit) };
            let kept = s
                .params
                .get(n.as_str())
                .map_or(String::new(), |v| format!(" (the fitted replay keeps {})", sig(*v)));
            Some(format!("{n} = {}{unit}{kept}", num(d.default)))
        })
        .collect();
    format!(
        "{} on {}: not identified, written as the model has it: {}",
        s.effect,
        s.joints.join(","),
        parts.join(", ")
    )
}

/// A value with 9 significant digits, as the shortest text that reads back as it (an inertia
/// of 1e-7 kg·m² must not round to 0 as `num`'s 6 decimals would).
fn sig(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return "0".into();
    }
    let r: f64 = format!("{v:.8e}").parse().unwrap_or(v);
    format!("{r}")
}

/// `text` safe inside an XML comment (no `--`).
fn xml_comment(text: &str) -> String {
    text.replace("--", "- -")
}

/// `<inertial …/>` of joint `jnt`'s child body as the model `m` holds it (body frame).
fn inertial_text(m: &mujoco_rs::prelude::MjModel, jnt: usize) -> Option<String> {
    let b = usize::try_from(*m.jnt_bodyid().get(jnt)?).ok()?;
    let join = |v: &[f64]| v.iter().map(|x| sig(*x)).collect::<Vec<_>>().join(" ");
    Some(format!(
        "<inertial pos=\"{}\" quat=\"{}\" mass=\"{}\" diaginertia=\"{}\"/>",
        join(m.body_ipos().get(b)?),
        join(m.body_iquat().get(b)?),
        sig(*m.body_mass().get(b)?),
        join(m.body_inertia().get(b)?)
    ))
}

/// The edit that puts `text` in place of `body`'s `<inertial>` element, or — without one —
/// as its first child, indented as the body's first child is.
fn inertial_edit(xml: &str, body: roxmltree::Node, text: String) -> (usize, usize, String) {
    if let Some(old) = body.children().find(|c| c.has_tag_name("inertial")) {
        let r = old.range();
        return (r.start, r.end, text);
    }
    let after_attrs = body
        .attributes()
        .next_back()
        .map_or(body.range().start + 1 + body.tag_name().name().len(), |a| a.range().end);
    let at = xml[after_attrs..].find('>').map_or(after_attrs, |k| after_attrs + k + 1);
    let indent = body
        .children()
        .find(|c| c.is_element())
        .map(|c| {
            let line = xml[..c.range().start].rfind('\n').map_or(0, |k| k + 1);
            xml[line..c.range().start].to_string()
        })
        .filter(|w| w.chars().all(char::is_whitespace))
        .unwrap_or_default();
    (at, at, format!("\n{indent}{text}"))
}

/// TOML with every selected effect (parameters, standard errors), and an Isaac Lab / mjlab
/// actuator snippet as comments.
pub fn actuators_toml(selected: &[Selected]) -> String {
    let mut s = String::from(
        "# Written by `modellint fit`: effects found missing in the model, with fitted parameters.\n# Effects MuJoCo cannot express (hook-only) are applied by a per-step torque/command hook.\n\n",
    );
    for x in selected {
        let hook = effects::by_id(&x.effect)
            .map(|e| matches!(e.write_back(&x.values), WriteBack::TomlOnly))
            .unwrap_or(true);
        s.push_str("[[effect]]\n");
        s.push_str(&format!(
            "id = \"{}\"\njoints = [{}]\nhook_only = {hook}\nheldout_improvement = {}\n",
            x.effect,
            x.joints.iter().map(|j| format!("\"{j}\"")).collect::<Vec<_>>().join(", "),
            num(x.heldout_improvement)
        ));
        if !x.unidentified.is_empty() {
            let names: Vec<String> = x.unidentified.iter().map(|u| format!("\"{u}\"")).collect();
            s.push_str(&format!(
                "# not identified by the recordings (the value is the fitted replay's, not an estimate)\nunidentified = [{}]\n",
                names.join(", ")
            ));
        }
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
    s.push_str("# Isaac Lab / mjlab actuator snippet: the Python file written beside this one.\n");
    s
}

/// `--write-actuators PATH`: the TOML at PATH and the Isaac Lab / mjlab snippet beside it
/// (`<stem>_isaaclab.py`). Returns the files written.
pub fn write_actuators(
    path: &std::path::Path,
    robot: &Robot,
    selected: &[Selected],
) -> Result<Vec<std::path::PathBuf>, String> {
    std::fs::write(path, actuators_toml(selected))
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "actuators".into());
    let py = path.with_file_name(format!("{stem}_isaaclab.py"));
    std::fs::write(&py, isaaclab_snippet(robot, selected))
        .map_err(|e| format!("cannot write {}: {e}", py.display()))?;
    Ok(vec![path.to_path_buf(), py])
}

/// A Python string literal (double-quoted, escaped).
fn py_str(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '\\' => o.push_str("\\\\"),
            '"' => o.push_str("\\\""),
            '\n' => o.push_str("\\n"),
            c if (c as u32) < 0x20 => o.push_str(&format!("\\x{:02x}", c as u32)),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// Valid Python: one `ImplicitActuatorCfg` per joint with the fitted values its fields can hold
/// (armature, friction, effort_limit); the values they cannot hold (passive joint damping, action
/// delay) as comments on lines of their own, in the units the simulators use. Each effect says
/// which ([`effects::Effect::isaaclab`]).
pub fn isaaclab_snippet(robot: &Robot, selected: &[Selected]) -> String {
    let mut per_joint: BTreeMap<String, (Vec<String>, Vec<String>)> = BTreeMap::new();
    for x in selected {
        let Some(e) = effects::by_id(&x.effect) else { continue };
        let line = e.isaaclab(&x.params, robot.opt.timestep);
        for j in &x.joints {
            let (fields, comments) = per_joint.entry(j.clone()).or_default();
            match &line {
                IsaacLab::Field(f) => fields.push(f.clone()),
                IsaacLab::Comment(c) => comments.push(c.clone()),
            }
        }
    }
    // `stiffness` and `damping` are required fields: the joint's position servo's kp / kv, as
    // the fitted effects write them back (a servo gain error scales them), else as modelled.
    for (j, (fields, _)) in per_joint.iter_mut() {
        let Some(act) =
            robot.joint(j).and_then(|jj| robot.actuators_on_joint(jj.id).first().copied())
        else {
            continue;
        };
        let crate::model::ActuatorKind::Position { kp, kv } = act.kind else { continue };
        if act.gear != 1.0 {
            continue;
        }
        let site = ActuatorSite {
            tag: "position",
            kind: Some(act.kind),
            timestep: robot.opt.timestep,
            gear: act.gear,
            forcerange: act.forcelimited.then_some(act.forcerange),
        };
        let (mut stiffness, mut damping) = (num(kp), num(kv));
        for x in selected.iter().filter(|x| x.joints.contains(j)) {
            let Some(e) = effects::by_id(&x.effect) else { continue };
            let WriteBack::Actuator(attrs) = e.write_back(&x.values) else { continue };
            for (a, v) in &attrs {
                for (name, text) in e.actuator_attr(a, *v, &site).unwrap_or_default() {
                    match name {
                        "kp" => stiffness = text,
                        "kv" => damping = text,
                        _ => {}
                    }
                }
            }
        }
        fields.insert(0, format!("damping={damping},"));
        fields.insert(0, format!("stiffness={stiffness},"));
    }
    let mut s = String::from(
        "# Written by `modellint fit`: fitted actuator parameters for Isaac Lab (mjlab has the same fields).\n\
         # Values MuJoCo can hold are also in the model written by --write-model.\n\
         from isaaclab.actuators import ImplicitActuatorCfg\n\n\
         actuators = {\n",
    );
    for (j, (fields, comments)) in per_joint {
        s.push_str(&format!("    {}: ImplicitActuatorCfg(\n", py_str(&j)));
        s.push_str(&format!("        joint_names_expr=[{}],\n", py_str(&regex_escape(&j))));
        for f in fields {
            s.push_str(&format!("        {f}\n"));
        }
        for c in comments {
            s.push_str(&format!("        {c}\n"));
        }
        s.push_str("    ),\n");
    }
    s.push_str("}\n");
    s
}

/// `joint_names_expr` entries are regular expressions: escape the metacharacters of a joint name.
fn regex_escape(name: &str) -> String {
    let mut o = String::new();
    for c in name.chars() {
        if "\\.+*?()|[]{}^$".contains(c) {
            o.push('\\');
        }
        o.push(c);
    }
    o
}

#[cfg(test)]
mod tests;
