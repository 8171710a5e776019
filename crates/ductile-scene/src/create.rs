//! New tools and volumes, placed sensibly around a mesh: what the Studio's Add menu makes.
//!
//! Every template is given the mesh's bounds (or a selected area's) and, where it needs one, a
//! point on the surface with its normal (under the cursor, or the mesh's front). The rules
//! (`docs/user-guide.md` shows them):
//!
//! * a **lattice** fits the bounds (padded by 2 %): Bernstein 3×3×3 (degree 2 per axis),
//!   B-spline 4×4×4 (quadratic), or a rational B-spline 4×4×4 (the same, its control weights
//!   meant to be edited; all 1 at first, so it starts as the identity);
//! * a **curve** (Bézier, cubic B-spline) and an **axial** axis run along the longest axis of
//!   the bounds through their centre, over 90 % of its length; the axial radius is a third of
//!   the bounds' second-longest side;
//! * an **FFSD point** is a directional point at the surface point: `R` on the surface, `C` a
//!   twentieth of the bounds' diagonal out along the normal, `γ = 1`, `α = 2`, `ε` a
//!   fifteenth of the diagonal: a bump pulled out along the normal, which grows as `C` is
//!   dragged out;
//! * a **DOGME** constraint and a **Direct FFD** constraint sit at the surface point with a
//!   displacement of a twentieth of the diagonal along the normal (DOGME: a support sphere of
//!   a fifth of the diagonal; Direct FFD: on a 3×3×3 lattice around the bounds);
//! * a **shape surface** is a 4×4 cubic net across the bounds' two longest sides, through the
//!   centre (no move yet: the identity);
//! * **volumes** sit at the centre of the bounds: a sphere of a quarter of the diagonal, a box
//!   of half the bounds, a capsule and a tube along the longest axis.

use ductile_core::axial::{AxialTool, AxisPoint};
use ductile_core::curve::{CurveBasis, CurveTool};
use ductile_core::direct_ffd::{DirectConstraint, DirectFfdTool};
use ductile_core::dogme::{Anchor, Constraint, DogmeTool, Support};
use ductile_core::ffsd::{ControlPoint, FfsdTool, PointMode};
use ductile_core::influence::{Falloff, Shape};
use ductile_core::lattice::{LatticeBasis, LatticeFrame, LatticeTool};
use ductile_core::mesh::RestMesh;
use ductile_core::sketch::camera::Ray;
use ductile_core::sketch::raycast::Bvh;
use ductile_core::surface::{ShapeSurfaceTool, SurfaceFrame};
use ductile_core::tool::Tool;
use glam::{Quat, Vec3};

use crate::transform::Transform;

/// The kinds of lattice the Add menu offers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LatticeKind {
    /// Bernstein basis (Sederberg–Parry), 3×3×3, degree 2.
    Bernstein,
    /// Quadratic B-spline basis, 4×4×4 (local support).
    BSpline,
    /// Rational quadratic B-spline, 4×4×4: control weights to edit (all 1 at first).
    Rational,
}

/// A tool the Add menu creates (the sketch tool is made by drawing strokes instead).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NewTool {
    /// One directional FFSD control point.
    FfsdPoint,
    /// One DOGME constraint point.
    Dogme,
    /// Direct FFD: one constraint on a lattice.
    DirectFfd,
    /// Axial deformation along the longest axis.
    Axial,
    /// Bézier curve deformation (De Casteljau, global).
    BezierCurve,
    /// Cubic B-spline curve deformation (De Boor, local).
    BSplineCurve,
    /// A shape surface across the bounds.
    ShapeSurface,
    /// A lattice fitting the bounds.
    Lattice(LatticeKind),
}

impl NewTool {
    /// Every tool kind, in menu order.
    pub const ALL: [NewTool; 10] = [
        NewTool::FfsdPoint,
        NewTool::Dogme,
        NewTool::DirectFfd,
        NewTool::Axial,
        NewTool::BezierCurve,
        NewTool::BSplineCurve,
        NewTool::ShapeSurface,
        NewTool::Lattice(LatticeKind::Bernstein),
        NewTool::Lattice(LatticeKind::BSpline),
        NewTool::Lattice(LatticeKind::Rational),
    ];

