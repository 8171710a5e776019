//! The offer to key an edit of animated fields: with auto-key off, an edit that would add a
//! key to an animated channel at a frame where it has none is held by the document
//! ([`SceneDocument::pending`]) and shown in the view; this bar, over the bottom of the 3-D
//! view, names what changed and offers **Key** (K, one undo step) or **Revert** (or Ctrl+Z),
//! and says that a new frame drops it — as Blender shows such fields in orange until they
//! are keyed.

use bevy_egui::egui;
use ductile_bevy::prelude::*;

use super::PanelContext;

/// The colour of fields and text for an edit of an animated channel that is not keyed yet
/// (Blender's orange).
pub const UNKEYED: egui::Color32 = egui::Color32::from_rgb(240, 150, 50);

/// The offer bar (no state of its own: it shows the document's pending edit).
#[derive(Debug, Default)]
pub struct KeyOffer;

/// A short description of the channels an edit would key: "target of 'bend'" or
/// "3 fields of 'bend', 'nose'".
#[must_use]
pub fn describe(channels: &[(String, String)]) -> String {
    let mut nodes: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
    nodes.dedup();
    let names = nodes
        .iter()
        .map(|n| format!("'{n}'"))
        .collect::<Vec<_>>()
        .join(", ");
    match channels {
        [(_, path)] => format!("{path} of {names}"),
        _ => format!("{} fields of {names}", channels.len()),
    }
}

impl KeyOffer {
    /// Draws the bar at the bottom of `view` (the 3-D view's rectangle) while an edit waits
    /// to be keyed.
    pub fn show(&mut self, ctx: &egui::Context, view: egui::Rect, cx: &mut PanelContext<'_>) {
        let Some(pending) = cx.doc.pending() else {
            return;
        };
        let fps = cx.doc.document().animation.fps;
        let frame = (pending.time() * fps).round();
        let what = describe(pending.channels());
        egui::Area::new(egui::Id::new("key-offer"))
            .order(egui::Order::Foreground)
            .pivot(egui::Align2::CENTER_BOTTOM)
            .fixed_pos(egui::pos2(view.center().x, view.bottom() - 10.0))
            .show(ctx, |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| {
                    ui.horizontal(|ui| {
                        ui.colored_label(UNKEYED, format!("Not keyed: {what} at frame {frame}"))
                            .on_hover_text(
                                "These fields are animated and have no key at this frame: \
                                 key the edit, or it is dropped when the frame changes",
                            );
                        if ui
                            .button("Key (K)")
                            .on_hover_text("Key the edit at this frame (one undo step)")
                            .clicked()
                        {
                            cx.commands.push(DocumentCommand::KeyPending);
                        }
                        if ui
                            .button("Revert")
                            .on_hover_text("Drop the edit (Ctrl+Z does too)")
                            .clicked()
                        {
                            cx.commands.push(DocumentCommand::RevertPending);
                        }
                    });
                });
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_channel_is_named_and_several_are_counted() {
        let c = |n: &str, p: &str| (n.to_owned(), p.to_owned());
        assert_eq!(
            describe(&[c("bend", "mode.target")]),
            "mode.target of 'bend'"
        );
        assert_eq!(
            describe(&[c("a", "x"), c("a", "y"), c("b", "z")]),
            "3 fields of 'a', 'b'"
        );
    }
}
