//! Which recordings train the fit and which judge it (held out), and time windows of a
//! recording (multiple shooting, or a held-out set cut from a single episode).
//!
//! 1. Declared: episodes whose metadata says `split: heldout` are held out and every other one
//!    trains, exactly as the recording's author intended.
//! 2. Otherwise, of n episodes ⌈n / holdout⌉ are held out, spread evenly over the sorted list
//!    (the middle of each block of `holdout`), so that the held-out set spans the session
//!    (a dataset sorted by time, gain or amplitude is not judged on its end alone).
//! 3. A single episode is cut into time windows, every `holdout`-th window held out.
//!
//! 4. By a metadata key (`--holdout-by KEY=VALUE`, [`split_by_key`]): the episodes whose
//!    metadata `KEY` equals `VALUE` are held out, every other one trains — e.g. the firmware gain
//!    `kp` of servo logs, so that the fit is judged on a gain it never saw. `--holdout-by KEY`
//!    rotates over every value of the key ([`key_values`]; leave-one-group-out).
//!
//! [`Split::note`] says which were held out and why; `modellint fit` prints it.

use crate::sim2real::recording::{Recording, Split as Declared};

/// The train / held-out sets and why they were chosen.
pub struct Split {
    pub train: Vec<Recording>,
    pub heldout: Vec<Recording>,
    /// The held-out set is made of time windows of a single episode.
    pub by_time: bool,
    /// Which episodes were held out, and why (one line).
    pub note: String,
}

/// Copy of samples `i0..i1` of a recording (the control-tick phase is kept).
pub fn slice_recording(rec: &Recording, i0: usize, i1: usize) -> Recording {
    let s = |v: &Vec<f64>| v[i0..i1].to_vec();
    let mut r = rec.clone();
    r.t = s(&rec.t);
    r.control_t0_s = Some(rec.control_t0_s.unwrap_or(rec.t[0]));
    for (j, o) in r.joints.iter_mut().zip(&rec.joints) {
        j.q = s(&o.q);
        j.qd = o.qd.as_ref().map(s);
        j.q_cmd = o.q_cmd.as_ref().map(s);
        j.tau = o.tau.as_ref().map(s);
        j.kp = o.kp.as_ref().map(s);
        j.kd = o.kd.as_ref().map(s);
        j.enabled = o.enabled.as_ref().map(|v| v[i0..i1].to_vec());
    }
    if let (Some(b), Some(ob)) = (r.base.as_mut(), rec.base.as_ref()) {
        b.pos = ob.pos[i0..i1].to_vec();
        b.quat = ob.quat[i0..i1].to_vec();
    }
    r.source = format!("{}@{:.2}s", rec.source.display(), rec.t[i0]).into();
    r
}

/// About `total_s` seconds of `recs`, spread evenly: from each of the n recordings the stretch
/// of `total_s / n` seconds with the largest summed `weight` (one weight per sample, e.g. the
/// squared residual: where the model is most wrong), the earliest of equal ones — the start
/// when the weights are equal. A recording that is not longer comes whole; a set that is not
/// longer than `total_s` (or `total_s <= 0`) comes back whole. A stretch replays from its
/// first row's recorded state (as [`windows`] do).
pub fn segments(recs: &[Recording], weight: &[Vec<f64>], total_s: f64) -> Vec<Recording> {
    let dur = |r: &Recording| match (r.t.first(), r.t.last()) {
        (Some(a), Some(b)) => b - a,
        _ => 0.0,
    };
    let all: f64 = recs.iter().map(dur).sum();
    if total_s <= 0.0 || recs.is_empty() || all <= total_s {
        return recs.to_vec();
    }
    let each = total_s / recs.len() as f64;
    recs.iter()
        .enumerate()
        .map(|(k, r)| {
            let n = r.t.len();
            if dur(r) <= each || n < 3 {
                return r.clone();
            }
            let w = |i: usize| {
                weight
                    .get(k)
                    .and_then(|v| v.get(i))
                    .copied()
                    .filter(|x| x.is_finite())
                    .unwrap_or(0.0)
            };
            // Sliding stretch [i0, i1) with t[i1 - 1] - t[i0] <= each.
            let (mut best, mut best_sum) = ((0usize, 0usize), f64::NEG_INFINITY);
            let (mut i1, mut sum) = (0usize, 0.0);
            for i0 in 0..n {
                while i1 < n && r.t[i1] - r.t[i0] <= each {
                    sum += w(i1);
                    i1 += 1;
                }
                if i1 - i0 >= 2 && sum > best_sum {
                    best = (i0, i1);
                    best_sum = sum;
                }
                if i1 == n {
                    break;
                }
                sum -= w(i0);
            }
            let mut p = slice_recording(r, best.0, best.1);
            if best.0 == 0 {
                p.source = r.source.clone();
            }
            p
        })
        .collect()
}

