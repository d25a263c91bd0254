//! A scene file's `[[instance]]` tables read one at a time: a field of 10^6 instances is a
//! 97 MB file, which the TOML parser, holding every token, event and value of a document at
//! once, read in 4.2 GB. The text is cut at its top-level table headers by the TOML lexer
//! (which streams); each `[[instance]]` table is parsed alone into an [`InstanceDesc`] and
//! its keys' lines recorded, and the rest of the file, the instance tables left as their
//! newlines (so every line keeps its number), is parsed as a whole as before.

use super::schema::InstanceDesc;
use super::text::KeyLines;
use toml_parser::Source;
use toml_parser::lexer::TokenKind;

/// A scene's text with its `[[instance]]` tables cut out.
pub(super) struct Cut<'a> {
    /// The text without the instance tables (each replaced by its newlines).
    pub rest: String,
    /// Each instance table's body (from the end of its header line) and its header's
    /// 1-based line.
    pub tables: Vec<(&'a str, usize)>,
}

/// Cut `text` at its top-level `[[instance]]` headers (`None`: it has none, and is parsed
/// whole). A header is a `[` first on its line outside any array or inline table.
pub(super) fn cut(text: &str) -> Option<Cut<'_>> {
    // (start of the header line's `[`, end of the header line, whether it is [[instance]])
    let mut headers: Vec<(usize, usize, bool)> = Vec::new();
    let (mut depth, mut line_start) = (0usize, true);
    let mut header: Option<(usize, String)> = None;
    let mut close = |header: &mut Option<(usize, String)>, end: usize| {
        if let Some((start, name)) = header.take() {
            headers.push((start, end, name == "[[instance]]"));
        }
    };
    for token in Source::new(text).lex() {
        let span = token.span();
        match token.kind() {
            TokenKind::Newline => {
                close(&mut header, span.start());
                line_start = true;
                continue;
            }
            TokenKind::Whitespace | TokenKind::Comment => continue,
            _ => {}
        }
        let piece = &text[span.start()..span.end()];
        if let Some((_, name)) = &mut header {
            name.push_str(piece);
            continue;
        }
        match token.kind() {
            TokenKind::LeftSquareBracket if depth == 0 && line_start => {
                header = Some((span.start(), piece.to_string()));
            }
            TokenKind::LeftSquareBracket | TokenKind::LeftCurlyBracket => depth += 1,
            TokenKind::RightSquareBracket | TokenKind::RightCurlyBracket => {
                depth = depth.saturating_sub(1)
            }
            _ => {}
        }
        line_start = false;
    }
    close(&mut header, text.len());
    if !headers.iter().any(|h| h.2) {
        return None;
    }
    let mut rest = String::with_capacity(text.len() / 4);
    let mut tables = Vec::new();
    let (mut copied, mut line, mut counted) = (0, 1, 0);
    for (k, &(start, end, instance)) in headers.iter().enumerate() {
        if !instance {
            continue;
        }
        let next = headers.get(k + 1).map_or(text.len(), |h| h.0);
        line += text[counted..start].matches('\n').count();
        counted = start;
        rest.push_str(&text[copied..start]);
        rest.extend(text[start..next].matches('\n'));
        copied = next;
        tables.push((&text[end..next], line));
    }
    rest.push_str(&text[copied..]);
    Some(Cut { rest, tables })
}

/// Instance table `i` (`body`, its header on line `line`): its description and its keys'
/// lines added to `lines`; an error is (line, column, message) in the file.
pub(super) fn instance(
    i: usize,
    body: &str,
    line: usize,
    lines: &mut KeyLines,
) -> std::result::Result<InstanceDesc, (usize, usize, String)> {
    // body line 1 is the rest of the header's line
    let shift = |(l, c): (usize, usize)| if l == 0 { (line, 0) } else { (line + l - 1, c) };
    let desc = toml::from_str::<InstanceDesc>(body).map_err(|e| {
        let at = e
            .span()
            .map_or((0, 0), |s| super::text::line_col(body.as_bytes(), s.start));
        let msg = e.message().lines().next().unwrap_or("invalid TOML").trim();
        let (l, c) = shift(at);
        (l, c, msg.to_string())
    })?;
    lines.extend_table(&format!("instance[{i}]"), body, line - 1);
    Ok(desc)
}