    /// The menu label.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            NewTool::FfsdPoint => "FFSD control point",
            NewTool::Dogme => "DOGME constraint",
            NewTool::DirectFfd => "Direct FFD",
            NewTool::Axial => "Axial deformation",
            NewTool::BezierCurve => "Bézier curve deformation",
            NewTool::BSplineCurve => "B-spline curve deformation",
            NewTool::ShapeSurface => "Shape surface",
            NewTool::Lattice(LatticeKind::Bernstein) => "Lattice (Bernstein)",
            NewTool::Lattice(LatticeKind::BSpline) => "Lattice (B-spline)",
            NewTool::Lattice(LatticeKind::Rational) => "Lattice (rational B-spline)",
        }
    }

    /// The stem of the new node's name.
    #[must_use]
    pub fn stem(self) -> &'static str {
        match self {
            NewTool::FfsdPoint => "point",
            NewTool::Dogme => "dogme",
            NewTool::DirectFfd => "direct-ffd",
            NewTool::Axial => "axial",
            NewTool::BezierCurve | NewTool::BSplineCurve => "curve",
            NewTool::ShapeSurface => "surface",
            NewTool::Lattice(_) => "lattice",
        }
    }

    /// True when the tool is placed at a surface point.
    #[must_use]
    pub fn needs_surface(self) -> bool {
        matches!(
            self,
            NewTool::FfsdPoint | NewTool::Dogme | NewTool::DirectFfd
        )
    }
}

/// A volume shape the Add menu creates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NewVolume {
    /// A sphere.
    Sphere,
    /// A box.
    Box,
    /// A capsule along the longest axis.
    Capsule,
    /// A generalised cylinder around a curve along the longest axis.
    Tube,
}

impl NewVolume {
    /// Every volume shape, in menu order.
    pub const ALL: [NewVolume; 4] = [
        NewVolume::Sphere,
        NewVolume::Box,
        NewVolume::Capsule,
        NewVolume::Tube,
    ];

    /// The menu label.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            NewVolume::Sphere => "Sphere volume",
            NewVolume::Box => "Box volume",
            NewVolume::Capsule => "Capsule volume",
            NewVolume::Tube => "Tube volume (around a curve)",
        }
    }

    /// The stem of the new node's name.
    #[must_use]
    pub fn stem(self) -> &'static str {
        match self {
            NewVolume::Sphere => "sphere",
            NewVolume::Box => "box",
            NewVolume::Capsule => "capsule",
            NewVolume::Tube => "tube",
        }
    }
}

/// A point on the surface and the outward normal there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// The point.
    pub position: Vec3,
    /// Unit outward normal.
    pub normal: Vec3,
}

/// Where a new tool goes: the bounds it should fit (the mesh's, or a selected area's, in the
/// mesh's frame) and, for tools placed on the surface, the surface point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
    /// A surface point (under the cursor, or the front of the mesh); the front of the bounds
    /// (their +Z face's centre, normal +Z) when `None`.
    pub surface: Option<SurfacePoint>,
}

impl Placement {
    /// The bounds of `points` (no surface point); `None` when there are none or they are not
    /// finite.
    #[must_use]
    pub fn around(points: &[Vec3]) -> Option<Self> {
        let (min, max) = ductile_core::mesh::bounds(points)?;
        (min.is_finite() && max.is_finite()).then_some(Self {
            min,
            max,
            surface: None,
        })
    }

    /// The rest mesh's bounds and its front point ([`front_point`]).
    #[must_use]
    pub fn on_mesh(rest: &RestMesh) -> Option<Self> {
        let mut p = Self::around(rest.welded_positions())?;
        p.surface = front_point(rest);
        Some(p)
    }

    fn centre(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    fn size(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::splat(1e-6))
    }

    fn diagonal(&self) -> f32 {
        self.size().length()
    }

    /// The unit axis of the longest side, and that side's length.
    fn longest(&self) -> (Vec3, f32) {
        let s = self.size();
        if s.x >= s.y && s.x >= s.z {
            (Vec3::X, s.x)
        } else if s.y >= s.z {
            (Vec3::Y, s.y)
        } else {
            (Vec3::Z, s.z)
        }
    }

