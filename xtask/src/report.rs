//! Splicing generated Markdown into hand-written documents.
//!
//! A generated section sits between `<!-- BEGIN generated:NAME -->` and
//! `<!-- END generated:NAME -->`. Everything outside the markers is left exactly as it was, so
//! `docs/VALIDATION.md` can mix prose with reports that each check rewrites on its own.

/// Replaces the body of section `name` in `doc` with `body`, or appends the section (after a
/// `## title` heading) when the document does not have it yet.
pub(crate) fn splice(doc: &str, name: &str, title: &str, body: &str) -> Result<String, String> {
    let begin = format!("<!-- BEGIN generated:{name} -->");
    let end = format!("<!-- END generated:{name} -->");
    let body = body.trim_end_matches('\n');
    match (doc.find(&begin), doc.find(&end)) {
        (Some(b), Some(e)) if b < e => {
            let mut out = String::with_capacity(doc.len() + body.len());
            out.push_str(&doc[..b + begin.len()]);
            out.push('\n');
            out.push_str(body);
            out.push('\n');
            out.push_str(&doc[e..]);
            Ok(out)
        }
        (None, None) => {
            let mut out = doc.trim_end_matches('\n').to_owned();
            out.push_str(&format!("\n\n## {title}\n\n{begin}\n{body}\n{end}\n"));
            Ok(out)
        }
        _ => Err(format!(
            "the markers of section `{name}` are unbalanced; fix them by hand ({begin} ... {end})"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::splice;

    #[test]
    fn appends_then_replaces_in_place() {
        let doc = "# Validation\n\nIntro.\n";
        let once = splice(doc, "queue", "Event queue", "first\n").unwrap();
        assert!(once.starts_with("# Validation\n\nIntro.\n\n## Event queue\n"));
        assert!(
            once.contains("<!-- BEGIN generated:queue -->\nfirst\n<!-- END generated:queue -->")
        );

        let with_tail = format!("{once}\nHand-written tail.\n");
        let twice = splice(&with_tail, "queue", "Event queue", "second").unwrap();
        assert!(twice.contains("generated:queue -->\nsecond\n<!-- END"));
        assert!(!twice.contains("first"));
        assert!(twice.ends_with("Hand-written tail.\n"));
        assert_eq!(twice.matches("## Event queue").count(), 1);
    }

    #[test]
    fn unbalanced_markers_are_an_error() {
        let doc = "<!-- END generated:x -->\n<!-- BEGIN generated:x -->\n";
        assert!(splice(doc, "x", "X", "body").is_err());
        assert!(splice("<!-- BEGIN generated:x -->", "x", "X", "body").is_err());
    }
}
