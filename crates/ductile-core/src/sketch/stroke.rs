//! Strokes drawn in the image plane and their placement in 3-D (Kho & Garland 2005, §4.1,
//! §5.1 "Preparation" and §5.2).
//!
//! A stroke is a polyline in pixels (origin top-left, y down, see
//! [`camera`](crate::sketch::camera)). [`filter_stroke`] smooths and regularises it,
//! [`project_stroke`] places the reference curve on the view-parallel plane through the
//! first ray–mesh hit, [`project_target_stroke`] places a target stroke on that same plane
//! and [`joint_curve`] builds the in-mesh twisting axis from front and back hits.

use glam::{Vec2, Vec3};

use crate::error::{CoreError, Result};
use crate::mesh::Topology;
use crate::sketch::camera::{Camera, Ray};
use crate::sketch::raycast::Bvh;

/// Shortest segment of a filtered stroke, in pixels (Kho & Garland §4.1: "merging
/// neighboring segments so that each segment will be at least 5 pixels in length").
pub const MIN_SEGMENT_PX: f32 = 5.0;

/// Weights of the averaging filter `(previous, self, next)` applied once to every interior
/// stroke point (Kho & Garland §4.1 "a simple averaging filter"; the paper gives no weights,
/// we take the plain three-point mean). End points are kept where the user pressed and
/// released.
pub const AVERAGING_WEIGHTS: [f32; 3] = [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0];

/// A plane parallel to the image plane: all points `x` with `normal · (x − point) = 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SketchPlane {
    /// A point on the plane (the first hit of the reference stroke).
    pub point: Vec3,
    /// Unit normal: the camera's view direction.
    pub normal: Vec3,
}

impl SketchPlane {
    /// The view-parallel plane of `camera` through `point` (Kho & Garland §4.1).
    #[must_use]
    pub fn view_parallel(camera: &Camera, point: Vec3) -> Self {
        Self {
            point,
            normal: camera.forward(),
        }
    }

    /// Where `ray` meets the plane, `None` when it is parallel to it or the plane is behind
    /// the ray's origin.
    #[must_use]
    pub fn intersect(&self, ray: &Ray) -> Option<Vec3> {
        let denom = self.normal.dot(ray.direction);
        if denom.abs() < 1e-8 {
            return None;
        }
        let t = self.normal.dot(self.point - ray.origin) / denom;
        (t >= 0.0 && t.is_finite()).then(|| ray.origin + ray.direction * t)
    }
}

/// Smooths and regularises a raw stroke (Kho & Garland §4.1).
///
/// 1. Averaging filter: every interior point `pᵢ` becomes `(pᵢ₋₁ + pᵢ + pᵢ₊₁)/3` (computed
///    from the raw points, see [`AVERAGING_WEIGHTS`]); the end points are kept.
/// 2. Merge: walking from the first point, a point is kept only when it is at least
///    [`MIN_SEGMENT_PX`] from the last kept point. The last point is always kept; if its
///    segment is shorter than 5 px it replaces the last kept point (the two last segments
///    merge), repeatedly, so every segment of the result is ≥ 5 px.
///
/// Input and output are in pixels.
///
/// # Errors
/// [`CoreError::NotFinite`] naming the stroke point index for a NaN/infinite coordinate;
/// [`CoreError::StrokeTooShort`] when fewer than two points remain (the stroke spans less
/// than 5 px).
pub fn filter_stroke(points_px: &[Vec2]) -> Result<Vec<Vec2>> {
    check_stroke("stroke", points_px)?;
    let [wp, ws, wn] = AVERAGING_WEIGHTS;
    let n = points_px.len();
    let smoothed: Vec<Vec2> = (0..n)
        .map(|i| {
            if i == 0 || i == n - 1 {
                points_px[i]
            } else {
                points_px[i - 1] * wp + points_px[i] * ws + points_px[i + 1] * wn
            }
        })
        .collect();
    Ok(merge_short_segments(&smoothed, MIN_SEGMENT_PX)).and_then(|kept| {
        if kept.len() < 2 {
            Err(CoreError::StrokeTooShort {
                what: format!("stroke (after merging segments shorter than {MIN_SEGMENT_PX} px)"),
                found: kept.len(),
                needed: 2,
            })
        } else {
            Ok(kept)
        }
    })
}

