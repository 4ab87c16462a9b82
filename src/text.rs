//! Text from users' files inside messages and result files.

/// `text` with control characters (newlines, tabs, escapes) written as
/// escape sequences: names and parser messages quote the input, and an
/// error must stay one line, a CSV row one row.
pub fn one_line(text: &str) -> String {
    if !text.chars().any(char::is_control) {
        return text.to_string();
    }
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped_and_the_rest_kept() {
        assert_eq!(one_line("plain 'é' ü"), "plain 'é' ü");
        assert_eq!(one_line("a\nb\r\tc\u{1b}[2J\0"), "a\\nb\\r\\tc\\u{1b}[2J\\u{0}");
        assert!(!one_line("x\u{85}y\u{7f}").chars().any(char::is_control));
    }
}
