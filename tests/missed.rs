//! Naming what a mode missed: missed.csv's rows, report.md's list and
//! `occlu render --show-missed`, for a culler that is wrong on purpose
//! (it drops the first visible object), checked against pixel footprints
//! computed on the CPU; and what a mode culled with, `occlu render
//! --occluders`.

mod common;

use common::{DropOneVisible, boxes, held, occlu, run_modes, still};
use glam::DVec3;
use occlu::cull::{Culler, ModeParams, create};
use occlu::gpu::Resolution;
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::measure::MissedObject;
use occlu::picture::{Look, PictureError, render};
use occlu::report::{MissedSummary, read_results, render_markdown, write_results};
use occlu::world::World;

const SIZE: Resolution = Resolution {
    width: 100,
    height: 100,
};

/// Two thin quads 10 units ahead of the eye, seen with a 90° field of view
/// at 100×100 (one unit is 5 pixels there); their edges lie between pixel
/// centres. The left one is object 0, the one the wrong culler drops.
fn two_quads() -> [(DVec3, DVec3); 2] {
    [
        (DVec3::new(-3.03, -0.77, -10.0), DVec3::new(-0.97, 0.77, -9.999)),
        (DVec3::new(1.17, -1.03, -10.0), DVec3::new(2.63, 1.03, -9.999)),
    ]
}

/// Pixel centres (x, y) whose ray hits the front face (z = -9.999) of the
/// quad `(min, max)`, row-major.
fn footprint(min: DVec3, max: DVec3) -> Vec<(u32, u32)> {
    let mut pixels = Vec::new();
    for py in 0..SIZE.height {
        for px in 0..SIZE.width {
            let ndc_x = (f64::from(px) + 0.5) / f64::from(SIZE.width) * 2.0 - 1.0;
            let ndc_y = 1.0 - (f64::from(py) + 0.5) / f64::from(SIZE.height) * 2.0;
            let (x, y) = (ndc_x * 9.999, ndc_y * 9.999); // tan(45°) = 1
            if min.x < x && x < max.x && min.y < y && y < max.y {
                pixels.push((px, py));
            }
        }
    }
    pixels
}

#[test]
fn a_dropped_object_is_named_with_its_wrong_pixels_and_the_first_of_them() {
    let quads = two_quads();
    let scene = boxes(&quads);
    let dropped = footprint(quads[0].0, quads[0].1);
    assert_eq!(dropped.len(), 10 * 8);
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let path = still(DVec3::ZERO, DVec3::NEG_Z, 90.0);
    for gpu in common::gpus() {
        let mut cullers: Vec<Box<dyn Culler>> = vec![
            Box::new(DropOneVisible(Vec::new())),
            create("dr", &scene, &ModeParams::default()).unwrap(),
        ];
        let out = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, SIZE);
        assert_eq!(out.rows[0].error_pixels, Some(80), "{}", gpu.adapter);
        let (x, y) = dropped[0];
        assert_eq!(
            out.missed,
            vec![MissedObject {
                mode: "drop-one".into(),
                frame: 0,
                object: 0,
                name: "box0".into(),
                drawn: false,
                wrong_pixels: 80,
                first_x: Some(x),
                first_y: Some(y),
            }],
            "{}: dr is exact and lists nothing",
            gpu.adapter
        );
    }
}

