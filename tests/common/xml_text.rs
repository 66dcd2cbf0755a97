//! A fixture's written text read as text: start tags and their attributes as written, so that a
//! test's expectation comes from the file and not from the parser the rule itself uses.

/// The value of `attr="…"` inside `tag` (a start tag's text), if written.
pub fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    Some(&tag[i..i + tag[i..].find('"')?])
}

/// Every `<tag …>` start tag of `text`, as written.
pub fn tags<'a>(text: &'a str, tag: &str) -> Vec<&'a str> {
    let open = format!("<{tag} ");
    text.match_indices(&open).map(|(i, _)| &text[i..i + text[i..].find('>').unwrap()]).collect()
}

/// Each body of an MJCF text with its own geoms' start tags (up to its first child body).
pub fn bodies_with_geoms(text: &str) -> Vec<(String, Vec<&str>)> {
    let mut out = Vec::new();
    for (i, _) in text.match_indices("<body name=\"") {
        let name = attr(&text[i..], "name").unwrap().to_string();
        let rest = &text[i + 1..];
        let end = [rest.find("<body "), rest.find("</body>")].into_iter().flatten().min().unwrap();
        out.push((name, tags(&rest[..end], "geom")));
    }
    out
}
