//! The two clocks of the simulated logging setup, on a 1 µs time base, and the RNG streams.
//!
//! * [`ControlClock`]: the robot's controller sends a position command at every tick
//!   t_k = t0 + k / rate (k ≥ 0; a tick −1 covers [t0 − 1/rate, t0) when t0 > 0); the command
//!   is held (zero-order hold) until the next tick.
//! * [`sample_times`]: an asynchronous recorder that logs a row every (1/rate)·(1 + U(−j, j))
//!   seconds, or exactly at the control ticks (`--log-at-ticks`).
//! * [`Commands`]: the per-tick commands with the servo-side view (the command in force at t,
//!   optionally delayed, averaged over one physics step).
//!
//! All times are integer microseconds where they decide which tick a row belongs to, so the
//! written `t` column (6 decimals) and the `q_cmd` of the row agree exactly.

/// The tool's splitmix64 generator; the synth takes one [`Rng::stream`] per purpose and episode,
/// so episodes are independent of the order they are simulated in.
pub use crate::util::Rng;

/// Microseconds per second.
pub const US: f64 = 1e6;

/// Seconds → integer microseconds (rounded).
pub fn to_us(t: f64) -> i64 {
    (t * US).round() as i64
}

/// The controller's tick clock, in recording time (0 = end of the settle).
#[derive(Debug, Clone, Copy)]
pub struct ControlClock {
    pub rate_hz: f64,
    /// Time of tick 0 [µs], in [0, 1/rate).
    pub t0_us: i64,
}

impl ControlClock {
    /// Time of tick `k` [µs] (rounded to the recorder's 1 µs clock).
    pub fn tick_us(&self, k: i64) -> i64 {
        self.t0_us + (k as f64 * US / self.rate_hz).round() as i64
    }
    /// First tick index (−1 when t0 > 0: that tick is in force at recording time 0).
    pub fn first_tick(&self) -> i64 {
        if self.t0_us > 0 { -1 } else { 0 }
    }
    /// The tick in force at `t_us`: the largest k with tick_us(k) ≤ t_us.
    pub fn tick_at(&self, t_us: i64) -> i64 {
        let mut k = ((t_us - self.t0_us) as f64 * self.rate_hz / US).floor() as i64;
        while self.tick_us(k) > t_us {
            k -= 1;
        }
        while self.tick_us(k + 1) <= t_us {
            k += 1;
        }
        k
    }
    /// Ticks covering recording time [0, duration): first..=last.
    pub fn ticks(&self, duration_us: i64) -> std::ops::RangeInclusive<i64> {
        self.first_tick()..=self.tick_at(duration_us.max(1) - 1)
    }
}

/// Recorder sample times [µs] in [0, duration): every (1/rate)(1 + U(−jitter, jitter)) from 0,
/// or the control ticks when `at_ticks`.
pub fn sample_times(
    duration_us: i64,
    rate_hz: f64,
    jitter: f64,
    at_ticks: Option<&ControlClock>,
    rng: &mut Rng,
) -> Vec<i64> {
    let mut out = Vec::new();
    if let Some(c) = at_ticks {
        let mut k = 0;
        loop {
            let t = c.tick_us(k);
            if t >= duration_us {
                break;
            }
            out.push(t);
            k += 1;
        }
        return out;
    }
    let period = US / rate_hz;
    let mut t = 0.0f64;
    loop {
        let us = t.round() as i64;
        if us >= duration_us {
            break;
        }
        if out.last().is_none_or(|&l| us > l) {
            out.push(us);
        }
        t += period * (1.0 + jitter * rng.range(-1.0, 1.0));
    }
    out
}

/// Per-tick commands of every driven joint and what the servo sees of them.
#[derive(Debug, Clone)]
pub struct Commands {
    pub clock: ControlClock,
    /// Index of `cmd[0]` (the clock's first tick).
    pub first: i64,
    /// `cmd[i][j]`: command of tick `first + i` for joint j.
    pub cmd: Vec<Vec<f64>>,
}