/// Merges neighbouring segments of a polyline until every segment is at least `min_len`
/// long (see [`filter_stroke`]). Returns a single point when the whole polyline stays
/// within `min_len` of its first point.
#[must_use]
pub fn merge_short_segments(points: &[Vec2], min_len: f32) -> Vec<Vec2> {
    let Some((&first, rest)) = points.split_first() else {
        return Vec::new();
    };
    let mut kept = vec![first];
    for &p in rest {
        if let Some(&last) = kept.last()
            && p.distance(last) >= min_len
        {
            kept.push(p);
        }
    }
    if let Some(&end) = points.last()
        && kept.len() > 1
        && kept.last() != Some(&end)
    {
        // The final raw point fell within `min_len` of the last kept one: it replaces it,
        // then merge backwards while the closing segment is still too short.
        kept.pop();
        while kept.len() > 1 && kept.last().is_some_and(|&l| l.distance(end) < min_len) {
            kept.pop();
        }
        if kept.last().is_some_and(|&l| l.distance(end) >= min_len) {
            kept.push(end);
        }
    }
    kept
}

/// Places a filtered reference stroke in 3-D (Kho & Garland §4.1): the ray through the
/// first stroke point that hits the mesh defines the hit point `h`; the curve is the
/// intersection of each stroke point's ray with the plane through `h` whose normal is the
/// view direction (so the curve projects exactly onto the stroke).
///
/// The paper uses the first stroke point; when it misses the mesh we use the first point
/// that hits (so a stroke may start in the background). `positions` and `topology` must be
/// the ones `bvh` was built from; they are only used to check that.
///
/// # Errors
/// [`CoreError::StrokeTooShort`] for fewer than two points, [`CoreError::NotFinite`] for a
/// bad coordinate, [`CoreError::Degenerate`] when the hierarchy does not match the
/// topology, [`CoreError::StrokeMissesMesh`] when no point hits and
/// [`CoreError::StrokeProjection`] naming a point whose ray does not meet the plane.
pub fn project_stroke(
    camera: &Camera,
    stroke_px: &[Vec2],
    positions: &[Vec3],
    topology: &Topology,
    bvh: &Bvh,
) -> Result<Vec<Vec3>> {
    check_stroke("reference stroke", stroke_px)?;
    if bvh.triangle_count() != topology.triangles.len()
        || positions.len() != topology.vertex_count()
    {
        return Err(CoreError::Degenerate {
            what: "reference stroke".to_owned(),
            problem: format!(
                "the ray-casting hierarchy has {} triangles and the topology {} ({} positions for {} welded vertices); rebuild it from the same mesh",
                bvh.triangle_count(),
                topology.triangles.len(),
                positions.len(),
                topology.vertex_count()
            ),
        });
    }
    let hit = stroke_px.iter().find_map(|&px| {
        let ray = camera.ray(px);
        bvh.intersect(&ray).map(|h| h.point(&ray))
    });
    let Some(hit) = hit else {
        return Err(CoreError::StrokeMissesMesh {
            what: "reference stroke".to_owned(),
            points: stroke_px.len(),
        });
    };
    project_onto_plane(
        camera,
        stroke_px,
        &SketchPlane::view_parallel(camera, hit),
        "reference stroke",
    )
}

/// Places a filtered target stroke on the sketch plane of `reference_curve` (Kho & Garland
/// §5.1 "Preparation"): the stroke is first translated in the image plane so that its first
/// point coincides with the projection of the reference curve's first point ("to prevent
/// the mesh from tearing"), then each point's ray is intersected with the view-parallel
/// plane through `reference_curve[0]`. The camera must be the one the reference curve was
/// drawn with.
///
/// # Errors
/// As [`project_onto_plane`]; [`CoreError::StrokeTooShort`] when the reference curve is
/// empty and [`CoreError::StrokeProjection`] when its first point is behind the eye.
pub fn project_target_stroke(
    camera: &Camera,
    target_px: &[Vec2],
    reference_curve: &[Vec3],
) -> Result<Vec<Vec3>> {
    check_stroke("target stroke", target_px)?;
    let Some(&start) = reference_curve.first() else {
        return Err(CoreError::StrokeTooShort {
            what: "reference curve of the target stroke".to_owned(),
            found: 0,
            needed: 1,
        });
    };
    let Some((start_px, _)) = camera.project(start) else {
        return Err(CoreError::StrokeProjection {
            what: "reference curve".to_owned(),
            index: 0,
            problem: "the point is behind the eye".to_owned(),
        });
    };
    let shift = start_px - target_px[0];
    let moved: Vec<Vec2> = target_px.iter().map(|&p| p + shift).collect();
    project_onto_plane(
        camera,
        &moved,
        &SketchPlane::view_parallel(camera, start),
        "target stroke",
    )
}