#[test]
fn missed_csv_and_report_list_what_was_missed_and_an_exact_run_removes_the_list() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let out = occlu(&[
        "bench",
        "--scene",
        "city:blocks=2",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--modes",
        "vfc",
        "--resolution",
        "64x48",
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", common::stderr(&out));
    assert!(!run.join("missed.csv").exists(), "an exact run names nothing");
    let (mut summary, rows) = read_results(&run).unwrap();
    assert_eq!(summary.missed, MissedSummary::default());
    // What the culler that drops a visible object missed, twice over (as
    // two frames would), then rows a table must cope with: names with '|',
    // one a spreadsheet would run as a formula and Markdown would render, a
    // drawn object, one with no wrong pixel.
    let quads = two_quads();
    let scene = boxes(&quads);
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let path = common::held(DVec3::ZERO, DVec3::NEG_Z, 90.0, 2);
    let gpu = common::gpus().remove(0);
    let mut cullers: Vec<Box<dyn Culler>> = vec![Box::new(DropOneVisible(Vec::new()))];
    let mut missed = run_modes(&gpu, &scene, &hierarchy, &path, &mut cullers, SIZE).missed;
    assert_eq!(missed.len(), 2);
    let (x, y) = footprint(quads[0].0, quads[0].1)[0];
    missed.extend((2..12).map(|k| MissedObject {
        mode: "vfc".into(),
        frame: 0,
        object: k,
        name: if k == 3 { "=cmd_<b>".into() } else { format!("part|{k}") },
        drawn: k % 2 == 0,
        wrong_pixels: u64::from(k),
        first_x: (k > 2).then_some(3),
        first_y: (k > 2).then_some(k),
    }));
    summary.missed = MissedSummary::of(&missed);
    let files = write_results(&run, &mut summary, &rows, &missed, None).unwrap();
    let csv_path = files.missed_csv.expect("written when something was missed");
    let csv = std::fs::read_to_string(&csv_path).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "mode,frame,object,name,drawn,wrong_pixels,first_x,first_y");
    assert_eq!(lines[1], format!("drop-one,0,0,box0,false,80,{x},{y}"));
    assert_eq!(lines[2], format!("drop-one,1,0,box0,false,80,{x},{y}"));
    assert_eq!(lines[3], "vfc,0,2,part|2,true,2,,");
    assert_eq!(lines[4], "vfc,0,3,'=cmd_<b>,false,3,3,3");
    assert_eq!(lines[12], "vfc,0,11,part|11,false,11,3,11");
    assert_eq!(lines.len(), 13);
    let report = std::fs::read_to_string(&files.report_md).unwrap();
    assert_eq!(report, render_markdown(&summary));
    assert!(report.contains("the first 10 of 12 rows of missed.csv"), "{report}");
    assert!(
        report.contains("| vfc | 0 | 9 | part\\|9 | no | 9 | (3, 9) |"),
        "{report}"
    );
    assert!(
        report.contains("| vfc | 0 | 3 | =cmd\\_\\<b\\> | no | 3 | (3, 3) |"),
        "{report}"
    );
    assert!(!report.contains("part\\|10"), "only the first ten");
    summary.missed = MissedSummary::default();
    let files = write_results(&run, &mut summary, &rows, &[], None).unwrap();
    assert!(
        files.missed_csv.is_none() && !csv_path.exists(),
        "a stale list is removed"
    );
}

#[test]
fn show_missed_paints_the_dropped_object_magenta_and_nothing_else() {
    let quads = two_quads();
    let scene = boxes(&quads);
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let path = still(DVec3::ZERO, DVec3::NEG_Z, 90.0);
    let look = Look {
        resolution: SIZE,
        overview: false,
        heat: false,
        show_missed: true,
        occluders: false,
    };
    let magenta = [255u8, 0, 255];
    for gpu in common::gpus() {
        let mut world = World::new(scene.clone(), hierarchy.clone());
        let picture = render(&gpu, &mut world, &path, Box::new(DropOneVisible(Vec::new())), 0, &look).unwrap();
        let wrong = picture.wrong.as_ref().expect("asked for");
        assert_eq!(wrong.pixels, 80, "{}", gpu.adapter);
        assert_eq!(wrong.objects.len(), 1);
        assert_eq!((wrong.objects[0].object, wrong.objects[0].drawn), (0, false));
        let at = |(x, y): (u32, u32)| {
            let i = 3 * (y * SIZE.width + x) as usize;
            [picture.rgb[i], picture.rgb[i + 1], picture.rgb[i + 2]]
        };
        for pixel in footprint(quads[0].0, quads[0].1) {
            assert_eq!(at(pixel), magenta, "{pixel:?} of the dropped quad on {}", gpu.adapter);
        }
        for pixel in footprint(quads[1].0, quads[1].1) {
            assert_ne!(at(pixel), magenta, "{pixel:?} of the drawn quad on {}", gpu.adapter);
        }
        // The outline of the dropped quad's box reaches beyond the wrong
        // pixels: magenta also where the quad is not.
        let painted = picture.rgb.chunks(3).filter(|p| *p == magenta).count();
        assert!(painted > 80, "{painted} magenta pixels");

        let plain = Look {
            show_missed: false,
            ..look
        };
        let mut world = World::new(scene.clone(), hierarchy.clone());
        let picture = render(&gpu, &mut world, &path, Box::new(DropOneVisible(Vec::new())), 0, &plain).unwrap();
        assert!(picture.wrong.is_none());
        assert!(picture.rgb.chunks(3).all(|p| p != magenta), "only when asked");
    }
}

