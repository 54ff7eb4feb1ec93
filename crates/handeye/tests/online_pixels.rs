//! The online calibrator on the pixels (`OnlinePixels`, `handeye online --intrinsics`, issue 35):
//! records with detections pushed one at a time give, at the end, the batch's calibration on the
//! pixels of the same records, and its refusals.

use handeye::calibrate::pixels::OnlinePixels;
use handeye::model::camera::{Detections, Frame};
use handeye::sim::pixels::{PixelSim, PixelSimConfig, simulate_pixels};
use handeye::{Options, Setup, Transform};
use nalgebra::{Translation3, UnitQuaternion, Vector3};

fn testdata(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata/pixels")
        .join(name)
}

fn names(frames: &[Frame]) -> Vec<String> {
    (1..=frames.len()).map(|i| format!("frame {i}")).collect()
}

/// Pushes every frame, returns the reports made on the way and the final one.
fn online(
    frames: &[Frame],
    camera: &handeye::Intrinsics,
    setup: Setup,
) -> (
    Vec<handeye::TrackReport>,
    handeye::Result<handeye::TrackReport>,
) {
    let mut c = OnlinePixels::new(*camera, setup, Options::default()).unwrap();
    let mut on_the_way = Vec::new();
    for (f, name) in frames.iter().zip(names(frames)) {
        on_the_way.extend(c.push(f.clone(), name));
    }
    assert_eq!(c.frames(), frames.len());
    (on_the_way, c.finish())
}

fn batch(
    frames: &[Frame],
    camera: &handeye::Intrinsics,
    setup: Setup,
) -> handeye::Result<handeye::HandEyeReport> {
    handeye::calibrate(
        handeye::Input::Pixels { frames, camera },
        setup,
        &Options::default(),
    )
    .map(|r| r.into_hand_eye().expect("the hand–eye report"))
}

/// The largest difference of the entries of two transforms' matrices (the angle of R̂ᵀR from its
/// trace is only good to about 1e-8 rad near zero).
fn entry_gap(a: &Transform, b: &Transform) -> f64 {
    (a.to_homogeneous() - b.to_homogeneous()).abs().max()
}

fn gap(a: &Transform, b: &Transform) -> (f64, f64) {
    (
        (a.rotation.inverse() * b.rotation).angle().to_degrees(),
        (a.translation.vector - b.translation.vector).norm(),
    )
}

#[test]
fn the_end_of_the_stream_is_the_batch_calibration_on_the_pixels_within_3_sigma_of_the_truth() {
    for (name, setup, frame) in [
        ("board_eth", Setup::EyeToHand, "base_from_camera"),
        ("tag_eih", Setup::EyeInHand, "gripper_from_camera"),
    ] {
        let camera =
            handeye::Intrinsics::read(testdata(&format!("{name}.intrinsics.yml"))).unwrap();
        let series = handeye::io::read_frames(&testdata(&format!("{name}.jsonl"))).unwrap();
        let (on_the_way, end) = online(&series.frames, &camera, setup);
        let end = end.unwrap();
        let b = batch(&series.frames, &camera, setup).unwrap();
        // The same solve: the same X, to rounding.
        let d = entry_gap(&end.estimate.x, &b.transform);
        assert!(d < 1e-9, "{name}: {d}");
        assert_eq!(end.reason, handeye::track::Reason::End);
        assert_eq!(end.estimate.poses, 30);
        let p = end.estimate.reprojection.expect("the fit on the pixels");
        let bp = b.reprojection.as_ref().unwrap();
        assert_eq!(p.rms_px, bp.rms_px);
        assert_eq!(p.outlier_detections, bp.outlier_detections.len());
        assert_eq!(end.verdict(), b.verdict, "{name}");
        assert_eq!(
            end.estimate.uncertainty_rotation_deg,
            Some(b.uncertainty.rotation_deg)
        );
        // One estimate on the way, at 16 records, from the pixels of those 16.
        assert_eq!(on_the_way.len(), 1, "{name}");
        assert_eq!(on_the_way[0].pose, 16);
        let b16 = batch(&series.frames[..16], &camera, setup).unwrap();
        let d = entry_gap(&on_the_way[0].estimate.x, &b16.transform);
        assert!(d < 1e-9, "{name} at 16: {d}");
        assert_eq!(end.number, 2);
        // Within three sigmas of the truth.
        let truth: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(testdata(&format!("{name}.truth.json"))).unwrap(),
        )
        .unwrap();
        let truth = handeye::io::transform_from_json(&truth[frame]).unwrap();
        let (deg, t) = gap(&end.estimate.x, &truth);
        let (sr, st) = (
            end.estimate.uncertainty_rotation_deg.unwrap(),
            end.estimate.uncertainty_translation.unwrap(),
        );
        assert!(
            deg < 3.0 * sr && t < 3.0 * st,
            "{name}: {deg}° {t} vs {sr}° {st}"
        );
        // The JSON line says where X came from and how it fits the pixels.
        let json = end.json(setup, None);
        assert_eq!(json["estimator"], "reprojection");
        assert_eq!(json["reason"], "end");
        assert_eq!(json["reprojection"]["rms_px"].as_f64(), Some(bp.rms_px));
    }
}

