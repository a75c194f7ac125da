//! The README of the reproduction: hand-written text with generated
//! blocks. A block is the text between `<!-- generated:NAME -->` and
//! `<!-- /generated:NAME -->`; regenerating replaces the blocks' contents
//! and keeps everything else, so the discussion written around the tables
//! survives every run.

/// The opening marker of block `name`.
fn open(name: &str) -> String {
    format!("<!-- generated:{name} -->")
}

/// The closing marker of block `name`.
fn close(name: &str) -> String {
    format!("<!-- /generated:{name} -->")
}

/// Whether `text` holds every block of `names` (each once, opened before
/// closed).
pub fn has_blocks(text: &str, names: &[&str]) -> bool {
    names.iter().all(|n| {
        let (o, c) = (open(n), close(n));
        matches!((text.find(&o), text.find(&c)), (Some(a), Some(b)) if a < b)
            && text.matches(&o).count() == 1
            && text.matches(&c).count() == 1
    })
}

/// `text` with the content of every block `(name, content)` replaced;
/// blocks missing from `text` are left out (check with [`has_blocks`]).
pub fn fill(text: &str, blocks: &[(&str, &str)]) -> String {
    let mut out = text.to_string();
    for (name, content) in blocks {
        let (o, c) = (open(name), close(name));
        let (Some(a), Some(b)) = (out.find(&o), out.find(&c)) else {
            continue;
        };
        if a > b {
            continue;
        }
        let start = a + o.len();
        out = format!("{}\n{}\n{}", &out[..start], content.trim_end(), &out[b..]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_are_replaced_and_the_rest_is_kept() {
        let text = "# T\nhand text\n<!-- generated:a -->\nold\n<!-- /generated:a -->\nmore text\n";
        assert!(has_blocks(text, &["a"]));
        assert!(!has_blocks(text, &["a", "b"]));
        let filled = fill(text, &[("a", "new 1\nnew 2\n")]);
        assert_eq!(
            filled,
            "# T\nhand text\n<!-- generated:a -->\nnew 1\nnew 2\n<!-- /generated:a -->\nmore text\n"
        );
        // Idempotent.
        assert_eq!(fill(&filled, &[("a", "new 1\nnew 2\n")]), filled);
    }
}
