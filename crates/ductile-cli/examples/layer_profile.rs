use ductile_cli::suite::{Fixtures, MIXED_NODE};
use ductile_core::stack::LayerBinding;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let threads: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(2);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let (doc, rest) = Fixtures::default().mixed()?;
    let stack = doc.resolve_stack(MIXED_NODE, &rest)?;
    pool.install(|| -> anyhow::Result<()> {
        let mut positions = rest.welded_positions().to_vec();
        let (mut tb, mut tm, mut td) = (0.0, 0.0, 0.0);
        for layer in &stack.layers {
            let t0 = Instant::now();
            let mask = match &layer.influence {
                Some(inf) => inf.mask(&positions),
                None => ductile_core::influence::Mask::all(positions.len()),
            };
            let t1 = Instant::now();
            let n = mask.indices.len();
            let b = LayerBinding::bind_masked(
                &layer.tool,
                std::sync::Arc::new(mask),
                &positions,
                rest.topology(),
            )?;
            let t2 = Instant::now();
            b.apply(layer, &mut positions)?;
            let t3 = Instant::now();
            let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
            tm += ms(t0, t1);
            tb += ms(t1, t2);
            td += ms(t2, t3);
            println!(
                "{:>30} active {:>8} mask {:7.2} bind {:7.2} deform {:7.2}",
                format!("{:?}", std::mem::discriminant(&layer.tool))
                    .chars()
                    .take(30)
                    .collect::<String>(),
                n,
                ms(t0, t1),
                ms(t1, t2),
                ms(t2, t3)
            );
        }
        println!("total mask {tm:.1} bind {tb:.1} deform {td:.1}");
        Ok(())
    })
}
