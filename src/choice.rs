//! Enums a user picks by name (on the command line, in a scene file, in the
//! TUI's configuration): each lists its values with the name written for
//! it and a line of help. The CLI offers them through its parser; the
//! layers below read them without knowing that parser exists.

/// A closed set of named values.
pub(crate) trait Choice: Copy + PartialEq + 'static {
    /// Every value, in the order they are offered.
    const ALL: &'static [Self];

    /// The name a user writes for it, and a line saying what it is.
    fn choice(self) -> (&'static str, &'static str);
}

/// The value named `s`, ignoring ASCII case and the spaces around it.
pub(crate) fn parse<T: Choice>(s: &str) -> Option<T> {
    let s = s.trim();
    T::ALL
        .iter()
        .copied()
        .find(|c| c.choice().0.eq_ignore_ascii_case(s))
}

/// Every value's name, in order.
pub(crate) fn names<T: Choice>() -> Vec<&'static str> {
    T::ALL.iter().map(|c| c.choice().0).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Pick {
        One,
        TwoWords,
    }

    impl Choice for Pick {
        const ALL: &'static [Self] = &[Pick::One, Pick::TwoWords];

        fn choice(self) -> (&'static str, &'static str) {
            match self {
                Pick::One => ("one", "the first"),
                Pick::TwoWords => ("two-words", "the second"),
            }
        }
    }

    #[test]
    fn names_parse_back_to_their_values() {
        assert_eq!(parse::<Pick>("two-words"), Some(Pick::TwoWords));
        assert_eq!(parse::<Pick>(" ONE "), Some(Pick::One));
        assert_eq!(parse::<Pick>("two"), None);
        assert_eq!(names::<Pick>(), ["one", "two-words"]);
    }
}
