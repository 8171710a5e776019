//! Smooth vertex normals.

use glam::Vec3;

/// Area-weighted smooth vertex normals: each vertex normal is the normalised sum of the
/// un-normalised face normals `(b − a) × (c − a)` of its triangles, so every face contributes
/// in proportion to twice its area.
///
/// Area weighting is used (rather than angle weighting) because it needs no trigonometry, is
/// exact for the planar case, and on the dense scanned meshes Ductile deforms the two differ
/// by far less than what a viewer can see. A vertex with no non-degenerate triangle gets
/// `Vec3::ZERO`'s fallback `Vec3::Z`.
#[must_use]
pub fn smooth_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut acc = vec![Vec3::ZERO; positions.len()];
    for &[a, b, c] in triangles {
        let (pa, pb, pc) = (
            positions[a as usize],
            positions[b as usize],
            positions[c as usize],
        );
        let n = (pb - pa).cross(pc - pa);
        acc[a as usize] += n;
        acc[b as usize] += n;
        acc[c as usize] += n;
    }
    for n in &mut acc {
        *n = n.try_normalize().unwrap_or(Vec3::Z);
    }
    acc
}
