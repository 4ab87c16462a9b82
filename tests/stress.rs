//! The numerical stress suite on every backend present: `occlu stress`
//! itself, translation invariance at 1e7, a culler that is wrong on
//! purpose, and a randomised property test (random scenes and cameras: every
//! conservative mode draws at least the objects visible in the reference).

mod common;

use std::ops::ControlFlow;

use common::{DropOneVisible, boxes, gpus, occlu, own_stderr, stdout};
use glam::DVec3;
use occlu::camera::{Camera, look_rotation};
use occlu::cull::{Culler, ModeId, ModeParams, create, modes};
use occlu::gpu::Resolution;
use occlu::hierarchy::HierarchyParams;
use occlu::rng::Rng;
use occlu::stress::{DepthTolerance, StressCase, StressRow, run_case, select};
use serde_json::Value;

const SIZE: Resolution = Resolution {
    width: 200,
    height: 150,
};

#[test]
fn occlu_stress_passes_on_every_backend() {
    for gpu in gpus() {
        let backend = gpu.adapter.backend.clone();
        let dir = tempfile::tempdir().unwrap();
        let out = occlu(&["stress", "--backend", &backend, "--out", dir.path().to_str().unwrap()]);
        let text = stdout(&out);
        assert!(out.status.success(), "{backend}: {text}\n{:?}", own_stderr(&out));
        let report: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("stress.json")).unwrap()).unwrap();
        let rows = report["rows"].as_array().unwrap();
        let cases = select(&[]).unwrap();
        let conservative = modes().filter(|m| m.conservative).count();
        assert!(
            rows.len() >= cases.len() * conservative,
            "{backend}: every case ran every mode"
        );
        for row in rows.iter().filter(|r| r["conservative"] == true) {
            assert_eq!(row["error_pixels"], 0, "{backend}: {row}");
            assert_eq!(row["missed_objects"], 0, "{backend}: {row}");
            assert_eq!(row["max_depth_error"], 0.0, "{backend}: {row}");
        }
        let checks = report["invariance"].as_array().unwrap();
        assert_eq!(checks.len(), 5, "three offsets and two scales");
        assert!(
            checks.iter().all(|c| c["difference"]["pixels_beyond"] == 0),
            "{backend}: {checks:?}"
        );
        let passed = rows.iter().filter(|r| r["conservative"] == true).count() + checks.len();
        assert!(
            text.ends_with(&format!("{passed} passed, 0 failed\n")),
            "{backend}: {text}"
        );
        assert!(std::fs::read_to_string(dir.path().join("stress.md")).unwrap() == text);
    }
}

#[test]
fn a_parameter_set_for_stress_runs_and_the_report_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let out = occlu(&[
        "stress",
        "--modes",
        "hiz",
        "--cases",
        "slits",
        "--param",
        "hiz.texels=2",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    let text = stdout(&out);
    assert!(out.status.success(), "{text}\n{:?}", own_stderr(&out));
    assert!(text.contains("parameters set: hiz.texels=2"), "{text}");
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("stress.json")).unwrap()).unwrap();
    assert_eq!(report["params"], serde_json::json!(["hiz.texels=2"]));
    assert_eq!(report["rows"][0]["error_pixels"], 0, "{report}");
}

#[test]
fn a_parameter_given_to_stress_reaches_every_culler_it_builds() {
    // hiz.texels=1 is out of hiz's range: only a culler built with it
    // refuses it, before anything renders.
    let cases = select(&["slits".to_string()]).unwrap();
    let given = ModeParams::default().with("hiz.texels", "1");
    for gpu in gpus().into_iter().filter(|g| g.gpu_driven) {
        let run = occlu::stress::run(&gpu, &cases, &[ModeId::Hiz], &given, SIZE, &mut |_| {
            ControlFlow::Continue(())
        });
        let error = run.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(error.contains("hiz.texels"), "{}: {error}", gpu.adapter.backend);
    }
}

