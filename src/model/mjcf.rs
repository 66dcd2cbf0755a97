//! Source index for MJCF: which XML element (and which attribute, possibly inherited from a
//! `<default class>`) produced each compiled MuJoCo object.

use std::collections::BTreeMap;

use super::source::{Loc, XNode};

/// Kinds of compiled objects that rules point at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ElemKind {
    Body,
    Joint,
    Geom,
    Site,
    Actuator,
    Tendon,
    Equality,
    Key,
    Mesh,
    /// `<contact><pair>` (compiled in signature order: matched by its geom names).
    Pair,
    /// A child of `<sensor>` (its tag is the sensor type).
    Sensor,
    /// An attribute setter inside `<default>` (`<joint>`, `<position>`, ...): indexed so that a
    /// suppression comment on it covers the findings that point at its attributes.
    Default,
}

/// Where an effective attribute value came from.
#[derive(Debug, Clone)]
pub struct AttrOrigin {
    pub value: String,
    pub loc: Loc,
    /// `Some(class)` when inherited from `<default class=...>` (`main` for the top default).
    pub class: Option<String>,
}

/// One source element of a compiled object.
#[derive(Debug, Clone)]
pub struct ElemSrc {
    pub tag: String,
    pub name: Option<String>,
    pub loc: Loc,
    pub full: Loc,
    /// Effective attributes: the element's own plus those inherited from its default classes.
    pub attrs: BTreeMap<String, AttrOrigin>,
    pub class: Option<String>,
    /// Indices into `SourceIndex::suppressions` that cover this element (its own and ancestors').
    pub suppressions: Vec<usize>,
    /// For joints, geoms and sites: index of the enclosing body in the `Body` list (`None` for
    /// the world body, whichever `<worldbody>` section or included file it came from).
    pub body: Option<usize>,
}

/// An inline `<!-- modellint: ignore[rule] reason -->`.
#[derive(Debug, Clone)]
pub struct Suppression {
    pub rules: Vec<String>,
    pub reason: String,
    pub loc: Loc,
}

#[derive(Debug, Clone, Default)]
pub struct SourceIndex {
    pub elems: BTreeMap<ElemKind, Vec<ElemSrc>>,
    pub suppressions: Vec<Suppression>,
    /// Malformed suppression comments: (loc, problem).
    pub bad_suppressions: Vec<(Loc, String)>,
    pub root: Option<Loc>,
}

impl SourceIndex {
    pub fn list(&self, kind: ElemKind) -> &[ElemSrc] {
        self.elems.get(&kind).map(Vec::as_slice).unwrap_or(&[])
    }
    pub fn by_name(&self, kind: ElemKind, name: &str) -> Option<&ElemSrc> {
        self.list(kind).iter().find(|e| e.name.as_deref() == Some(name))
    }
}

const ACTUATOR_TAGS: &[&str] = &[
    "general",
    "motor",
    "position",
    "velocity",
    "intvelocity",
    "damper",
    "cylinder",
    "muscle",
    "adhesion",
    "plugin",
    "dcmotor",
];

struct Defaults<'a> {
    /// class -> (parent class, default node)
    classes: BTreeMap<String, (Option<String>, &'a XNode)>,
}

impl<'a> Defaults<'a> {
    fn collect(root: &'a XNode) -> Self {
        let mut d = Defaults { classes: BTreeMap::new() };
        for top in root.children_tagged("default") {
            d.add(top, None);
        }
        d
    }
    fn add(&mut self, node: &'a XNode, parent: Option<String>) {
        let name = node.get("class").map(str::to_string).unwrap_or_else(|| "main".into());
        self.classes.insert(name.clone(), (parent, node));
        for c in node.children_tagged("default") {
            self.add(c, Some(name.clone()));
        }
    }
    /// The chain of classes from `class` up to `main`.
    fn chain(&self, class: &str) -> Vec<(&str, &'a XNode)> {
        let mut out = Vec::new();
        let mut cur = Some(class.to_string());
        let mut guard = 0;
        while let Some(c) = cur {
            guard += 1;
            if guard > 64 {
                break;
            }
            match self.classes.get_key_value(&c) {
                Some((k, (parent, node))) => {
                    out.push((k.as_str(), *node));
                    cur = parent.clone();
                }
                None => break,
            }
        }
        out
    }
}

