//! The solve on the pixels (`solve::reprojection`: PnP of every frame, the start, both
//! Levenberg–Marquardt passes and the covariance) on 25, 50 and 100 frames of a 9×6 board (54
//! corners each), beside the pose-based `refine` over every pair of the same frames' PnP poses,
//! measured in the same run (fixed seeds); and on frames that span the image, the solve with the
//! intrinsics refined (`refine_intrinsics`) beside the one with them fixed.
//!
//! `cargo bench -p handeye --bench reprojection`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use handeye::sim::pixels::{PixelSimConfig, simulate_pixels};
use handeye::solve::reprojection::{PixelOptions, planar_poses, reprojection};
use handeye::{AllPairs, Method, PosePair, solve};
use nalgebra::{Vector2, Vector3};
use std::hint::black_box;

fn on_pixels(c: &mut Criterion) {
    let mut group = c.benchmark_group("reprojection");
    for frames in [25usize, 50, 100] {
        let sim = simulate_pixels(
            &PixelSimConfig {
                frames,
                ..PixelSimConfig::board()
            },
            7,
        );
        let poses: Vec<PosePair> = sim
            .frames
            .iter()
            .map(|f| {
                let points: Vec<Vector3<f64>> = f
                    .detections
                    .target
                    .iter()
                    .map(|p| Vector3::from(*p))
                    .collect();
                let pixels: Vec<Vector2<f64>> = f
                    .detections
                    .pixels
                    .iter()
                    .map(|p| Vector2::from(*p))
                    .collect();
                let best = planar_poses(&points, &pixels, &sim.intrinsics)
                    .unwrap()
                    .into_iter()
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .unwrap()
                    .0;
                PosePair {
                    base_from_gripper: f.base_from_gripper,
                    camera_from_target: best,
                }
            })
            .collect();
        group.bench_with_input(BenchmarkId::new("pixels", frames), &sim, |b, sim| {
            b.iter(|| {
                reprojection(
                    black_box(&sim.frames),
                    &sim.intrinsics,
                    sim.setup,
                    &PixelOptions::default(),
                )
                .unwrap()
            })
        });
        // The intrinsics refined too (`--refine-intrinsics`), on frames that span the image; the
        // fixed-intrinsics solve of the same frames beside it for the ratio.
        let spanning = simulate_pixels(
            &PixelSimConfig {
                frames,
                ..PixelSimConfig::board().spanning()
            },
            7,
        );
        for (name, refine) in [
            ("spanning_fixed", false),
            ("spanning_refine_intrinsics", true),
        ] {
            let options = PixelOptions {
                refine_intrinsics: refine,
                ..PixelOptions::default()
            };
            group.bench_with_input(BenchmarkId::new(name, frames), &spanning, |b, sim| {
                b.iter(|| {
                    reprojection(black_box(&sim.frames), &sim.intrinsics, sim.setup, &options)
                        .unwrap()
                })
            });
        }
        group.bench_with_input(BenchmarkId::new("refine_poses", frames), &poses, |b, p| {
            b.iter(|| solve(Method::Refine, &AllPairs::new(black_box(p), sim.setup)).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, on_pixels);
criterion_main!(benches);
