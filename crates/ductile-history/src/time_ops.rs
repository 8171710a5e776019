//! How the time operations (keys, tracks, timeline, variants) run, in both directions.
//! [`Operation`](crate::operation::Operation) dispatches to these functions; like every
//! operation they check that the document holds the expected "before" value, check the new
//! value when applying, and change nothing when they fail.

use ductile_anim::key::Key;
use ductile_scene::prelude::*;
use ductile_scene::time::track_problem;

use crate::check::{node_index, same};
use crate::error::{HistoryError, Result};

/// The position of the key at exactly `time` in `keys`.
fn key_index(keys: &[Key], time: f32) -> Option<usize> {
    keys.iter().position(|k| k.time == time)
}

/// The key at `time` on node `node`'s channel `param`, if any.
pub(crate) fn key_at<'a>(doc: &'a Document, node: &str, param: &str, time: f32) -> Option<&'a Key> {
    let keys = doc.animation.track(node, param)?;
    key_index(keys, time).map(|i| &keys[i])
}

/// The track `keys` (possibly empty: no track) written back: an empty track is removed, and a
/// node without tracks leaves the map, so that adding then removing a key restores the
/// document exactly.
fn put_track(doc: &mut Document, node: &str, param: &str, keys: Vec<Key>) {
    let tracks = &mut doc.animation.tracks;
    if keys.is_empty() {
        if let Some(t) = tracks.get_mut(node) {
            t.remove(param);
            if t.is_empty() {
                tracks.remove(node);
            }
        }
    } else {
        tracks
            .entry(node.to_owned())
            .or_default()
            .insert(param.to_owned(), keys);
    }
}

fn track_error(node: &str, param: &str, problem: String) -> HistoryError {
    SceneError::Track {
        node: node.to_owned(),
        param: param.to_owned(),
        problem,
    }
    .into()
}

/// Checks a whole new track for channel `param` of node `node`.
fn check_track(doc: &Document, node: &str, param: &str, keys: &[Key]) -> Result<()> {
    let n = &doc.nodes[node_index(doc, node)?];
    match track_problem(n, param, keys) {
        Some(p) => Err(track_error(node, param, p)),
        None => Ok(()),
    }
}

/// Runs a key edit: the key at `time` goes from `expected` to `target` (`None`: absent).
pub(crate) fn set_key(
    doc: &mut Document,
    node: &str,
    param: &str,
    time: f32,
    expected: Option<&Key>,
    target: Option<&Key>,
    check: bool,
) -> Result<()> {
    if !time.is_finite() {
        return Err(SceneError::NotFinite {
            what: format!("node '{node}', parameter '{param}': key time"),
            value: time.to_string(),
        }
        .into());
    }
    same(&key_at(doc, node, param, time), &expected, || {
        format!("node '{node}', parameter '{param}': key at {time} s")
    })?;
    if let Some(k) = target
        && k.time != time
    {
        return Err(track_error(
            node,
            param,
            format!(
                "the key's time {} s is not the edited time {time} s",
                k.time
            ),
        ));
    }
    let mut keys: Vec<Key> = doc
        .animation
        .track(node, param)
        .map(<[Key]>::to_vec)
        .unwrap_or_default();
    if let Some(i) = key_index(&keys, time) {
        keys.remove(i);
    }
    if let Some(k) = target {
        let at = keys.partition_point(|x| x.time < time);
        keys.insert(at, k.clone());
    }
    if check && target.is_some() {
        check_track(doc, node, param, &keys)?;
    }
    put_track(doc, node, param, keys);
    Ok(())
}

/// Runs a key move from `from` to `to` on node `node`'s channel `param`.
pub(crate) fn move_key(
    doc: &mut Document,
    node: &str,
    param: &str,
    from: f32,
    to: f32,
) -> Result<()> {
    let what = || format!("node '{node}', parameter '{param}'");
    let Some(keys) = doc.animation.track(node, param) else {
        return Err(track_error(
            node,
            param,
            format!("there is no key at {from} s"),
        ));
    };
    let mut keys = keys.to_vec();
    let Some(i) = key_index(&keys, from) else {
        return Err(track_error(
            node,
            param,
            format!("there is no key at {from} s"),
        ));
    };
    if !to.is_finite() {
        return Err(SceneError::NotFinite {
            what: format!("{}: key time", what()),
            value: to.to_string(),
        }
        .into());
    }
    if from != to && key_index(&keys, to).is_some() {
        return Err(track_error(
            node,
            param,
            format!("there is already a key at {to} s"),
        ));
    }
    let mut k = keys.remove(i);
    k.time = to;
    let at = keys.partition_point(|x| x.time < to);
    keys.insert(at, k);
    put_track(doc, node, param, keys);
    Ok(())
}

/// Runs a whole-track edit.
pub(crate) fn set_track(
    doc: &mut Document,
    node: &str,
    param: &str,
    expected: Option<&[Key]>,
    target: Option<&[Key]>,
    check: bool,
) -> Result<()> {
    same(&doc.animation.track(node, param), &expected, || {
        format!("node '{node}', parameter '{param}': track")
    })?;
    if check && let Some(keys) = target {
        check_track(doc, node, param, keys)?;
    }
    put_track(
        doc,
        node,
        param,
        target.map(<[Key]>::to_vec).unwrap_or_default(),
    );
    Ok(())
}

/// Runs a timeline edit.
pub(crate) fn set_timeline(
    doc: &mut Document,
    expected: &Timeline,
    target: &Timeline,
    check: bool,
) -> Result<()> {
    same(&doc.animation.timeline(), expected, || {
        "timeline".to_owned()
    })?;
    if check && let Some(p) = target.problems().into_iter().next() {
        return Err(p.into());
    }
    doc.animation.set_timeline(*target);
    Ok(())
}

/// Runs a variant edit: `name` goes from `expected` to `target` (`None`: absent).
pub(crate) fn set_variant(
    doc: &mut Document,
    name: &str,
    expected: Option<&Variant>,
    target: Option<&Variant>,
    check: bool,
) -> Result<()> {
    same(&doc.variants.get(name), &expected, || {
        format!("variant '{name}'")
    })?;
    if check
        && let Some(v) = target
        && let Some(p) = doc.variant_problems_of(name, v).into_iter().next()
    {
        return Err(p.into());
    }
    match target {
        Some(v) => {
            doc.variants.insert(name.to_owned(), v.clone());
        }
        None => {
            doc.variants.remove(name);
        }
    }
    Ok(())
}

/// Runs a variant rename from `from` to `to`.
pub(crate) fn rename_variant(doc: &mut Document, from: &str, to: &str) -> Result<()> {
    let v = doc.variant(from)?.clone();
    if from == to {
        return Ok(());
    }
    if doc.variants.contains_key(to) {
        return Err(SceneError::Variant {
            variant: to.to_owned(),
            problem: "a variant of this name already exists".to_owned(),
        }
        .into());
    }
    if let Some(p) = doc
        .variant_problems_of(
            to,
            &Variant {
                states: Default::default(),
                origin: None,
            },
        )
        .into_iter()
        .next()
    {
        return Err(p.into());
    }
    doc.variants.remove(from);
    doc.variants.insert(to.to_owned(), v);
    Ok(())
}