/// A recording whose frames all turn about one axis: refused, as the batch refuses it.
#[test]
fn rotations_about_one_axis_are_refused_as_the_batch_refuses_them() {
    let sim = simulate_pixels(&PixelSimConfig::board().noise_free(), 3);
    let frames = one_axis(&sim);
    let b = batch(&frames, &sim.intrinsics, sim.setup).unwrap_err();
    let (on_the_way, end) = online(&frames, &sim.intrinsics, sim.setup);
    let end = end.unwrap_err();
    assert!(on_the_way.is_empty());
    assert_eq!(end.to_string(), b.to_string());
    assert!(matches!(end, handeye::Error::Degenerate { .. }), "{end}");
}

/// Frames of a noise-free board whose robot poses turn about the gripper's z axis only, each seen
/// from where the truth puts the camera.
fn one_axis(sim: &PixelSim) -> Vec<Frame> {
    assert_eq!(sim.setup, Setup::EyeInHand);
    let q0 = sim.frames[0].base_from_gripper;
    let points = &sim.frames[0].detections.target;
    (0..30)
        .map(|i| {
            let angle = (i as f64 - 15.0).to_radians();
            let turn = Transform::from_parts(
                Translation3::new(0.002 * i as f64, -0.001 * i as f64, 0.0),
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angle).into(),
            );
            let q = q0 * turn;
            let camera_from_target = (q * sim.x).inverse() * sim.y;
            let pixels = points
                .iter()
                .map(|p| {
                    let c = camera_from_target * nalgebra::Point3::from(Vector3::from(*p));
                    let px = sim.intrinsics.pixel(&c.coords);
                    [px.x, px.y]
                })
                .collect();
            Frame {
                base_from_gripper: q,
                camera_from_target: None,
                detections: Detections {
                    target: points.clone(),
                    pixels,
                },
            }
        })
        .collect()
}

/// Robot poses written inverted, a target in millimetres with the robot in metres: refused with
/// the batch's words; mis-detected corners: left out and counted, X still right.
#[test]
fn inverted_unit_mismatched_and_outlier_laden_streams_as_the_batch() {
    for setup in [Setup::EyeInHand, Setup::EyeToHand] {
        let sim = simulate_pixels(&PixelSimConfig::board().with_setup(setup), 5);
        let inverted: Vec<Frame> = sim
            .frames
            .iter()
            .map(|f| Frame {
                base_from_gripper: f.base_from_gripper.inverse(),
                ..f.clone()
            })
            .collect();
        let mm: Vec<Frame> = sim
            .frames
            .iter()
            .map(|f| {
                let mut f = f.clone();
                f.base_from_gripper.translation.vector *= 1000.0;
                f
            })
            .collect();
        for (what, frames) in [("inverted", &inverted), ("mm robot", &mm)] {
            let b = batch(frames, &sim.intrinsics, setup).unwrap_err();
            let (on_the_way, end) = online(frames, &sim.intrinsics, setup);
            let end = end.unwrap_err();
            assert!(on_the_way.is_empty(), "{what}: an estimate on the way");
            assert_eq!(end.to_string(), b.to_string(), "{what}");
            assert!(
                matches!(
                    end,
                    handeye::Error::Misread { .. } | handeye::Error::PixelsUnfit { .. }
                ),
                "{what}: {end}"
            );
        }
    }
    let mut config = PixelSimConfig::board();
    config.outliers = 6;
    let sim = simulate_pixels(&config, 11);
    let (_, end) = online(&sim.frames, &sim.intrinsics, sim.setup);
    let end = end.unwrap();
    let p = end.estimate.reprojection.unwrap();
    assert!(p.outlier_detections >= 6, "{p:?}");
    let (deg, t) = gap(&end.estimate.x, &sim.x);
    assert!(deg < 0.5 && t < 0.005, "{deg}° {t}");
}

