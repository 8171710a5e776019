//! The influence heat-map: a layer's per-vertex weight or displacement as vertex colours.

use bevy::prelude::*;

/// What the heat-map shows for the selected layer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum HeatMap {
    /// The layer's weight per vertex (mask weight × layer weight), in [0, 1].
    #[default]
    Weight,
    /// How far the layer moves each vertex, normalised by the largest displacement.
    Displacement,
}

impl HeatMap {
    /// The mode's name for menus.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            HeatMap::Weight => "Weight",
            HeatMap::Displacement => "Displacement",
        }
    }
}

/// Colour of a value `t` in [0, 1] on the heat ramp: dark blue (0) → cyan → green → yellow
/// → red (1), linear RGBA. Values outside [0, 1] (and NaN) are clamped to the ends.
#[must_use]
pub fn ramp(t: f32) -> [f32; 4] {
    const STOPS: [[f32; 3]; 5] = [
        [0.05, 0.08, 0.35],
        [0.0, 0.65, 0.9],
        [0.1, 0.8, 0.2],
        [1.0, 0.85, 0.0],
        [0.9, 0.05, 0.02],
    ];
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    let a = STOPS[i];
    let b = STOPS[i + 1];
    let c = Color::srgb(
        a[0] + (b[0] - a[0]) * f,
        a[1] + (b[1] - a[1]) * f,
        a[2] + (b[2] - a[2]) * f,
    )
    .to_linear();
    [c.red, c.green, c.blue, 1.0]
}

/// Vertex colours for per-vertex `values`: weights map directly, displacements are
/// normalised by their maximum (all zero → all at the cold end).
#[must_use]
pub fn heat_colors(mode: HeatMap, values: &[f32]) -> Vec<[f32; 4]> {
    let scale = match mode {
        HeatMap::Weight => 1.0,
        HeatMap::Displacement => {
            let max = values
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .fold(0.0_f32, f32::max);
            if max > 0.0 { 1.0 / max } else { 0.0 }
        }
    };
    values.iter().map(|&v| ramp(v * scale)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_ends_and_clamping() {
        assert_eq!(ramp(0.0), ramp(-3.0));
        assert_eq!(ramp(1.0), ramp(7.0));
        assert_eq!(ramp(f32::NAN), ramp(0.0));
        assert!(ramp(1.0)[0] > 0.5 && ramp(1.0)[2] < 0.1, "hot end is red");
        assert!(ramp(0.0)[2] > ramp(0.0)[0], "cold end is blue");
    }

    #[test]
    fn displacement_is_normalised_by_its_maximum() {
        let c = heat_colors(HeatMap::Displacement, &[0.0, 0.5, 2.0]);
        assert_eq!(c[2], ramp(1.0));
        assert_eq!(c[1], ramp(0.25));
        assert_eq!(
            heat_colors(HeatMap::Displacement, &[0.0, 0.0])[1],
            ramp(0.0)
        );
    }
}
