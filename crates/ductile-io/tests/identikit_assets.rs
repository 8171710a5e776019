//! The shipped identikit (`scenes/identikit-head.ron`, `scenes/identikit-demo.ron`, generated
//! by `tools/identikit/generate.py`, documented in `docs/identikit.md`): the scenes load and
//! validate, every macro has its area, layer and node, the library is mirror-symmetric about
//! the documented plane `x = −0.09`, and mirrored macros give mirrored displacements.

#![allow(clippy::unwrap_used)] // Tests may unwrap (house rules).

use std::path::{Path, PathBuf};

use ductile_core::ffsd::{ControlPoint, FfsdMacro, PointMode};
use ductile_core::influence::Shape;
use ductile_core::mesh::{Mesh, RestMesh};
use ductile_scene::prelude::*;
use glam::Vec3;

/// The mirror plane of the head: `x = X0` (docs/identikit.md).
const X0: f32 = -0.09;
/// Coordinates are written with 4 decimals; mirrored ones agree to f32 rounding.
const TOL: f32 = 1e-5;
const GROUPS: [&str; 7] = [
    "Nose",
    "Eyes",
    "Mouth",
    "Ears",
    "Chin & Jaw",
    "Brows & Forehead",
    "Cheeks",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn load(name: &str) -> Document {
    ductile_io::read_scene(root().join("scenes").join(name)).unwrap()
}

fn mirror(p: Vec3) -> Vec3 {
    Vec3::new(2.0 * X0 - p.x, p.y, p.z)
}

fn near(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() <= TOL
}

fn mirrored_point(p: &ControlPoint) -> ControlPoint {
    ControlPoint {
        position: mirror(p.position),
        mode: match p.mode {
            PointMode::Directional { reference } => PointMode::Directional {
                reference: mirror(reference),
            },
            other => other,
        },
        ..*p
    }
}

fn same_point(a: &ControlPoint, b: &ControlPoint) -> bool {
    let modes = match (a.mode, b.mode) {
        (PointMode::Basic, PointMode::Basic) | (PointMode::Virtual, PointMode::Virtual) => true,
        (PointMode::Directional { reference: r }, PointMode::Directional { reference: s }) => {
            near(r, s)
        }
        _ => false,
    };
    modes
        && near(a.position, b.position)
        && a.gamma == b.gamma
        && a.alpha == b.alpha
        && a.epsilon == b.epsilon
}

fn head(doc: &Document) -> &MeshNode {
    doc.mesh("head").unwrap()
}

fn region(area: &Area) -> &[RegionShape] {
    match area {
        Area::Region(shapes) => shapes,
        Area::Vertices(_) => panic!("identikit areas are regions"),
    }
}

fn same_shape(a: &RegionShape, b: &RegionShape) -> bool {
    a.shape == b.shape
        && a.transform.rotation == b.transform.rotation
        && a.transform.scale == b.transform.scale
        && near(a.transform.translation, b.transform.translation)
}

fn mirrored_shape(s: &RegionShape) -> RegionShape {
    assert!(
        !matches!(s.shape, Shape::Capsule { .. }) || s.transform.rotation == glam::Quat::IDENTITY,
        "mirroring rotated capsules is not covered"
    );
    let mut m = s.clone();
    m.transform.translation = mirror(s.transform.translation);
    m
}

/// Every element of `a` has its mirror image in `b`, and the other way round.
fn mirror_sets<T>(
    a: &[T],
    b: &[T],
    mirror: impl Fn(&T) -> T,
    same: impl Fn(&T, &T) -> bool,
) -> bool {
    a.len() == b.len()
        && a.iter().all(|x| b.iter().any(|y| same(&mirror(x), y)))
        && b.iter().all(|y| a.iter().any(|x| same(&mirror(y), x)))
}

#[test]
fn scenes_load_and_validate() {
    for name in ["identikit-head.ron", "identikit-demo.ron"] {
        let doc = load(name);
        assert_eq!(doc.problems(), vec![], "{name}");
        assert_eq!(
            head(&doc).source,
            "../assets/meshes/lee-perry-smith-head.glb",
            "{name}"
        );
    }
}

#[test]
fn scenes_evaluate_on_the_head() {
    let head_scene = ductile_io::load_scene(root().join("scenes/identikit-head.ron")).unwrap();
    let rest = &head_scene.mesh("head").unwrap().rest;
    assert_eq!(rest.welded_positions().len(), 8_844);
    // Every macro at 0: the rest mesh, bit for bit.
    let out = head_scene.evaluate("head").unwrap();
    assert_eq!(out.positions, rest.mesh().positions);
    // The demo: a visible change everywhere a macro is set, finite and bounded.
    let demo = ductile_io::load_scene(root().join("scenes/identikit-demo.ron")).unwrap();
    let out = demo.evaluate("head").unwrap();
    let moved: Vec<f32> = out
        .positions
        .iter()
        .zip(&rest.mesh().positions)
        .map(|(p, r)| p.distance(*r))
        .collect();
    assert!(moved.iter().all(|d| d.is_finite()));
    let max = moved.iter().copied().fold(0.0, f32::max);
    assert!(max > 0.1 && max < 0.5, "largest displacement {max}");
    assert!(moved.iter().filter(|&&d| d > 0.01).count() > 1_000);
}

#[test]
fn library_is_complete_and_consistent() {
    let doc = load("identikit-head.ron");
    let mesh = head(&doc);
    assert!(doc.macros.len() >= 30, "{} macros", doc.macros.len());
    for (name, m) in &doc.macros {
        let area = m
            .area
            .as_deref()
            .unwrap_or_else(|| panic!("{name}: no area"));
        assert!(mesh.areas.contains_key(area), "{name}: unknown area {area}");
        assert!(
            GROUPS.contains(&m.group.as_str()),
            "{name}: group {}",
            m.group
        );
        assert!(!m.label.is_empty() && !m.points.is_empty(), "{name}");
        assert!(
            m.range.0 < 0.0 && m.range.1 > 0.0,
            "{name}: range {:?}",
            m.range
        );
        // One macro node at 0 and one layer restricted to the macro's area.
        let node = doc.node(name).unwrap();
        assert_eq!(
            node.kind,
            NodeKind::Macro(MacroUse {
                name: name.clone(),
                value: 0.0
            })
        );
        let layers: Vec<_> = mesh.stack.iter().filter(|l| &l.tool == name).collect();
        assert_eq!(layers.len(), 1, "{name}");
        let inf = layers[0].influence.as_ref().unwrap();
        assert_eq!(inf.area.as_deref(), Some(area), "{name}");
    }
    assert_eq!(mesh.stack.len(), doc.macros.len());
    for area in [
        "left-ear",
        "right-ear",
        "left-eye",
        "right-eye",
        "nose",
        "mouth",
        "chin",
        "left-brow",
        "right-brow",
        "left-cheek",
        "right-cheek",
        "jaw",
        "forehead",
    ] {
        assert!(mesh.areas.contains_key(area), "missing area {area}");
    }
}

#[test]
fn demo_sets_at_least_ten_macros() {
    let demo = load("identikit-demo.ron");
    let head_scene = load("identikit-head.ron");
    assert_eq!(demo.macros, head_scene.macros);
    assert_eq!(head(&demo), head(&head_scene));
    let set = demo
        .nodes
        .iter()
        .filter(|n| matches!(&n.kind, NodeKind::Macro(m) if m.value != 0.0))
        .count();
    assert!(set >= 10, "{set} macros set");
}

/// `left-X` / `right-X` macros and areas are mirror images; every other macro and area is
/// its own mirror image (bilateral or on the midline).
#[test]
fn library_is_mirror_symmetric() {
    let doc = load("identikit-head.ron");
    let partner = |name: &str| -> String {
        if let Some(rest) = name.strip_prefix("left-") {
            format!("right-{rest}")
        } else if let Some(rest) = name.strip_prefix("right-") {
            format!("left-{rest}")
        } else {
            name.to_owned()
        }
    };
    let mut pairs = 0;
    for (name, m) in &doc.macros {
        let other: &FfsdMacro = &doc.macros[&partner(name)];
        assert!(
            mirror_sets(&m.points, &other.points, mirrored_point, same_point),
            "{name} is not the mirror image of {}",
            partner(name)
        );
        assert_eq!(m.height, other.height, "{name}");
        pairs += usize::from(name.starts_with("left-"));
    }
    assert!(pairs >= 2, "{pairs} left/right macro pairs");
    let areas = &head(&doc).areas;
    for (name, area) in areas {
        let other = &areas[&partner(name)];
        assert!(
            mirror_sets(region(area), region(other), mirrored_shape, same_shape),
            "area {name} is not the mirror image of {}",
            partner(name)
        );
    }
}

/// A height field symmetric about `x = X0`, in front of where the face is: vertices come in
/// exact pairs `i` ↔ `mirror_of[i]`.
fn symmetric_patch() -> (RestMesh, Vec<usize>) {
    let (n, m) = (24_i32, 40_i32);
    let (h, k) = (1.6 / n as f32, 2.4 / m as f32);
    let mut positions = Vec::new();
    for j in 0..=m {
        for i in -n..=n {
            let a = (i.abs() as f32) * h;
            let x = if i < 0 { X0 - a } else { X0 + a };
            let y = 0.8 + j as f32 * k;
            positions.push(Vec3::new(
                x,
                y,
                2.3 - 0.3 * a * a - 0.05 * (y - 2.0).powi(2),
            ));
        }
    }
    let row = (2 * n + 1) as u32;
    let mut indices = Vec::new();
    for j in 0..m as u32 {
        for i in 0..row - 1 {
            let (a, b, c, d) = (
                j * row + i,
                j * row + i + 1,
                (j + 1) * row + i,
                (j + 1) * row + i + 1,
            );
            indices.extend_from_slice(&[a, b, d, a, d, c]);
        }
    }
    let mirror_of = (0..positions.len())
        .map(|v| {
            let (j, i) = (v / row as usize, v % row as usize);
            j * row as usize + (row as usize - 1 - i)
        })
        .collect();
    let mesh = Mesh {
        positions,
        normals: None,
        uvs: None,
        indices,
    };
    (RestMesh::new(mesh, "patch").unwrap(), mirror_of)
}

/// Displacements of the welded vertices of `rest` with only `macro_name` at `value`.
fn displacements(doc: &Document, rest: &RestMesh, macro_name: &str, value: f32) -> Vec<Vec3> {
    let mut doc = doc.clone();
    let mesh = doc.mesh_mut("head").unwrap();
    mesh.stack.retain(|l| l.tool == macro_name);
    if let NodeKind::Macro(m) = &mut doc.node_mut(macro_name).unwrap().kind {
        m.value = value;
    }
    let out = doc
        .resolve_stack("head", rest)
        .unwrap()
        .evaluate_welded(rest)
        .unwrap();
    out.iter()
        .zip(rest.welded_positions())
        .map(|(p, r)| *p - *r)
        .collect()
}

fn reflect(d: Vec3) -> Vec3 {
    Vec3::new(-d.x, d.y, d.z)
}

#[test]
fn mirrored_macros_give_mirrored_displacements() {
    let doc = load("identikit-head.ron");
    let (rest, mirror_of) = symmetric_patch();
    // The patch welds nothing: welded order is stored order.
    assert_eq!(rest.welded_positions().len(), mirror_of.len());
    let left = displacements(&doc, &rest, "left-brow-height", 0.8);
    let right = displacements(&doc, &rest, "right-brow-height", 0.8);
    let moved = left.iter().filter(|d| d.length() > 1e-3).count();
    assert!(
        moved > 20,
        "the left brow macro moved {moved} patch vertices"
    );
    for (v, &w) in mirror_of.iter().enumerate() {
        let (a, b) = (left[v], reflect(right[w]));
        assert!((a - b).length() < 1e-4, "vertex {v}: {a} vs mirrored {b}");
    }
    // A bilateral macro is its own mirror image.
    for name in ["brow-height", "eye-spacing", "nose-width"] {
        let d = displacements(&doc, &rest, name, -0.7);
        assert!(d.iter().any(|d| d.length() > 1e-3), "{name} moved nothing");
        for (v, &w) in mirror_of.iter().enumerate() {
            let (a, b) = (d[v], reflect(d[w]));
            assert!(
                (a - b).length() < 1e-4,
                "{name}, vertex {v}: {a} vs mirrored {b}"
            );
        }
    }
}
