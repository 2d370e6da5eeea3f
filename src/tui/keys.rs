//! The one key table. Key handling, the `?` help overlay, the key-hint bar,
//! the Features panel's keys and the README's table are all generated from
//! [`ROWS`], so they cannot disagree.

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyEventKind, KeyModifiers};

use crate::render::{Feature, Worst};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Key {
    Char(char),
    Ctrl(char),
    Up,
    Down,
    Left,
    Right,
    PageUp,
    PageDown,
    Enter,
    Tab,
    Esc,
}

impl Key {
    /// The table's key for a terminal key press; `None` for releases and
    /// keys the table does not use.
    pub(crate) fn from_event(e: &KeyEvent) -> Option<Key> {
        if e.kind == KeyEventKind::Release {
            return None;
        }
        Some(match e.code {
            KeyCode::Char(c) if e.modifiers.contains(KeyModifiers::CONTROL) => {
                Key::Ctrl(c.to_ascii_lowercase())
            }
            KeyCode::Char(c) => Key::Char(c),
            KeyCode::Up => Key::Up,
            KeyCode::Down => Key::Down,
            KeyCode::Left => Key::Left,
            KeyCode::Right => Key::Right,
            KeyCode::PageUp => Key::PageUp,
            KeyCode::PageDown => Key::PageDown,
            KeyCode::Enter => Key::Enter,
            KeyCode::Tab => Key::Tab,
            KeyCode::Esc => Key::Esc,
            _ => return None,
        })
    }

    pub(crate) fn label(self) -> String {
        match self {
            Key::Char(' ') => "Space".into(),
            Key::Char(c) => c.to_string(),
            Key::Ctrl(c) => format!("Ctrl-{}", c.to_ascii_uppercase()),
            Key::Up => "↑".into(),
            Key::Down => "↓".into(),
            Key::Left => "←".into(),
            Key::Right => "→".into(),
            Key::PageUp => "PgUp".into(),
            Key::PageDown => "PgDn".into(),
            Key::Enter => "Enter".into(),
            Key::Tab => "Tab".into(),
            Key::Esc => "Esc".into(),
        }
    }
}

/// Where a binding applies: arrows orbit the camera in view mode and move
/// the pixel cursor in select mode; while a popup is open only its own keys
/// work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Mode {
    /// View and select mode.
    Any,
    View,
    Select,
    Popup,
}

