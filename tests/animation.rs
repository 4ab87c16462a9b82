//! `occlu flythrough` and `bench --animate`: the animation decoded frame by
//! frame, each panel held against `occlu render` of the same frame and mode
//! (shrunk here by its own rule), on every backend, on a built-in scene and
//! a model file.

mod common;

use std::path::{Path, PathBuf};

use common::{occlu, own_stderr};

/// A decoded APNG: its size, each frame's pixels (RGB) and delay.
struct Decoded {
    width: u32,
    height: u32,
    frames: Vec<Vec<u8>>,
    delays: Vec<(u16, u16)>,
}

fn decode(path: &Path) -> Decoded {
    let mut decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().unwrap();
    let (width, height) = (reader.info().width, reader.info().height);
    let count = reader.info().animation_control.expect("an animated PNG").num_frames;
    let mut frames = Vec::new();
    let mut delays = Vec::new();
    for _ in 0..count {
        let mut rgb = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut rgb).unwrap();
        assert_eq!((info.width, info.height), (width, height), "every frame whole");
        let control = reader.info().frame_control.expect("a frame control per frame");
        assert_eq!((control.x_offset, control.y_offset), (0, 0));
        delays.push((control.delay_num, control.delay_den));
        rgb.truncate(info.buffer_size());
        assert_eq!(rgb.len(), (width * height * 3) as usize, "RGB, 8 bits");
        frames.push(rgb);
    }
    Decoded {
        width,
        height,
        frames,
        delays,
    }
}

/// An RGB PNG's size and pixels.
fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let mut decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().unwrap();
    let mut rgb = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut rgb).unwrap();
    rgb.truncate(info.buffer_size());
    (info.width, info.height, rgb)
}

/// `rgb` shrunk by `k`: each pixel the mean of a k × k block, rounded half
/// up (as the README says the panels are made).
fn shrunk(rgb: &[u8], width: u32, height: u32, k: u32) -> Vec<u8> {
    let (w, h) = (width / k, height / k);
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            for c in 0..3 {
                let mut sum = 0u32;
                for yy in y * k..(y + 1) * k {
                    for xx in x * k..(x + 1) * k {
                        sum += u32::from(rgb[((yy * width + xx) * 3 + c) as usize]);
                    }
                }
                out.push(((sum + k * k / 2) / (k * k)) as u8);
            }
        }
    }
    out
}