fn parse_suppression(c: &super::source::XComment) -> Option<Result<Suppression, String>> {
    let text = c.text.trim();
    let rest = text.strip_prefix("modellint:")?.trim();
    let Some(rest) = rest.strip_prefix("ignore[") else {
        return Some(Err(
            "unknown modellint directive; expected `modellint: ignore[<rule-id>] <reason>`".into(),
        ));
    };
    let Some(end) = rest.find(']') else {
        return Some(Err("unclosed `ignore[`".into()));
    };
    let rules: Vec<String> =
        rest[..end].split(',').map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect();
    let reason = rest[end + 1..].trim().to_string();
    if rules.is_empty() {
        return Some(Err("`ignore[]` names no rule".into()));
    }
    if reason.is_empty() {
        return Some(Err(
            "a suppression must give a reason: `modellint: ignore[<rule-id>] <why this is fine>`"
                .into(),
        ));
    }
    Some(Ok(Suppression { rules, reason, loc: c.loc }))
}

struct Builder<'a> {
    defaults: Defaults<'a>,
    idx: SourceIndex,
    /// Source body of the elements being pushed (None: world).
    cur_body: Option<usize>,
}

impl<'a> Builder<'a> {
    fn suppressions_of(&mut self, n: &XNode) -> Vec<usize> {
        let mut out = Vec::new();
        for c in &n.comments {
            match parse_suppression(c) {
                Some(Ok(s)) => {
                    self.idx.suppressions.push(s);
                    out.push(self.idx.suppressions.len() - 1);
                }
                Some(Err(msg)) => self.idx.bad_suppressions.push((c.loc, msg)),
                None => {}
            }
        }
        out
    }

    fn resolve(
        &self,
        n: &XNode,
        class: Option<&str>,
        actuator: bool,
    ) -> BTreeMap<String, AttrOrigin> {
        let mut attrs = BTreeMap::new();
        let class_name = n.get("class").or(class).unwrap_or("main");
        // Walk from the most general (main) to the most specific so later inserts win.
        let chain = self.defaults.chain(class_name);
        for (cname, dnode) in chain.iter().rev() {
            let mut setters: Vec<&XNode> = Vec::new();
            if actuator {
                setters.extend(
                    dnode
                        .children
                        .iter()
                        .filter(|c| ACTUATOR_TAGS.contains(&c.tag.as_str()) && c.tag != n.tag),
                );
            }
            setters.extend(dnode.children.iter().filter(|c| c.tag == n.tag));
            for s in setters {
                for a in &s.attrs {
                    attrs.insert(
                        a.name.clone(),
                        AttrOrigin {
                            value: a.value.clone(),
                            loc: a.loc,
                            class: Some(cname.to_string()),
                        },
                    );
                }
            }
        }
        for a in &n.attrs {
            attrs.insert(
                a.name.clone(),
                AttrOrigin { value: a.value.clone(), loc: a.loc, class: None },
            );
        }
        attrs
    }

    fn push(
        &mut self,
        kind: ElemKind,
        n: &XNode,
        class: Option<&str>,
        inherited: &[usize],
        actuator: bool,
    ) -> Vec<usize> {
        let mut sup = inherited.to_vec();
        sup.extend(self.suppressions_of(n));
        let attrs = self.resolve(n, class, actuator);
        let eff_class = n.get("class").or(class).map(str::to_string);
        self.idx.elems.entry(kind).or_default().push(ElemSrc {
            tag: n.tag.clone(),
            name: n.name().map(str::to_string),
            loc: n.loc,
            full: n.full,
            attrs,
            class: eff_class,
            suppressions: sup.clone(),
            body: if kind == ElemKind::Body { None } else { self.cur_body },
        });
        sup
    }