/// Cuts a recording into windows of about `len_s` (the last one absorbs the remainder).
pub fn windows(rec: &Recording, len_s: f64) -> Vec<Recording> {
    let n = rec.t.len();
    let mut out = Vec::new();
    let mut i0 = 0;
    while i0 + 2 < n {
        let tend = rec.t[i0] + len_s;
        let mut i1 = rec.t.partition_point(|&x| x < tend).max(i0 + 2);
        if rec.t[n - 1] - rec.t[i1.min(n - 1)] < 0.5 * len_s {
            i1 = n;
        }
        out.push(slice_recording(rec, i0, i1.min(n)));
        i0 = i1;
    }
    out
}

fn name(r: &Recording) -> String {
    r.source
        .file_name()
        .map_or_else(|| r.source.display().to_string(), |f| f.to_string_lossy().into_owned())
}

fn names(rs: &[&Recording]) -> String {
    let v: Vec<String> = rs.iter().map(|r| name(r)).collect();
    if v.len() <= 6 {
        v.join(", ")
    } else {
        format!("{}, … ({} episodes)", v[..5].join(", "), v.len())
    }
}

/// Distinct values of metadata `key` over `recs`, sorted (numerically when every value is a
/// number); episodes without the key are not counted.
pub fn key_values(recs: &[Recording], key: &str) -> Vec<String> {
    let mut v: Vec<String> = recs.iter().filter_map(|r| r.meta.get(key).cloned()).collect();
    v.sort();
    v.dedup();
    let nums: Option<Vec<f64>> = v.iter().map(|x| x.trim().parse::<f64>().ok()).collect();
    if let Some(n) = nums {
        let mut idx: Vec<usize> = (0..v.len()).collect();
        idx.sort_by(|&a, &b| n[a].total_cmp(&n[b]));
        v = idx.into_iter().map(|i| v[i].clone()).collect();
    }
    v
}

/// Holds out the episodes whose metadata `key` equals `value` (numerically equal when both are
/// numbers); every other episode, including those without the key, trains. An error when
/// nothing or everything would be held out.
pub fn split_by_key(recs: &[Recording], key: &str, value: &str) -> Result<Split, String> {
    let same = |v: &str| match (v.trim().parse::<f64>(), value.trim().parse::<f64>()) {
        (Ok(a), Ok(b)) => a == b,
        _ => v == value,
    };
    let (ho, tr): (Vec<&Recording>, Vec<&Recording>) =
        recs.iter().partition(|r| r.meta.get(key).is_some_and(|v| same(v)));
    if ho.is_empty() {
        let vals = key_values(recs, key);
        return Err(if vals.is_empty() {
            format!("--holdout-by: no recording has the metadata key `{key}`")
        } else {
            format!("--holdout-by: no recording has {key} = {value}; values: {}", vals.join(", "))
        });
    }
    if tr.is_empty() {
        return Err(format!(
            "--holdout-by: every recording has {key} = {value}; nothing to train on"
        ));
    }
    let note = format!(
        "held out the {} episodes with {key} = {value} ({}); trained on the other {}",
        ho.len(),
        names(&ho),
        tr.len()
    );
    Ok(Split {
        train: tr.into_iter().cloned().collect(),
        heldout: ho.into_iter().cloned().collect(),
        by_time: false,
        note,
    })
}