impl Commands {
    /// The command of tick `k` for joint `j` (ticks before the first hold the first command —
    /// the settle —, after the last hold the last).
    pub fn of_tick(&self, k: i64, j: usize) -> f64 {
        let i = (k - self.first).clamp(0, self.cmd.len() as i64 - 1) as usize;
        self.cmd[i][j]
    }
    /// The command in force at `t_us` (what a row stamped `t_us` logs).
    pub fn in_force(&self, t_us: i64, j: usize) -> f64 {
        self.of_tick(self.clock.tick_at(t_us), j)
    }
    /// Mean of the zero-order-hold command of joint j over [a, b] seconds (b > a): the servo's
    /// set-point for one physics step (exact for a tick switch inside the step). A transport
    /// delay d is `mean(a − d, b − d)`.
    pub fn mean(&self, a: f64, b: f64, j: usize) -> f64 {
        let (a_us, b_us) = (a * US, b * US);
        // Tick in force at a (continuous time; ticks at integer µs).
        let mut k = self.clock.tick_at(a_us.floor() as i64);
        let mut t = a_us;
        let mut acc = 0.0;
        while t < b_us {
            let next = (self.clock.tick_us(k + 1) as f64).min(b_us);
            acc += (next - t) * self.of_tick(k, j);
            t = next;
            k += 1;
        }
        acc / (b_us - a_us)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_at_100_hz_with_a_phase() {
        let c = ControlClock { rate_hz: 100.0, t0_us: 4000 };
        assert_eq!(c.first_tick(), -1);
        assert_eq!(c.tick_us(0), 4000);
        assert_eq!(c.tick_us(3), 34000);
        assert_eq!(c.tick_at(0), -1);
        assert_eq!(c.tick_at(3999), -1);
        assert_eq!(c.tick_at(4000), 0);
        assert_eq!(c.tick_at(13999), 0);
        assert_eq!(c.tick_at(14000), 1);
        assert_eq!(c.ticks(1_000_000), -1..=99);
    }

    #[test]
    fn tick_at_non_integer_period() {
        // 88 Hz: period 11363.63… µs; tick 3 at round(34090.9) = 34091 µs.
        let c = ControlClock { rate_hz: 88.0, t0_us: 0 };
        assert_eq!(c.tick_us(3), 34091);
        assert_eq!(c.tick_at(34090), 2);
        assert_eq!(c.tick_at(34091), 3);
    }

    #[test]
    fn zoh_mean_over_a_step_straddling_a_tick() {
        let c = ControlClock { rate_hz: 100.0, t0_us: 2500 };
        let cmds = Commands { clock: c, first: -1, cmd: vec![vec![0.0], vec![1.0], vec![3.0]] };
        // [0.002, 0.003]: tick −1 (0) until 0.0025, tick 0 (1) after: mean 0.5.
        assert!((cmds.mean(0.002, 0.003, 0) - 0.5).abs() < 1e-12);
        // Whole step inside tick 1: 3.
        assert!((cmds.mean(0.0130, 0.0140, 0) - 3.0).abs() < 1e-12);
        // The step [0.0026, 0.0036] delayed by 0.0004 s sees [0.0022, 0.0032]: 0.3 ms of
        // tick −1 (0), 0.7 ms of tick 0 (1).
        assert!((cmds.mean(0.0026 - 0.0004, 0.0036 - 0.0004, 0) - 0.7).abs() < 1e-12);
        assert_eq!(cmds.in_force(12499, 0), 1.0);
        assert_eq!(cmds.in_force(12500, 0), 3.0);
        // Before the first tick: the first command (settle); long after: the last.
        assert_eq!(cmds.in_force(-5_000_000, 0), 0.0);
        assert_eq!(cmds.in_force(5_000_000, 0), 3.0);
    }

    #[test]
    fn jittered_sample_spacing_stays_in_bounds() {
        let mut rng = Rng::stream(1, 2, 3);
        let t = sample_times(10_000_000, 88.0, 0.15, None, &mut rng);
        assert_eq!(t[0], 0);
        let p = 1e6 / 88.0;
        for w in t.windows(2) {
            let d = (w[1] - w[0]) as f64;
            assert!(d >= 0.85 * p - 1.0 && d <= 1.15 * p + 1.0, "{d}");
        }
        let mean = (t[t.len() - 1] - t[0]) as f64 / (t.len() - 1) as f64;
        assert!((mean / p - 1.0).abs() < 0.01, "mean {mean}");
        let c = ControlClock { rate_hz: 100.0, t0_us: 0 };
        let k = sample_times(1_000_000, 88.0, 0.15, Some(&c), &mut rng);
        assert_eq!(k.len(), 100);
        assert_eq!(k[7], 70_000);
    }
}