impl Mode {
    fn overlaps(self, o: Mode) -> bool {
        let any = |m: Mode| m == Mode::Any && o != Mode::Popup && self != Mode::Popup;
        self == o || any(self) || any(o)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Action {
    /// Yaw and pitch steps about the target.
    Orbit(i8, i8),
    /// Steps right, up and forward.
    Move(i8, i8, i8),
    /// Field of view steps (negative zooms in).
    Fov(i8),
    ResetView,
    Toggle(Feature),
    /// Change the maximum depth by steps.
    Depth(i8),
    SwitchBuilder,
    SelectMode,
    /// Leave select mode.
    Back,
    /// Pixel cursor steps right and down.
    Cursor(i8, i8),
    /// Open or close the fold at the debug cursor.
    Fold,
    /// Move the debug cursor by lines.
    Line(i8),
    /// Move the debug cursor by pages.
    Page(i8),
    Worst(Worst),
    /// Cycle the selected pixel's overlay.
    PixelOverlay,
    Overlay,
    /// Step the BVH overlay level.
    Level(i8),
    SavePng,
    /// The viewport alone on the screen, or back.
    FullScreen,
    /// The ray-tree pane: normal, tall, hidden.
    TreePane,
    /// The overlays' whole legend in a popup.
    Legend,
    Stability,
    Help,
    /// List what loading the scene warned about.
    Warnings,
    /// Scroll the popup by lines, or by pages.
    ScrollPopup(i8),
    PagePopup(i8),
    ClosePopup,
    /// Give the terminal back and stop, as Ctrl-Z does outside raw mode.
    Suspend,
    Quit,
}

/// One line of the help: keys with their actions, and what they do.
pub(crate) struct KeyRow {
    pub(crate) mode: Mode,
    pub(crate) keys: &'static [(Key, Action)],
    pub(crate) help: &'static str,
    /// Short label for the key-hint bar, for the bindings worth showing there.
    pub(crate) hint: Option<&'static str>,
}

use Action as A;
use Key as K;

pub(crate) const ROWS: &[KeyRow] = &[
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('?'), A::Help)],
        help: "this help",
        hint: Some("help"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('q'), A::Quit), (K::Ctrl('c'), A::Quit)],
        help: "quit",
        hint: Some("quit"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Ctrl('z'), A::Suspend)],
        help: "suspend to the shell (fg resumes)",
        hint: None,
    },
    KeyRow {
        mode: Mode::View,
        keys: &[
            (K::Left, A::Orbit(-1, 0)),
            (K::Right, A::Orbit(1, 0)),
            (K::Up, A::Orbit(0, 1)),
            (K::Down, A::Orbit(0, -1)),
        ],
        help: "orbit the camera around its target",
        hint: Some("orbit"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[
            (K::Char('w'), A::Move(0, 0, 1)),
            (K::Char('s'), A::Move(0, 0, -1)),
            (K::Char('a'), A::Move(-1, 0, 0)),
            (K::Char('d'), A::Move(1, 0, 0)),
        ],
        help: "move forward, back, left, right",
        hint: Some("move"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[
            (K::Char('e'), A::Move(0, 1, 0)),
            (K::Char('c'), A::Move(0, -1, 0)),
        ],
        help: "move up, down",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[
            (K::Char('+'), A::Fov(-1)),
            (K::Char('='), A::Fov(-1)),
            (K::Char('-'), A::Fov(1)),
        ],
        help: "zoom in, in, out (field of view, or an orthographic view's height)",
        hint: Some("zoom"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('r'), A::ResetView)],
        help: "reset the view",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[
            (K::Char('1'), A::Toggle(Feature::Shadows)),
            (K::Char('2'), A::Toggle(Feature::Reflections)),
            (K::Char('3'), A::Toggle(Feature::SmoothNormals)),
            (K::Char('4'), A::Toggle(Feature::Textures)),
            (K::Char('5'), A::Toggle(Feature::Bilinear)),
            (K::Char('6'), A::Toggle(Feature::SoftShadows)),
            (K::Char('7'), A::Toggle(Feature::Supersampling)),
            (K::Char('8'), A::Toggle(Feature::Glossy)),
            (K::Char('9'), A::Toggle(Feature::Environment)),
            (K::Char('0'), A::Toggle(Feature::Bloom)),
            (K::Char('t'), A::Toggle(Feature::Bvh)),
            (K::Char('N'), A::Toggle(Feature::NormalMaps)),
            (K::Char('E'), A::Toggle(Feature::Emission)),
            (K::Char('i'), A::Toggle(Feature::Indirect)),
            (K::Char('A'), A::Toggle(Feature::Alpha)),
            (K::Char('R'), A::Toggle(Feature::Regularize)),
        ],
        help: "toggle a feature (each key is listed in the Features panel)",
        hint: Some("features"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('<'), A::Depth(-1)), (K::Char('>'), A::Depth(1))],
        help: "fewer, more bounces (the maximum depth of paths and ray trees)",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('b'), A::SwitchBuilder)],
        help: "switch the BVH builder (sah, median) and rebuild",
        hint: Some("builder"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('v'), A::SelectMode), (K::Tab, A::SelectMode)],
        help: "select mode on/off: pick the pixel to inspect (or click it)",
        hint: Some("select"),
    },
    KeyRow {
        mode: Mode::Select,
        keys: &[
            (K::Char('h'), A::Cursor(-1, 0)),
            (K::Char('j'), A::Cursor(0, 1)),
            (K::Char('k'), A::Cursor(0, -1)),
            (K::Char('l'), A::Cursor(1, 0)),
            (K::Left, A::Cursor(-1, 0)),
            (K::Down, A::Cursor(0, 1)),
            (K::Up, A::Cursor(0, -1)),
            (K::Right, A::Cursor(1, 0)),
        ],
        help: "move the pixel cursor (select mode)",
        hint: Some("cursor"),
    },
    KeyRow {
        mode: Mode::Select,
        keys: &[
            (K::Char('H'), A::Cursor(-8, 0)),
            (K::Char('J'), A::Cursor(0, 8)),
            (K::Char('K'), A::Cursor(0, -8)),
            (K::Char('L'), A::Cursor(8, 0)),
        ],
        help: "move the pixel cursor 8 pixels (select mode)",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Esc, A::Back)],
        help: "leave select mode",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Enter, A::Fold), (K::Char(' '), A::Fold)],
        help: "fold or unfold the list at the debug cursor",
        hint: Some("fold"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char(']'), A::Line(1)), (K::Char('['), A::Line(-1))],
        help: "move the debug cursor down, up",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::PageDown, A::Page(1)), (K::PageUp, A::Page(-1))],
        help: "scroll the debug pane a page down, up",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[
            (K::Char('n'), A::Worst(Worst::Nan)),
            (K::Char('V'), A::Worst(Worst::Variance)),
            (K::Char('B'), A::Worst(Worst::Brightest)),
        ],
        help: "jump to the worst pixel: NaN/Inf sample, highest variance, brightest",
        hint: Some("worst"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('o'), A::PixelOverlay)],
        help: "pixel overlay: rays, rays in colour, lights, traversal, normals, texture, environment, glossy, samples, off",
        hint: Some("overlay"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('g'), A::Overlay)],
        help: "view overlay: off, BVH level k, leaves, heat map (nodes, tests), bloom, spp, error per pixel",
        hint: Some("view overlay"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('.'), A::Level(1)), (K::Char(','), A::Level(-1))],
        help: "BVH overlay level k up, down",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('O'), A::Legend)],
        help: "the overlays' whole legend (beneath the view, it may be shortened)",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('f'), A::FullScreen)],
        help: "full screen: the view alone (f again brings the panels back)",
        hint: Some("full screen"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('T'), A::TreePane)],
        help: "ray-tree pane: taller, hidden, back to its size",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('p'), A::SavePng)],
        help: "save a PNG of this view (rendered in the background)",
        hint: Some("png"),
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('W'), A::Warnings)],
        help: "the last message in full and the scene's load warnings",
        hint: None,
    },
    KeyRow {
        mode: Mode::Any,
        keys: &[(K::Char('x'), A::Stability)],
        help: "run the numerical stability battery on this scene",
        hint: Some("stability"),
    },
    KeyRow {
        mode: Mode::Popup,
        keys: &[
            (K::Up, A::ScrollPopup(-1)),
            (K::Down, A::ScrollPopup(1)),
            (K::Char('k'), A::ScrollPopup(-1)),
            (K::Char('j'), A::ScrollPopup(1)),
        ],
        help: "scroll a popup (help, stability table) up, down",
        hint: Some("scroll"),
    },
    KeyRow {
        mode: Mode::Popup,
        keys: &[
            (K::PageUp, A::PagePopup(-1)),
            (K::PageDown, A::PagePopup(1)),
        ],
        help: "scroll a popup a page up, down",
        hint: None,
    },
    KeyRow {
        mode: Mode::Popup,
        keys: &[
            (K::Esc, A::ClosePopup),
            (K::Char('q'), A::ClosePopup),
            (K::Char('?'), A::ClosePopup),
        ],
        help: "close the popup",
        hint: Some("close"),
    },
    KeyRow {
        mode: Mode::Popup,
        keys: &[(K::Ctrl('c'), A::Quit)],
        help: "quit",
        hint: None,
    },
    KeyRow {
        mode: Mode::Popup,
        keys: &[(K::Ctrl('z'), A::Suspend)],
        help: "suspend to the shell (fg resumes)",
        hint: None,
    },
];

