//! Cost of one haptic tick's force work: the penalty force over a contact set, the coupling step and the
//! safety layer (`cargo bench -p forcecomp`).

use criterion::{Criterion, criterion_group, criterion_main};
use forcecomp::{BodyMotion, CouplingConfig, Material, SafetyConfig, SafetyLayer, VirtualCoupling, volumetric_penalty};
use glam::Vec3;
use haptic_common::{Contact, ContactSet, DeviceState, ForceTorque};

fn contacts(n: usize) -> ContactSet {
    let mut set = ContactSet::new();
    for i in 0..n {
        let a = i as f32 * 0.37;
        set.push(Contact {
            point: Vec3::new(a.cos(), a.sin(), 0.1) * 0.005,
            normal: Vec3::new(0.1 * a.sin(), 1.0, 0.1 * a.cos()).normalize(),
            volume: 1e-9,
            depth: 1e-4,
        });
        set.total_volume += 1e-9;
    }
    set
}

fn force_tick(c: &mut Criterion) {
    let tool = BodyMotion { linear_velocity: Vec3::new(0.01, -0.02, 0.0), ..BodyMotion::default() };
    for n in [100, 1000, 4096] {
        let set = contacts(n);
        c.bench_function(&format!("volumetric_penalty, {n} pairs"), |b| {
            b.iter(|| volumetric_penalty(&set, &tool, &BodyMotion::default(), &Material::default()))
        });
    }
    let mut coupling = VirtualCoupling::new(CouplingConfig::default());
    let device = DeviceState::default();
    let env = ForceTorque { force: Vec3::Y, torque: Vec3::ZERO };
    c.bench_function("virtual coupling step", |b| b.iter(|| coupling.step(&device, env, 0.001)));
    let mut safety = SafetyLayer::new(SafetyConfig::for_limits(8.5, 0.188));
    c.bench_function("safety layer apply", |b| b.iter(|| safety.apply(env, 0.001, 0.001)));
}

criterion_group!(benches, force_tick);
criterion_main!(benches);
