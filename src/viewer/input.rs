//! The keys the viewer knows, by the names scripts use, and what each
//! does. Window events and script lines both become [`Key`]s, so a
//! script drives exactly the code a person at the keyboard does.

/// A key: a letter or digit (upper case), or one of the named keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Key {
    Char(char),
    Named(NamedKey),
}

/// The named keys a script may press (winit's names).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NamedKey {
    ArrowUp,
    ArrowDown,
    ArrowLeft,
    ArrowRight,
    Space,
    Shift,
    Control,
    Home,
    End,
    PageUp,
    PageDown,
    Escape,
    Enter,
    Tab,
    F1,
    F2,
    F3,
    F4,
    F5,
    F6,
    F7,
    F8,
    F9,
    F10,
    F11,
    F12,
}

const NAMED: &[(&str, NamedKey)] = &[
    ("ArrowUp", NamedKey::ArrowUp),
    ("ArrowDown", NamedKey::ArrowDown),
    ("ArrowLeft", NamedKey::ArrowLeft),
    ("ArrowRight", NamedKey::ArrowRight),
    ("Space", NamedKey::Space),
    ("Shift", NamedKey::Shift),
    ("Control", NamedKey::Control),
    ("Home", NamedKey::Home),
    ("End", NamedKey::End),
    ("PageUp", NamedKey::PageUp),
    ("PageDown", NamedKey::PageDown),
    ("Escape", NamedKey::Escape),
    ("Enter", NamedKey::Enter),
    ("Tab", NamedKey::Tab),
    ("F1", NamedKey::F1),
    ("F2", NamedKey::F2),
    ("F3", NamedKey::F3),
    ("F4", NamedKey::F4),
    ("F5", NamedKey::F5),
    ("F6", NamedKey::F6),
    ("F7", NamedKey::F7),
    ("F8", NamedKey::F8),
    ("F9", NamedKey::F9),
    ("F10", NamedKey::F10),
    ("F11", NamedKey::F11),
    ("F12", NamedKey::F12),
];

impl Key {
    /// Parses a script's key: one letter, digit, `+` or `-` (letters in
    /// either case), or a named key as winit spells it (`ArrowUp`, `F12`).
    pub fn parse(text: &str) -> Result<Key, String> {
        let mut chars = text.chars();
        if let (Some(c), None) = (chars.next(), chars.next()) {
            if c.is_ascii_alphanumeric() || c == '+' || c == '-' {
                return Ok(Key::Char(c.to_ascii_uppercase()));
            }
        }
        NAMED
            .iter()
            .find(|(name, _)| *name == text)
            .map(|(_, k)| Key::Named(*k))
            .ok_or_else(|| {
                format!(
                    "unknown key '{text}': a key is a letter, a digit, '+', '-' or one of {}",
                    NAMED.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                )
            })
    }

    /// The key from a winit key event, if the viewer knows it.
    pub fn from_winit(key: &winit::keyboard::Key) -> Option<Key> {
        use winit::keyboard::{Key as W, NamedKey as N};
        match key {
            W::Character(s) => {
                let mut chars = s.chars();
                match (chars.next(), chars.next()) {
                    // '=' is '+' without Shift on most layouts.
                    (Some('='), None) => Some(Key::Char('+')),
                    (Some(c), None) if c.is_ascii_alphanumeric() || c == '+' || c == '-' => {
                        Some(Key::Char(c.to_ascii_uppercase()))
                    }
                    _ => None,
                }
            }
            W::Named(n) => {
                let named = match n {
                    N::ArrowUp => NamedKey::ArrowUp,
                    N::ArrowDown => NamedKey::ArrowDown,
                    N::ArrowLeft => NamedKey::ArrowLeft,
                    N::ArrowRight => NamedKey::ArrowRight,
                    N::Space => NamedKey::Space,
                    N::Shift => NamedKey::Shift,
                    N::Control => NamedKey::Control,
                    N::Home => NamedKey::Home,
                    N::End => NamedKey::End,
                    N::PageUp => NamedKey::PageUp,
                    N::PageDown => NamedKey::PageDown,
                    N::Escape => NamedKey::Escape,
                    N::Enter => NamedKey::Enter,
                    N::Tab => NamedKey::Tab,
                    N::F1 => NamedKey::F1,
                    N::F2 => NamedKey::F2,
                    N::F3 => NamedKey::F3,
                    N::F4 => NamedKey::F4,
                    N::F5 => NamedKey::F5,
                    N::F6 => NamedKey::F6,
                    N::F7 => NamedKey::F7,
                    N::F8 => NamedKey::F8,
                    N::F9 => NamedKey::F9,
                    N::F10 => NamedKey::F10,
                    N::F11 => NamedKey::F11,
                    N::F12 => NamedKey::F12,
                    _ => return None,
                };
                Some(Key::Named(named))
            }
            _ => None,
        }
    }
}

/// What a key does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Held: move along the view direction (+1 forward, -1 back), to the
    /// right (+1) or left, up (+1) or down along the local vertical.
    Move { forward: i8, right: i8, up: i8 },
    /// Held: move ten times faster.
    Fast,
    /// Held: turn the sun along its arc, later (+1) or earlier (-1) in
    /// the day.
    Sun(i8),
    /// Pressed: narrow (+1, zoom in) or widen the field of view.
    Zoom(i8),
    /// Pressed: back to the scene's camera.
    ResetCamera,
    /// Pressed: back to the scene's sun.
    ResetSun,
    /// Pressed: the next value of knob N (1-based, as listed by `F1`; key
    /// 0 is knob 10, F2 to F11 knobs 11 to 20).
    CycleKnob(usize),
    /// Pressed: print the per-pass times.
    PrintTimings,
    /// Pressed: write a screenshot (PNG and EXR) and print the camera.
    Screenshot,
    /// Pressed: print the key bindings and knobs.
    Help,
    /// Pressed: close the viewer.
    Quit,
}