    /// The second-longest side's length.
    fn second(&self) -> f32 {
        let mut s = self.size().to_array();
        s.sort_by(f32::total_cmp);
        s[1]
    }

    fn surface_or_front(&self) -> SurfacePoint {
        self.surface.unwrap_or(SurfacePoint {
            position: Vec3::new(self.centre().x, self.centre().y, self.max.z),
            normal: Vec3::Z,
        })
    }

    /// `count` points along the longest axis through the centre, over 90 % of its length.
    fn axis_points(&self, count: usize) -> Vec<Vec3> {
        let (axis, len) = self.longest();
        let half = 0.45 * len;
        (0..count)
            .map(|i| self.centre() + axis * (-half + 2.0 * half * i as f32 / (count - 1) as f32))
            .collect()
    }

    fn lattice_frame(&self) -> LatticeFrame {
        let pad = self.size() * 0.02;
        let (min, size) = (self.min - pad, self.size() + 2.0 * pad);
        LatticeFrame {
            origin: min,
            s: Vec3::X * size.x,
            t: Vec3::Y * size.y,
            u: Vec3::Z * size.z,
        }
    }
}

/// The first surface hit of a ray from in front of the mesh (+Z) towards the centre of its
/// bounds, with the hit triangle's outward normal; `None` when the ray misses.
#[must_use]
pub fn front_point(rest: &RestMesh) -> Option<SurfacePoint> {
    front_point_of(rest.welded_positions(), &rest.topology().triangles)
}

/// [`front_point`] of any triangle mesh (a deformed one, say).
#[must_use]
pub fn front_point_of(positions: &[Vec3], triangles: &[[u32; 3]]) -> Option<SurfacePoint> {
    let (min, max) = ductile_core::mesh::bounds(positions)?;
    let centre = 0.5 * (min + max);
    let bvh = Bvh::build(positions, triangles).ok()?;
    let ray = Ray {
        origin: Vec3::new(centre.x, centre.y, max.z + (max - min).length()),
        direction: Vec3::NEG_Z,
    };
    let hit = bvh.intersect(&ray)?;
    let [a, b, c] = triangles[hit.triangle as usize].map(|i| positions[i as usize]);
    let mut normal = (b - a).cross(c - a).try_normalize()?;
    if normal.dot(ray.direction) > 0.0 {
        normal = -normal;
    }
    Some(SurfacePoint {
        position: hit.point(&ray),
        normal,
    })
}

/// A new tool of kind `kind` placed by `place` (see the module documentation), in the
/// mesh's frame.
#[must_use]
pub fn tool(kind: NewTool, place: &Placement) -> Tool {
    let diag = place.diagonal();
    let s = place.surface_or_front();
    match kind {
        NewTool::FfsdPoint => Tool::Ffsd(FfsdTool::new(vec![ControlPoint {
            position: s.position + s.normal * (diag / 20.0),
            mode: PointMode::Directional {
                reference: s.position,
            },
            gamma: 1.0,
            alpha: 2.0,
            epsilon: diag / 15.0,
        }])),
        NewTool::Dogme => Tool::Dogme(DogmeTool {
            constraints: vec![Constraint {
                at: Anchor::Point(s.position),
                displacement: s.normal * (diag / 20.0),
                support: Support::Sphere { radius: diag / 5.0 },
            }],
            degree: 3,
        }),
        NewTool::DirectFfd => Tool::DirectFfd(DirectFfdTool {
            lattice: lattice(LatticeKind::Bernstein, place),
            constraints: vec![DirectConstraint {
                at: Anchor::Point(s.position),
                displacement: s.normal * (diag / 20.0),
            }],
        }),
        NewTool::Axial => {
            let points: Vec<AxisPoint> = place
                .axis_points(5)
                .into_iter()
                .map(|position| AxisPoint {
                    position,
                    twist: 0.0,
                    scale: 1.0,
                })
                .collect();
            Tool::Axial(AxialTool {
                deformed: points.clone(),
                rest: points,
                radius: place.second() / 3.0,
                falloff: Falloff::Smooth,
                ..AxialTool::new(Vec::new(), 1.0)
            })
        }
        NewTool::BezierCurve | NewTool::BSplineCurve => {
            let points = place.axis_points(5);
            Tool::Curve(CurveTool {
                basis: if kind == NewTool::BezierCurve {
                    CurveBasis::Bezier
                } else {
                    CurveBasis::BSpline { degree: 3 }
                },
                deformed: points.clone(),
                rest: points,
            })
        }
        NewTool::ShapeSurface => {
            let size = place.size();
            // The two longest sides span the surface; it lies across the third.
            let mut axes = [(Vec3::X, size.x), (Vec3::Y, size.y), (Vec3::Z, size.z)];
            axes.sort_by(|a, b| b.1.total_cmp(&a.1));
            let (u, v) = (axes[0].0 * axes[0].1, axes[1].0 * axes[1].1);
            Tool::ShapeSurface(ShapeSurfaceTool {
                frame: SurfaceFrame {
                    origin: place.centre() - 0.5 * (u + v),
                    u_edge: u,
                    v_edge: v,
                },
                counts: (4, 4),
                degree: (3, 3),
                rest: Vec::new(),
                moves: Vec::new(),
                heights: Vec::new(),
            })
        }
        NewTool::Lattice(k) => Tool::Lattice(lattice(k, place)),
    }
}

