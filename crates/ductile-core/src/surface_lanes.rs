//! The shape-surface bind's projection onto a *planar* rest surface (one without rest edits,
//! the paper's case and the Add menu's) for a lane group of points at a time, on `lane.rs`'s
//! lanes in [`pulp`]'s runtime dispatch.
//!
//! The rest surface is then the frame's plane, `S(u, v) = O + u·U + v·V` (B-splines reproduce
//! linear functions from the Greville abscissae), so a point's closest point solves the 2×2
//! normal equations `[U·U U·V; U·V V·V] (u, v) = ((x − O)·U, (x − O)·V)` by Cramer's rule,
//! clamped to `[0, 1]²`; `u₃ = (x − S(u, v))·N` with the plane's unit normal `N = U × V / |U × V|`,
//! and the point projects when the residual `|x − S − u₃ N|` is at most `10⁻⁴ (|U| + |V|)` or
//! NaN (docs/algorithms/shape-surface.md). `PlanarProjection::project` (built for the tests)
//! is the scalar form; every lane of [`PlanarProjection::project_each`] does its operations in
//! their order, so each answer has its bits.

use glam::Vec3;

use crate::lane::{LANES, Lane, Lanes3, Mask};
use crate::surface::SurfaceFrame;

/// The projection onto a planar rest surface: the frame and what every point's projection
/// shares.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PlanarProjection {
    /// `O`.
    pub(crate) origin: Vec3,
    /// `U`, the rest surface's `S_u` everywhere.
    pub(crate) u_edge: Vec3,
    /// `V`, the rest surface's `S_v` everywhere.
    pub(crate) v_edge: Vec3,
    /// `U·U`, `U·V`, `V·V` and the determinant `U·U V·V − (U·V)²`.
    gram: [f32; 4],
    /// The unit normal `U × V / |U × V|`; `None` where `U × V` is zero or NaN (then no point
    /// projects).
    pub(crate) normal: Option<Vec3>,
    /// The largest residual of a point that projects, `10⁻⁴ (|U| + |V|)`.
    limit: f32,
}

/// One point's projection: `(u₁, u₂, u₃)`.
pub(crate) type Projected = (f32, f32, f32);

impl PlanarProjection {
    /// The projection onto `frame`'s plane; `None` when the determinant is not positive
    /// (parallel or zero edges: the bind then searches the surface instead).
    #[must_use]
    pub(crate) fn new(frame: &SurfaceFrame) -> Option<Self> {
        let (eu, ev) = (frame.u_edge, frame.v_edge);
        let (a, b, c) = (eu.dot(eu), eu.dot(ev), ev.dot(ev));
        let det = a * c - b * b;
        if det.is_nan() || det <= 0.0 {
            return None;
        }
        let n = eu.cross(ev);
        let l2 = n.length_squared();
        let normal = (!l2.is_nan() && l2 > 0.0).then(|| n.normalize());
        Some(Self {
            origin: frame.origin,
            u_edge: eu,
            v_edge: ev,
            gram: [a, b, c, det],
            normal,
            limit: 1e-4 * (eu.length() + ev.length()),
        })
    }

    /// The projection of `x` (module documentation), or `None` where it does not project:
    /// the scalar form the lanes are tested against.
    #[cfg(test)]
    #[must_use]
    pub(crate) fn project(&self, x: Vec3) -> Option<Projected> {
        let n = self.normal?;
        let (o, eu, ev) = (self.origin, self.u_edge, self.v_edge);
        let [a, b, c, det] = self.gram;
        let r = x - o;
        let (g1, g2) = (r.dot(eu), r.dot(ev));
        let u = ((c * g1 - b * g2) / det).clamp(0.0, 1.0);
        let v = ((a * g2 - b * g1) / det).clamp(0.0, 1.0);
        let r = x - (o + eu * u + ev * v);
        let u3 = r.dot(n);
        if (r - n * u3).length() > self.limit {
            return None;
        }
        Some((u, v, u3))
    }

    /// `PlanarProjection::project` of every point of `xs`, written to `out` (as long as
    /// `xs`): the same bits, a lane group at a time.
    ///
    /// # Panics
    /// When `out` and `xs` differ in length.
    pub(crate) fn project_each(&self, xs: &[Vec3], out: &mut [Option<Projected>]) {
        assert_eq!(xs.len(), out.len(), "one answer per point");
        let Some(normal) = self.normal else {
            out.fill(None);
            return;
        };
        pulp::Arch::new().dispatch(ProjectEach {
            plane: self,
            normal,
            xs,
            out,
        });
    }

