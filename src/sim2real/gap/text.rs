//! The human summary of a [`GapReport`] (angles in degrees; the JSON stays SI).

use super::GapReport;

fn deg(x: f64) -> String {
    if x.is_finite() { format!("{:.2}°", x.to_degrees()) } else { "n/a".into() }
}
fn num(x: f64, p: usize) -> String {
    if x.is_finite() { format!("{x:.p$}") } else { "n/a".into() }
}

impl GapReport {
    /// Human summary (angles in degrees, angular velocities in °/s; the JSON stays SI). `title` heads the block ("gap", "before", "after").
    pub fn to_text(&self, title: &str) -> String {
        let mut o = String::new();
        o.push_str(&format!(
            "{title}: {} episode(s), {} samples, {:.1} s (spectra at {} Hz)\n",
            self.episodes, self.samples, self.duration_s, self.uniform_rate_hz
        ));
        o.push_str(&format!(
            "  position  MAE {}  RMSE {}  max {}\n  velocity  MAE {}°/s  RMSE {}°/s\n  correlation mean {}   spectral KL {}\n",
            deg(self.position_mae),
            deg(self.position_rmse),
            deg(self.position_max),
            num(self.velocity_mae.to_degrees(), 3),
            num(self.velocity_rmse.to_degrees(), 3),
            num(self.correlation_mean, 3),
            num(self.spectral_kl, 3)
        ));
        o.push_str(&format!(
            "  gap  kinematic {}  dynamic {}  control {}  overall {}\n",
            num(self.gap_kinematic, 3),
            num(self.gap_dynamic, 3),
            num(self.gap_control, 3),
            num(self.gap_overall, 3)
        ));
        o.push_str(
            "  (correlation and KL weigh each joint by its motion share: 1 − its noise / its \
             recorded variance, `motion`; a joint at its noise floor weighs ~0)\n",
        );
        o.push_str(&format!(
            "\n  {:<24} {:<6} {:>8} {:>8} {:>8} {:>6} {:>9} {:>7} {:>13} {:>6}\n",
            "joint",
            "region",
            "MAE",
            "RMSE",
            "max",
            "corr",
            "vel [°/s]",
            "KL",
            "dom Hz r/s",
            "motion"
        ));
        for s in &self.localisation.joints {
            let Some(j) = self.per_joint.iter().find(|j| j.name == s.name) else { continue };
            o.push_str(&format!(
                "  {:<24} {:<6} {:>8} {:>8} {:>8} {:>6} {:>9} {:>7} {:>6}/{:<6} {:>6.2}\n",
                j.name,
                j.region,
                deg(j.mae),
                deg(j.rmse),
                deg(j.max),
                j.corr.map_or("n/a".into(), |c| format!("{c:.2}")),
                num(j.vel_rmse.to_degrees(), 3),
                num(j.spectral_kl, 3),
                num(j.dominant_hz_real, 1),
                num(j.dominant_hz_sim, 1),
                j.motion_share
            ));
        }
        if self.per_region.len() > 1 {
            o.push_str("\n  region   joints      MAE     RMSE   corr\n");
            for r in &self.per_region {
                o.push_str(&format!(
                    "  {:<8} {:>6} {:>8} {:>8} {:>6}\n",
                    r.region,
                    r.joints,
                    deg(r.mae),
                    deg(r.rmse),
                    r.corr.map_or("n/a".into(), |c| format!("{c:.2}"))
                ));
            }
        }
        let l = &self.localisation;
        o.push_str("\n  where the gap is:\n");
        for s in l.joints.iter().take(5) {
            o.push_str(&format!("    {:>5.1} % of squared error  {}\n", 100.0 * s.share, s.name));
        }
        for s in l.regions.iter().take(4) {
            o.push_str(&format!("    {:>5.1} % region {}\n", 100.0 * s.share, s.name));
        }
        if let Some(b) = &l.worst_band {
            o.push_str(&format!("    largest PSD mismatch in band {b}\n"));
        }
        for p in l.phases.iter().take(3) {
            o.push_str(&format!(
                "    {}: RMSE {} ({:.2}× outside phases)\n",
                p.phase,
                deg(p.rmse),
                p.ratio_to_other
            ));
        }
        for c in l.causes.iter().take(8) {
            o.push_str(&format!("    {:<24} {}\n", c.name, c.summary));
        }
        if !self.diverged.is_empty() {
            o.push_str(&format!(
                "\n  {} episode(s) DIVERGED and are excluded:\n",
                self.diverged.len()
            ));
            for d in &self.diverged {
                o.push_str(&format!("    {d}\n"));
            }
        }
        o
    }
}
