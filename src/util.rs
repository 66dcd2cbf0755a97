//! Small helpers shared by several modules.

/// Up to three names closest to `want` (by Levenshtein distance over chars, ties by name).
pub fn near_matches(want: &str, names: &[String]) -> Vec<String> {
    let core = want.trim_matches('*');
    let mut scored: Vec<(usize, &String)> = names
        .iter()
        .map(|n| {
            (if !core.is_empty() && n.contains(core) { 0 } else { strsim::levenshtein(want, n) }, n)
        })
        .filter(|(d, _)| *d <= want.len().max(3) / 2 + 1)
        .collect();
    scored.sort();
    scored.into_iter().take(3).map(|(_, n)| n.clone()).collect()
}

/// Formats a float compactly with `sig` significant digits (deterministic, no trailing zeros).
pub fn fmt_num(x: f64, sig: usize) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".into();
    }
    let mag = x.abs().log10().floor() as i32;
    let decimals = (sig as i32 - 1 - mag).max(0) as usize;
    if !(-4..9).contains(&mag) {
        return format!("{:.*e}", sig.saturating_sub(1), x);
    }
    let s = format!("{:.*}", decimals, x);
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

/// The one deterministic random generator of the tool: splitmix64 (Steele, Lea & Flood 2014).
/// The optimisers, the probes' command sequences and the synth all draw from it; the same state
/// gives the same sequence on every platform.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator whose state starts at `state` (its first output mixes `state + γ`).
    pub fn from_state(state: u64) -> Rng {
        Rng(state)
    }

    /// An independent stream for `(seed, purpose, index)` (e.g. one per purpose and episode, so
    /// episodes do not depend on the order they are made in).
    pub fn stream(seed: u64, purpose: u64, index: u64) -> Rng {
        let mut r = Rng(seed ^ 0x6A09_E667_F3BC_C908);
        r.0 = r.0.wrapping_add(purpose.wrapping_mul(0xBB67_AE85_84CA_A73B));
        r.next_u64();
        r.0 = r.0.wrapping_add(index.wrapping_mul(0x3C6E_F372_FE94_F82B));
        r.next_u64();
        r
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) (53 bits).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }

    /// Standard normal (Box–Muller on U₁ ∈ [1e-300, 1)).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// Standard normal (Box–Muller on U₁ = 1 − U ∈ (0, 1]): the optimisers' draw. The same
    /// distribution as [`Rng::normal`], another sequence; kept so that fits stay byte-identical.
    pub fn normal_complement(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// Fisher–Yates shuffle.
    pub fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            let j = (self.next_u64() % (i as u64 + 1)) as usize;
            v.swap(i, j);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn distance_and_near() {
        assert_eq!(strsim::levenshtein("knee", "knea"), 1);
        let names =
            vec!["left_knee".to_string(), "right_knee".to_string(), "left_hip_pitch".to_string()];
        assert_eq!(near_matches("left_kne", &names)[0], "left_knee");
        assert_eq!(fmt_num(0.0565056, 4), "0.05651");
        assert_eq!(fmt_num(65.0, 4), "65");
        assert_eq!(fmt_num(12.57, 4), "12.57");
    }

    #[test]
    fn splitmix64_reference_sequence() {
        // The reference outputs of splitmix64 seeded with 1234567 (Vigna's splitmix64.c).
        let mut r = Rng::from_state(1234567);
        let want: [u64; 3] = [6457827717110365317, 3203168211198807973, 9817491932198370423];
        for w in want {
            assert_eq!(r.next_u64(), w);
        }
        let u = Rng::from_state(7).uniform();
        assert!((0.0..1.0).contains(&u));
    }
}