/// Intersects the ray through every stroke point with `plane` (no translation). `what`
/// names the stroke in errors.
///
/// # Errors
/// [`CoreError::StrokeProjection`] naming the first point whose ray is parallel to the
/// plane or meets it behind the eye.
pub fn project_onto_plane(
    camera: &Camera,
    stroke_px: &[Vec2],
    plane: &SketchPlane,
    what: &str,
) -> Result<Vec<Vec3>> {
    stroke_px
        .iter()
        .enumerate()
        .map(|(i, &px)| {
            plane
                .intersect(&camera.ray(px))
                .ok_or_else(|| CoreError::StrokeProjection {
                    what: what.to_owned(),
                    index: i,
                    problem: "its ray does not meet the view-parallel plane in front of the eye"
                        .to_owned(),
                })
        })
        .collect()
}

/// The joint curve for twisting (Kho & Garland §5.2): for each node of the (filtered)
/// reference stroke, the ray through it is cast against the mesh and the joint is the
/// midpoint of the first hit (nearest front face) and the second distinct hit (the back
/// face where the ray leaves the part). The curve projects onto the same stroke on screen.
///
/// Hits closer than `1e-5 · max(t₁, 1)` along the ray (`t₁` the first hit distance) count as
/// one (a ray through a shared edge reports both triangles).
///
/// # Errors
/// [`CoreError::StrokeTooShort`] / [`CoreError::NotFinite`] for a bad stroke and
/// [`CoreError::SingleHit`] naming the first node whose ray hits the mesh fewer than twice
/// (the paper disallows twisting then).
pub fn joint_curve(camera: &Camera, reference_px: &[Vec2], bvh: &Bvh) -> Result<Vec<Vec3>> {
    check_stroke("twist reference stroke", reference_px)?;
    reference_px
        .iter()
        .enumerate()
        .map(|(node, &px)| {
            let ray = camera.ray(px);
            let hits = bvh.intersect_all(&ray);
            let mut distinct = hits.iter().map(|h| h.t);
            let first = distinct.next();
            let second = first.and_then(|f| distinct.find(|&t| t - f > 1e-5 * f.max(1.0)));
            match (first, second) {
                (Some(a), Some(b)) => Ok(ray.origin + ray.direction * (0.5 * (a + b))),
                _ => Err(CoreError::SingleHit {
                    what: "twist reference curve".to_owned(),
                    node,
                    hits: usize::from(first.is_some()),
                }),
            }
        })
        .collect()
}

/// [`joint_curve`] for a reference curve already in 3-D: its nodes are projected to pixels
/// with `camera` first.
///
/// # Errors
/// As [`joint_curve`]; [`CoreError::StrokeProjection`] for a node behind the eye.
pub fn joint_curve_from_curve(camera: &Camera, curve: &[Vec3], bvh: &Bvh) -> Result<Vec<Vec3>> {
    let px = curve
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            camera
                .project(p)
                .map(|(px, _)| px)
                .ok_or_else(|| CoreError::StrokeProjection {
                    what: "twist reference curve".to_owned(),
                    index: i,
                    problem: "the node is behind the eye".to_owned(),
                })
        })
        .collect::<Result<Vec<_>>>()?;
    joint_curve(camera, &px, bvh)
}

