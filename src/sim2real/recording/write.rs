//! Writing the CSV format.

use super::{
    BASE_SUFFIXES, JOINT_SUFFIXES, KEY_CONTROL_RATE, KEY_CONTROL_T0, RATE_NONE, Recording,
};

/// The comment (no colon: not metadata) above a `converted_from_units` line: the key names the
/// units the source was in, while every value of the file is in SI (a reader took `deg` for the
/// unit of the radians below it).
pub const VALUES_IN_SI: &str = "# values in SI units (rad, rad/s, s, N·m; m, m/s, N on a slide joint) - \
                                 converted on reading from the units below\n";

/// Serialises a recording; `parse_csv(write_csv(r))` gives back `r` exactly (except `source`)
/// for any recording `parse_csv` would accept. Metadata keys must not contain ':' and neither
/// keys nor values may contain line breaks (they are replaced by spaces) or begin/end with spaces.
pub fn write_csv(rec: &Recording) -> String {
    use std::fmt::Write;
    let clean = |s: &str| s.replace(['\r', '\n'], " ");
    let mut out = String::new();
    if let Some(r) = rec.control_rate_hz {
        let _ = writeln!(out, "# {KEY_CONTROL_RATE}: {r}");
    }
    if let Some(t0) = rec.control_t0_s {
        let _ = writeln!(out, "# {KEY_CONTROL_T0}: {t0}");
    }
    for (k, v) in &rec.meta {
        // `control_rate_hz: none` (no rate, declared) is kept; a number is the field's.
        let declared_none = rec.control_rate_hz.is_none() && v == RATE_NONE;
        if (k == KEY_CONTROL_RATE && !declared_none) || k == KEY_CONTROL_T0 {
            continue;
        }
        if k == super::units::KEY_CONVERTED {
            // The declaration the values were read in is kept; the values are no longer in it.
            out.push_str(VALUES_IN_SI);
        }
        let _ = writeln!(out, "# {}: {}", clean(k), clean(v));
    }
    let mut header = vec!["t".to_string()];
    for j in &rec.joints {
        let present = [
            true,
            j.qd.is_some(),
            j.q_cmd.is_some(),
            j.tau.is_some(),
            j.kp.is_some(),
            j.kd.is_some(),
            j.enabled.is_some(),
        ];
        for (si, p) in present.iter().enumerate() {
            if *p {
                header.push(format!("{}.{}", j.name, JOINT_SUFFIXES[si]));
            }
        }
    }
    if rec.base.is_some() {
        header.extend(BASE_SUFFIXES.iter().map(|s| format!("base.{s}")));
    }
    out.push_str(&header.join(","));
    out.push('\n');
    let num =
        |v: Option<&Vec<f64>>, i: usize| v.and_then(|v| v.get(i)).copied().unwrap_or(f64::NAN);
    for i in 0..rec.t.len() {
        let _ = write!(out, "{}", rec.t[i]);
        for j in &rec.joints {
            let _ = write!(out, ",{}", num(Some(&j.q), i));
            for v in [&j.qd, &j.q_cmd, &j.tau, &j.kp, &j.kd].into_iter().flatten() {
                let _ = write!(out, ",{}", num(Some(v), i));
            }
            if let Some(e) = &j.enabled {
                out.push_str(if e.get(i).copied().unwrap_or(false) { ",1" } else { ",0" });
            }
        }
        if let Some(b) = &rec.base {
            let p = b.pos.get(i).copied().unwrap_or([f64::NAN; 3]);
            let q = b.quat.get(i).copied().unwrap_or([f64::NAN; 4]);
            for v in p.iter().chain(q.iter()) {
                let _ = write!(out, ",{v}");
            }
        }
        out.push('\n');
    }
    out
}
