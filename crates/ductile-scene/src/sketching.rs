//! Sketch mode's logic without the engine: strokes drawn on the view become a sketch tool
//! (Kho & Garland 2005), with a preview of its region of interest while drawing.
//!
//! * The **reference stroke** is projected onto the layer's input mesh
//!   ([`ductile_core::sketch::stroke::project_stroke`] for a bend, the joint
//!   curve inside the mesh for a twist) and gives the partition (cutting planes at its ends,
//!   §4.2) and the skinning `s(v)` shown as a blue-to-red ramp ([`preview`]).
//! * A **cut line** (two points on screen) splits the region with a minimum cut (§4.2.1) and
//!   makes the far parts rigid ([`cut`]).
//! * The **target stroke** of a bend makes the tool ([`bend_tool`]); for a twist, the second
//!   stroke's length sets `θ_max` ([`twist_angle`]).

use ductile_core::error::Result;
use ductile_core::mesh::Topology;
use ductile_core::sketch::camera::Camera;
use ductile_core::sketch::cut::{combine_cuts, cut_with_line};
use ductile_core::sketch::partition::Partition;
use ductile_core::sketch::raycast::Bvh;
use ductile_core::sketch::roi::partition_from_curve;
use ductile_core::sketch::skin::{Polyline, skin};
use ductile_core::sketch::stroke::{
    filter_stroke, joint_curve, project_stroke, project_target_stroke,
};
use ductile_core::sketch::tool::{Curve, SketchMode, SketchTool, Stroke};
use ductile_core::tool::Tool;
use glam::{Vec2, Vec3};

/// What a sketch makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SketchKind {
    /// Bend the region so the reference follows a target stroke (§5.1).
    Bend,
    /// Twist the region about the reference (§5.2).
    Twist,
}

/// The region of interest of a reference stroke, for display and for the tool.
#[derive(Debug, Clone, PartialEq)]
pub struct Preview {
    /// The reference curve in the mesh (3-D).
    pub curve: Vec<Vec3>,
    /// The partition (region of interest and rigid parts).
    pub partition: Partition,
    /// `s(v)` of every region vertex, in the order of `partition.roi`.
    pub s: Vec<f32>,
}

impl Preview {
    /// A colour per welded vertex: the paper's ramp from blue (`s = 0`) to red (`s = 1`)
    /// over the region of interest, orange for rigid parts, grey elsewhere (RGBA, linear).
    #[must_use]
    pub fn colors(&self, vertex_count: usize) -> Vec<[f32; 4]> {
        let mut out = vec![[0.55, 0.55, 0.58, 1.0]; vertex_count];
        for part in &self.partition.rigid {
            for &v in part {
                if let Some(c) = out.get_mut(v as usize) {
                    *c = [0.95, 0.6, 0.15, 1.0];
                }
            }
        }
        for (&v, &s) in self.partition.roi.iter().zip(&self.s) {
            if let Some(c) = out.get_mut(v as usize) {
                *c = [s, 0.15, 1.0 - s, 1.0];
            }
        }
        out
    }
}

/// The 3-D reference curve of a stroke on the mesh (`positions`: the layer's input, welded).
pub fn reference_curve(
    kind: SketchKind,
    stroke: &Stroke,
    positions: &[Vec3],
    topology: &Topology,
) -> Result<Vec<Vec3>> {
    let bvh = Bvh::build(positions, &topology.triangles)?;
    let filtered = filter_stroke(&stroke.pixels)?;
    match kind {
        SketchKind::Bend => project_stroke(&stroke.camera, &filtered, positions, topology, &bvh),
        SketchKind::Twist => joint_curve(&stroke.camera, &filtered, &bvh),
    }
}

/// The reference stroke's curve, partition and skinning (see the module documentation).
pub fn preview(
    kind: SketchKind,
    stroke: &Stroke,
    positions: &[Vec3],
    topology: &Topology,
) -> Result<Preview> {
    let curve = reference_curve(kind, stroke, positions, topology)?;
    let partition = partition_from_curve(positions, topology, &curve)?;
    let s = skin(
        &Polyline::new(&curve, "reference curve")?,
        positions,
        &partition.roi,
    );
    Ok(Preview {
        curve,
        partition,
        s,
    })
}

