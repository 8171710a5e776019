//! Characters typed with Ctrl (or Super) held are shortcuts, never text.
//!
//! bevy_egui decides whether a key press is text from the modifiers as they stand after the
//! frame's last key message. When Ctrl goes down, S goes down and up and Ctrl comes up within
//! one frame (a slow frame under software rendering, or a quick hand), Ctrl+S arrives in egui
//! as the text "s" — which the Save dialog that Ctrl+S opens then types into its search field
//! (and filters its file list by). This system follows Ctrl through the frame's key messages
//! in order and takes such characters back out of egui's input before egui's pass reads it.

use bevy::input::keyboard::{Key, KeyboardFocusLost, KeyboardInput};
use bevy::prelude::*;
use bevy_egui::{EguiInput, egui};

/// Removes from every egui context's input the text events of characters pressed while Ctrl
/// or Super was held (runs after bevy_egui writes its events, before the egui pass). `held`:
/// whether Ctrl or Super was down after the key messages seen so far (across frames).
pub fn strip_ctrl_text(
    mut keys: MessageReader<KeyboardInput>,
    mut focus_lost: MessageReader<KeyboardFocusLost>,
    mut held: Local<bool>,
    mut inputs: Query<&mut EguiInput>,
) {
    if focus_lost.read().count() > 0 {
        *held = false;
    }
    let typed = typed_with_modifier(
        keys.read().map(|k| (&k.logical_key, k.state.is_pressed())),
        &mut held,
    );
    if typed.is_empty() {
        return;
    }
    for mut input in &mut inputs {
        remove_texts(&mut input.events, &typed);
    }
}

/// The characters pressed while Ctrl or Super was held, following the key messages `keys`
/// (logical key, pressed) in order from `held` (updated to the state after them).
fn typed_with_modifier<'a>(
    keys: impl Iterator<Item = (&'a Key, bool)>,
    held: &mut bool,
) -> Vec<String> {
    let mut typed = Vec::new();
    for (key, pressed) in keys {
        match key {
            Key::Control | Key::Super | Key::Meta => *held = pressed,
            Key::Character(c) if *held && pressed => typed.push(c.to_string()),
            _ => {}
        }
    }
    typed
}

/// Removes one `Text` event per entry of `typed` (the first equal one), keeping the order of
/// the rest.
fn remove_texts(events: &mut Vec<egui::Event>, typed: &[String]) {
    let mut pending: Vec<&str> = typed.iter().map(String::as_str).collect();
    events.retain(|e| match e {
        egui::Event::Text(t) => match pending.iter().position(|s| s == t) {
            Some(i) => {
                pending.remove(i);
                false
            }
            None => true,
        },
        _ => true,
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ch(c: &str) -> Key {
        Key::Character(c.into())
    }

    #[test]
    fn ctrl_s_pressed_and_released_in_one_frame_is_not_text() {
        let (ctrl, s) = (Key::Control, ch("s"));
        let mut held = false;
        // Ctrl down, S down, S up, Ctrl up: all in one frame.
        let frame = [(&ctrl, true), (&s, true), (&s, false), (&ctrl, false)];
        let typed = typed_with_modifier(frame.into_iter(), &mut held);
        assert_eq!(typed, ["s"]);
        assert!(!held);
        let mut events = vec![
            egui::Event::Text("s".into()),
            egui::Event::Text("a".into()),
            egui::Event::Copy,
        ];
        remove_texts(&mut events, &typed);
        assert_eq!(events, [egui::Event::Text("a".into()), egui::Event::Copy]);
    }

    #[test]
    fn text_typed_without_ctrl_stays_and_ctrl_carries_over_frames() {
        let (ctrl, a, s) = (Key::Control, ch("a"), ch("s"));
        let mut held = false;
        // "a" typed, then Ctrl pressed (and held into the next frame).
        assert!(typed_with_modifier([(&a, true), (&ctrl, true)].into_iter(), &mut held).is_empty());
        assert!(held);
        // Next frame: S with Ctrl still held from before, then Ctrl released.
        let typed = typed_with_modifier([(&s, true), (&ctrl, false)].into_iter(), &mut held);
        assert_eq!(typed, ["s"]);
        // Only one "s" goes: a second one was typed after Ctrl came up.
        let mut events = vec![egui::Event::Text("s".into()), egui::Event::Text("s".into())];
        remove_texts(&mut events, &typed);
        assert_eq!(events, [egui::Event::Text("s".into())]);
    }
}
