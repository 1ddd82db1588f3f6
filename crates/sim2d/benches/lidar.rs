//! A 1081-ray lidar scan and ideal detections in the `qlink-200` world (200 landmarks), and
//! the baseline the issue asks for beside it: the same rays cast against every landmark with
//! parry's ray casts in a plain loop, no acceleration structure.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rand::SeedableRng;
use rapier2d::parry::query::{Ray, RayCast};
use rapier2d::parry::shape::Ball;
use rapier2d::prelude::{Pose as Iso, Vector};
use sim2d::{LidarConfig, Pose, scenario};

fn brute_force(spec: &sim2d::WorldSpec, pose: &Pose, cfg: &LidarConfig) -> Vec<f32> {
    let balls: Vec<(Ball, Iso)> = spec
        .landmarks
        .iter()
        .map(|l| {
            (
                Ball::new(l.radius as f32),
                Iso::from_translation(Vector::new(l.pos[0] as f32, l.pos[1] as f32)),
            )
        })
        .collect();
    let origin = Vector::new(pose.x as f32, pose.y as f32);
    cfg.angles()
        .iter()
        .map(|a| {
            let th = pose.theta + a;
            let ray = Ray::new(origin, Vector::new(th.cos() as f32, th.sin() as f32));
            balls
                .iter()
                .filter_map(|(b, p)| b.cast_ray(p, &ray, cfg.max_range as f32, true))
                .fold(f32::INFINITY, f32::min)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let sc = scenario("qlink-200", 1, None).expect("built in");
    let pose = Pose {
        x: 100.0,
        y: 100.0,
        theta: 0.3,
    };
    let cfg = LidarConfig {
        max_range: 20.0,
        ..LidarConfig::default()
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut g = c.benchmark_group("lidar_1081_rays_qlink200");
    g.throughput(Throughput::Elements(cfg.rays as u64));
    g.bench_function("rapier_query_pipeline", |b| {
        b.iter(|| sc.world.lidar(&pose, &cfg, &mut rng).expect("valid"))
    });
    g.bench_function("parry_loop_no_bvh", |b| {
        b.iter(|| brute_force(sc.world.spec(), &pose, &cfg))
    });
    g.finish();
    let mut g = c.benchmark_group("ideal_detector_qlink200");
    g.throughput(Throughput::Elements(1));
    g.bench_function("detect_full_occlusion", |b| {
        b.iter(|| {
            sc.world
                .detect(&pose, &sc.detector, &mut rng)
                .expect("valid")
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