#[test]
fn occluders_lays_swrs_buffer_over_the_quads_it_culled_with_and_dims_the_rest() {
    let quads = two_quads();
    // And a box behind the first quad, which the buffer hides.
    let hidden = (DVec3::new(-2.5, -0.5, -12.0), DVec3::new(-1.5, 0.5, -11.0));
    let scene = boxes(&[quads[0], quads[1], hidden]);
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    // Frame 2: the quads drawn in frame 1 are frame 2's occluders.
    let path = held(DVec3::ZERO, DVec3::NEG_Z, 90.0, 3);
    let look = Look {
        resolution: SIZE,
        overview: false,
        heat: false,
        show_missed: false,
        occluders: true,
    };
    // Built every frame, whatever it costs (a buffer that spares less
    // drawing than it costs rests, and is empty).
    let building = |resolution: &str| {
        let params = [format!("swr.resolution={resolution}"), "swr.rests=false".to_string()];
        ModeParams::parse(&params, &["swr".parse().unwrap()]).unwrap()
    };
    let one_cell_per_pixel = building("100x100");
    let inside: Vec<Vec<(u32, u32)>> = quads.iter().map(|&(min, max)| footprint(min, max)).collect();
    for gpu in common::gpus() {
        let mut world = World::new(scene.clone(), hierarchy.clone());
        let swr = create("swr", &scene, &one_cell_per_pixel).unwrap();
        let picture = render(&gpu, &mut world, &path, swr, 2, &look).unwrap();
        let at = |(x, y): (u32, u32)| {
            let i = 3 * (y * SIZE.width + x) as usize;
            [picture.rgb[i], picture.rgb[i + 1], picture.rgb[i + 2]]
        };
        // Both quads' front faces lie at one depth: one colour, the far
        // end of the ramp, over every pixel of them, their diagonals too.
        for pixel in inside.iter().flatten() {
            assert_eq!(at(*pixel), [26, 64, 153], "{pixel:?} on {}", gpu.adapter);
        }
        // The rest is the frame dimmed to a third.
        let covered: usize = inside.iter().map(Vec::len).sum();
        let dimmed = picture
            .rgb
            .chunks(3)
            .filter(|p| p.iter().all(|&c| c <= 255 / 3))
            .count();
        assert_eq!(dimmed, (SIZE.width * SIZE.height) as usize - covered, "{}", gpu.adapter);

        // Cells of 2 × 2 pixels: some of the quads' edges cut through
        // cells, whose covered pixels the working layer holds. Those are
        // orange, and only those: every pixel of the quads is coloured or
        // orange, and no pixel outside them is either.
        let mut world = World::new(scene.clone(), hierarchy.clone());
        let coarse = building("50x50");
        let swr = create("swr", &scene, &coarse).unwrap();
        let picture = render(&gpu, &mut world, &path, swr, 2, &look).unwrap();
        // The depth ramp's blue is at least 0.6 of full and its red at
        // least 0.1; a dimmed pixel's every channel at most a third; mixed
        // half and half with orange, the ramp's red comes to 140 or more
        // and its blue to half or less.
        let kind = |i: usize| match &picture.rgb[3 * i..3 * i + 3] {
            &[_, _, b] if b >= 153 => "depth",
            &[r, _, b] if r >= 140 && b <= 128 => "orange",
            p if p.iter().all(|&c| c <= 85) => "dimmed",
            _ => "neither",
        };
        let (mut orange, mut depth) = (0, 0);
        for i in 0..(SIZE.width * SIZE.height) as usize {
            let pixel = ((i as u32) % SIZE.width, (i as u32) / SIZE.width);
            let on_a_quad = inside.iter().flatten().any(|&p| p == pixel);
            match (kind(i), on_a_quad) {
                ("orange", true) => orange += 1,
                ("depth", true) => depth += 1,
                ("dimmed", false) => {}
                (k, _) => panic!("{pixel:?} is {k} on {}", gpu.adapter),
            }
        }
        assert_eq!(orange + depth, covered, "{}", gpu.adapter);
        assert!(
            orange > 0 && depth > 0,
            "{orange} orange, {depth} coloured on {}",
            gpu.adapter
        );

        let mut world = World::new(scene.clone(), hierarchy.clone());
        let roc = create("roc", &scene, &ModeParams::default()).unwrap();
        match render(&gpu, &mut world, &path, roc, 2, &look) {
            Err(e @ PictureError::NoOccluderDepths { .. }) => assert!(e.is_input_error()),
            other => panic!("roc keeps no CPU buffer: {:?}", other.map(|p| p.drawn)),
        }
    }
}
