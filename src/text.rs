//! Text from users' files inside messages and result files.

/// `text` with control characters (newlines, tabs, escapes) and characters
/// that reorder, hide or break text written as escape sequences, and each
/// backslash doubled, so that an escape sequence in the result always
/// stands for the character it names (a name that holds the six
/// characters `\u{1b}` shows as `\\u{1b}`): names and parser messages
/// quote the input, an error must stay one line, a CSV row one row, and a
/// name must read as what it is. Apply it once, where text is shown (a
/// second pass doubles the backslashes of the first).
pub fn one_line(text: &str) -> String {
    if !text.chars().any(|c| c == '\\' || is_hidden(c)) {
        return text.to_string();
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            c if is_hidden(c) => out.extend(c.escape_default()),
            c => out.push(c),
        }
    }
    out
}

/// Characters a message line keeps at most ([`shortened`]).
pub const MESSAGE_CHARACTERS: usize = 2000;

/// `line` with its middle left out where it holds more than `most`
/// characters, saying how many: a name or a parser's quote from a hostile
/// file (a mesh named with a megabyte) must not make a message that
/// floods a terminal or a CI log. Its start and end stay, which say what
/// failed and why.
pub fn shortened(line: &str, most: usize) -> std::borrow::Cow<'_, str> {
    let count = line.chars().count();
    if count <= most {
        return line.into();
    }
    let kept = most / 2;
    let head: String = line.chars().take(kept).collect();
    let tail: String = line.chars().skip(count - kept).collect();
    format!("{head} … ({} characters left out) … {tail}", count - 2 * kept).into()
}

/// Whether `c` acts on text instead of showing: a control character; a
/// line or paragraph separator (U+2028, U+2029: a line break to many
/// terminals and editors); or a default-ignorable code point, which
/// Unicode says to render invisibly (DerivedCoreProperties.txt, Unicode
/// 16): bidirectional controls that reorder what follows ("Trojan Source":
/// U+202E makes `gpj.exe` read `exe.jpg`), zero-width characters, the
/// combining grapheme joiner, fillers, variation selectors, the byte order
/// mark, tag characters that spell invisible text; and the interlinear
/// annotation marks, which hide what they enclose.
fn is_hidden(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{2028}'
                | '\u{2029}'
                // Default_Ignorable_Code_Point.
                | '\u{00AD}'
                | '\u{034F}'
                | '\u{061C}'
                | '\u{115F}'..='\u{1160}'
                | '\u{17B4}'..='\u{17B5}'
                | '\u{180B}'..='\u{180F}'
                | '\u{200B}'..='\u{200F}'
                | '\u{202A}'..='\u{202E}'
                | '\u{2060}'..='\u{206F}'
                | '\u{3164}'
                | '\u{FE00}'..='\u{FE0F}'
                | '\u{FEFF}'
                | '\u{FFA0}'
                | '\u{FFF0}'..='\u{FFF8}'
                | '\u{1BCA0}'..='\u{1BCA3}'
                | '\u{1D173}'..='\u{1D17A}'
                | '\u{E0000}'..='\u{E0FFF}'
                // Interlinear annotations.
                | '\u{FFF9}'..='\u{FFFB}'
        )
}

/// `text` as part of a file name that means the same on every system: ASCII
/// letters, digits, `.` and `_` kept, every other run of characters one
/// `-`, no `-` at either end, at most [`SLUG_LENGTH`] characters, and
/// never empty (`x`), so it cannot name a parent or hidden folder.
pub fn slug(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        if c.is_ascii_alphanumeric() || c == '_' || (c == '.' && !out.is_empty()) {
            out.push(c);
        } else if !out.is_empty() && !out.ends_with('-') {
            out.push('-');
        }
    }
    out.truncate(SLUG_LENGTH);
    let out = out.trim_end_matches(['-', '.']);
    if out.is_empty() { "x".into() } else { out.into() }
}