/// At least two finite points.
fn check_stroke(what: &str, stroke_px: &[Vec2]) -> Result<()> {
    if let Some(i) = stroke_px.iter().position(|p| !p.is_finite()) {
        return Err(CoreError::NotFinite {
            what: format!("{what}: point {i}"),
            value: format!("{}", stroke_px[i]),
        });
    }
    if stroke_px.len() < 2 {
        return Err(CoreError::StrokeTooShort {
            what: what.to_owned(),
            found: stroke_px.len(),
            needed: 2,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::sketch::camera::Projection;
    use crate::sketch::raycast::tests::cylinder;

    fn camera(projection: Projection) -> Camera {
        Camera {
            eye: Vec3::new(0.0, 2.0, 6.0),
            target: Vec3::new(0.0, 2.0, 0.0),
            up: Vec3::Y,
            projection,
            near: 0.1,
            far: 100.0,
            viewport: Vec2::new(800.0, 600.0),
        }
    }

    fn cylinder_mesh() -> (Vec<Vec3>, Topology, Bvh) {
        let (p, t) = cylinder(32, 16, 0.5, 4.0);
        let mesh = Mesh {
            positions: p.clone(),
            normals: None,
            uvs: None,
            indices: t.iter().flatten().copied().collect(),
        };
        let topo = Topology::weld(&mesh);
        let welded = topo.gather(&mesh.positions);
        let bvh = Bvh::build(&welded, &topo.triangles).unwrap();
        (welded, topo, bvh)
    }

    #[test]
    fn merge_rule_makes_every_segment_at_least_five_pixels() {
        // 1-px steps along x: keeps 0, 5, 10, ... and merges the 2-px tail.
        let raw: Vec<Vec2> = (0..=22).map(|i| Vec2::new(i as f32, 0.0)).collect();
        let out = merge_short_segments(&raw, 5.0);
        let xs: Vec<f32> = out.iter().map(|p| p.x).collect();
        assert_eq!(xs, vec![0.0, 5.0, 10.0, 15.0, 22.0]);
        for w in out.windows(2) {
            assert!(w[0].distance(w[1]) >= 5.0);
        }
        // A stroke spanning less than 5 px collapses to one point.
        let tiny = [Vec2::ZERO, Vec2::new(1.0, 1.0), Vec2::new(2.0, 2.0)];
        assert_eq!(merge_short_segments(&tiny, 5.0).len(), 1);
        assert!(matches!(
            filter_stroke(&tiny),
            Err(CoreError::StrokeTooShort { found: 1, .. })
        ));
    }

    #[test]
    fn averaging_filter_uses_the_three_point_mean() {
        // A zig-zag of ±3 px in y around a line with 6-px x steps.
        let raw: Vec<Vec2> = (0..6)
            .map(|i| Vec2::new(6.0 * i as f32, if i % 2 == 0 { 3.0 } else { -3.0 }))
            .collect();
        let out = filter_stroke(&raw).unwrap();
        assert_eq!(out[0], raw[0]);
        assert_eq!(*out.last().unwrap(), raw[5]);
        // Interior point 1: ((0,3) + (6,-3) + (12,3))/3 = (6, 1).
        assert!((out[1] - Vec2::new(6.0, 1.0)).length() < 1e-5);
        // Point 2: ((6,-3) + (12,3) + (18,-3))/3 = (12, -1).
        assert!((out[2] - Vec2::new(12.0, -1.0)).length() < 1e-5);
    }

    #[test]
    fn non_finite_stroke_point_is_named() {
        let err = filter_stroke(&[Vec2::ZERO, Vec2::new(f32::NAN, 1.0)]).unwrap_err();
        assert!(err.to_string().contains("stroke: point 1"), "{err}");
    }

    #[test]
    fn projection_lies_on_view_parallel_plane_through_first_hit() {
        let (p, topo, bvh) = cylinder_mesh();
        for proj in [
            Projection::Perspective { fov_y: 0.8 },
            Projection::Orthographic { height: 6.0 },
        ] {
            let cam = camera(proj);
            // Stroke from beside the cylinder (a miss) across its front to the far side.
            let a = cam.project(Vec3::new(-1.5, 1.0, 0.0)).unwrap().0;
            let b = cam.project(Vec3::new(1.5, 3.0, 0.0)).unwrap().0;
            let stroke: Vec<Vec2> = (0..=20).map(|i| a.lerp(b, i as f32 / 20.0)).collect();
            let curve = project_stroke(&cam, &stroke, &p, &topo, &bvh).unwrap();
            assert_eq!(curve.len(), stroke.len());
            // The first hitting point lies on the front of the cylinder, z ≈ depth of hit.
            let first = stroke
                .iter()
                .find_map(|&px| bvh.intersect(&cam.ray(px)).map(|h| h.point(&cam.ray(px))))
                .unwrap();
            for (c, &px) in curve.iter().zip(&stroke) {
                // On the plane through the hit with the view normal (here: z = first.z).
                assert!((c.z - first.z).abs() < 1e-3, "{proj:?} {c} {first}");
                // Projects back onto the stroke.
                let back = cam.project(*c).unwrap().0;
                assert!(back.distance(px) < 1e-2, "{proj:?}");
            }
            assert!(first.z > 0.0 && first.z <= 0.5 + 1e-4);
        }
    }

    #[test]
    fn stroke_missing_the_mesh_is_an_error() {
        let (p, topo, bvh) = cylinder_mesh();
        let cam = camera(Projection::Perspective { fov_y: 0.8 });
        let stroke = [Vec2::new(10.0, 10.0), Vec2::new(30.0, 10.0)];
        let err = project_stroke(&cam, &stroke, &p, &topo, &bvh).unwrap_err();
        assert!(matches!(err, CoreError::StrokeMissesMesh { points: 2, .. }));
    }

    #[test]
    fn target_stroke_starts_at_reference_start_on_the_same_plane() {
        let (p, topo, bvh) = cylinder_mesh();
        let cam = camera(Projection::Perspective { fov_y: 0.8 });
        let a = cam.project(Vec3::new(0.0, 1.0, 0.5)).unwrap().0;
        let b = cam.project(Vec3::new(0.0, 3.0, 0.5)).unwrap().0;
        let reference = project_stroke(&cam, &[a, b], &p, &topo, &bvh).unwrap();
        let target = [a + Vec2::new(40.0, 0.0), a + Vec2::new(140.0, -60.0)];
        let curve = project_target_stroke(&cam, &target, &reference).unwrap();
        assert!(curve[0].distance(reference[0]) < 1e-3);
        for c in &curve {
            assert!((c.z - reference[0].z).abs() < 1e-3);
        }
    }

    #[test]
    fn joint_curve_of_a_cylinder_lies_on_its_axis() {
        let (_, _, bvh) = cylinder_mesh();
        let cam = camera(Projection::Orthographic { height: 6.0 });
        let a = cam.project(Vec3::new(0.0, 0.5, 0.5)).unwrap().0;
        let b = cam.project(Vec3::new(0.0, 3.5, 0.5)).unwrap().0;
        let stroke: Vec<Vec2> = (0..=10).map(|i| a.lerp(b, i as f32 / 10.0)).collect();
        let joints = joint_curve(&cam, &stroke, &bvh).unwrap();
        for j in &joints {
            // The cylinder is a 32-gon, so the midpoint of front/back lies on the axis.
            assert!(j.x.abs() < 1e-3 && j.z.abs() < 1e-3, "{j}");
        }
        assert!((joints[0].y - 0.5).abs() < 1e-3 && (joints[10].y - 3.5).abs() < 1e-3);
        // The same from a 3-D curve.
        let curve: Vec<Vec3> = (0..=4)
            .map(|i| Vec3::new(0.1, 0.5 + 0.75 * i as f32, 0.5))
            .collect();
        let joints = joint_curve_from_curve(&cam, &curve, &bvh).unwrap();
        assert!(joints.iter().all(|j| j.x.abs() < 0.11 && j.z.abs() < 1e-3));
    }

    #[test]
    fn joint_curve_names_the_node_with_one_hit() {
        let (_, _, bvh) = cylinder_mesh();
        let cam = camera(Projection::Orthographic { height: 6.0 });
        let inside = cam.project(Vec3::new(0.0, 2.0, 0.5)).unwrap().0;
        let beside = cam.project(Vec3::new(2.0, 2.0, 0.5)).unwrap().0;
        let stroke = [inside, inside + Vec2::new(0.0, 10.0), beside];
        let err = joint_curve(&cam, &stroke, &bvh).unwrap_err();
        assert!(
            matches!(
                err,
                CoreError::SingleHit {
                    node: 2,
                    hits: 0,
                    ..
                }
            ),
            "{err}"
        );
        assert!(err.to_string().contains("node 2"));
        // An open sheet gives exactly one hit.
        let sheet = Bvh::build(
            &[
                Vec3::new(-5.0, -5.0, 0.0),
                Vec3::new(5.0, -5.0, 0.0),
                Vec3::new(0.0, 5.0, 0.0),
            ],
            &[[0, 1, 2]],
        )
        .unwrap();
        let err = joint_curve(&cam, &stroke, &sheet).unwrap_err();
        assert!(matches!(
            err,
            CoreError::SingleHit {
                node: 0,
                hits: 1,
                ..
            }
        ));
    }
}
