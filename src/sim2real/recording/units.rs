//! The CSV header key `units`: `# units: deg, deg/s` (a unit per kind of column) or
//! `# units: knee.q=deg, *.tau=mN·m` (glob patterns on column names; a pattern wins over a
//! kind). Values are converted to SI on read, and the key is replaced by
//! `converted_from_units` (a re-written CSV is in SI and must not be converted again). An unknown
//! unit, a unit of the wrong dimension for its columns, a pattern that names no column, or
//! another key that declares units (`time_unit`, `angle_units`) is an error at the key's line.

use std::f64::consts::PI;

use super::Recording;

/// Metadata key of the unit declaration.
pub const KEY_UNITS: &str = "units";
/// Metadata key the declaration is kept under once the values are in SI.
pub const KEY_CONVERTED: &str = "converted_from_units";

#[derive(Clone, Copy, PartialEq, Debug)]
enum Dim {
    Angle,
    AngVel,
    Length,
    LinVel,
    Time,
    Torque,
    Force,
    /// N·m/rad (`kp`).
    Stiffness,
    /// N·m·s/rad (`kd`).
    Damping,
}

/// (unit, dimension, factor to SI).
const UNITS: &[(&str, Dim, f64)] = &[
    ("rad", Dim::Angle, 1.0),
    ("deg", Dim::Angle, PI / 180.0),
    ("rad/s", Dim::AngVel, 1.0),
    ("deg/s", Dim::AngVel, PI / 180.0),
    ("rpm", Dim::AngVel, 2.0 * PI / 60.0),
    ("m", Dim::Length, 1.0),
    ("cm", Dim::Length, 1e-2),
    ("mm", Dim::Length, 1e-3),
    ("m/s", Dim::LinVel, 1.0),
    ("mm/s", Dim::LinVel, 1e-3),
    ("s", Dim::Time, 1.0),
    ("ms", Dim::Time, 1e-3),
    ("us", Dim::Time, 1e-6),
    ("µs", Dim::Time, 1e-6),
    ("ns", Dim::Time, 1e-9),
    ("N·m", Dim::Torque, 1.0),
    ("Nm", Dim::Torque, 1.0),
    ("N*m", Dim::Torque, 1.0),
    ("N.m", Dim::Torque, 1.0),
    ("mN·m", Dim::Torque, 1e-3),
    ("mNm", Dim::Torque, 1e-3),
    ("N", Dim::Force, 1.0),
    ("N·m/rad", Dim::Stiffness, 1.0),
    ("Nm/rad", Dim::Stiffness, 1.0),
    ("N·m/deg", Dim::Stiffness, 180.0 / PI),
    ("Nm/deg", Dim::Stiffness, 180.0 / PI),
    ("N·m·s/rad", Dim::Damping, 1.0),
    ("Nms/rad", Dim::Damping, 1.0),
];

/// The dimensions a column may be declared in: the first is what a bare unit of that
/// dimension applies to.
fn column_dims(col: &str) -> &'static [Dim] {
    if col == "t" {
        return &[Dim::Time];
    }
    match col.rsplit_once('.').map(|(j, s)| (j == "base", s)) {
        Some((true, "x" | "y" | "z")) => &[Dim::Length],
        Some((true, _)) => &[],
        Some((false, "q" | "q_cmd")) => &[Dim::Angle, Dim::Length],
        Some((false, "qd")) => &[Dim::AngVel, Dim::LinVel],
        Some((false, "tau")) => &[Dim::Torque, Dim::Force],
        Some((false, "kp")) => &[Dim::Stiffness],
        Some((false, "kd")) => &[Dim::Damping],
        _ => &[],
    }
}

/// A bare unit's columns: its dimension is the first one the column takes (an angle unit
/// applies to every `.q`/`.q_cmd`; a length unit to `base.x/y/z` only — a slide joint's
/// positions are named: `rail.q=mm`).
fn bare_applies(col: &str, d: Dim) -> bool {
    column_dims(col).first() == Some(&d)
}

fn unit(u: &str) -> Option<(Dim, f64)> {
    let u = u.trim().replace(' ', "");
    UNITS.iter().find(|(n, _, _)| *n == u).map(|(_, d, f)| (*d, *f))
}

/// Is `key` (a metadata key) a unit declaration other than `units`?
pub fn other_unit_key(key: &str) -> bool {
    let k = key.to_lowercase();
    k != KEY_UNITS && k != KEY_CONVERTED && k.contains("unit")
}

