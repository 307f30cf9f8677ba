//! `ptui bench accel`: the flat scan against the BVH as the primitive count grows, and the
//! crossover the scene build uses (`accel::BVH_CROSSOVER`).

use super::{BenchArgs, BenchTarget};
use crate::accel::{bench, BVH_CROSSOVER};

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    match args.target {
        BenchTarget::Accel => {
            println!("closest-hit queries on random spheres and triangles, 1 thread");
            println!("{}", bench::HEADER);
            let mut rows = Vec::new();
            for n in bench::counts(args.max_prims) {
                let row = bench::measure(n, args.work);
                // Print as we go: the large counts take a while.
                println!("{}", bench::line(&row));
                rows.push(row);
            }
            match bench::crossover(&rows) {
                Some(n) => println!("measured crossover: the BVH is faster from {n} primitives on"),
                None => println!("measured crossover: the flat scan won at every count"),
            }
            println!("crossover used by the scene build (accel::BVH_CROSSOVER): {BVH_CROSSOVER}");
        }
    }
    Ok(())
}
