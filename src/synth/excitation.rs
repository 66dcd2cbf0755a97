//! Excitation: the commands the simulated controller sends. Per episode: a 0.3 s hold at the
//! centre pose, then one or a shuffled mix of
//! * ramped steps (random levels, 0.4–1.2 s dwell, 0.05 s linear rise),
//! * an exponential chirp 0.1 → 5 Hz (amplitude × min(1, 1 Hz / f): fast sweeps stay small),
//! * a smoothed random walk (knots every 0.2 s, smoothstep between them),
//!
//! around each joint's centre pose with a given amplitude, inside the joint range (5 % margin at
//! each end). Segment changes blend over 0.05 s, so the command never jumps.

use super::clock::Rng;

/// Hold at the centre before the excitation [s].
pub const HOLD_S: f64 = 0.3;
/// Rise time of a step, and blend time between segments [s].
pub const RISE_S: f64 = 0.05;
pub const CHIRP_HZ: (f64, f64) = (0.1, 5.0);
/// Above this frequency the chirp amplitude falls as 1/f.
pub const CHIRP_CORNER_HZ: f64 = 1.0;
const WALK_KNOT_S: f64 = 0.2;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Excitation {
    Mix,
    Chirp,
    Steps,
    Random,
}

impl Excitation {
    pub fn parse(s: &str) -> Option<Excitation> {
        Some(match s {
            "mix" => Excitation::Mix,
            "chirp" => Excitation::Chirp,
            "steps" => Excitation::Steps,
            "random" => Excitation::Random,
            _ => return None,
        })
    }
    pub fn label(self) -> &'static str {
        match self {
            Excitation::Mix => "mix",
            Excitation::Chirp => "chirp",
            Excitation::Steps => "steps",
            Excitation::Random => "random",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Chirp,
    Steps,
    Walk,
}

impl Kind {
    pub fn label(self) -> &'static str {
        match self {
            Kind::Chirp => "chirp",
            Kind::Steps => "steps",
            Kind::Walk => "walk",
        }
    }
}

/// One segment of an episode's excitation, in recording time.
#[derive(Debug, Clone, Copy)]
pub struct Segment {
    pub kind: Kind,
    pub t0: f64,
    pub t1: f64,
}

/// Where one joint moves: centre and half-width of its command band.
#[derive(Debug, Clone, Copy)]
pub struct Band {
    pub centre: f64,
    pub amp: f64,
}

impl Band {
    /// The band around `key` with half-width `amplitude`, shrunk and shifted to stay inside
    /// `range` less a 5 % margin at each end (no range: unchanged).
    pub fn new(key: f64, amplitude: f64, range: Option<[f64; 2]>) -> Band {
        match range {
            Some([lo, hi]) if hi > lo => {
                let m = 0.05 * (hi - lo);
                let (lo, hi) = (lo + m, hi - m);
                let amp = amplitude.min(0.5 * (hi - lo));
                Band { centre: key.clamp(lo + amp, hi - amp), amp }
            }
            _ => Band { centre: key, amp: amplitude },
        }
    }
}

/// Per-joint random content of one segment (normalised to [−1, 1]).
#[derive(Debug, Clone)]
enum Content {
    Chirp {
        sign: f64,
    },
    /// (start time, level) of each step.
    Steps(Vec<(f64, f64)>),
    /// Knot values every WALK_KNOT_S from the segment start.
    Walk(Vec<f64>),
}

/// The excitation plan of one episode: segments and, per joint, the content of each.
#[derive(Debug, Clone)]
pub struct Plan {
    pub segments: Vec<Segment>,
    bands: Vec<Band>,
    content: Vec<Vec<Content>>,
}

impl Plan {
    pub fn new(kind: Excitation, duration: f64, bands: &[Band], rng: &mut Rng) -> Plan {
        let mut kinds = match kind {
            Excitation::Mix => vec![Kind::Chirp, Kind::Steps, Kind::Walk],
            Excitation::Chirp => vec![Kind::Chirp],
            Excitation::Steps => vec![Kind::Steps],
            Excitation::Random => vec![Kind::Walk],
        };
        rng.shuffle(&mut kinds);
        let w: Vec<f64> = kinds.iter().map(|_| rng.range(0.6, 1.4)).collect();
        let total: f64 = w.iter().sum();
        let span = (duration - HOLD_S).max(0.0);
        let mut segments = Vec::new();
        let mut t = HOLD_S.min(duration);
        for (k, wk) in kinds.iter().zip(&w) {
            let len = span * wk / total;
            segments.push(Segment { kind: *k, t0: t, t1: t + len });
            t += len;
        }
        if let Some(s) = segments.last_mut() {
            s.t1 = duration.max(s.t0);
        }
        let content = bands
            .iter()
            .map(|_| {
                segments
                    .iter()
                    .map(|s| match s.kind {
                        Kind::Chirp => {
                            Content::Chirp { sign: if rng.uniform() < 0.5 { -1.0 } else { 1.0 } }
                        }
                        Kind::Steps => {
                            let mut v = Vec::new();
                            let mut x = s.t0;
                            while x < s.t1 {
                                v.push((x, rng.range(-1.0, 1.0)));
                                x += rng.range(0.4, 1.2);
                            }
                            Content::Steps(v)
                        }
                        Kind::Walk => {
                            let n = ((s.t1 - s.t0) / WALK_KNOT_S).ceil() as usize + 2;
                            let mut v = vec![0.0];
                            for _ in 1..n {
                                let last = v[v.len() - 1];
                                v.push((last + 0.35 * rng.normal()).clamp(-1.0, 1.0));
                            }
                            Content::Walk(v)
                        }
                    })
                    .collect()
            })
            .collect();
        Plan { segments, bands: bands.to_vec(), content }
    }

