//! Element and attribute names whose namespace prefix no `xmlns` declares.
//!
//! MuJoCo reads XML without namespaces (tinyxml2): `<xacro:include>` left in a URDF by a
//! xacro run that never happened is, to it, an element named `xacro:include`, which its URDF
//! reader skips. roxmltree follows the Namespaces in XML recommendation and rejects the whole
//! file ("unknown namespace prefix"). So that modellint reads what MuJoCo reads, such a file is
//! parsed from a copy in which each undeclared `prefix:` of a tag or attribute name is written
//! `prefix_`: one byte for one byte, so every offset of the copy is the offset in the file and
//! every finding points at the file's own text. The renamed start tags are kept for
//! `undeclared-xml-prefix` (`crate::lint`).

use std::borrow::Cow;

/// At most this many distinct undeclared prefixes are renamed in one file: each costs a parse,
/// and a file with more is not an unexpanded template but not XML a robot model is written in.
pub const MAX_UNDECLARED_PREFIXES: usize = 8;

/// A start tag whose name carries an undeclared prefix: byte range of the name (after `<`).
#[derive(Debug, Clone, PartialEq)]
pub struct UndeclaredTag {
    pub start: usize,
    pub end: usize,
    /// The name as written in the file (`xacro:include`).
    pub name: String,
    pub prefix: String,
}

/// `None` when `text` parses as it is or fails for another reason than an undeclared prefix;
/// else the renamed copy (which parses, or fails for another reason) and the start tags renamed.
pub fn renamed_undeclared(text: &str) -> Option<(String, Vec<UndeclaredTag>)> {
    let mut copy: Option<Vec<u8>> = None;
    let mut tags = Vec::new();
    let mut seen: Vec<String> = Vec::new();
    loop {
        let current = match &copy {
            Some(b) => Cow::Owned(String::from_utf8(b.clone()).ok()?),
            None => Cow::Borrowed(text),
        };
        let unknown = match roxmltree::Document::parse_with_options(
            &current,
            roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() },
        ) {
            Err(roxmltree::Error::UnknownNamespace(p, _)) => Some(p.to_string()),
            _ => None,
        };
        let Some(prefix) = unknown else { break };
        if seen.contains(&prefix) || seen.len() >= MAX_UNDECLARED_PREFIXES {
            break;
        }
        let mut bytes = current.into_owned().into_bytes();
        tags.extend(rename(&mut bytes, &prefix, text));
        seen.push(prefix);
        copy = Some(bytes);
    }
    let bytes = copy?;
    tags.sort_by_key(|t| t.start);
    Some((String::from_utf8(bytes).ok()?, tags))
}

/// Writes `prefix_` for `prefix:` in every tag and attribute name of the markup (not in
/// comments, processing instructions, CDATA or quoted values); returns the start tags renamed.
fn rename(b: &mut [u8], prefix: &str, original: &str) -> Vec<UndeclaredTag> {
    let p = prefix.as_bytes();
    let mut tags = Vec::new();
    let mut i = 0;
    let is_name_end = |c: u8| c.is_ascii_whitespace() || c == b'/' || c == b'>' || c == b'=';
    let at_prefix = |b: &[u8], j: usize| {
        b.len() > j + p.len() && &b[j..j + p.len()] == p && b[j + p.len()] == b':'
    };
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let skip_to = |b: &[u8], from: usize, end: &[u8]| {
            b[from..]
                .windows(end.len())
                .position(|w| w == end)
                .map_or(b.len(), |k| from + k + end.len())
        };
        if b[i..].starts_with(b"<!--") {
            i = skip_to(b, i + 4, b"-->");
            continue;
        }
        if b[i..].starts_with(b"<![CDATA[") {
            i = skip_to(b, i + 9, b"]]>");
            continue;
        }
        if b[i..].starts_with(b"<?") {
            i = skip_to(b, i + 2, b"?>");
            continue;
        }
        if b[i..].starts_with(b"<!") {
            i = skip_to(b, i + 2, b">");
            continue;
        }
        // A start or end tag: its name, then attributes until the closing '>'.
        let closing = b.get(i + 1) == Some(&b'/');
        let name_at = i + 1 + usize::from(closing);
        if at_prefix(b, name_at) {
            let end = (name_at..b.len()).find(|&k| is_name_end(b[k])).unwrap_or(b.len());
            if !closing {
                tags.push(UndeclaredTag {
                    start: name_at,
                    end,
                    name: original.get(name_at..end).unwrap_or("").to_string(),
                    prefix: prefix.to_string(),
                });
            }
            b[name_at + p.len()] = b'_';
        }
        let mut k = name_at;
        let mut quote: Option<u8> = None;
        while k < b.len() {
            let c = b[k];
            match quote {
                Some(q) if c == q => quote = None,
                Some(_) => {}
                None if c == b'"' || c == b'\'' => quote = Some(c),
                None if c == b'>' => break,
                None if c.is_ascii_whitespace() && at_prefix(b, k + 1) => {
                    b[k + 1 + p.len()] = b'_';
                }
                None => {}
            }
            k += 1;
        }
        i = k + 1;
    }
    tags
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undeclared_prefixes_are_renamed_in_place_and_their_start_tags_kept() {
        let t = "<robot name=\"r\">\n  <xacro:include filename=\"a.xacro\"/>\n  <!-- <xacro:x/> -->\n  <xacro:cam a=\"xacro:v\" gz:b=\"1\">\n    <origin/>\n  </xacro:cam>\n  <link name=\"l\"/>\n</robot>\n";
        let (copy, tags) = renamed_undeclared(t).expect("renamed");
        assert_eq!(copy.len(), t.len());
        assert!(roxmltree::Document::parse(&copy).is_ok(), "{copy}");
        let names: Vec<&str> = tags.iter().map(|g| g.name.as_str()).collect();
        assert_eq!(names, ["xacro:include", "xacro:cam"]);
        assert_eq!(&t[tags[1].start..tags[1].end], "xacro:cam");
        // Comments and attribute values keep their text; a second prefix (`gz:`) is renamed too.
        assert!(copy.contains("<!-- <xacro:x/> -->") && copy.contains("a=\"xacro:v\""), "{copy}");
        assert!(copy.contains("gz_b=\"1\""), "{copy}");
    }

    #[test]
    fn declared_prefixes_and_other_errors_are_left_alone() {
        let declared = "<robot xmlns:xacro=\"http://www.ros.org/wiki/xacro\"><xacro:property name=\"a\" value=\"1\"/></robot>";
        assert_eq!(renamed_undeclared(declared), None);
        assert_eq!(renamed_undeclared("<robot><link></robot>"), None);
        // Renaming cannot mend other malformed XML: the copy is returned and still fails.
        let (copy, tags) = renamed_undeclared("<robot><xacro:a/><link></robot>").expect("renamed");
        assert!(roxmltree::Document::parse(&copy).is_err());
        assert_eq!(tags.len(), 1);
    }
}
