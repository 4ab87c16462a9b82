//! A setting that occlu chooses (`auto`) or the user gives: `--up`, `ac`'s
//! threshold, a GPU walk's depths. One type, so that each parses, prints
//! and serialises `auto` the same way.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AutoOr<T> {
    /// occlu chooses, from the scene or the viewport.
    #[default]
    Auto,
    Given(T),
}

/// `auto` (any case), or what `T` parses; `T`'s error says what it expects
/// besides `auto`.
impl<T: FromStr<Err = String>> FromStr for AutoOr<T> {
    type Err = String;

    fn from_str(text: &str) -> Result<AutoOr<T>, String> {
        if text.eq_ignore_ascii_case("auto") {
            Ok(AutoOr::Auto)
        } else {
            text.parse().map(AutoOr::Given)
        }
    }
}

impl<T: fmt::Display> fmt::Display for AutoOr<T> {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            AutoOr::Auto => f.write_str("auto"),
            AutoOr::Given(value) => value.fmt(f),
        }
    }
}

/// As text, as the command line takes it.
impl<T: fmt::Display> Serialize for AutoOr<T> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de, T: FromStr<Err = String>> Deserialize<'de> for AutoOr<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<AutoOr<T>, D::Error> {
        String::deserialize(d)?.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq)]
    struct Even(u32);

    impl FromStr for Even {
        type Err = String;
        fn from_str(s: &str) -> Result<Even, String> {
            match s.parse::<u32>() {
                Ok(n) if n % 2 == 0 => Ok(Even(n)),
                _ => Err("expected 'auto' or an even number".into()),
            }
        }
    }

    impl fmt::Display for Even {
        fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
            write!(f, "{}", self.0)
        }
    }

    #[test]
    fn auto_in_any_case_or_what_the_value_parses_round_trips_through_text_and_json() {
        assert_eq!("auto".parse(), Ok(AutoOr::<Even>::Auto));
        assert_eq!("AUTO".parse(), Ok(AutoOr::<Even>::Auto));
        assert_eq!("4".parse(), Ok(AutoOr::Given(Even(4))));
        assert_eq!(
            "3".parse::<AutoOr<Even>>(),
            Err("expected 'auto' or an even number".into())
        );
        assert_eq!(AutoOr::Given(Even(4)).to_string(), "4");
        assert_eq!(serde_json::to_string(&AutoOr::<Even>::Auto).unwrap(), "\"auto\"");
        let back: AutoOr<Even> = serde_json::from_str("\"8\"").unwrap();
        assert_eq!(back, AutoOr::Given(Even(8)));
        assert!(serde_json::from_str::<AutoOr<Even>>("\"7\"").is_err());
    }
}