/// Converts `rec` by its `units` declaration (`decl`, from its header; `names` are the CSV's
/// column names). `Err` is a message for the key's line.
pub fn apply(rec: &mut Recording, decl: &str, names: &[&str]) -> Result<(), String> {
    // Per column: factor, and whether a pattern (not a bare unit) set it.
    let mut factor: Vec<(f64, bool)> = vec![(1.0, false); names.len()];
    for item in decl.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let known = || UNITS.iter().map(|(n, _, _)| *n).collect::<Vec<_>>().join(", ");
        match item.split_once('=') {
            None => {
                let (d, f) = unit(item)
                    .ok_or_else(|| format!("units: unknown unit '{item}' (known: {})", known()))?;
                let mut any = false;
                for (ci, c) in names.iter().enumerate() {
                    if bare_applies(c, d) {
                        any = true;
                        if !factor[ci].1 {
                            factor[ci].0 = f;
                        }
                    }
                }
                // A kind the file does not have (`rad/s` without `.qd` columns) is vacuously
                // honoured; a length, linear velocity or force without its columns meant a
                // slide joint's, which a bare unit does not name.
                if !any && matches!(d, Dim::Length | Dim::LinVel | Dim::Force) {
                    return Err(format!(
                        "units: '{item}' applies to no column (a bare {} unit is for {}); name the \
                         columns: e.g. `rail.q={item}`",
                        dim_name(d),
                        dim_cols(d)
                    ));
                }
            }
            Some((glob, u)) => {
                let (glob, u) = (glob.trim(), u.trim());
                let (d, f) = unit(u)
                    .ok_or_else(|| format!("units: unknown unit '{u}' (known: {})", known()))?;
                let g = globset::Glob::new(glob)
                    .map_err(|e| format!("units: pattern '{glob}': {e}"))?
                    .compile_matcher();
                let mut any = false;
                for (ci, c) in names.iter().enumerate() {
                    if !g.is_match(c) {
                        continue;
                    }
                    any = true;
                    if !column_dims(c).contains(&d) {
                        return Err(format!(
                            "units: column '{c}' cannot be in {u} (a {}): it takes {}",
                            dim_name(d),
                            column_dims(c)
                                .iter()
                                .map(|d| dim_name(*d))
                                .collect::<Vec<_>>()
                                .join(" or ")
                        ));
                    }
                    factor[ci] = (f, true);
                }
                if !any {
                    return Err(format!("units: '{glob}' names no column of the header"));
                }
            }
        }
    }
    // All in SI already (`# units: rad, rad/s`): nothing to convert, the key stays as it is.
    if factor.iter().all(|(f, _)| *f == 1.0) {
        return Ok(());
    }
    let scale = |v: &mut Vec<f64>, f: f64| v.iter_mut().for_each(|x| *x *= f);
    for (ci, c) in names.iter().enumerate() {
        let f = factor[ci].0;
        if f == 1.0 {
            continue;
        }
        if *c == "t" {
            scale(&mut rec.t, f);
            if let Some(t0) = rec.control_t0_s.as_mut() {
                *t0 *= f;
            }
            continue;
        }
        let Some((joint, suffix)) = c.rsplit_once('.') else { continue };
        if joint == "base" {
            if let Some(b) = rec.base.as_mut() {
                let i = ["x", "y", "z"].iter().position(|s| *s == suffix).unwrap_or(0);
                b.pos.iter_mut().for_each(|p| p[i] *= f);
            }
            continue;
        }
        let Some(j) = rec.joints.iter_mut().find(|j| j.name == joint) else { continue };
        let v = match suffix {
            "q" => Some(&mut j.q),
            "q_cmd" => j.q_cmd.as_mut(),
            "qd" => j.qd.as_mut(),
            "tau" => j.tau.as_mut(),
            "kp" => j.kp.as_mut(),
            "kd" => j.kd.as_mut(),
            _ => None,
        };
        if let Some(v) = v {
            scale(v, f);
        }
    }
    if let Some(v) = rec.meta.remove(KEY_UNITS) {
        rec.meta.insert(KEY_CONVERTED.into(), v);
    }
    Ok(())
}

fn dim_name(d: Dim) -> &'static str {
    match d {
        Dim::Angle => "angle",
        Dim::AngVel => "angular velocity",
        Dim::Length => "length",
        Dim::LinVel => "linear velocity",
        Dim::Time => "time",
        Dim::Torque => "torque",
        Dim::Force => "force",
        Dim::Stiffness => "stiffness (kp)",
        Dim::Damping => "damping (kd)",
    }
}

fn dim_cols(d: Dim) -> &'static str {
    match d {
        Dim::Angle => ".q and .q_cmd",
        Dim::AngVel => ".qd",
        Dim::Length => "base.x/y/z",
        Dim::Time => "t",
        Dim::Torque => ".tau",
        Dim::Stiffness => ".kp",
        Dim::Damping => ".kd",
        Dim::LinVel | Dim::Force => "a named column only",
    }
}
