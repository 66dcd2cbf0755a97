//! Names the template gives: a motor family's from its classes, a joint's body region from its
//! name.

/// The leading words that every class name shares (`size3`, `size3_limited` → `size3`).
pub(super) fn class_stem(classes: &[String]) -> String {
    let split = |c: &str| -> Vec<String> {
        c.split(|ch: char| !ch.is_ascii_alphanumeric())
            .filter(|w| !w.is_empty())
            .map(|w| w.to_ascii_lowercase())
            .collect()
    };
    let lists: Vec<Vec<String>> = classes.iter().map(|c| split(c)).collect();
    let Some(first) = lists.first() else { return String::new() };
    let n =
        (0..first.len()).take_while(|&k| lists.iter().all(|l| l.get(k) == Some(&first[k]))).count();
    first[..n].join("_")
}

/// Words of joint names that name no motor: every joint is a joint.
pub(super) const GENERIC_WORDS: [&str; 3] = ["joint", "jnt", "link"];

/// The region a joint name suggests (the classifier `gap` uses too).
pub(super) fn region(name: &str) -> Option<&'static str> {
    crate::model::region::from_name(name)
}