    /// `(u₁, u₂, u₃)` of each lane and whether it projects (`PlanarProjection::project`'s
    /// operations on the lanes).
    #[inline(always)]
    fn project_lanes(&self, x: &Lanes3, n: Vec3) -> (Lane, Lane, Lane, Mask) {
        let s = Lane::splat;
        let (o, eu, ev) = (self.origin, self.u_edge, self.v_edge);
        let [a, b, c, det] = self.gram.map(s);
        let (rx, ry, rz) = (x.x - s(o.x), x.y - s(o.y), x.z - s(o.z));
        let g1 = rx * s(eu.x) + ry * s(eu.y) + rz * s(eu.z);
        let g2 = rx * s(ev.x) + ry * s(ev.y) + rz * s(ev.z);
        let u = ((c * g1 - b * g2) / det).clamp01();
        let v = ((a * g2 - b * g1) / det).clamp01();
        let (rx, ry, rz) = (
            x.x - ((s(o.x) + s(eu.x) * u) + s(ev.x) * v),
            x.y - ((s(o.y) + s(eu.y) * u) + s(ev.y) * v),
            x.z - ((s(o.z) + s(eu.z) * u) + s(ev.z) * v),
        );
        let u3 = rx * s(n.x) + ry * s(n.y) + rz * s(n.z);
        let (ex, ey, ez) = (rx - s(n.x) * u3, ry - s(n.y) * u3, rz - s(n.z) * u3);
        let residual = (ex * ex + ey * ey + ez * ez).sqrt();
        (u, v, u3, !residual.simd_gt(s(self.limit)))
    }
}

/// [`PlanarProjection::project_each`]'s kernel.
struct ProjectEach<'a> {
    plane: &'a PlanarProjection,
    normal: Vec3,
    xs: &'a [Vec3],
    out: &'a mut [Option<Projected>],
}

impl pulp::WithSimd for ProjectEach<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        for (xs, out) in self.xs.chunks(LANES).zip(self.out.chunks_mut(LANES)) {
            let (u, v, u3, projects) = self.plane.project_lanes(&Lanes3::load(xs), self.normal);
            let (u, v, u3) = (u.as_array(), v.as_array(), u3.as_array());
            for (j, o) in out.iter_mut().enumerate() {
                *o = projects.lane(j).then_some((u[j], v[j], u3[j]));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn bits(p: Option<Projected>) -> Option<[u32; 3]> {
        p.map(|(u, v, w)| [u.to_bits(), v.to_bits(), w.to_bits()])
    }

    fn frame(o: [f32; 3], u: [f32; 3], v: [f32; 3]) -> SurfaceFrame {
        SurfaceFrame {
            origin: Vec3::from(o),
            u_edge: Vec3::from(u),
            v_edge: Vec3::from(v),
        }
    }

    #[test]
    fn lanes_give_the_scalar_bits_inside_outside_and_on_odd_points() {
        let plane =
            PlanarProjection::new(&frame([0.1, -0.2, 0.3], [1.5, 0.1, 0.0], [0.2, 0.9, 0.3]))
                .expect("a plane");
        // Points over the frame and past its borders, on both sides.
        let mut xs: Vec<Vec3> = (0..203)
            .map(|k| {
                let t = k as f32 * 0.173;
                let (a, b) = (0.5 + 0.8 * t.sin(), 0.5 + 0.8 * (t * 0.7).cos());
                Vec3::new(0.1, -0.2, 0.3)
                    + a * Vec3::new(1.5, 0.1, 0.0)
                    + b * Vec3::new(0.2, 0.9, 0.3)
                    + Vec3::new(0.0, -0.1, 0.4) * (t * 1.3).sin()
            })
            .collect();
        xs.extend([
            Vec3::NAN,
            Vec3::INFINITY,
            Vec3::new(1e30, -1e30, 3.0),
            Vec3::ZERO,
        ]);
        let mut out = vec![None; xs.len()];
        plane.project_each(&xs, &mut out);
        let (mut inside, mut outside) = (0, 0);
        for (x, o) in xs.iter().zip(&out) {
            assert_eq!(bits(*o), bits(plane.project(*x)), "point {x}");
            if o.is_some() {
                inside += 1
            } else {
                outside += 1
            }
        }
        // Both answers occur, so the test compares both.
        assert!(
            inside > 20 && outside > 20,
            "{inside} inside, {outside} outside"
        );
    }

    #[test]
    fn parallel_or_zero_edges_have_no_plane() {
        for (u, v) in [
            ([1.0, 0.0, 0.0], [2.0, 0.0, 0.0]),
            ([0.0; 3], [0.0, 1.0, 0.0]),
        ] {
            assert!(PlanarProjection::new(&frame([0.0; 3], u, v)).is_none());
        }
        assert!(
            PlanarProjection::new(&frame([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])).is_some()
        );
    }

    proptest! {
        #[test]
        fn lanes_match_the_scalar_projection(
            o in prop::array::uniform3(-10.0f32..10.0),
            u in prop::array::uniform3(-5.0f32..5.0),
            v in prop::array::uniform3(-5.0f32..5.0),
            pts in prop::collection::vec(prop::array::uniform3(-20.0f32..20.0), 1..70),
        ) {
            let Some(plane) = PlanarProjection::new(&frame(o, u, v)) else {
                return Ok(());
            };
            let xs: Vec<Vec3> = pts.into_iter().map(Vec3::from).collect();
            let mut out = vec![None; xs.len()];
            plane.project_each(&xs, &mut out);
            for (x, o) in xs.iter().zip(&out) {
                prop_assert_eq!(bits(*o), bits(plane.project(*x)));
            }
        }
    }
}