#[test]
fn the_scene_at_1e7_renders_the_image_at_the_origin_bit_for_bit() {
    let cases = select(&["offset-1e7".to_string()]).unwrap();
    let (origin, far) = (&cases[0], &cases[1]);
    assert_eq!(far.baseline.as_ref().unwrap().tolerance, DepthTolerance::EXACT);
    assert!(
        far.scene.bounds.min.min_element().abs() > 9e6,
        "the geometry itself is far away"
    );
    for gpu in gpus() {
        let depth = |case: &StressCase| {
            let mut dr = [create("dr", &case.scene, &ModeParams::default()).unwrap()];
            let hierarchy = HierarchyParams::default();
            run_case(&gpu, case, &hierarchy, &mut dr, SIZE, true, &mut |_| {})
                .unwrap()
                .depths
        };
        let (a, b) = (depth(origin), depth(far));
        assert_eq!(a.len(), 10);
        for (frame, (a, b)) in a.iter().zip(&b).enumerate() {
            let covered = a.iter().filter(|&&d| d > 0.0).count();
            assert!(covered > a.len() / 2, "frame {frame} shows the town");
            let differing = a.iter().zip(b).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
            assert_eq!(differing, 0, "{}: frame {frame}", gpu.adapter.backend);
        }
    }
}

#[test]
fn a_case_at_a_size_the_adapter_cannot_hold_is_skipped_and_the_run_goes_on() {
    let mut too_wide = select(&["slits".to_string()]).unwrap().remove(0);
    too_wide.name = "too wide".into();
    too_wide.resolution = Some(Resolution {
        width: 1 << 20,
        height: 1,
    });
    let cases = [too_wide, select(&["vertical".to_string()]).unwrap().remove(0)];
    for gpu in gpus() {
        let report = occlu::stress::run(&gpu, &cases, &[ModeId::Vfc], &ModeParams::default(), SIZE, &mut |_| {
            ControlFlow::Continue(())
        })
        .unwrap();
        assert_eq!(report.skipped_cases.len(), 1, "{}", gpu.adapter.backend);
        assert_eq!(report.skipped_cases[0].case, "too wide");
        assert!(
            report.skipped_cases[0].reason.contains("render target side"),
            "{:?}",
            report.skipped_cases
        );
        assert_eq!(report.rows.len(), 1, "the other case ran");
        assert!(occlu::stress::render_markdown(&report).contains("skipped case: too wide: 1048576x1"));
        // The run's own size the adapter cannot hold is refused: every case
        // without a size of its own would be skipped, checking nothing.
        let refused = occlu::stress::run(
            &gpu,
            &cases[1..],
            &[ModeId::Vfc],
            &ModeParams::default(),
            Resolution {
                width: 1 << 20,
                height: 1,
            },
            &mut |_| ControlFlow::Continue(()),
        );
        let Err(error) = refused else { panic!("refused") };
        assert!(
            error.is_input_error() && error.to_string().contains("render target side"),
            "{error}"
        );
    }
}

#[test]
fn an_auto_candidate_the_adapter_cannot_run_given_a_parameter_is_reported_skipped() {
    let cases = select(&["vertical".to_string()]).unwrap();
    let given = ModeParams::default().with("chc.visible_for", "3");
    for mut gpu in gpus() {
        // An adapter that cannot count visible pixels, as some GL ones.
        gpu.pixel_counts = false;
        let stress = |modes: &[ModeId], given: &ModeParams| {
            occlu::stress::run(&gpu, &cases, modes, given, SIZE, &mut |_| ControlFlow::Continue(()))
        };
        let report = stress(&[ModeId::Auto], &given).unwrap();
        let skipped: Vec<(&str, &str)> = report
            .skipped
            .iter()
            .map(|s| (s.mode.as_str(), s.reason.as_str()))
            .collect();
        assert_eq!(skipped.len(), 1, "{}: {skipped:?}", gpu.adapter.backend);
        assert_eq!(skipped[0].0, "chc");
        assert!(
            skipped[0]
                .1
                .ends_with(": auto runs without it, so chc.visible_for is not used")
        );
        assert!(occlu::stress::render_markdown(&report).contains("skipped: chc: "));
        // Not given one, auto's candidates say which ran: nothing skipped.
        assert!(
            stress(&[ModeId::Auto], &ModeParams::default())
                .unwrap()
                .skipped
                .is_empty()
        );
        // chc alone cannot run: nothing would be checked.
        let refused = stress(&[ModeId::Chc], &given);
        assert!(
            matches!(refused, Err(occlu::stress::StressError::NoModeRuns { .. })),
            "{:?}",
            refused.err().map(|e| e.to_string())
        );
    }
}

#[test]
fn a_culler_that_drops_a_visible_object_fails_the_stress_verdict() {
    let case = select(&["on-face".to_string()]).unwrap().remove(0);
    for gpu in gpus() {
        let mut cullers: Vec<Box<dyn Culler>> = vec![Box::new(DropOneVisible(Vec::new()))];
        let outcome = run_case(
            &gpu,
            &case,
            &HierarchyParams::default(),
            &mut cullers,
            SIZE,
            false,
            &mut |_| {},
        )
        .unwrap();
        let row = StressRow::tally(&case.name, "drop-one", true, &outcome.rows);
        assert_eq!(row.missed_objects, case.cameras.len() as u64, "{row:?}");
        assert!(row.error_pixels > 0 && row.max_depth_error > 0.0, "{row:?}");
        assert_eq!(row.passed(), Some(false));
    }
}

