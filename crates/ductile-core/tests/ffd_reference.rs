//! Compares the Bernstein lattice with the independent NumPy evaluation of the
//! Sederberg–Parry formula in `tools/reference/ffd_reference.py` (fixture committed in
//! `tests/data/ffd-reference.json`; regenerate it with that script).

#![allow(clippy::unwrap_used)]

use ductile_core::lattice::{ControlEdit, LatticeFrame, LatticeTool};
use ductile_core::tool::Deformer;
use glam::Vec3;
use serde::Deserialize;

#[derive(Deserialize)]
struct Edit {
    at: [u32; 3],
    offset: [f64; 3],
}

#[derive(Deserialize)]
struct Case {
    name: String,
    origin: [f64; 3],
    s: [f64; 3],
    t: [f64; 3],
    u: [f64; 3],
    counts: [u32; 3],
    edits: Vec<Edit>,
    points: Vec<[f64; 3]>,
    expected: Vec<[f64; 3]>,
}

#[derive(Deserialize)]
struct Fixture {
    cases: Vec<Case>,
}

fn v(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

#[test]
fn bernstein_lattice_matches_the_numpy_reference() {
    let text = include_str!("data/ffd-reference.json");
    let fixture: Fixture = serde_json::from_str(text).unwrap();
    assert!(fixture.cases.len() >= 5);
    for case in &fixture.cases {
        let frame = LatticeFrame {
            origin: v(case.origin),
            s: v(case.s),
            t: v(case.t),
            u: v(case.u),
        };
        let mut tool =
            LatticeTool::bernstein(frame, (case.counts[0], case.counts[1], case.counts[2]));
        tool.points = case
            .edits
            .iter()
            .map(|e| ControlEdit {
                at: (e.at[0], e.at[1], e.at[2]),
                offset: v(e.offset),
                weight: 1.0,
            })
            .collect();
        tool.validate("reference").unwrap();
        let lattice = tool.prepare("reference").unwrap();
        // Relative to the size of the lattice (sum of its edge lengths).
        let size = (frame.s.length() + frame.t.length() + frame.u.length()) as f64;
        let mut moved = 0;
        for (p, e) in case.points.iter().zip(&case.expected) {
            let q = lattice.deform_point(v(*p));
            let err = ((q.x as f64 - e[0]).powi(2)
                + (q.y as f64 - e[1]).powi(2)
                + (q.z as f64 - e[2]).powi(2))
            .sqrt();
            assert!(
                err <= 1e-5 * size,
                "{}: point {p:?} gave {q}, reference {e:?} (error {err:e})",
                case.name
            );
            moved += usize::from(p != e);
        }
        assert!(moved > 0, "{}: the case must move points", case.name);
    }
}
