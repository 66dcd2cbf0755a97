//! An effect with one of its parameters held at its nominal value ([`ParamDef::default`]: the
//! model as given for a body effect's place): the same change with one component fewer. What
//! the floor's rival ([`crate::fit::floor_rival`]) fits to ask whether that component is
//! identified apart from the ground's compliance. Not a candidate of the search: an effect
//! declares its variants ([`Effect::held_components`]); `--told com_offset~along@root_pitch`
//! names one (`EFFECT~PARAMETER`, [`super::by_id`]).

use super::*;

/// `inner` with its parameter `held` at its default; `meta` lists the other parameters in
/// `inner`'s order and the id `INNER~HELD`.
pub struct Held {
    pub inner: &'static dyn Effect,
    pub held: usize,
    pub meta: &'static EffectMeta,
}

impl Held {
    /// `inner`'s full parameter vector from this variant's: the held one inserted at its default.
    fn full(&self, p: &[f64]) -> Vec<f64> {
        let mut v = p.to_vec();
        let nominal = self.inner.params().get(self.held).map_or(0.0, |d| d.default);
        v.insert(self.held.min(v.len()), nominal);
        v
    }
    /// This variant's parameters from `inner`'s (the held one left out).
    fn reduced(&self, p: Vec<f64>) -> Vec<f64> {
        p.into_iter().enumerate().filter(|(i, _)| *i != self.held).map(|(_, v)| v).collect()
    }
}

impl Declared for Held {
    fn meta(&self) -> &'static EffectMeta {
        self.meta
    }
}

impl Effect for Held {
    fn initial(&self, m: &MjModel, t: &JointTarget) -> Vec<f64> {
        self.reduced(self.inner.initial(m, t))
    }
    fn bounds(&self, m: &MjModel, t: &JointTarget) -> (Vec<f64>, Vec<f64>) {
        let (lo, hi) = self.inner.bounds(m, t);
        (self.reduced(lo), self.reduced(hi))
    }
    fn apply_model(&self, m: &mut MjModel, t: &JointTarget, p: &[f64]) {
        self.inner.apply_model(m, t, &self.full(p));
    }
    fn torque(&self, cx: HookCtx<'_>) {
        let full = self.full(cx.p);
        self.inner.torque(HookCtx { p: &full, ..cx });
    }
    fn measurement_bias(&self, p: &[f64]) -> f64 {
        self.inner.measurement_bias(&self.full(p))
    }
    fn fitted(&self) -> usize {
        let k = self.inner.fitted();
        if self.held < k { k - 1 } else { k }
    }
    fn smooth(&self) -> bool {
        self.inner.smooth()
    }
    fn signature(&self, s: &Samples) -> Signature {
        self.inner.signature(s)
    }
    fn screened(&self) -> usize {
        self.inner.screened().min(self.fitted()).max(1)
    }
    fn stepped(&self) -> usize {
        self.inner.stepped().min(self.fitted()).max(self.screened())
    }
    fn write_back(&self, p: &[f64]) -> WriteBack {
        self.inner.write_back(&self.full(p))
    }
    fn applies(&self, recs: &[Recording]) -> bool {
        self.inner.applies(recs)
    }
    fn start(&self, st: &mut EffectState, meta: &BTreeMap<String, String>, p: &[f64]) {
        self.inner.start(st, meta, &self.full(p));
    }
    fn stage(&self) -> u8 {
        self.inner.stage()
    }
    fn by_default(&self) -> bool {
        false
    }
    fn acts_on(&self, t: &JointTarget) -> bool {
        self.inner.acts_on(t)
    }
    fn alike(&self, a: &JointTarget, b: &JointTarget) -> bool {
        self.inner.alike(a, b)
    }
}

/// Declares `static $name: Held`: `$inner` (a unit struct of this module's parent) with its
/// parameter number `$held` held, id `$id`, and the other parameters `[$($keep),*]` (indices).
#[macro_export]
macro_rules! held_variant {
    ($name:ident, $inner:ident, $id:expr, $held:expr, [$($keep:expr),*]) => {
        pub static $name: $crate::fit::effects::held::Held = $crate::fit::effects::held::Held {
            inner: &$inner,
            held: $held,
            meta: &$crate::fit::effects::EffectMeta {
                id: $id,
                entry: $inner::META.entry,
                params: &[$($inner::META.params[$keep]),*],
                docs: "",
            },
        };
    };
}