fn lattice(kind: LatticeKind, place: &Placement) -> LatticeTool {
    let (counts, basis) = match kind {
        LatticeKind::Bernstein => ((3, 3, 3), LatticeBasis::Bernstein),
        LatticeKind::BSpline | LatticeKind::Rational => {
            ((4, 4, 4), LatticeBasis::BSpline { degree: (2, 2, 2) })
        }
    };
    LatticeTool {
        frame: place.lattice_frame(),
        counts,
        basis,
        points: Vec::new(),
        falloff: 0.0,
    }
}

/// A new volume of shape `kind` placed by `place`: its shape and the node's transform (in
/// the mesh's frame; see the module documentation).
#[must_use]
pub fn volume(kind: NewVolume, place: &Placement) -> (Shape, Transform) {
    let diag = place.diagonal();
    let centre = place.centre();
    let (axis, len) = place.longest();
    // Capsules and tubes are along local Y: turn Y onto the longest axis.
    let along = Quat::from_rotation_arc(Vec3::Y, axis);
    match kind {
        NewVolume::Sphere => (
            Shape::Sphere { radius: diag / 4.0 },
            Transform::from_translation(centre),
        ),
        NewVolume::Box => (
            Shape::Box {
                half_extents: place.size() * 0.25,
            },
            Transform::from_translation(centre),
        ),
        NewVolume::Capsule => (
            Shape::Capsule {
                radius: place.second() / 4.0,
                half_height: len / 4.0,
            },
            Transform {
                translation: centre,
                rotation: along,
                scale: Vec3::ONE,
            },
        ),
        NewVolume::Tube => {
            let r = place.second() / 4.0;
            let points: Vec<Vec3> = (0..4)
                .map(|i| Vec3::Y * (len * (-0.3 + 0.2 * i as f32)))
                .collect();
            (
                Shape::Tube {
                    radii: vec![r; points.len()],
                    points,
                },
                Transform {
                    translation: centre,
                    rotation: along,
                    scale: Vec3::ONE,
                },
            )
        }
    }
}