impl Key {
    /// This key's action, if it has one.
    pub fn action(self) -> Option<Action> {
        use NamedKey as N;
        let mv = |forward, right, up| Some(Action::Move { forward, right, up });
        match self {
            Key::Char('W') | Key::Named(N::ArrowUp) => mv(1, 0, 0),
            Key::Char('S') | Key::Named(N::ArrowDown) => mv(-1, 0, 0),
            Key::Char('D') | Key::Named(N::ArrowRight) => mv(0, 1, 0),
            Key::Char('A') | Key::Named(N::ArrowLeft) => mv(0, -1, 0),
            Key::Char('E') => mv(0, 0, 1),
            Key::Char('Q') => mv(0, 0, -1),
            Key::Named(N::Shift) => Some(Action::Fast),
            Key::Char('L') | Key::Named(N::PageUp) => Some(Action::Sun(1)),
            Key::Char('K') | Key::Named(N::PageDown) => Some(Action::Sun(-1)),
            Key::Char('+') => Some(Action::Zoom(1)),
            Key::Char('-') => Some(Action::Zoom(-1)),
            Key::Named(N::Home) => Some(Action::ResetCamera),
            Key::Named(N::End) => Some(Action::ResetSun),
            Key::Char(c @ '1'..='9') => Some(Action::CycleKnob(c as usize - '0' as usize)),
            Key::Char('0') => Some(Action::CycleKnob(10)),
            Key::Named(n) if FUNCTION_KNOB_KEYS.contains(&n) => Some(Action::CycleKnob(
                11 + FUNCTION_KNOB_KEYS.iter().position(|k| *k == n).unwrap_or(0),
            )),
            Key::Char('T') => Some(Action::PrintTimings),
            Key::Named(N::F12) => Some(Action::Screenshot),
            Key::Named(N::F1) | Key::Char('H') => Some(Action::Help),
            Key::Named(N::Escape) => Some(Action::Quit),
            _ => None,
        }
    }
}

/// The function keys that cycle knobs 11 to 20, in order (F1 is help,
/// F12 the screenshot).
const FUNCTION_KNOB_KEYS: [NamedKey; 10] = [
    NamedKey::F2,
    NamedKey::F3,
    NamedKey::F4,
    NamedKey::F5,
    NamedKey::F6,
    NamedKey::F7,
    NamedKey::F8,
    NamedKey::F9,
    NamedKey::F10,
    NamedKey::F11,
];

/// How many knobs have a key: the digits, then F2 to F11.
pub const KNOB_KEYS: usize = 10 + FUNCTION_KNOB_KEYS.len();

/// The key that cycles knob `n` (1-based), as the help prints it.
pub fn knob_key(n: usize) -> Option<String> {
    match n {
        1..=10 => Some((n % 10).to_string()),
        11..=KNOB_KEYS => Some(format!("F{}", n - 9)),
        _ => None,
    }
}

/// The key bindings, for `F1` and docs/viewer.md.
pub const HELP: &str = "\
keys: W/S or Up/Down forward/back, A/D or Left/Right sideways, E/Q up/down, Shift x10 speed;
      drag with the left mouse button to look around; wheel or +/- field of view;
      L/K (PageUp/PageDown) sun later/earlier, End the scene's sun; Home the scene's camera;
      1-9, 0, F2-F11 cycle the knob listed with that key; T print per-pass GPU times;
      F12 screenshot (PNG + EXR) and the [camera] that reproduces it; F1/H this help; Esc quit";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_parse_by_letter_and_winit_name() {
        assert_eq!(Key::parse("w"), Ok(Key::Char('W')));
        assert_eq!(Key::parse("W"), Ok(Key::Char('W')));
        assert_eq!(Key::parse("3"), Ok(Key::Char('3')));
        assert_eq!(Key::parse("ArrowUp"), Ok(Key::Named(NamedKey::ArrowUp)));
        assert_eq!(Key::parse("F12"), Ok(Key::Named(NamedKey::F12)));
        let err = Key::parse("Arrowup").unwrap_err();
        assert!(
            err.contains("unknown key 'Arrowup'") && err.contains("ArrowUp"),
            "{err}"
        );
        assert!(Key::parse("").is_err());
        assert!(Key::parse("é").is_err());
    }

    #[test]
    fn movement_keys_have_the_documented_directions() {
        assert_eq!(
            Key::Char('W').action(),
            Some(Action::Move {
                forward: 1,
                right: 0,
                up: 0
            })
        );
        assert_eq!(
            Key::Named(NamedKey::ArrowDown).action(),
            Key::Char('S').action()
        );
        assert_eq!(Key::Char('5').action(), Some(Action::CycleKnob(5)));
        assert_eq!(Key::Char('0').action(), Some(Action::CycleKnob(10)));
        assert_eq!(
            Key::Named(NamedKey::F2).action(),
            Some(Action::CycleKnob(11))
        );
        assert_eq!(
            Key::Named(NamedKey::F11).action(),
            Some(Action::CycleKnob(20))
        );
        for n in 1..=KNOB_KEYS {
            let key = Key::parse(&knob_key(n).unwrap()).unwrap();
            assert_eq!(key.action(), Some(Action::CycleKnob(n)), "knob {n}");
        }
        assert_eq!(knob_key(KNOB_KEYS + 1), None);
    }
}
