//! Cost of one haptic tick's force work: the penalty force over a contact set, the 3-DOF god-object on
//! the spheres near the tip, the coupling step and the safety layer (`cargo bench -p forcecomp`).

use criterion::{Criterion, criterion_group, criterion_main};
use forcecomp::{
    Ball, BodyMotion, CouplingConfig, GodObject, Material, ProxyConfig, SafetyConfig, SafetyLayer, VirtualCoupling,
    volumetric_penalty,
};
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
    // A face of packed spheres (1.5 mm, 3 mm apart, two layers) under a tip pressed 2 mm in and
    // dragged along it: each tick slides the proxy.
    for n in [50usize, 150, 500] {
        let side = ((n / 2) as f32).sqrt().ceil() as i32;
        let balls: Vec<Ball> = (0..n)
            .map(|i| {
                let (layer, k) = ((i % 2) as f32, (i / 2) as i32);
                let (x, z) = ((k % side - side / 2) as f32 * 0.003, (k / side - side / 2) as f32 * 0.003);
                Ball { center: Vec3::new(x + layer * 0.0015, -0.0015 - layer * 0.003, z), radius: 0.0015 }
            })
            .collect();
        let config = ProxyConfig::default();
        let mut god = GodObject::new();
        god.update(&config, Vec3::new(0.0, 0.01, 0.0), Vec3::ZERO, &balls, 1.0);
        let mut x = 0.0f32;
        c.bench_function(&format!("god-object update, {n} spheres near the tip, sliding"), |b| {
            b.iter(|| {
                x = (x + 1e-5) % 0.004;
                god.update(&config, Vec3::new(x, -0.002, 0.0), Vec3::ZERO, &balls, 1.0)
            })
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