/// Splits `recs` (see the module docs); `holdout` ≥ 2 is the "one in N" ratio.
pub fn split(recs: &[Recording], holdout: usize) -> Split {
    let h = holdout.max(2);
    let declared: Vec<Option<Declared>> = recs.iter().map(Recording::split).collect();
    if declared.contains(&Some(Declared::Heldout)) {
        let (mut tr, mut ho) = (vec![], vec![]);
        for (r, d) in recs.iter().zip(&declared) {
            if *d == Some(Declared::Heldout) { ho.push(r) } else { tr.push(r) }
        }
        if !tr.is_empty() {
            let note = format!(
                "held out {} (declared `split: heldout`); trained on {}",
                names(&ho),
                names(&tr)
            );
            return Split {
                train: tr.into_iter().cloned().collect(),
                heldout: ho.into_iter().cloned().collect(),
                by_time: false,
                note,
            };
        }
    }
    if recs.len() == 1 {
        let d = recs[0].duration();
        let len = (d / (2 * h) as f64).clamp(0.5, 2.0);
        let w = windows(&recs[0], len);
        let (mut tr, mut ho) = (vec![], vec![]);
        for (i, r) in w.into_iter().enumerate() {
            if (i + 1) % h == 0 { ho.push(r) } else { tr.push(r) }
        }
        if ho.is_empty() && tr.len() >= 2 {
            ho.push(tr.pop().expect("len ≥ 2"));
        }
        let note = format!(
            "one episode ({}): cut into {:.1} s windows, every {h}th window held out ({} held out, {} train)",
            name(&recs[0]),
            len,
            ho.len(),
            tr.len()
        );
        return Split { train: tr, heldout: ho, by_time: true, note };
    }
    let n = recs.len();
    let k = n.div_ceil(h).max(1).min(n.saturating_sub(1));
    // The middle of each of k equal blocks of the sorted list.
    let picked: Vec<usize> = (0..k).map(|b| (((2 * b + 1) * n) / (2 * k)).min(n - 1)).collect();
    let (mut tr, mut ho) = (vec![], vec![]);
    for (i, r) in recs.iter().enumerate() {
        if picked.contains(&i) { ho.push(r) } else { tr.push(r) }
    }
    let why = if declared.iter().any(Option::is_some) {
        " (no episode declares `split: heldout`)"
    } else {
        ""
    };
    let note = if ho.is_empty() {
        String::new()
    } else {
        format!(
            "held out {} of {n} episodes, spread evenly over the sorted list{why}: {}",
            ho.len(),
            names(&ho)
        )
    };
    Split {
        train: tr.into_iter().cloned().collect(),
        heldout: ho.into_iter().cloned().collect(),
        by_time: false,
        note,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim2real::recording::JointTrace;

    fn rec(n: usize, dt: f64) -> Recording {
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let mut j = JointTrace::new("a", t.iter().map(|x| x.sin()).collect());
        j.q_cmd = Some(j.q.clone());
        Recording::at_100hz(t, vec![j])
    }

    fn named(i: usize, split: Option<&str>) -> Recording {
        let mut r = rec(100, 0.01);
        r.source = format!("ep_{i:02}.csv").into();
        if let Some(s) = split {
            r.meta.insert("split".into(), s.into());
        }
        r
    }

    #[test]
    fn segments_take_the_heaviest_stretch_of_every_episode() {
        let (a, b) = (rec(1001, 0.01), rec(501, 0.01)); // 10 s and 5 s
        // Equal weights: the start of each.
        let p = segments(&[a.clone(), b.clone()], &[], 6.0);
        assert_eq!(p.len(), 2);
        assert!((p[0].t.last().unwrap() - 3.0).abs() < 0.011, "{:?}", p[0].t.last());
        assert!((p[1].t.last().unwrap() - 3.0).abs() < 0.011);
        assert_eq!(p[0].joints[0].q[..], a.joints[0].q[..p[0].t.len()]);
        assert_eq!(p[0].source, a.source, "a start keeps its episode's name");
        // The weight sits at 6–7 s of the first: its stretch holds it.
        let w0: Vec<f64> =
            (0..1001).map(|i| if (600..700).contains(&i) { 1.0 } else { 0.0 }).collect();
        let p = segments(&[a.clone(), b.clone()], &[w0, vec![0.0; 501]], 6.0);
        assert!(
            p[0].t[0] <= 6.0 && *p[0].t.last().unwrap() >= 6.99,
            "{:?}",
            (p[0].t[0], p[0].t.last())
        );
        assert_eq!(p[1].t[0], 0.0);
        // Shorter than the share: whole. Not longer than the total, or no total: all whole.
        let p = segments(&[a.clone(), rec(101, 0.01)], &[], 6.0);
        assert_eq!(p[1].t.len(), 101);
        assert_eq!(segments(&[a.clone(), b.clone()], &[], 15.0)[0].t.len(), 1001);
        assert_eq!(segments(&[a, b], &[], 0.0)[1].t.len(), 501);
    }

    #[test]
    fn windows_cover_the_recording_and_keep_the_tick_phase() {
        let r = rec(1001, 0.005); // 5 s
        let w = windows(&r, 1.0);
        assert_eq!(w.len(), 5);
        assert_eq!(w.iter().map(|x| x.t.len()).sum::<usize>(), 1001);
        assert!(w.iter().all(|x| x.control_t0_s == Some(0.0)));
        assert_eq!(w[2].joints[0].q[0], r.joints[0].q[w[0].t.len() + w[1].t.len()]);
    }

    #[test]
    fn declared_split_is_honoured() {
        let recs = vec![
            named(0, Some("train")),
            named(1, Some("heldout")),
            named(2, Some("train")),
            named(3, Some("train")),
        ];
        let s = split(&recs, 4);
        let ho: Vec<String> = s.heldout.iter().map(name).collect();
        assert_eq!(ho, ["ep_01.csv"]);
        assert_eq!(s.train.len(), 3);
        assert!(s.note.contains("declared"), "{}", s.note);
    }

    #[test]
    fn automatic_split_spans_the_sorted_list() {
        let recs: Vec<Recording> = (0..8).map(|i| named(i, None)).collect();
        let s = split(&recs, 4);
        let ho: Vec<String> = s.heldout.iter().map(name).collect();
        // Two blocks of four: their middles, 2 and 6 (not 3 and 7, the ends of the blocks).
        assert_eq!(ho, ["ep_02.csv", "ep_06.csv"]);
        assert_eq!((s.train.len(), s.by_time), (6, false));
        assert!(s.note.contains("ep_02.csv") && s.note.contains("spread evenly"), "{}", s.note);
        let s = split(&recs[..3], 4);
        assert_eq!((s.train.len(), s.heldout.len()), (2, 1));
        assert_eq!(name(&s.heldout[0]), "ep_01.csv");
        // All declared train: falls back to the automatic choice and says so.
        let recs: Vec<Recording> = (0..4).map(|i| named(i, Some("train"))).collect();
        let s = split(&recs, 4);
        assert_eq!(s.heldout.len(), 1);
        assert!(s.note.contains("no episode declares"), "{}", s.note);
    }

    #[test]
    fn split_by_metadata_key() {
        let recs: Vec<Recording> = (0..6)
            .map(|i| {
                let mut r = named(i, None);
                r.meta.insert("kp".into(), ["100", "200", "800"][i % 3].into());
                r
            })
            .collect();
        assert_eq!(key_values(&recs, "kp"), ["100", "200", "800"]);
        let s = split_by_key(&recs, "kp", "200.0").expect("numeric match");
        let ho: Vec<String> = s.heldout.iter().map(name).collect();
        assert_eq!(ho, ["ep_01.csv", "ep_04.csv"]);
        assert_eq!(s.train.len(), 4);
        assert!(s.note.contains("kp = 200.0"), "{}", s.note);
        let e = split_by_key(&recs, "kp", "300").err().expect("no such value");
        assert!(e.contains("100, 200, 800"), "{e}");
        assert!(split_by_key(&recs, "vin", "7").is_err());
        // Numeric order, not lexical.
        let mut r = named(9, None);
        r.meta.insert("kp".into(), "50".into());
        let mut more = recs.clone();
        more.push(r);
        assert_eq!(key_values(&more, "kp"), ["50", "100", "200", "800"]);
    }

    #[test]
    fn single_episode_is_split_by_time() {
        let s = split(&[rec(2001, 0.005)], 4);
        assert!(
            s.by_time && !s.train.is_empty() && !s.heldout.is_empty(),
            "{} {}",
            s.train.len(),
            s.heldout.len()
        );
        assert!(s.note.contains("windows"));
    }
}