/// The preview after a cut line `line` (pixels, drawn with `camera`): the region is split
/// along the minimum cut, the part holding the reference curve stays deformable and the others
/// become rigid (§4.2.1).
pub fn cut(
    preview: &Preview,
    camera: &Camera,
    line: [Vec2; 2],
    positions: &[Vec3],
    topology: &Topology,
) -> Result<Preview> {
    let c = cut_with_line(camera, line, positions, topology)?;
    let partition = combine_cuts(
        positions,
        topology,
        Some(&preview.partition),
        &[c],
        &preview.curve,
    )?;
    let s = skin(
        &Polyline::new(&preview.curve, "reference curve")?,
        positions,
        &partition.roi,
    );
    Ok(Preview {
        curve: preview.curve.clone(),
        partition,
        s,
    })
}

/// The length of a stroke in pixels.
#[must_use]
pub fn stroke_length(pixels: &[Vec2]) -> f32 {
    pixels.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// `θ_max` of a twist from its strokes (the paper: "proportional to the length of the second
/// line"). Decision: a second stroke as long as the reference is one full turn (2π), and the
/// sign is the side it is drawn towards: a stroke going to the left of the reference's
/// direction on screen (counter-clockwise, y up) twists positively (right-handed about the
/// curve). Radians.
#[must_use]
pub fn twist_angle(reference: &[Vec2], twist: &[Vec2]) -> f32 {
    let (Some(&r0), Some(&r1), Some(&t0), Some(&t1)) = (
        reference.first(),
        reference.last(),
        twist.first(),
        twist.last(),
    ) else {
        return 0.0;
    };
    let length = stroke_length(reference);
    if length <= 0.0 {
        return 0.0;
    }
    // Screen y points down: flip it so that "left" is counter-clockwise.
    let r = Vec2::new(r1.x - r0.x, r0.y - r1.y);
    let t = Vec2::new(t1.x - t0.x, t0.y - t1.y);
    let side = r.perp_dot(t);
    let sign = if side < 0.0 { -1.0 } else { 1.0 };
    sign * std::f32::consts::TAU * stroke_length(twist) / length
}

/// A bend tool from its two strokes; `partition` as cut by the user (`None`: computed when
/// the tool binds, from the cutting planes at the reference's ends).
#[must_use]
pub fn bend_tool(reference: Stroke, target: Stroke, partition: Option<Partition>) -> Tool {
    Tool::Sketch(Box::new(SketchTool {
        partition,
        reference: Curve::Stroke(reference),
        normal: None,
        mode: SketchMode::Bend {
            target: Curve::Stroke(target),
            turning: None,
        },
        scale: None,
        smooth: true,
        refine: None,
    }))
}

/// A bend tool whose curves are stored as 3-D points, so that its target is an animatable
/// channel (`mode.target`, a curve in the sketch plane) — what the Studio makes.
///
/// `reference_curve` is the reference stroke projected on the mesh ([`reference_curve`],
/// exactly what the bind would compute from the stroke, so the tool binds as
/// [`bend_tool`]'s would); the sketch-plane normal is the direction towards the reference
/// stroke's eye (as [`bend_tool`] leaves it implicit); the target stroke is placed on the
/// plane as at evaluation time (§5.1) and resampled by arc length to as many points as the
/// reference curve, so that keys of the target (and [`straight_target`]) interpolate
/// skeleton-style instead of stepping.
///
/// # Errors
/// A target stroke too short or not meeting the plane, a degenerate camera.
pub fn bend_tool_on(
    reference_curve: &[Vec3],
    reference: &Stroke,
    target: &Stroke,
    partition: Option<Partition>,
) -> Result<Tool> {
    let normal = -reference.camera.forward();
    if normal == Vec3::ZERO {
        return Err(ductile_core::error::CoreError::Degenerate {
            what: "reference stroke".to_owned(),
            problem: "its camera looks nowhere (eye = target)".to_owned(),
        });
    }
    let filtered = filter_stroke(&target.pixels)?;
    let placed = project_target_stroke(&target.camera, &filtered, reference_curve)?;
    let target = resampled(&placed, reference_curve.len())?;
    Ok(Tool::Sketch(Box::new(SketchTool {
        partition,
        reference: Curve::Points(reference_curve.to_vec()),
        normal: Some(normal),
        mode: SketchMode::Bend {
            target: Curve::Points(target),
            turning: None,
        },
        scale: None,
        smooth: true,
        refine: None,
    })))
}

/// `points` resampled to `n ≥ 2` points evenly spaced by arc length (the ends kept).
///
/// # Errors
/// Fewer than two points, or a curve of zero length.
pub fn resampled(points: &[Vec3], n: usize) -> Result<Vec<Vec3>> {
    let line = Polyline::new(points, "target curve")?;
    let n = n.max(2);
    Ok((0..n)
        .map(|i| line.point_at(i as f32 / (n - 1) as f32))
        .collect())
}

/// The target of a bend tool whose reference is a 3-D curve that leaves the region
/// undeformed: the reference itself (the rest pose an animator keys before a bend).
#[must_use]
pub fn straight_target(tool: &SketchTool) -> Option<Vec<Vec3>> {
    match (&tool.reference, &tool.mode) {
        (Curve::Points(p), SketchMode::Bend { .. }) => Some(p.clone()),
        _ => None,
    }
}

/// A twist tool about the joint curve of `reference`, by `angle` radians.
#[must_use]
pub fn twist_tool(reference: Stroke, angle: f32, partition: Option<Partition>) -> Tool {
    Tool::Sketch(Box::new(SketchTool {
        partition,
        reference: Curve::Joints(reference),
        normal: None,
        mode: SketchMode::Twist { angle, speed: None },
        scale: None,
        smooth: true,
        refine: None,
    }))
}

#[cfg(test)]
mod tests {
    use ductile_core::mesh::{Mesh, RestMesh};
    use ductile_core::primitives::grid;
    use ductile_core::sketch::camera::Projection;

    use super::*;

    /// A tube along +x, seen from +z with an orthographic camera 10 units wide: pixel x =
    /// 40·(x + 5), y = 40·(5 − y).
    fn tube() -> RestMesh {
        let m: Mesh = grid(41, 17, false, |r, c| {
            let a = std::f32::consts::TAU * (c % 16) as f32 / 16.0;
            Vec3::new(-4.0 + 0.2 * r as f32, 0.5 * a.cos(), 0.5 * a.sin())
        });
        RestMesh::new(m, "tube").unwrap()
    }

    fn camera() -> Camera {
        Camera {
            eye: Vec3::new(0.0, 0.0, 20.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            projection: Projection::Orthographic { height: 10.0 },
            near: 0.1,
            far: 100.0,
            viewport: Vec2::new(400.0, 400.0),
        }
    }

    fn px(x: f32, y: f32) -> Vec2 {
        Vec2::new(40.0 * (x + 5.0), 40.0 * (5.0 - y))
    }

    fn stroke(points: &[(f32, f32)]) -> Stroke {
        let mut pixels = Vec::new();
        for w in points.windows(2) {
            for k in 0..10 {
                let t = k as f32 / 10.0;
                pixels.push(px(
                    w[0].0 + (w[1].0 - w[0].0) * t,
                    w[0].1 + (w[1].1 - w[0].1) * t,
                ));
            }
        }
        let last = points[points.len() - 1];
        pixels.push(px(last.0, last.1));
        Stroke {
            pixels,
            camera: camera(),
        }
    }

    #[test]
    fn a_reference_stroke_gives_a_region_with_a_ramp_and_a_rigid_end() {
        let rest = tube();
        let p = preview(
            SketchKind::Bend,
            &stroke(&[(-1.0, 0.0), (2.0, 0.0)]),
            rest.welded_positions(),
            rest.topology(),
        )
        .unwrap();
        assert!(!p.partition.roi.is_empty() && !p.partition.rigid.is_empty());
        assert!(p.s.iter().all(|s| (0.0..=1.0).contains(s)));
        let colors = p.colors(rest.topology().vertex_count());
        // A region vertex near the start is blue, one near the end red.
        let pos = rest.welded_positions();
        let (first, _) = p
            .partition
            .roi
            .iter()
            .zip(&p.s)
            .min_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
        assert!(pos[*first as usize].x < 0.0);
        assert!(colors[*first as usize][2] > 0.8);
    }

    #[test]
    fn strokes_make_valid_tools() {
        let rest = tube();
        let reference = stroke(&[(-1.0, 0.0), (2.0, 0.0)]);
        let target = stroke(&[(-1.0, 0.0), (0.5, 0.0), (1.5, 1.0)]);
        let tool = bend_tool(reference.clone(), target, None);
        tool.validate("bend").unwrap();
        let layer = ductile_core::stack::Layer::new("bend", tool);
        let out = ductile_core::stack::Stack {
            layers: vec![layer],
        }
        .evaluate_welded(&rest)
        .unwrap();
        assert!(
            out.iter()
                .zip(rest.welded_positions())
                .any(|(a, b)| a.distance(*b) > 0.1)
        );
        let twist = twist_tool(reference, 1.0, None);
        twist.validate("twist").unwrap();
    }

    #[test]
    fn a_bend_on_points_deforms_as_the_stroke_bend_and_its_target_is_keyable() {
        let rest = tube();
        let reference = stroke(&[(-1.0, 0.0), (2.0, 0.0)]);
        let target = stroke(&[(-1.0, 0.0), (0.5, 0.0), (1.5, 1.0)]);
        let run = |tool: Tool| {
            ductile_core::stack::Stack {
                layers: vec![ductile_core::stack::Layer::new("bend", tool)],
            }
            .evaluate_welded(&rest)
            .unwrap()
        };
        let strokes = run(bend_tool(reference.clone(), target.clone(), None));
        let curve = reference_curve(
            SketchKind::Bend,
            &reference,
            rest.welded_positions(),
            rest.topology(),
        )
        .unwrap();
        let tool = bend_tool_on(&curve, &reference, &target, None).unwrap();
        tool.validate("bend").unwrap();
        let points = run(tool.clone());
        // The same bend up to the target's resampling: well under the tube's radius (0.5).
        let worst = strokes
            .iter()
            .zip(&points)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0_f32, f32::max);
        assert!(worst < 0.05, "largest difference {worst}");
        let channels = ductile_anim::channel::tool_channels(&tool);
        assert!(
            channels.iter().any(|(p, _)| p == "mode.target"),
            "{channels:?}"
        );
        // The straight target (the reference itself) leaves the mesh where it is.
        let Tool::Sketch(mut s) = tool else { panic!() };
        let straight = straight_target(&s).unwrap();
        assert_eq!(straight.len(), curve.len());
        if let SketchMode::Bend { target, .. } = &mut s.mode {
            *target = Curve::Points(straight);
        }
        let still = run(Tool::Sketch(s));
        let moved = still
            .iter()
            .zip(rest.welded_positions())
            .map(|(a, b)| a.distance(*b))
            .fold(0.0_f32, f32::max);
        assert!(
            moved < 1e-4,
            "the straight target moved a vertex by {moved}"
        );
    }

    #[test]
    fn twist_angle_is_a_full_turn_per_reference_length_with_a_side() {
        let reference = [Vec2::new(0.0, 100.0), Vec2::new(100.0, 100.0)];
        // 50 px upwards on screen (to the left of a rightward reference): +π.
        let up = [Vec2::new(50.0, 100.0), Vec2::new(50.0, 50.0)];
        assert!((twist_angle(&reference, &up) - std::f32::consts::PI).abs() < 1e-5);
        let down = [Vec2::new(50.0, 100.0), Vec2::new(50.0, 150.0)];
        assert!((twist_angle(&reference, &down) + std::f32::consts::PI).abs() < 1e-5);
        assert_eq!(twist_angle(&[], &up), 0.0);
    }

    #[test]
    fn a_cut_line_makes_the_far_part_rigid() {
        let rest = tube();
        let p = preview(
            SketchKind::Bend,
            &stroke(&[(-3.0, 0.0), (3.0, 0.0)]),
            rest.welded_positions(),
            rest.topology(),
        )
        .unwrap();
        let before = p.partition.roi.len();
        let after = cut(
            &p,
            &camera(),
            [px(1.0, 2.0), px(1.0, -2.0)],
            rest.welded_positions(),
            rest.topology(),
        )
        .unwrap();
        assert!(
            after.partition.roi.len() < before,
            "{} !< {before}",
            after.partition.roi.len()
        );
        assert!(after.partition.rigid.len() >= p.partition.rigid.len());
    }
}