/// `n` and `noun`, plural unless `n` is 1: "1 run", "2 runs".
pub fn count(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// `x` as a message shows it: as Rust writes it, but in scientific
/// notation beyond everyday magnitudes, so `1e308` does not print 309
/// digits.
pub fn number(x: f64) -> String {
    let magnitude = x.abs();
    if magnitude != 0.0 && magnitude.is_finite() && !(1e-4..1e16).contains(&magnitude) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// `v`'s components as [`number`] writes them: `[0, 1, 0]`.
pub fn vector(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", number(v[0]), number(v[1]), number(v[2]))
}

/// The longest [`slug`].
pub const SLUG_LENGTH: usize = 40;

/// `text` as literal Markdown inline text: on one line, with every
/// character that could start a construct (emphasis, code, links, HTML,
/// table cells, entities, strikethrough) escaped by a backslash. A name
/// from a model file then reads as itself in report.md, whatever it holds.
pub fn markdown(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in one_line(text).chars() {
        if matches!(
            c,
            '\\' | '`' | '*' | '_' | '[' | ']' | '<' | '>' | '|' | '&' | '~' | '!'
        ) {
            out.push('\\');
        }
        out.push(c);
    }
    out
}

/// `text` as a CSV cell a spreadsheet shows rather than runs: a cell that
/// starts as a formula would (`=`, `+`, `-`, `@`, a tab or a carriage
/// return, as OWASP lists them) gets a leading `'`, which spreadsheets read
/// as "text follows".
pub fn spreadsheet_safe(text: &str) -> String {
    if text.starts_with(['=', '+', '-', '@', '\t', '\r']) {
        format!("'{text}")
    } else {
        text.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_as_themselves_in_markdown_and_spreadsheets() {
        assert_eq!(
            markdown("wall_2 [a](b) <img> | x\ny"),
            "wall\\_2 \\[a\\](b) \\<img\\> \\| x\\\\ny",
            "a newline shows as \\n, its backslash escaped"
        );
        assert_eq!(markdown("plain name.obj"), "plain name.obj");
        assert_eq!(spreadsheet_safe("=cmd|' /C calc'!A0"), "'=cmd|' /C calc'!A0");
        assert_eq!(spreadsheet_safe("-2+3"), "'-2+3");
        assert_eq!(spreadsheet_safe("door 2"), "door 2");
    }

    #[test]
    fn control_characters_are_escaped_and_the_rest_kept() {
        assert_eq!(one_line("plain 'é' ü"), "plain 'é' ü");
        assert_eq!(one_line("a\nb\r\tc\u{1b}[2J\0"), "a\\nb\\r\\tc\\u{1b}[2J\\u{0}");
        assert!(!one_line("x\u{85}y\u{7f}").chars().any(char::is_control));
    }

    #[test]
    fn an_escape_in_the_result_always_stands_for_the_character_it_names() {
        // The six characters of an escape, and the escape character itself:
        // shown alike, one would pass for the other.
        assert_eq!(one_line("a\\u{1b}b"), "a\\\\u{1b}b");
        assert_eq!(one_line("a\u{1b}b"), "a\\u{1b}b");
        assert_eq!(one_line("C:\\models"), "C:\\\\models");
        assert_eq!(markdown("a\\n"), "a\\\\\\\\n");
    }

    #[test]
    fn line_separators_and_every_default_ignorable_character_are_escaped() {
        for (c, escaped) in [
            ('\u{2028}', "\\u{2028}"),
            ('\u{2029}', "\\u{2029}"),
            ('\u{034F}', "\\u{34f}"),
            ('\u{115F}', "\\u{115f}"),
            ('\u{3164}', "\\u{3164}"),
            ('\u{FE0F}', "\\u{fe0f}"),
            ('\u{E0100}', "\\u{e0100}"),
        ] {
            assert_eq!(one_line(&format!("a{c}b")), format!("a{escaped}b"), "{c:?}");
        }
    }

    #[test]
    fn characters_that_reorder_or_hide_text_are_escaped_too() {
        // Trojan Source's bidirectional overrides and isolates, and
        // invisible characters: shown raw, they make a name read as another.
        assert_eq!(one_line("wall\u{202E}gpj.exe"), "wall\\u{202e}gpj.exe");
        assert_eq!(
            one_line("a\u{2066}b\u{200B}c\u{FEFF}d\u{200F}"),
            "a\\u{2066}b\\u{200b}c\\u{feff}d\\u{200f}"
        );
        assert_eq!(markdown("x\u{202E}y"), "x\\\\u{202e}y");
        assert_eq!(one_line("naïve ünïcode 日本"), "naïve ünïcode 日本");
    }

    #[test]
    fn slugs_are_safe_file_name_parts() {
        assert_eq!(slug("city:blocks=1,seed=2"), "city-blocks-1-seed-2");
        assert_eq!(slug("../walk.json"), "walk.json");
        assert_eq!(
            slug("NVIDIA GeForce RTX 4090 (Vulkan)"),
            "NVIDIA-GeForce-RTX-4090-Vulkan"
        );
        assert_eq!(slug("..."), "x");
        assert_eq!(slug("ünïcode"), "n-code");
        assert_eq!(slug(&"a".repeat(100)).len(), SLUG_LENGTH);
    }

    #[test]
    fn a_long_line_keeps_its_start_and_end_and_says_how_much_it_left_out() {
        assert_eq!(shortened("short", 5), "short");
        assert_eq!(shortened("abcdefghij", 4), "ab … (6 characters left out) … ij");
        let name = "é".repeat(10_000);
        let line = format!("mesh '{name}' is broken");
        let said = shortened(&line, MESSAGE_CHARACTERS);
        assert!(
            said.starts_with("mesh 'éé") && said.ends_with("éé' is broken"),
            "{said}"
        );
        assert!(
            said.chars().count() < MESSAGE_CHARACTERS + 50,
            "{}",
            said.chars().count()
        );
        assert!(said.contains(&format!(
            "({} characters left out)",
            line.chars().count() - MESSAGE_CHARACTERS
        )));
    }
}