/// The `w` × `h` pixels of `rgb` (rows of `width`) from (`x`, `y`).
fn crop(rgb: &[u8], width: u32, (x, y): (u32, u32), (w, h): (u32, u32)) -> Vec<u8> {
    (y..y + h)
        .flat_map(|row| {
            let start = ((row * width + x) * 3) as usize;
            rgb[start..start + (w * 3) as usize].iter().copied()
        })
        .collect()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const SIZE: &str = "96x72";
const MODES: [&str; 2] = ["vfc", "roc"];

/// A model file (an OBJ town of boxes) and a built-in scene, as arguments.
fn scenes(dir: &Path) -> Vec<Vec<String>> {
    let town: PathBuf = common::write(dir, "town.obj", common::boxes_obj(&common::town(false)));
    vec![
        vec!["--scene".into(), "city:blocks=1".into(), "--movers".into(), "3".into()],
        vec![s(&town).into()],
    ]
}

#[test]
fn every_panel_of_a_flythrough_is_what_render_paints_of_its_frame_and_mode() {
    let dir = tempfile::tempdir().unwrap();
    for backend in common::backends() {
        for scene in scenes(dir.path()) {
            let scene: Vec<&str> = scene.iter().map(String::as_str).collect();
            let with = |command: &str, extra: &[&str], out: &Path| {
                let mut args = vec![command, "--backend", &backend, "--resolution", SIZE, "-o", s(out)];
                args.extend_from_slice(&scene);
                args.extend_from_slice(extra);
                let run = occlu(&args);
                assert!(run.status.success(), "{backend} {args:?}: {:?}", own_stderr(&run));
                run
            };
            let exact = dir.path().join("exact.png");
            let fly = ["--modes", "vfc,roc", "--overview", "--range", "3..8:2", "--quiet"];
            let mut true_colour = fly.to_vec();
            true_colour.push("--true-colour");
            with("flythrough", &true_colour, &exact);
            let animation = decode(&exact);
            // Frames 3, 5 and 7, each shown 2/30 s; the two modes side by
            // side, each its view and the overview shrunk by 2 under a
            // caption.
            assert_eq!(animation.frames.len(), 3, "{backend} {scene:?}");
            assert!(animation.delays.iter().all(|&d| d == (2, 30)), "{:?}", animation.delays);
            let (panel_w, picture_h) = (96 * 2 / 2, 72 / 2);
            assert_eq!(animation.width, 2 * panel_w, "two panels in a row");
            let caption = animation.height - picture_h;
            assert!(
                (10..=40).contains(&caption),
                "a caption above the picture: {}",
                animation.height
            );
            for (i, frame) in [3, 5, 7].into_iter().enumerate() {
                for (k, mode) in MODES.into_iter().enumerate() {
                    let still = dir.path().join(format!("{mode}-{frame}.png"));
                    let f = frame.to_string();
                    with("render", &["--frame", &f, "--mode", mode, "--overview"], &still);
                    let (w, h, rgb) = read_png(&still);
                    let x = k as u32 * panel_w;
                    let panel = crop(
                        &animation.frames[i],
                        animation.width,
                        (x, caption),
                        (panel_w, picture_h),
                    );
                    assert!(
                        panel == shrunk(&rgb, w, h, 2),
                        "{backend} {scene:?}: frame {frame}, {mode}: the panel is not render's picture shrunk"
                    );
                    let text = crop(&animation.frames[i], animation.width, (x, 0), (panel_w, caption));
                    assert!(
                        text.iter().any(|&c| c > 200) && text.iter().filter(|&&c| c == 40).count() > text.len() / 2,
                        "white text on the caption's grey"
                    );
                }
            }

            // One palette for the whole animation: the same frames, each
            // pixel close to the exact one.
            let palette = dir.path().join("palette.png");
            with("flythrough", &fly, &palette);
            let indexed = decode(&palette);
            assert_eq!((indexed.width, indexed.height), (animation.width, animation.height));
            assert_eq!(indexed.frames.len(), 3);
            for (a, b) in animation.frames.iter().zip(&indexed.frames) {
                let diff: Vec<u32> = a.iter().zip(b).map(|(&x, &y)| u32::from(x.abs_diff(y))).collect();
                let mean = diff.iter().sum::<u32>() as f64 / diff.len() as f64;
                let far = diff.iter().filter(|&&d| d > 32).count();
                assert!(
                    mean < 4.0 && far * 100 < diff.len(),
                    "{backend}: mean {mean}, {far} far off"
                );
            }
        }
    }
}

#[test]
fn bench_animates_its_run_beside_the_charts_and_report_md_shows_it() {
    let dir = tempfile::tempdir().unwrap();
    let backend = &common::backends()[0];
    for scene in scenes(dir.path()) {
        let out = dir.path().join("run");
        let bench = |extra: &[&str]| {
            let mut args = vec!["bench", "--backend", backend, "--resolution", SIZE, "--out", s(&out)];
            args.extend(scene.iter().map(String::as_str));
            args.extend_from_slice(&["--modes", "vfc,roc,hiz", "--frames", "4", "--warmup", "1", "--quiet"]);
            args.extend_from_slice(extra);
            let run = occlu(&args);
            assert!(run.status.success(), "{args:?}: {:?}", own_stderr(&run));
        };
        bench(&["--animate"]);
        let animation = decode(&out.join("flythrough.png"));
        assert_eq!(animation.frames.len(), 4, "every recorded frame");
        // Three panels (view and overview, halved) in a row of 1600 pixels
        // at most: all three side by side.
        assert_eq!(animation.width, 3 * 96);
        let report = std::fs::read_to_string(out.join("report.md")).unwrap();
        assert!(report.contains("](flythrough.png)"), "{report}");
        let (summary, _) = occlu::report::read_results(&out).unwrap();
        assert_eq!(summary.animation.as_deref(), Some("flythrough.png"));
        // A merged report's copy of the run keeps what its report.md shows.
        let merged = dir.path().join("merged");
        let merge = occlu(&["merge", s(&out), "--out", s(&merged)]);
        assert!(merge.status.success(), "{:?}", own_stderr(&merge));
        let copies: Vec<PathBuf> = std::fs::read_dir(merged.join("runs"))
            .unwrap()
            .map(|e| e.unwrap().path().join("flythrough.png"))
            .collect();
        assert!(copies.len() == 1 && copies[0].is_file(), "{copies:?}");
        std::fs::remove_dir_all(&merged).unwrap();
        // A run without one removes the earlier run's.
        bench(&[]);
        assert!(!out.join("flythrough.png").exists(), "a stale animation is removed");
        let report = std::fs::read_to_string(out.join("report.md")).unwrap();
        assert!(!report.contains("flythrough.png"));
    }
}

#[test]
fn bad_ranges_and_scales_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png");
    let refuse = |extra: &[&str], needle: &str| {
        let mut args = vec![
            "flythrough",
            "--scene",
            "city:blocks=1",
            "--modes",
            "vfc",
            "--resolution",
            "32x24",
            "-o",
            s(&out),
        ];
        args.extend_from_slice(extra);
        let run = occlu(&args);
        let lines = own_stderr(&run);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {lines:?}");
        assert!(lines.len() == 1 && lines[0].contains(needle), "{args:?}: {lines:?}");
        assert!(!out.exists(), "nothing written");
    };
    refuse(&["--range", "100..130"], "the path has 120 frames");
    refuse(&["--range", "9..3"], "A..B needs A < B");
    refuse(&["--range", "3"], "is not A..B");
    refuse(&["--scale", "0"], "0 is not in 1..=8");
    refuse(&["--modes", "warp"], "unknown mode 'warp'");
}
