//! The axial and curve tools as stack layers: parallel chunked evaluation equals one-piece
//! deformation, unmoved tools leave the mesh bit-exact, and the zone of influence composes
//! with the layer weight.

use ductile_core::axial::{AxialTool, AxisPoint, AxisShape};
use ductile_core::curve::{CurveBasis, CurveTool};
use ductile_core::prelude::*;
use ductile_core::primitives;
use glam::Vec3;

/// A wavy `n × n` grid over `[0, 2] × [−0.5, 0.5]`; n = 131 has more vertices than the
/// stack's parallel threshold, so it deforms in chunks.
fn grid(n: usize) -> RestMesh {
    let mesh = primitives::grid(n, n, false, |j, i| {
        let x = 2.0 * i as f32 / (n - 1) as f32;
        let y = j as f32 / (n - 1) as f32 - 0.5;
        Vec3::new(x, y, 0.1 * (3.0 * x).sin() * (2.0 * y).cos())
    });
    RestMesh::new(mesh, "grid").unwrap()
}

fn direct(tool: &Tool, rest: &RestMesh) -> Vec<Vec3> {
    let p = rest.welded_positions();
    let active: Vec<u32> = (0..p.len() as u32).collect();
    let bind = tool
        .bind(&BindInput {
            positions: p,
            topology: rest.topology(),
            active: &active,
        })
        .unwrap();
    let mut out = vec![Vec3::ZERO; p.len()];
    tool.deform(&bind, p, &active, &mut out);
    out
}

fn tools() -> Vec<(Tool, Tool)> {
    let spine: Vec<Vec3> = (0..6)
        .map(|i| Vec3::new(0.4 * i as f32, 0.0, 0.0))
        .collect();
    let mut bent = spine.clone();
    bent[4] += Vec3::new(0.0, 0.3, 0.1);
    bent[5] += Vec3::new(-0.2, 0.7, 0.0);
    let axis: Vec<AxisPoint> = spine.iter().copied().map(AxisPoint::at).collect();
    let mut axis_bent: Vec<AxisPoint> = bent.iter().copied().map(AxisPoint::at).collect();
    axis_bent[5].twist = 0.5;
    axis_bent[3].scale = 1.2;
    let axial = AxialTool {
        shape: AxisShape::BSpline { degree: 3 },
        ..AxialTool::new(axis, 0.4)
    };
    let curve = CurveTool::new(CurveBasis::BSpline { degree: 3 }, spine);
    vec![
        (
            Tool::Axial(axial.clone()),
            Tool::Axial(AxialTool {
                deformed: axis_bent,
                ..axial
            }),
        ),
        (
            Tool::Curve(curve.clone()),
            Tool::Curve(CurveTool {
                deformed: bent,
                ..curve
            }),
        ),
    ]
}

#[test]
fn chunked_stack_equals_direct_and_unmoved_is_bit_exact() {
    let rest = grid(131);
    assert!(rest.welded_positions().len() > 16_384);
    for (unmoved, moved) in tools() {
        let stack = Stack {
            layers: vec![Layer::new("still", unmoved)],
        };
        assert_eq!(
            stack.evaluate_welded(&rest).unwrap(),
            rest.welded_positions()
        );
        let stack = Stack {
            layers: vec![Layer::new("bend", moved.clone())],
        };
        let out = stack.evaluate_welded(&rest).unwrap();
        assert_eq!(out, direct(&moved, &rest));
        assert!(
            out.iter()
                .zip(rest.welded_positions())
                .any(|(a, b)| a.distance(*b) > 0.1)
        );
    }
}

#[test]
fn layer_weight_scales_the_displacement() {
    let rest = grid(31);
    for (_, moved) in tools() {
        let full = direct(&moved, &rest);
        let mut layer = Layer::new("half", moved);
        layer.weight = 0.5;
        let half = Stack {
            layers: vec![layer],
        }
        .evaluate_welded(&rest)
        .unwrap();
        for ((h, f), r) in half.iter().zip(&full).zip(rest.welded_positions()) {
            assert!((*h - (*r + (*f - *r) * 0.5)).length() < 1e-6);
        }
    }
}
