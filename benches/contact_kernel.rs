//! Criterion benchmarks of the contact core: the per-particle multi-contact kernel for 2, 6 and 12
//! contacts (standard and advanced MC) and the particle–particle force. Report ns per contact.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use mcdem::physics::contact_set::{radius_changes, ContactLoad, McParams};
use mcdem::physics::ghods2022::{Cap, MprTest};
use mcdem::physics::material::{Material, PairCoeffs};
use mcdem::physics::pair::{particle_particle, Body};
use mcdem::physics::Vec3;

/// `n` loaded contacts spread over the sphere (the hard cases' many-contact particle).
fn contacts(n: usize, r: f64) -> Vec<ContactLoad> {
    mcdem::harness::spread_contacts(n, r, 1e-3)
}

fn kernel(c: &mut Criterion) {
    let r = 1e-3;
    let mut g = c.benchmark_group("contact_set");
    for &n in &[2usize, 6, 12] {
        let cs = contacts(n, r);
        let mut delta = vec![0.0; n];
        let mut fb = vec![false; n];
        g.throughput(Throughput::Elements(n as u64));
        for (label, cap) in [("standard", None), ("advanced", Some(Cap { mpr: 0.11, test: MprTest::Abs }))] {
            let p = McParams { radius: r, youngs_modulus: 23.3e3, poisson_ratio: 0.5, gamma: 0.81, cap };
            g.bench_with_input(BenchmarkId::new(label, n), &n, |b, _| {
                b.iter(|| radius_changes(black_box(&p), black_box(&cs), &mut delta, &mut fb).unwrap())
            });
        }
    }
    g.finish();
}

fn pair(c: &mut Criterion) {
    let m = Material::hertz(23.3e3, 0.5).unwrap();
    let coeffs = PairCoeffs::new(&m, &m, 0.95, 0.03).unwrap();
    let bi = Body {
        x: Vec3::new(1e-4, 0.0, 1.9e-3),
        v: Vec3::new(0.01, 0.0, -0.01),
        omega: Vec3::new(1.0, 2.0, 3.0),
        radius: 1e-3,
        mass: 5e-8,
    };
    let bj = Body { x: Vec3::zeros(), v: Vec3::zeros(), omega: Vec3::zeros(), radius: 1e-3, mass: 5e-8 };
    let mut shear = Vec3::zeros();
    c.bench_function("pair_force_hertz_history", |b| {
        b.iter(|| {
            particle_particle(black_box(&coeffs), black_box(&bi), black_box(&bj), 0.0, 0.0, 1e-5, &mut shear)
                .unwrap()
        })
    });
}

criterion_group!(benches, kernel, pair);
criterion_main!(benches);