    /// Bodies in MuJoCo's compiled order (pre-order), each body's joints/geoms/sites first.
    fn body(&mut self, b: &XNode, class: Option<&str>, sup: &[usize]) {
        let saved = self.cur_body;
        let class_here = b.get("childclass").or(class).map(str::to_string);
        let sup = self.push(ElemKind::Body, b, class, sup, false);
        // A comment on the body's `<inertial>` covers the body's own findings (its mass
        // properties), not its children's.
        for inertial in b.children.iter().filter(|c| c.tag == "inertial") {
            let own = self.suppressions_of(inertial);
            if let Some(e) = self.idx.elems.get_mut(&ElemKind::Body).and_then(|v| v.last_mut()) {
                e.suppressions.extend(own);
            }
        }
        self.cur_body = Some(self.idx.list(ElemKind::Body).len() - 1);
        let mut items = Vec::new();
        let mut bodies = Vec::new();
        flatten_frames(b, class_here.as_deref(), &mut items, &mut bodies, &sup, self);
        self.items(items);
        for (child, cls, s) in bodies {
            self.body(child, cls.as_deref(), &s);
        }
        self.cur_body = saved;
    }

    fn items(&mut self, items: Vec<Item>) {
        for (n, cls, s) in items {
            match n.tag.as_str() {
                "joint" | "freejoint" => {
                    self.push(ElemKind::Joint, n, cls.as_deref(), &s, false);
                }
                "geom" => {
                    self.push(ElemKind::Geom, n, cls.as_deref(), &s, false);
                }
                "site" => {
                    self.push(ElemKind::Site, n, cls.as_deref(), &s, false);
                }
                _ => {}
            }
        }
    }
}

type Item<'n> = (&'n XNode, Option<String>, Vec<usize>);

fn flatten_frames<'n>(
    parent: &'n XNode,
    class: Option<&str>,
    items: &mut Vec<Item<'n>>,
    bodies: &mut Vec<Item<'n>>,
    sup: &[usize],
    b: &mut Builder,
) {
    for c in &parent.children {
        match c.tag.as_str() {
            "joint" | "freejoint" | "geom" | "site" => {
                items.push((c, class.map(str::to_string), sup.to_vec()))
            }
            "body" => bodies.push((c, class.map(str::to_string), sup.to_vec())),
            "frame" => {
                let mut s = sup.to_vec();
                s.extend(b.suppressions_of(c));
                let cls = c.get("childclass").or(class).map(str::to_string);
                flatten_frames(c, cls.as_deref(), items, bodies, &s, b);
            }
            _ => {}
        }
    }
}

/// Builds the source index of an MJCF tree (includes already expanded).
pub fn index_mjcf(root: &XNode) -> SourceIndex {
    let mut b = Builder {
        defaults: Defaults::collect(root),
        idx: SourceIndex { root: Some(root.loc), ..Default::default() },
        cur_body: None,
    };
    let root_sup = b.suppressions_of(root);
    // MuJoCo merges every <worldbody> section (e.g. the robot file's and the scene's, which
    // adds a floor) into the world body: its own geoms/sites come first in the compiled lists,
    // then the bodies of all sections in order.
    let mut items = Vec::new();
    let mut bodies = Vec::new();
    for wb in root.children_tagged("worldbody") {
        let mut all = root_sup.clone();
        all.extend(b.suppressions_of(wb));
        flatten_frames(wb, None, &mut items, &mut bodies, &all, &mut b);
    }
    b.cur_body = None;
    b.items(items);
    for (child, cls, s) in bodies {
        b.body(child, cls.as_deref(), &s);
    }
    for sec in root.children_tagged("actuator") {
        let s = b.suppressions_of(sec);
        for a in &sec.children {
            if ACTUATOR_TAGS.contains(&a.tag.as_str()) {
                b.push(ElemKind::Actuator, a, None, &s, true);
            }
        }
    }
    for sec in root.children_tagged("tendon") {
        for t in &sec.children {
            if t.tag == "spatial" || t.tag == "fixed" {
                b.push(ElemKind::Tendon, t, None, &[], false);
            }
        }
    }
    for sec in root.children_tagged("equality") {
        for e in &sec.children {
            b.push(ElemKind::Equality, e, None, &[], false);
        }
    }
    for sec in root.children_tagged("contact") {
        for p in sec.children_tagged("pair") {
            b.push(ElemKind::Pair, p, None, &[], false);
        }
    }
    for sec in root.children_tagged("keyframe") {
        for k in sec.children_tagged("key") {
            b.push(ElemKind::Key, k, None, &[], false);
        }
    }
    for sec in root.children_tagged("asset") {
        for m in sec.children_tagged("mesh") {
            b.push(ElemKind::Mesh, m, None, &[], false);
        }
    }
    for sec in root.children_tagged("sensor") {
        for e in &sec.children {
            b.push(ElemKind::Sensor, e, None, &[], false);
        }
    }
    for d in root.children_tagged("default") {
        default_setters(d, &root_sup, &mut b);
    }
    b.idx
}