/// A random scene of boxes: sizes from 1 cm to 30 m, some flat, some
/// overlapping, around the origin.
fn random_boxes(rng: &mut Rng) -> Vec<(DVec3, DVec3)> {
    (0..rng.int(20, 120))
        .map(|_| {
            let centre = DVec3::new(rng.range(-40.0, 40.0), rng.range(-10.0, 20.0), rng.range(-40.0, 40.0));
            let mut half = DVec3::new(rng.range(-4.6, 3.4), rng.range(-4.6, 3.4), rng.range(-4.6, 3.4)).exp();
            if rng.int(0, 5) == 0 {
                half[rng.int(0, 2) as usize] = 0.0;
            }
            (centre - half, centre + half)
        })
        .collect()
}

/// Random cameras: anywhere (inside boxes too) looking anywhere, looking at
/// a box, or just in front of a box's face (closer than twice the near
/// distance, so the near plane often cuts the box), with random near planes
/// and fields of view.
fn random_cameras(rng: &mut Rng, list: &[(DVec3, DVec3)]) -> Vec<Camera> {
    (0..6)
        .map(|k| {
            let near = 10f64.powf(rng.range(-3.0, 0.0));
            let (min, max) = list[rng.int(0, list.len() as u32 - 1) as usize];
            let anywhere = DVec3::new(rng.range(-50.0, 50.0), rng.range(-5.0, 30.0), rng.range(-50.0, 50.0));
            let (eye, forward) = match k % 3 {
                0 => (
                    anywhere,
                    DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)),
                ),
                1 => (anywhere, (min + max) / 2.0 - anywhere),
                _ => {
                    let axis = rng.int(0, 2) as usize;
                    let mut eye = DVec3::new(
                        rng.range(min.x, max.x),
                        rng.range(min.y, max.y),
                        rng.range(min.z, max.z),
                    );
                    eye[axis] = max[axis] + rng.range(0.0, 2.0 * near);
                    let mut forward = DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), rng.range(-0.5, 0.5));
                    forward[axis] = -1.0;
                    (eye, forward)
                }
            };
            Camera {
                eye,
                rotation: look_rotation(if forward.length() > 1e-6 { forward } else { DVec3::Z }, DVec3::Y),
                fov_y: rng.range(5.0, 150.0).to_radians(),
                near,
                aspect: 1.0,
            }
        })
        .collect()
}

#[test]
fn conservative_modes_draw_every_visible_object_of_random_scenes() {
    let mut rng = Rng::new(0xC0FFEE);
    let scenes: Vec<StressCase> = (0..8)
        .map(|k| {
            let list = random_boxes(&mut rng);
            StressCase {
                name: format!("random {k}"),
                summary: String::new(),
                cameras: random_cameras(&mut rng, &list),
                scene: boxes(&list),
                baseline: None,
                resolution: None,
            }
        })
        .collect();
    let modes: Vec<&str> = modes().filter(|m| m.conservative).map(|m| m.id.name()).collect();
    for gpu in gpus() {
        let mut visible = 0;
        for (k, case) in scenes.iter().enumerate() {
            // Every other scene one object per leaf: each box is then tested
            // on its own, with no neighbour in its leaf to make it visible.
            let params = if k % 2 == 0 {
                HierarchyParams::default()
            } else {
                common::one_object_per_leaf()
            };
            let mut cullers = modes
                .iter()
                .map(|m| create(m, &case.scene, &ModeParams::default()).unwrap())
                .collect::<Vec<_>>();
            let outcome = run_case(&gpu, case, &params, &mut cullers, SIZE, false, &mut |_| {}).unwrap();
            for row in &outcome.rows {
                let at = format!(
                    "{}: {} frame {} ({})",
                    gpu.adapter.backend, case.name, row.frame, row.mode
                );
                assert_eq!(row.missed_objects, Some(0), "{at}: drew fewer than the visible set");
                assert_eq!(row.error_pixels, Some(0), "{at}");
                visible += row.visible_objects.unwrap();
            }
        }
        // The cameras see something: the property is not vacuous.
        assert!(
            visible > 100,
            "{}: {visible} visible objects in all",
            gpu.adapter.backend
        );
    }
}
