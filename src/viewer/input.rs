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
    /// 0 is knob 10).
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
            Key::Char('T') => Some(Action::PrintTimings),
            Key::Named(N::F12) => Some(Action::Screenshot),
            Key::Named(N::F1) | Key::Char('H') => Some(Action::Help),
            Key::Named(N::Escape) => Some(Action::Quit),
            _ => None,
        }
    }
}

/// The key bindings, for `F1` and docs/viewer.md.
pub const HELP: &str = "\
keys: W/S or Up/Down forward/back, A/D or Left/Right sideways, E/Q up/down, Shift x10 speed;
      drag with the left mouse button to look around; wheel or +/- field of view;
      L/K (PageUp/PageDown) sun later/earlier, End the scene's sun; Home the scene's camera;
      1-9, 0 cycle the knob listed with that number; T print per-pass GPU times;
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
    }
}
