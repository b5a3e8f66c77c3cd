//! Unbalance-response sweep: 1000 speeds on the ROSS reference machine A
//! (15 Timoshenko elements, 3 disks, 2 cross-coupled bearings on pedestals:
//! 68 DOF here, 100 as ROSS counts them with 6 per node). Compare with `python3 tests/reference/ross/make_reference.py --time`
//! (or scripts/bench-sim.sh for both side by side).

use criterion::{criterion_group, criterion_main, Criterion};
use plinth::sim::{EffectSet, Machine, UnbalanceSolver};
use std::hint::black_box;

fn sweep(c: &mut Criterion) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/reference/ross/machine-a.toml"
    );
    let machine = match Machine::from_toml_path(path) {
        Ok(m) => m,
        Err(e) => panic!("bench machine: {e}"),
    };
    let speeds: Vec<f64> = (0..1000).map(|i| 5.0 + 195.0 * i as f64 / 999.0).collect();
    let solver = match UnbalanceSolver::new(&machine, &EffectSet::none()) {
        Ok(s) => s,
        Err(e) => panic!("bench solver: {e}"),
    };
    let (kl, ku) = solver.assembly().bandwidths();
    eprintln!(
        "machine-a: {} DOF, band kl = {kl}, ku = {ku}, 1000 speeds",
        solver.assembly().n_dof
    );
    let mut group = c.benchmark_group("unbalance_sweep");
    group.sample_size(20);
    group.bench_function("machine-a 1000 speeds (assembled once)", |b| {
        b.iter(|| black_box(solver.run(black_box(&speeds)).map(|r| r.bearings.len())))
    });
    group.bench_function("machine-a 1000 speeds (incl. assembly)", |b| {
        b.iter(|| {
            black_box(
                plinth::sim::unbalance_response(&machine, black_box(&speeds), &EffectSet::none())
                    .map(|r| r.bearings.len()),
            )
        })
    });
    group.finish();
}

criterion_group!(benches, sweep);
criterion_main!(benches);