/// What `key` does in `mode`.
pub(crate) fn action(key: Key, mode: Mode) -> Option<Action> {
    ROWS.iter()
        .filter(|r| r.mode.overlaps(mode))
        .flat_map(|r| r.keys)
        .find(|(k, _)| *k == key)
        .map(|(_, a)| *a)
}

/// The first key bound to `action`.
pub(crate) fn key_for(action: Action) -> Option<Key> {
    ROWS.iter()
        .flat_map(|r| r.keys)
        .find(|(_, a)| *a == action)
        .map(|(k, _)| *k)
}

/// A row's keys as one label, e.g. `w s a d`.
pub(crate) fn keys_label(r: &KeyRow) -> String {
    r.keys
        .iter()
        .map(|(k, _)| k.label())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Key-hint bar entries for `mode`: short keys label and hint.
pub(crate) fn hints(mode: Mode) -> Vec<(String, &'static str)> {
    ROWS.iter()
        .filter(|r| r.mode.overlaps(mode))
        .filter_map(|r| {
            let hint = r.hint?;
            // Single characters run together (`wsad`), longer names take a
            // slash (`v/Tab`); long lists show their first four keys.
            let labels: Vec<String> = r.keys.iter().take(4).map(|(k, _)| k.label()).collect();
            let sep = if labels.iter().all(|l| l.chars().count() == 1) {
                ""
            } else {
                "/"
            };
            let more = if r.keys.len() > 4 { "…" } else { "" };
            let label = labels.join(sep) + more;
            Some((label, hint))
        })
        .collect()
}

/// The key table as Markdown, as in the README.
#[cfg(test)]
pub(crate) fn markdown_table() -> String {
    let mut s = String::from("| keys | mode | action |\n|---|---|---|\n");
    for r in ROWS {
        let keys = r
            .keys
            .iter()
            .map(|(k, _)| format!("`{}`", k.label()))
            .collect::<Vec<_>>()
            .join(" ");
        let mode = match r.mode {
            Mode::Any => "any",
            Mode::View => "view",
            Mode::Select => "select",
            Mode::Popup => "popup",
        };
        s += &format!("| {keys} | {mode} | {} |\n", r.help);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_maps_to_its_action() {
        for r in ROWS {
            for &(k, a) in r.keys {
                let modes: &[Mode] = match r.mode {
                    Mode::Any => &[Mode::View, Mode::Select],
                    Mode::View => &[Mode::View],
                    Mode::Select => &[Mode::Select],
                    Mode::Popup => &[Mode::Popup],
                };
                for &m in modes {
                    assert_eq!(action(k, m), Some(a), "{k:?} in {m:?}");
                }
            }
        }
    }

    #[test]
    fn no_key_is_bound_twice() {
        let all: Vec<(Key, Mode)> = ROWS
            .iter()
            .flat_map(|r| r.keys.iter().map(|(k, _)| (*k, r.mode)))
            .collect();
        for (i, (k, m)) in all.iter().enumerate() {
            for (k2, m2) in &all[i + 1..] {
                assert!(
                    !(k == k2 && m.overlaps(*m2)),
                    "{k:?} bound twice ({m:?}, {m2:?})"
                );
            }
        }
    }

    #[test]
    fn every_feature_has_a_key() {
        for f in Feature::ALL {
            assert!(key_for(Action::Toggle(f)).is_some(), "{}", f.name());
        }
    }

    #[test]
    fn popups_take_their_own_keys() {
        assert_eq!(
            action(Key::Char('q'), Mode::Popup),
            Some(Action::ClosePopup)
        );
        assert_eq!(action(Key::Ctrl('c'), Mode::Popup), Some(Action::Quit));
        assert_eq!(action(Key::Ctrl('z'), Mode::Popup), Some(Action::Suspend));
        assert_eq!(action(Key::Char('w'), Mode::Popup), None);
        assert_eq!(action(Key::Char('q'), Mode::View), Some(Action::Quit));
    }

    #[test]
    fn arrows_depend_on_mode() {
        assert_eq!(action(Key::Left, Mode::View), Some(Action::Orbit(-1, 0)));
        assert_eq!(action(Key::Left, Mode::Select), Some(Action::Cursor(-1, 0)));
        assert_eq!(action(Key::Char('h'), Mode::View), None);
    }

    #[test]
    fn terminal_keys_translate() {
        let ev = |code, modifiers| KeyEvent::new(code, modifiers);
        assert_eq!(
            Key::from_event(&ev(KeyCode::Char('c'), KeyModifiers::CONTROL)),
            Some(Key::Ctrl('c'))
        );
        assert_eq!(
            Key::from_event(&ev(KeyCode::Char('V'), KeyModifiers::SHIFT)),
            Some(Key::Char('V'))
        );
        let mut release = ev(KeyCode::Char('q'), KeyModifiers::NONE);
        release.kind = KeyEventKind::Release;
        assert_eq!(Key::from_event(&release), None);
    }

    #[test]
    fn readme_key_table_matches() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/README.md");
        let readme = std::fs::read_to_string(path).expect("README.md exists");
        assert!(
            readme.contains(&markdown_table()),
            "the key table in {path} is out of date; it should read:\n{}",
            markdown_table()
        );
    }
}