/// The one reader of records with detections, record by record: a bad record costs its line and
/// names it; the others are read as `read_frames` reads them.
#[test]
fn a_bad_record_costs_its_line_only() {
    let text = std::fs::read_to_string(testdata("tag_eih.jsonl")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let n = lines.len();
    lines[2] = "{\"base_from_gripper\": ".into();
    lines[5] = lines[5].replacen("[[", "[[1, 2], [", 1); // one pixel more than target points
    lines[8] = lines[8].replacen("\"pixels\": [[", "\"pixels\": [[\"nan\", ", 1);
    lines[11] = lines[11].replace("\"pixels\"", "\"pixelz\"");
    let joined = lines.join("\n");
    let records: Vec<_> =
        handeye::io::FrameRecording::records(joined.as_bytes(), "s.jsonl").collect();
    let bad: Vec<(usize, String)> = records
        .iter()
        .filter_map(|r| match r {
            Err(handeye::Error::Parse { line, field, .. }) => Some((*line, field.clone())),
            Err(e) => panic!("{e}"),
            Ok(_) => None,
        })
        .collect();
    assert_eq!(
        bad.iter().map(|b| b.0).collect::<Vec<_>>(),
        vec![3, 6, 9, 12],
        "{bad:?}"
    );
    assert!(bad[1].1.starts_with("detections"), "{bad:?}");
    assert!(bad[2].1.starts_with("detections.pixels"), "{bad:?}");
    assert!(bad[3].1.starts_with("detections"), "{bad:?}");
    let good: Vec<usize> = records
        .iter()
        .filter_map(|r| r.as_ref().ok().map(|(l, _)| *l))
        .collect();
    assert_eq!(good.len(), n - 4);
    let whole = handeye::io::read_frames(&testdata("tag_eih.jsonl")).unwrap();
    for (line, frame) in records.iter().filter_map(|r| r.as_ref().ok()) {
        assert_eq!(frame, &whole.frames[line - 1]);
    }
}

/// A long stream keeps at most `max_frames` frames (memory bounded: counted, not timed), solves
/// over them on a bounded schedule, and its end stays within 3 sigma of the truth; the frames
/// thinned out are the ones whose robot pose another kept frame repeats.
#[test]
fn a_long_stream_keeps_a_bounded_number_of_frames() {
    for (k, setup) in [Setup::EyeInHand, Setup::EyeToHand].into_iter().enumerate() {
        let config = PixelSimConfig {
            frames: 1500,
            ..PixelSimConfig::tag().with_setup(setup)
        };
        let sim = simulate_pixels(&config, 9100 + k as u64);
        let mut c = OnlinePixels::new(sim.intrinsics, setup, Options::default())
            .unwrap()
            .with_max_frames(64)
            .unwrap();
        let start = std::time::Instant::now();
        let mut most = 0;
        let mut reports = Vec::new();
        for (i, f) in sim.frames.iter().enumerate() {
            reports.extend(c.push(f.clone(), format!("frame {}", i + 1)));
            most = most.max(c.kept_frames());
        }
        let end = c.finish().unwrap();
        eprintln!(
            "{setup:?}: 1500 records, at most {most} frames kept, {} reports, {:.2} s",
            reports.len() + 1,
            start.elapsed().as_secs_f64()
        );
        assert_eq!(most, 64);
        assert_eq!(c.frames(), 1500);
        assert!(end.estimate.poses <= 64, "{}", end.estimate.poses);
        assert_eq!(end.pose, 1500);
        // 16, 32, 64, then every 64 records: 1500 / 64 = 23 more.
        let at: Vec<usize> = reports.iter().map(|r| r.pose).collect();
        assert_eq!(&at[..4], [16, 32, 64, 128]);
        assert!(at.windows(2).all(|w| w[1] - w[0] <= 64), "{at:?}");
        let (deg, t) = gap(&end.estimate.x, &sim.x);
        let (sr, st) = (
            end.estimate.uncertainty_rotation_deg.unwrap(),
            end.estimate.uncertainty_translation.unwrap(),
        );
        assert!(
            deg < 3.0 * sr && t < 3.0 * st,
            "{setup:?}: {deg}° {t} vs {sr}° {st}"
        );
    }
    // A stream that repeats one robot pose 30 times after 20 views keeps 20 frames, and solves.
    let sim = simulate_pixels(&PixelSimConfig::tag(), 9110);
    let mut c = OnlinePixels::new(sim.intrinsics, sim.setup, Options::default())
        .unwrap()
        .with_max_frames(20)
        .unwrap();
    for (i, f) in sim.frames.iter().take(20).enumerate() {
        c.push(f.clone(), format!("frame {}", i + 1));
    }
    for i in 0..30 {
        c.push(sim.frames[3].clone(), format!("repeat {i}"));
    }
    assert_eq!(c.kept_frames(), 20);
    let end = c.finish().unwrap();
    assert_eq!(end.estimate.poses, 20);
    assert!(
        OnlinePixels::new(sim.intrinsics, sim.setup, Options::default())
            .unwrap()
            .with_max_frames(15)
            .is_err()
    );
}

/// A long stream of distinct views with the camera's own intrinsics: the focal-length check runs at
/// every estimate over the frames kept, and warns none of them (the estimates of one stream share
/// most of their frames, so one false alarm would repeat).
#[test]
fn the_camera_s_own_intrinsics_raise_no_focal_warning_on_a_long_stream() {
    let mut warned = Vec::new();
    let mut estimates = 0;
    for (config, name) in [
        (PixelSimConfig::tag(), "tag"),
        (PixelSimConfig::board(), "board"),
    ] {
        for setup in [Setup::EyeInHand, Setup::EyeToHand] {
            for seed in 0..1 {
                let config = PixelSimConfig {
                    frames: 1200,
                    ..config.with_setup(setup)
                };
                let sim = simulate_pixels(&config, 8100 + seed);
                let mut c = OnlinePixels::new(sim.intrinsics, setup, Options::default()).unwrap();
                for (f, frame_name) in sim.frames.iter().zip(names(&sim.frames)) {
                    if c.push(f.clone(), frame_name).is_some() {
                        estimates += 1;
                        let codes: Vec<&str> = c.warnings().iter().map(|w| w.code()).collect();
                        if codes.contains(&"intrinsics_disagree") {
                            warned.push(format!("{name} {setup:?} {seed} at {}", c.frames()));
                        }
                    }
                }
            }
        }
    }
    eprintln!(
        "{} of {estimates} estimates warned: {warned:?}",
        warned.len()
    );
    assert!(estimates >= 30, "{estimates}");
    assert!(warned.is_empty(), "{warned:?}");
}

/// A robot program that tours the same 30 poses again and again (fresh images each time, as a
/// camera takes them): thinning drops repeated poses first and keeps every distinct view, and the
/// images of one pose count once (they share its robot error). Before, two equal rotations had a
/// NaN distance (nalgebra's acos), so repeated poses were never "nearest": the distinct views were
/// thinned out instead, the uncertainty grew tenfold and the stream ended refused at 11 poses.
#[test]
fn a_stream_that_tours_the_same_poses_keeps_every_view_and_counts_each_pose_once() {
    use rand::{RngExt, SeedableRng};
    for setup in [Setup::EyeInHand, Setup::EyeToHand] {
        let sim = simulate_pixels(&PixelSimConfig::tag().with_setup(setup), 8200);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(1);
        let tours: Vec<Frame> = (0..60)
            .flat_map(|_| sim.frames.iter().cloned())
            .map(|mut f| {
                for p in &mut f.detections.pixels {
                    p[0] += rng.random_range(-0.5..0.5);
                    p[1] += rng.random_range(-0.5..0.5);
                }
                f
            })
            .collect();
        let one_tour = batch(&tours[..30], &sim.intrinsics, setup).unwrap();
        let (_, end) = online(&tours, &sim.intrinsics, setup);
        let end = end.unwrap_or_else(|e| panic!("{setup:?}: {e}"));
        let (deg, t) = gap(&end.estimate.x, &sim.x);
        let (sigma_deg, sigma_t) = (
            end.estimate.uncertainty_rotation_deg.unwrap(),
            end.estimate.uncertainty_translation.unwrap(),
        );
        eprintln!(
            "{setup:?}: end {deg:.3}° {:.2} mm, sigma {sigma_deg:.3}° {:.2} mm; one tour's sigma {:.3}° {:.2} mm",
            t * 1e3,
            sigma_t * 1e3,
            one_tour.uncertainty.rotation_deg,
            one_tour.uncertainty.translation * 1e3
        );
        assert!(
            deg < 3.0 * sigma_deg && t < 3.0 * sigma_t,
            "{setup:?}: beyond 3 sigma"
        );
        // Sixty tours of the same poses know what one tour knows about the robot's error, and
        // about as much: not ten times less (views thinned out), not eight times more (images
        // counted as poses).
        for (online, once) in [
            (sigma_deg, one_tour.uncertainty.rotation_deg),
            (sigma_t, one_tour.uncertainty.translation),
        ] {
            assert!(
                online < 1.5 * once && online > 0.4 * once,
                "{setup:?}: {online} vs {once}"
            );
        }
    }
}

/// The one online calibrator both faces drive (`OnlineCalibrator::on_pixels`, issue 31): the same
/// reports as the pixel calibrator behind it, its step and last report, the unit the poses tell;
/// poses refused on it, frames refused on a calibrator of poses, the settings that do not apply
/// refused by name, and its state never saved as another calibrator's.
#[test]
fn the_online_calibrator_on_the_pixels_reports_what_the_pixel_calibrator_does() {
    use handeye::{Estimator, Name, OnlineCalibrator, OnlineConfig, PosePair, Record, Unit};
    let config = OnlineConfig {
        estimator: Estimator::Accumulate,
        ..OnlineConfig::default()
    };
    for (name, setup) in [
        ("board_eth", Setup::EyeToHand),
        ("tag_eih", Setup::EyeInHand),
    ] {
        let camera =
            handeye::Intrinsics::read(testdata(&format!("{name}.intrinsics.yml"))).unwrap();
        let series = handeye::io::read_frames(&testdata(&format!("{name}.jsonl"))).unwrap();
        let (on_the_way, end) = online(&series.frames, &camera, setup);
        let mut c = OnlineCalibrator::on_pixels(camera, OnlineConfig { setup, ..config }).unwrap();
        assert!(c.on_the_pixels());
        assert!(
            c.pending().is_some(),
            "{name}: nothing yet, and it says why"
        );
        let mut reports = Vec::new();
        for (f, n) in series.frames.iter().zip(names(&series.frames)) {
            let r = c
                .push(Record::frame(f.clone()).named(Name::Text(&n)))
                .unwrap()
                .report;
            // The estimate to use is what the push returned, or, when it returned none, the
            // one before it (a push without a report changes nothing a face would print).
            let before = reports.last().cloned();
            assert_eq!(c.last_report(), r.clone().or(before), "{name}");
            reports.extend(r);
        }
        assert_eq!(reports, on_the_way, "{name}");
        assert_eq!(c.poses(), series.frames.len());
        assert_eq!(c.last_report(), on_the_way.last().cloned());
        let last = c.finish().unwrap().report.expect("the end's report");
        assert_eq!(last, end.unwrap(), "{name}");
        assert_eq!(c.last_report(), Some(last));
        assert!(c.pending().is_none(), "{name}");
        // The testdata are in metres: the first robot pose and the target's place tell.
        assert_eq!(c.unit(), Unit::Metre, "{name}");
        // Poses are not taken on the pixels; the state (the frames) is not saved.
        let pose = PosePair {
            base_from_gripper: Transform::identity(),
            camera_from_target: Transform::identity(),
        };
        assert!(c.push(&pose).is_err());
        let saved = serde_json::to_string(&c).unwrap_err().to_string();
        assert!(saved.contains("not saved"), "{saved}");
    }
    // Frames are not taken on poses; the settings that do not apply on the pixels are named.
    let camera = handeye::Intrinsics::read(testdata("tag_eih.intrinsics.yml")).unwrap();
    let series = handeye::io::read_frames(&testdata("tag_eih.jsonl")).unwrap();
    let mut poses = OnlineCalibrator::new(config).unwrap();
    let frame = Record::frame(series.frames[0].clone()).named(Name::Text("frame 1"));
    let e = poses.push(frame).unwrap_err();
    assert!(e.to_string().contains("intrinsics"), "{e}");
    for (what, bad) in [
        (
            "paper's estimator",
            OnlineConfig {
                estimator: Estimator::Paper,
                ..config
            },
        ),
        (
            "optimal",
            OnlineConfig {
                optimal: true,
                ..config
            },
        ),
    ] {
        let e = OnlineCalibrator::on_pixels(camera, bad).unwrap_err();
        assert!(e.to_string().contains(what), "{what}: {e}");
    }
    let prior: handeye::Prior = "tz=0.1".parse().unwrap();
    let e = OnlineCalibrator::on_pixels(camera, config)
        .unwrap()
        .with_priors(&[prior])
        .unwrap_err();
    assert!(e.to_string().contains("prior"), "{e}");
    // A calibrator of poses still saves and resumes.
    let state = serde_json::to_string(&poses).unwrap();
    let resumed: OnlineCalibrator = serde_json::from_str(&state).unwrap();
    assert!(!resumed.on_the_pixels());
}