    /// Normalised offset of joint j in segment i at time t (0 at the segment start).
    fn raw(&self, i: usize, j: usize, t: f64) -> f64 {
        let s = self.segments[i];
        let tau = (t - s.t0).max(0.0);
        match &self.content[j][i] {
            Content::Chirp { sign } => {
                let (f0, f1) = CHIRP_HZ;
                let len = (s.t1 - s.t0).max(1e-9);
                let r = f1 / f0;
                let x = (tau / len).min(1.0);
                let f = f0 * r.powf(x);
                let phase = std::f64::consts::TAU * f0 * len / r.ln() * (r.powf(x) - 1.0);
                sign * (CHIRP_CORNER_HZ / f).min(1.0) * phase.sin()
            }
            Content::Steps(v) => {
                // Ramp from the previous level (0 before the first step).
                let mut prev = 0.0;
                let mut out = 0.0;
                for &(ts, level) in v {
                    if t < ts {
                        break;
                    }
                    let a = ((t - ts) / RISE_S).min(1.0);
                    out = prev + a * (level - prev);
                    prev = level;
                }
                out
            }
            Content::Walk(v) => {
                let x = tau / WALK_KNOT_S;
                let k = (x.floor() as usize).min(v.len() - 2);
                let a = (x - k as f64).clamp(0.0, 1.0);
                let s = a * a * (3.0 - 2.0 * a);
                v[k] + s * (v[k + 1] - v[k])
            }
        }
    }

    /// Normalised offset of joint j at recording time t (segment changes blended over RISE_S).
    pub fn offset(&self, j: usize, t: f64) -> f64 {
        let Some(i) = self.segments.iter().rposition(|s| t >= s.t0) else { return 0.0 };
        let s = self.segments[i];
        let mut v = self.raw(i, j, t);
        let since = t - s.t0;
        if since < RISE_S {
            let before = if i == 0 { 0.0 } else { self.raw(i - 1, j, s.t0) };
            v += (1.0 - since / RISE_S) * (before - self.raw(i, j, s.t0));
        }
        v.clamp(-1.0, 1.0)
    }

    /// Command of joint j at time t (t < 0: the hold pose).
    pub fn command(&self, j: usize, t: f64) -> f64 {
        let b = self.bands[j];
        b.centre + b.amp * self.offset(j, t.max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_stays_inside_the_range() {
        // Knee at its lower limit 0 with range [0, 2]: margin 0.1, band shifted up.
        let b = Band::new(0.0, 0.35, Some([0.0, 2.0]));
        assert!((b.centre - 0.45).abs() < 1e-12 && (b.amp - 0.35).abs() < 1e-12);
        // Narrow range [−0.1, 0.1]: margin 0.01, amplitude shrunk to 0.09.
        let b = Band::new(0.0, 0.35, Some([-0.1, 0.1]));
        assert!((b.amp - 0.09).abs() < 1e-12 && b.centre.abs() < 1e-12);
        let b = Band::new(0.3, 0.35, None);
        assert_eq!((b.centre, b.amp), (0.3, 0.35));
    }

    #[test]
    fn hold_then_bounded_continuous_commands() {
        let bands = [Band { centre: 0.3, amp: 0.35 }, Band { centre: -1.0, amp: 0.1 }];
        let mut rng = Rng::stream(5, 1, 0);
        let p = Plan::new(Excitation::Mix, 10.0, &bands, &mut rng);
        assert_eq!(p.segments.len(), 3);
        assert!(
            (p.segments[0].t0 - HOLD_S).abs() < 1e-12 && (p.segments[2].t1 - 10.0).abs() < 1e-12
        );
        let mut kinds: Vec<&str> = p.segments.iter().map(|s| s.kind.label()).collect();
        kinds.sort();
        assert_eq!(kinds, ["chirp", "steps", "walk"]);
        for (j, b) in bands.iter().enumerate() {
            assert_eq!(p.command(j, 0.0), b.centre);
            assert_eq!(p.command(j, 0.29), b.centre);
            let mut last = p.command(j, 0.0);
            let mut k = 1;
            while k as f64 * 1e-3 < 10.0 {
                let c = p.command(j, k as f64 * 1e-3);
                assert!((c - b.centre).abs() <= b.amp + 1e-12);
                // Slope bound: a step rises 2·amp in RISE_S at most; chirp/walk are slower.
                assert!(
                    (c - last).abs() <= 2.0 * b.amp / RISE_S * 1e-3 + 1e-9,
                    "jump at {k} ms: {last} → {c}"
                );
                last = c;
                k += 1;
            }
        }
    }
}
