//! The commands about a scene itself, before any run: `info` (what occlu
//! reads of it), `export` (it and a path as one GLB) and `path gen` (a
//! camera path made from it).

use std::fmt::Write as _;
use std::time::Instant;

use occlu::camera::generate::plan_heard;
use occlu::camera::path::{CameraPath, Keyframe, PathError};
use occlu::gpu::Resolution;
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::raycast::{Budget, RayCaster, Stopped};
use occlu::report::SceneFacts;
use occlu::scene::{Scene, load};
use occlu::text::number;

use super::args::{ExportArgs, InfoArgs, PathGenArgs};
use super::output::{emit, say};
use super::progress::{Progress, near_not_counted};
use super::signals::stop_listening;

/// `occlu info`: what occlu reads of a scene, as text or JSON.
pub fn info(args: &InfoArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let scene = load(&args.scene.spec()?, &args.scene.options())?;
    let load_ms = start.elapsed().as_secs_f64() * 1e3;
    let start = Instant::now();
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let report = SceneFacts::of(&scene, &hierarchy, load_ms, build_ms);
    if args.json {
        return emit(&(serde_json::to_string_pretty(&report)? + "\n"));
    }
    let h = report.hierarchy;
    let mut text = String::new();
    let w = &mut text;
    // Names from the file, shown as themselves (see say!).
    let shown = occlu::text::one_line;
    let _ = writeln!(w, "source      {}", shown(&report.source));
    let _ = writeln!(w, "objects     {} ({} meshes)", report.objects, report.meshes);
    if report.movers > 0 {
        let _ = writeln!(w, "movers      {} objects move from frame to frame", report.movers);
    }
    let _ = writeln!(w, "triangles   {}", report.triangles);
    let _ = writeln!(w, "vertices    {}", report.vertices);
    let _ = writeln!(w, "bounds      {:?} to {:?}", report.bounds_min, report.bounds_max);
    let _ = writeln!(w, "up          {} ({})", report.up.axis, report.up.why);
    let _ = writeln!(
        w,
        "hierarchy   {} nodes, {} leaves, depth {}, at most {} objects per leaf",
        h.nodes, h.leaves, h.depth, h.max_leaf_objects
    );
    let p = report.load_phases;
    let _ = writeln!(
        w,
        "load        {load_ms:.1} ms (read {:.1}, parse {:.1}, validate {:.1}, closed-solid test {:.1}, clustering {:.1})",
        p.read_ms, p.parse_ms, p.validate_ms, p.closed_ms, p.cluster_ms
    );
    let _ = writeln!(w, "build       {build_ms:.1} ms (hierarchy)");
    for c in &report.cameras {
        let fov = c.fov_y_deg.map_or(String::new(), |f| format!(", fov {f:.1}°"));
        let near = c.near.map_or(String::new(), |n| format!(", near {n}"));
        let _ = writeln!(
            w,
            "camera      '{}' (node {}, {}{fov}{near})",
            shown(&c.name),
            c.node,
            c.projection
        );
    }
    for a in &report.animations {
        let moves = a.camera.as_ref().map_or("moves no camera".to_string(), |c| {
            format!("moves camera '{}'", shown(c))
        });
        let _ = writeln!(
            w,
            "animation   '{}' ({} channels, {:.2} s, {moves})",
            shown(&a.name),
            a.channels,
            a.duration
        );
    }
    if scene.warnings.is_empty() {
        let _ = writeln!(w, "warnings    none");
    }
    for warning in &scene.warnings {
        let _ = writeln!(w, "warning     {}", shown(warning));
    }
    emit(&text)
}

/// `occlu export`: the scene and a path as one GLB.
pub fn export(args: &ExportArgs) -> anyhow::Result<()> {
    let (input, output) = (&args.scene, &args.output);
    input.refuse_as_output(output)?;
    occlu::report::check_writable(output)?;
    let (scene, path) = input.load(output)?;
    if !scene.movers.is_empty() {
        say!(
            "warning: {} moving objects are written where frame 0 puts them (glTF animation of objects is not exported)",
            scene.movers.len()
        );
    }
    // A camera's field of view is not a glTF animation target: the export
    // keeps the first keyframe's, which frame 0 has.
    let degrees = |k: &Keyframe| k.fov_y.to_degrees();
    let (narrowest, widest) = path
        .keyframes
        .iter()
        .map(degrees)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| (lo.min(d), hi.max(d)));
    if narrowest < widest {
        say!(
            "warning: the path's field of view changes ({}° to {}°): the export keeps frame 0's, {}°, throughout (glTF animates a camera's place and turn, not its field of view)",
            number(narrowest),
            number(widest),
            number(degrees(&path.keyframes[0]))
        );
    }
    let bytes = occlu::export::glb(&scene, &path, Resolution::DEFAULT.aspect())?;
    occlu::report::write_whole(output, &bytes)?;
    say!(
        "wrote {} ({} objects, {} triangles, {} and {} frames as the animation 'occlu path')",
        output.display(),
        scene.objects.len(),
        scene.triangles(),
        path.source,
        path.frames
    );
    Ok(())
}

/// `occlu path gen`: a camera path planned from the scene, written as JSON.
pub fn path_gen(args: &PathGenArgs) -> anyhow::Result<()> {
    let (scene_args, output) = (&args.scene, &args.output);
    if let Some(model) = &scene_args.model {
        occlu::report::refuse_input_as_output(output, &[model])?;
    }
    // Refused before a long load and path planning, not after.
    occlu::report::check_writable(output)?;
    let scene: Scene = load(&scene_args.spec()?, &scene_args.options())?;
    occlu::report::refuse_input_as_output(output, &scene.files)?;
    let mut progress = Progress::new(false, 0, String::new());
    let generated = plan_heard(
        args.kind.as_ref(),
        &scene,
        args.frames,
        progress.listener("planning the path"),
    )?;
    // Validate what is written, so a generated file always loads.
    let path = CameraPath::from_file(&generated.file, &format!("generated:{}", generated.kind))?;
    let budget = Budget {
        tests: occlu::camera::generate::PLANNING_TESTS,
        listener: progress.listener("counting frames with geometry within the near plane"),
    };
    let caster = RayCaster::with_budget(&scene, budget);
    // Counted before the file is written, so Ctrl-C meanwhile writes nothing.
    let near = match path.frames_with_geometry_within_near(&caster, Resolution::DEFAULT.aspect()) {
        Ok(0) => None,
        Ok(near) => Some(format!(
            "warning: {near} of {} frames have geometry nearer than the near plane's corners (at 4:3)",
            path.frames
        )),
        Err(Stopped::Spent) => Some(near_not_counted()),
        Err(Stopped::Interrupted) => return Err(PathError::Interrupted.into()),
    };
    stop_listening()?;
    let text = serde_json::to_string_pretty(&generated.file)? + "\n";
    occlu::report::write_whole(output, text.as_bytes())?;
    say!(
        "wrote {} ({}: {}; {} frames, {} keyframes)",
        output.display(),
        generated.kind,
        generated.why,
        path.frames,
        generated.file.keyframes.len()
    );
    if let Some(near) = near {
        say!("{near}");
    }
    Ok(())
}
