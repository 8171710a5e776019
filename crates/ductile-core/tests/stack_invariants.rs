//! Invariants of the deformation stack with FFSD tools, checked on random inputs.

use ductile_core::prelude::*;
use ductile_core::primitives;
use glam::{Affine3A, Vec3};
use proptest::prelude::*;

/// A bumpy `n × n` grid (n odd) that is exactly mirror-symmetric about x = 0: vertex
/// `(i, j)` mirrors to `(n − 1 − i, j)`.
fn grid(n: usize) -> RestMesh {
    let c = (n / 2) as f32;
    let h = 2.0 / (n - 1) as f32;
    let mesh = primitives::grid(n, n, false, |j, i| {
        let x = (i as f32 - c) * h;
        let y = (j as f32 - c) * h;
        Vec3::new(x, y, 0.2 * (2.0 * x).cos() * (1.5 * y).sin())
    });
    RestMesh::new(mesh, "grid").unwrap()
}

fn mirror(p: Vec3) -> Vec3 {
    Vec3::new(-p.x, p.y, p.z)
}

fn point() -> impl Strategy<Value = ControlPoint> {
    (
        -1.0f32..1.0,
        -1.0f32..1.0,
        0.05f32..0.8,
        -0.8f32..0.8,
        0.3f32..2.0,
        0.1f32..0.8,
        0..3u8,
    )
        .prop_map(|(x, y, z, gamma, alpha, epsilon, mode)| {
            let position = Vec3::new(x, y, z);
            let mode = match mode {
                0 => PointMode::Basic,
                1 => PointMode::Virtual,
                _ => PointMode::Directional {
                    reference: Vec3::new(x * 0.8, y * 0.8, 0.0),
                },
            };
            ControlPoint {
                position,
                mode,
                gamma,
                alpha,
                epsilon,
            }
        })
}

fn evaluate(rest: &RestMesh, layers: Vec<Layer>) -> Vec<Vec3> {
    Stack { layers }.evaluate_welded(rest).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// With ϑ from above, no vertex moves further than ϑ·S_ref, and a vertex whose
    /// unlimited displacement was within that bound moves exactly as without the limit.
    #[test]
    fn height_from_above_bounds_every_displacement(points in prop::collection::vec(point(), 1..4), theta in 0.05f32..1.0) {
        let rest = grid(15);
        let free = FfsdTool::new(points);
        let mut limited = free.clone();
        limited.height = Some(HeightLimit::Above { theta });
        let all: Vec<u32> = (0..rest.welded_positions().len() as u32).collect();
        let bind = limited
            .bind(&BindInput { positions: rest.welded_positions(), topology: rest.topology(), active: &all })
            .unwrap();
        let s_max = theta * bind.reference_size();
        let a = evaluate(&rest, vec![Layer::new("free", Tool::Ffsd(free))]);
        let b = evaluate(&rest, vec![Layer::new("limited", Tool::Ffsd(limited))]);
        for ((v, pa), pb) in rest.welded_positions().iter().zip(&a).zip(&b) {
            let (da, db) = ((*pa - *v).length(), (*pb - *v).length());
            prop_assert!(db <= s_max * (1.0 + 1e-5) + 1e-6, "moved {db} > S_max {s_max}");
            if da < s_max * (1.0 - 1e-4) {
                prop_assert_eq!(pa, pb);
            }
        }
    }

    /// Vertices outside a layer's influence keep their input bits; a disabled layer and a
    /// layer of weight 0 leave the mesh bit-identical to the rest mesh.
    #[test]
    fn outside_disabled_and_zero_weight_are_bit_exact(points in prop::collection::vec(point(), 1..4), radius in 0.2f32..0.9, cx in -0.5f32..0.5) {
        let rest = grid(15);
        let tool = Tool::Ffsd(FfsdTool::new(points));
        let volume = Volume::new(Shape::Sphere { radius }, Affine3A::from_translation(Vec3::new(cx, 0.0, 0.0)), "v").unwrap();
        let mut layer = Layer::new("t", tool.clone());
        layer.influence = Some(Influence { volumes: vec![volume.clone()], area: None, falloff: Falloff::Smooth, inner: 0.2, invert: false });
        let out = evaluate(&rest, vec![layer]);
        for (v, p) in rest.welded_positions().iter().zip(&out) {
            if volume.normalized_distance(*v) >= 1.0 {
                prop_assert_eq!(v.to_array().map(f32::to_bits), p.to_array().map(f32::to_bits));
            }
        }
        let mut disabled = Layer::new("t", tool.clone());
        disabled.enabled = false;
        let mut zero = Layer::new("t", tool);
        zero.weight = 0.0;
        let out = evaluate(&rest, vec![disabled, zero]);
        prop_assert_eq!(out.as_slice(), rest.welded_positions());
    }

    /// A macro made of mirrored point pairs gives a mirror-symmetric result on a
    /// mirror-symmetric mesh.
    #[test]
    fn symmetric_macros_give_symmetric_results(points in prop::collection::vec(point(), 1..3), theta in 0.3f32..1.0) {
        let rest = grid(15);
        let mut all_points = Vec::new();
        for p in points {
            let mut m = p;
            m.position = mirror(p.position);
            if let PointMode::Directional { reference } = p.mode {
                m.mode = PointMode::Directional { reference: mirror(reference) };
            }
            all_points.extend([p, m]);
        }
        let mac = FfsdMacro { label: "pair".into(), group: String::new(), area: None, points: all_points, height: Some(HeightLimit::Above { theta }), range: (-1.0, 1.0) };
        let out = evaluate(&rest, vec![Layer::new("m", Tool::Ffsd(mac.tool(0.7)))]);
        let n = 15;
        for j in 0..n {
            for i in 0..n {
                let (a, b) = (out[j * n + i], out[j * n + (n - 1 - i)]);
                prop_assert!((mirror(a) - b).length() < 1e-5, "({i},{j}): {a} vs {b}");
            }
        }
    }
}

#[test]
fn named_area_limits_evaluation_to_its_vertices() {
    let rest = grid(9);
    let area: Vec<u32> = (0..20).collect();
    let mut layer = Layer::new(
        "t",
        Tool::Ffsd(FfsdTool::new(vec![ControlPoint::basic(
            Vec3::new(0.0, 0.0, 0.5),
            0.8,
            1.0,
            1.0,
        )])),
    );
    layer.influence = Some(Influence {
        area: Some(area.clone()),
        ..Influence::default()
    });
    let out = evaluate(&rest, vec![layer]);
    for (i, (v, p)) in rest.welded_positions().iter().zip(&out).enumerate() {
        if area.contains(&(i as u32)) {
            assert_ne!(v, p, "vertex {i} in the area should move");
        } else {
            assert_eq!(v, p, "vertex {i} outside the area moved");
        }
    }
}
