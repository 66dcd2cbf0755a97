//! Small helpers shared by several modules.

/// Levenshtein distance between two strings (by chars).
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != *cb)).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Up to three names closest to `want` (by edit distance, ties by name).
pub fn near_matches(want: &str, names: &[String]) -> Vec<String> {
    let core = want.trim_matches('*');
    let mut scored: Vec<(usize, &String)> = names
        .iter()
        .map(|n| (if !core.is_empty() && n.contains(core) { 0 } else { edit_distance(want, n) }, n))
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

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn distance_and_near() {
        assert_eq!(edit_distance("knee", "knea"), 1);
        let names =
            vec!["left_knee".to_string(), "right_knee".to_string(), "left_hip_pitch".to_string()];
        assert_eq!(near_matches("left_kne", &names)[0], "left_knee");
        assert_eq!(fmt_num(0.0565056, 4), "0.05651");
        assert_eq!(fmt_num(65.0, 4), "65");
        assert_eq!(fmt_num(12.57, 4), "12.57");
    }
}