/// Indexes the setters of a `<default>` tree with their suppression comments (a comment on a
/// `<default class=...>` covers every setter inside it), so that a finding pointing at a class's
/// attribute can be suppressed where it is written — and an unused or invalid suppression there
/// is reported like any other.
fn default_setters(d: &XNode, inherited: &[usize], b: &mut Builder) {
    let mut sup = inherited.to_vec();
    sup.extend(b.suppressions_of(d));
    for c in &d.children {
        if c.tag == "default" {
            default_setters(c, &sup, b);
        } else {
            let mut s = sup.clone();
            s.extend(b.suppressions_of(c));
            b.idx.elems.entry(ElemKind::Default).or_default().push(ElemSrc {
                tag: c.tag.clone(),
                name: None,
                loc: c.loc,
                full: c.full,
                attrs: BTreeMap::new(),
                class: d.get("class").map(str::to_string),
                suppressions: s,
                body: None,
            });
        }
    }
}

/// Builds a (smaller) source index of a URDF tree: links as bodies, joints with their limits.
pub fn index_urdf(root: &XNode) -> SourceIndex {
    let mut b = Builder {
        defaults: Defaults { classes: BTreeMap::new() },
        idx: SourceIndex { root: Some(root.loc), ..Default::default() },
        cur_body: None,
    };
    // MuJoCo's URDF importer keeps `<visual>` geoms only with `discardvisual="false"` (in the
    // file's `<mujoco><compiler>`; the default for URDF is true). A link's geoms compile in
    // document order: `<collision>` ones (contype = conaffinity = 1), kept `<visual>` ones
    // (contype = conaffinity = 0, group 1).
    let keep_visual = root
        .children_tagged("mujoco")
        .any(|m| m.children_tagged("compiler").any(|c| c.get("discardvisual") == Some("false")));
    for l in root.children_tagged("link") {
        b.push(ElemKind::Body, l, None, &[], false);
        b.cur_body = Some(b.idx.list(ElemKind::Body).len() - 1);
        for g in &l.children {
            if g.tag == "collision" || (keep_visual && g.tag == "visual") {
                b.push(ElemKind::Geom, g, None, &[], false);
            }
        }
        b.cur_body = None;
    }
    for j in root.children_tagged("joint") {
        b.push(ElemKind::Joint, j, None, &[], false);
        // Lift <limit>/<dynamics> attributes onto the joint under their URDF names.
        let last = b.idx.elems.get_mut(&ElemKind::Joint).and_then(|v| v.last_mut());
        if let Some(e) = last {
            for c in &j.children {
                if c.tag == "limit" || c.tag == "dynamics" || c.tag == "axis" {
                    for a in &c.attrs {
                        e.attrs.insert(
                            format!("{}.{}", c.tag, a.name),
                            AttrOrigin { value: a.value.clone(), loc: a.loc, class: None },
                        );
                    }
                }
            }
        }
    }
    b.idx
}
