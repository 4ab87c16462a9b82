//! `occlu render` (one frame of one mode as a PNG) and `occlu flythrough`
//! (a range of frames in many modes as an animated PNG).

use occlu::animation::{AnimationOptions, DEFAULT_SCALE, FrameRange};
use occlu::cull::{ModeError, ModeId, ModeParams, parse_modes, unrunnable};
use occlu::hierarchy::{Hierarchy, HierarchyParams};
use occlu::picture::LEAD_IN;
use occlu::world::World;

use super::args::{FlythroughArgs, RenderArgs};
use super::output::say;
use super::progress::Progress;
use super::signals::go_on;

/// `occlu render`: one frame of one mode as a PNG, and what it shows on stderr.
pub fn render(args: RenderArgs) -> anyhow::Result<()> {
    let modes = parse_modes(std::slice::from_ref(&args.mode))?;
    let [mode] = modes[..] else {
        anyhow::bail!(ModeError::NotOne(args.mode.clone()));
    };
    let params = ModeParams::parse(&args.picture.params, &modes)?;
    args.scene.refuse_as_output(&args.picture.output)?;
    // Refused before a long load and path planning, not after.
    occlu::report::check_writable(&args.picture.output)?;
    let backend = args.picture.backend.unwrap_or_default();
    backend.backends()?;
    let (scene, path) = args.scene.load(&args.picture.output)?;
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let gpu = occlu::gpu::GpuContext::new(backend)?;
    if let Some(reason) = mode.info().unsupported_on(&gpu) {
        anyhow::bail!("mode '{mode}' cannot run on {}: {reason}", gpu.adapter);
    }
    // An `auto` candidate it cannot run, given parameters.
    for skipped in unrunnable(&[(mode, &params)], |m| m.info().unsupported_on(&gpu)) {
        say!("skipped: {}: {}", skipped.mode, skipped.reason);
    }
    let culler = mode.create(&scene, &params)?;
    let mut world = World::new(scene, hierarchy);
    let look = args.picture.look(args.show_missed, args.occluders);
    let picture = occlu::picture::render(&gpu, &mut world, &path, culler, args.frame, &look)?;
    let output = &args.picture.output;
    occlu::report::write_png(output, picture.width, picture.height, &picture.rgb)?;
    say!(
        "wrote {} ({}x{}): {mode} drew {} objects at frame {}, culled {} inside the frustum",
        output.display(),
        picture.width,
        picture.height,
        picture.drawn,
        args.frame,
        picture.culled_in_frustum
    );
    if let Some([written, partial, pixels]) = picture.occluder_pixels {
        say!(
            "its buffer holds an occluder's depth at {written} of the {pixels} pixels (coloured), {partial} of them at the nearer depth of occluders covering only part of their cell (tinted orange); the rest dimmed"
        );
    }
    if let Some(wrong) = &picture.wrong {
        say!(
            "{} pixels differ from direct rendering (magenta); {} objects got wrong (boxes outlined)",
            wrong.pixels,
            wrong.objects.len()
        );
        for m in &wrong.objects {
            let first = match (m.first_x, m.first_y) {
                (Some(x), Some(y)) => format!(", first at ({x}, {y})"),
                _ => String::new(),
            };
            let drawn = if m.drawn { "drawn" } else { "not drawn" };
            say!(
                "  object {} '{}': {drawn}, {} wrong pixels{first}",
                m.object,
                m.name,
                m.wrong_pixels
            );
        }
    }
    Ok(())
}

/// `occlu flythrough`: a range of the path in many modes as an animated PNG.
pub fn flythrough(args: FlythroughArgs) -> anyhow::Result<()> {
    let modes = parse_modes(&args.modes)?;
    let params = ModeParams::parse(&args.picture.params, &modes)?;
    let output = &args.picture.output;
    args.scene.refuse_as_output(output)?;
    occlu::report::check_writable(output)?;
    let backend = args.picture.backend.unwrap_or_default();
    backend.backends()?;
    let note = |text: String| {
        if !args.quiet {
            say!("{text}");
        }
    };
    let (scene, path) = args.scene.load(output)?;
    let range = args.range.unwrap_or(FrameRange::all(path.frames));
    range.check(path.frames)?;
    let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
    let gpu = occlu::gpu::GpuContext::new(backend)?;
    note(format!("adapter: {}", gpu.adapter));
    let unsupported = |mode: ModeId| mode.info().unsupported_on(&gpu);
    let named: Vec<(ModeId, &ModeParams)> = modes.iter().map(|&mode| (mode, &params)).collect();
    for skipped in unrunnable(&named, unsupported) {
        note(format!("skipped: {}: {}", skipped.mode, skipped.reason));
    }
    let mut cullers = Vec::new();
    for &mode in modes.iter().filter(|&&mode| unsupported(mode).is_none()) {
        cullers.push(mode.create(&scene, &params)?);
    }
    anyhow::ensure!(!cullers.is_empty(), "no mode of --modes runs on {}", gpu.adapter);
    let mut world = World::new(scene, hierarchy);
    let options = AnimationOptions {
        look: args.picture.look(false, false),
        scale: args.scale.unwrap_or(DEFAULT_SCALE),
        true_colour: args.true_colour,
    };
    let lead_in = range.start.min(LEAD_IN);
    let mut progress = Progress::new(args.quiet, lead_in, format!("{} modes", cullers.len()));
    let reel = occlu::animation::flythrough(
        &gpu,
        &mut world,
        &path,
        &mut cullers,
        &options,
        range,
        &mut |done, total| {
            progress.frame(done, total);
            go_on()
        },
    )?;
    progress.finish();
    note(format!("encoding the animation's {} frames", reel.frames()));
    let animation = reel.encode(&mut |done, total| {
        progress.encoding(done, total);
        go_on()
    })?;
    occlu::report::write_whole(output, &animation.png)?;
    note(format!(
        "wrote {} ({}x{}, {} frames, {:.1} MB)",
        output.display(),
        animation.width,
        animation.height,
        animation.frames,
        animation.png.len() as f64 / 1e6
    ));
    Ok(())
}