/// The lattice `l` with `counts` control points per axis (each ≥ 2; 2 to 16 for a Bernstein
/// basis, and more points than its degree for a B-spline one). A moved control point keeps
/// its offset and weight when the new grid has a point at the same place in the lattice:
/// index `i` of `n` points maps to `i·(m − 1)/(n − 1)` of `m` points when that is a whole
/// number (the corners always do; doubling `n − 1` keeps every point). The others are
/// dropped. Frame, basis and falloff are kept.
#[must_use]
pub fn resized_lattice(l: &LatticeTool, counts: (u32, u32, u32)) -> LatticeTool {
    let map = |i: u32, n: u32, m: u32| -> Option<u32> {
        if n < 2 || m < 2 {
            return None;
        }
        let num = u64::from(i) * u64::from(m - 1);
        let den = u64::from(n - 1);
        (num % den == 0).then(|| (num / den) as u32)
    };
    let (n, m) = (l.counts, counts);
    let points = l
        .points
        .iter()
        .filter_map(|e| {
            let (i, j, k) = e.at;
            Some(ductile_core::lattice::ControlEdit {
                at: (map(i, n.0, m.0)?, map(j, n.1, m.1)?, map(k, n.2, m.2)?),
                ..*e
            })
        })
        .collect();
    LatticeTool {
        counts,
        points,
        ..l.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn place() -> Placement {
        Placement {
            min: Vec3::new(-1.0, -2.0, -0.5),
            max: Vec3::new(1.0, 2.0, 0.5),
            surface: Some(SurfacePoint {
                position: Vec3::new(0.0, 0.0, 0.5),
                normal: Vec3::Z,
            }),
        }
    }

    #[test]
    fn every_new_tool_and_volume_is_valid() {
        for kind in NewTool::ALL {
            let t = tool(kind, &place());
            t.validate(kind.label()).unwrap();
        }
        for kind in NewVolume::ALL {
            let (shape, transform) = volume(kind, &place());
            shape.validate(kind.label()).unwrap();
            assert!(transform.is_finite());
        }
    }

    #[test]
    fn lattices_fit_the_bounds_and_curves_run_along_the_longest_axis() {
        let Tool::Lattice(l) = tool(NewTool::Lattice(LatticeKind::Bernstein), &place()) else {
            panic!()
        };
        assert!(l.frame.origin.x < -1.0 && l.frame.origin.x > -1.1);
        assert!((l.frame.t.y - 4.16).abs() < 1e-5, "{:?}", l.frame);
        let Tool::Curve(c) = tool(NewTool::BSplineCurve, &place()) else {
            panic!()
        };
        assert!(c.rest.iter().all(|p| p.x == 0.0 && p.z == 0.0));
        assert!((c.rest[4].y - c.rest[0].y - 3.6).abs() < 1e-5);
        assert_eq!(c.rest, c.deformed, "a new curve is the identity");
    }

    #[test]
    fn a_new_ffsd_point_pulls_the_surface_out_along_its_normal() {
        let Tool::Ffsd(f) = tool(NewTool::FfsdPoint, &place()) else {
            panic!()
        };
        let p = f.points[0];
        let PointMode::Directional { reference } = p.mode else {
            panic!()
        };
        assert_eq!(reference, Vec3::new(0.0, 0.0, 0.5));
        assert!((p.position - reference).normalize().dot(Vec3::Z) > 0.999);
    }

    #[test]
    fn a_resized_lattice_keeps_the_points_that_have_a_place() {
        use ductile_core::lattice::ControlEdit;
        let Tool::Lattice(mut l) = tool(NewTool::Lattice(LatticeKind::Bernstein), &place()) else {
            panic!()
        };
        let edit = |at, z| ControlEdit {
            at,
            offset: Vec3::new(0.0, 0.0, z),
            weight: 1.0,
        };
        l.points = vec![
            edit((1, 1, 1), 0.3),
            edit((2, 0, 2), -0.2),
            edit((0, 1, 2), 0.1),
        ];
        // 3 → 5 points per axis: every old point has a place (index doubles).
        let big = resized_lattice(&l, (5, 5, 5));
        assert_eq!(
            big.points.iter().map(|e| e.at).collect::<Vec<_>>(),
            [(2, 2, 2), (4, 0, 4), (0, 2, 4)]
        );
        Tool::Lattice(big.clone()).validate("big").unwrap();
        // 3 → 4: only the corner-aligned indices (0 and 2) map.
        let odd = resized_lattice(&l, (4, 4, 4));
        assert_eq!(
            odd.points.iter().map(|e| e.at).collect::<Vec<_>>(),
            [(3, 0, 3)]
        );
        assert_eq!(odd.points[0].offset.z, -0.2);
    }
}
