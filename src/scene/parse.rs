//! One-line messages for TOML syntax errors, unknown keys and missing fields.
//!
//! `toml`'s own `Display` shows a multi-line excerpt of the file; here the error
//! becomes `NAME line L: MESSAGE (at `KEY = …`)`, the line being that of the
//! start of the error's span; a missing field reads
//! `NAME line L: missing field `x` (in `[table]`)`, or `NAME: missing field `x``
//! at the top level.

/// At most this many characters of the offending line are quoted.
const QUOTE_MAX: usize = 60;

/// The error `e` from parsing `text` as one line prefixed with `name`.
pub(crate) fn one_line(name: &str, text: &str, e: &toml::de::Error) -> String {
    let message = e.message().split_whitespace().collect::<Vec<_>>().join(" ");
    let Some(span) = e.span() else {
        return format!("{name}: {message}");
    };
    let bytes = text.as_bytes();
    let start = span.start.min(bytes.len());
    let missing = message.starts_with("missing field");
    if missing && start == 0 && (span.end == 0 || span.end >= text.trim_end().len()) {
        // A key missing from the top level: the span is empty or the whole file.
        return format!("{name}: {message}");
    }
    let line = bytes[..start].iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = bytes[..start].iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
    let line_end = bytes[start..].iter().position(|&b| b == b'\n').map_or(bytes.len(), |p| start + p);
    let quoted: String = String::from_utf8_lossy(&bytes[line_start..line_end])
        .trim()
        .chars()
        .map(|c| if c.is_control() { '\u{fffd}' } else { c })
        .collect();
    let mut out = format!("{name} line {line}: {message}");
    if !quoted.is_empty() {
        let short: String = quoted.chars().take(QUOTE_MAX).collect();
        let ellipsis = if short.len() < quoted.len() { "…" } else { "" };
        let place = if missing { "in" } else { "at" };
        out.push_str(&format!(" ({place} `{short}{ellipsis}`)"));
    }
    out
}
