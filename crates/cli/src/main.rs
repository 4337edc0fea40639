//! `radia`: renders Mitsuba 3 XML and glTF 2.0 scenes.
//!
//! ```text
//! radia render scenes/cornell-box.xml -o cornell.exr --spp 256 --threads 2 --seed 0
//! radia render model.glb -o model.png --spp 64 --camera 0
//! ```

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use radia_formats::{load_scene, GltfOptions, SceneFormat, SceneOptions};
use radia_render::part::{read_part, write_part, Merger, Part, RenderIdentity};
use radia_render::{
    image_io::write_image_with_aovs, render_part_until, render_until, RenderOptions, SampleRange,
};
use radia_sampling::SamplerKind;
use radia_scene::{parse_aovs, AovDesc, FilterDesc, LightSamplerKind, Scene};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(
    name = "radia",
    version,
    about = "A physically based Monte Carlo path tracer"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a Mitsuba 3 XML or glTF 2.0 (.gltf, .glb) scene to an EXR (linear float32 RGB)
    /// or PNG (sRGB 8-bit) image.
    Render {
        /// The scene file (.gltf and .glb are read as glTF, anything else as Mitsuba XML).
        scene: PathBuf,
        /// Output image (.exr or .png). Default: the scene's name with .exr, in the current folder.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Samples per pixel (overrides the scene's sampler).
        #[arg(long)]
        spp: Option<u32>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Seed of the sample sequences (overrides the scene's sampler).
        #[arg(long)]
        seed: Option<u64>,
        /// Define or override a scene parameter, as Mitsuba's -D: NAME=VALUE.
        #[arg(short = 'D', value_name = "NAME=VALUE")]
        define: Vec<String>,
        /// No progress bar.
        #[arg(short, long)]
        quiet: bool,
        /// The sampler (overrides the scene's): independent, stratified, multijitter,
        /// orthogonal, ldsampler (Mitsuba's) or sobol (radia's default when a scene names none).
        #[arg(long, value_name = "NAME", value_parser = parse_sampler)]
        sampler: Option<SamplerKind>,
        /// Adaptive sampling: --spp becomes the average per pixel. A pilot pass of a quarter
        /// of it measures the noise; the rest goes where it lowers the relative error most,
        /// each pixel's count made from its neighbours' noise only, so the image stays
        /// unbiased. Needs the independent or sobol sampler (else the samples are spread
        /// evenly, with a warning); under a wide filter samples are placed by the filter.
        #[arg(long)]
        adaptive: bool,
        /// Film size (overrides the scene's film): WIDTHxHEIGHT, or one number for a square.
        #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
        resolution: Option<(u32, u32)>,
        /// Reconstruction filter (overrides the scene's film): box, or gaussian (stddev 0.5).
        #[arg(long, value_name = "box|gaussian", value_parser = parse_filter)]
        rfilter: Option<FilterDesc>,
        /// How next-event estimation chooses a light: uniform (Mitsuba's choice), power, or
        /// bvh (a light BVH that accounts for distance and orientation; the default). power
        /// and bvh leave a constant environment to BSDF sampling, as pbrt-v4 does, and
        /// sample every point, spot and directional light (up to eight) at every vertex.
        #[arg(long, value_name = "uniform|power|bvh")]
        light_sampler: Option<LightSamplerKind>,
        /// Render passes of 16 spp until the next one would end after SECONDS, then write
        /// the image (up to --spp if given, else without a sample limit). `--time` is the
        /// same option.
        #[arg(long, visible_alias = "time", value_name = "SECONDS", value_parser = parse_seconds)]
        time_budget: Option<Duration>,
        /// Render only the sample indices A..B (B excluded) of the --spp of every pixel, to a
        /// partial EXR (weighted sums and weights, with the seed, range, spp and scene
        /// fingerprint in its header) for `radia merge`.
        #[arg(long, value_name = "A..B", value_parser = SampleRange::parse)]
        samples: Option<SampleRange>,
        /// glTF: the camera to render from, an index into the file's cameras (default: the
        /// first perspective camera of the scene, else one framing the scene).
        #[arg(long, value_name = "N")]
        camera: Option<usize>,
        /// glTF: radiance of a constant environment (default: 1 when the file has no light
        /// and no emissive material, else none; 0 for none).
        #[arg(long, value_name = "RADIANCE")]
        environment: Option<f32>,
        /// Also write AOVs, as if the scene's integrator were nested in Mitsuba's `aov`
        /// integrator with this `aovs` string: NAME:TYPE pairs such as
        /// `dd:depth,nn:sh_normal,albedo:albedo` (types: albedo, depth, position, uv,
        /// geo_normal, sh_normal, dp_du, dp_dv, prim_index, shape_index). EXR output only.
        #[arg(long, value_name = "LIST")]
        aov: Option<String>,
    },
    /// Merge partial renders (`render --samples`) of one scene into its image: the same image,
    /// up to float rounding, as one render of all their samples. Refuses parts of different
    /// scenes, seeds, samplers or sample counts, and parts that share samples; warns when
    /// samples are missing.
    Merge {
        /// The partial EXRs.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// The merged image (.exr or .png), or a partial EXR again with --partial.
        #[arg(short, long)]
        output: PathBuf,
        /// Write the merged sums as a partial EXR (to merge further) instead of the image.
        #[arg(long)]
        partial: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(message) => {
            eprintln!("radia: error: {message}");
            ExitCode::FAILURE
        }
    }
}

/// Ctrl-C (SIGINT) and SIGTERM. The first stops the render at the end of the current pass
/// (that pass is dropped, the finished ones are written) and is recorded in `signal`; a
/// second one exits at once, with the conventional status 128 + signal and no image.
fn handle_signals(cancel: Arc<AtomicBool>, signal: Arc<AtomicI32>) -> Result<(), String> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])
        .map_err(|e| format!("cannot install the signal handlers: {e}"))?;
    std::thread::spawn(move || {
        for sig in signals.forever() {
            if cancel.load(Ordering::SeqCst) {
                eprintln!(
                    "\nradia: {} again: exiting without writing",
                    signal_name(sig)
                );
                std::process::exit(128 + sig);
            }
            signal.store(sig, Ordering::SeqCst);
            cancel.store(true, Ordering::SeqCst);
        }
    });
    Ok(())
}

fn signal_name(sig: i32) -> &'static str {
    match sig {
        signal_hook::consts::SIGINT => "SIGINT",
        signal_hook::consts::SIGTERM => "SIGTERM",
        _ => "signal",
    }
}

fn run(cli: Cli) -> Result<ExitCode, String> {
    match cli.command {
        Command::Merge {
            parts,
            output,
            partial,
        } => merge(&parts, &output, partial).map(|()| ExitCode::SUCCESS),
        render @ Command::Render { .. } => run_render(render),
    }
}

fn merge(parts: &[PathBuf], output: &std::path::Path, partial: bool) -> Result<(), String> {
    check_output(output, partial)?;
    let mut merger = Merger::new();
    for path in parts {
        let part = read_part(path).map_err(|e| e.to_string())?;
        merger
            .push(part, &path.display().to_string())
            .map_err(|e| e.to_string())?;
    }
    let merged = merger.finish().map_err(|e| e.to_string())?;
    let gaps = merged.gaps();
    if !gaps.is_empty() {
        let list: Vec<String> = gaps.iter().map(ToString::to_string).collect();
        eprintln!(
            "radia: warning: samples {} of 0..{} are in no part: the image has {} of {} spp",
            list.join(", "),
            merged.identity.spp,
            merged.sample_count(),
            merged.identity.spp
        );
    }
    if partial {
        write_part(&merged, output).map_err(|e| e.to_string())?;
    } else {
        let spp = Some(merged.sample_count());
        write_image_with_aovs(&merged.develop(), None, spp, output).map_err(|e| e.to_string())?;
    }
    println!(
        "radia: merged {} parts, {} of {} spp -> {}",
        parts.len(),
        merged.sample_count(),
        merged.identity.spp,
        output.display()
    );
    Ok(())
}

/// An image output must end in .exr or .png; a partial one in .exr.
fn check_output(output: &std::path::Path, partial: bool) -> Result<(), String> {
    match output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("exr") => Ok(()),
        Some("png") if !partial => Ok(()),
        _ if partial => Err(format!(
            "{}: a partial render (weighted sums) is written as .exr",
            output.display()
        )),
        _ => Err(format!(
            "{}: output must end in .exr or .png",
            output.display()
        )),
    }
}

fn run_render(command: Command) -> Result<ExitCode, String> {
    let Command::Render {
        scene: scene_path,
        output,
        spp,
        threads,
        seed,
        define,
        quiet,
        light_sampler,
        sampler,
        adaptive,
        resolution,
        rfilter,
        time_budget,
        samples,
        camera,
        environment,
        aov,
    } = command
    else {
        unreachable!("run_render is called with Command::Render")
    };
    if let Some(s) = spp {
        let max = SamplerKind::MAX_SAMPLE_COUNT;
        if s == 0 || s > max {
            return Err(format!("--spp {s}: must be in the range [1, {max}]"));
        }
    }
    let defines = define
        .iter()
        .map(|d| {
            d.split_once('=')
                .map(|(k, v)| (k.trim().to_string(), v.to_string()))
                .ok_or_else(|| format!("-D expects NAME=VALUE, got '{d}'"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let output = output.unwrap_or_else(|| {
        PathBuf::from(scene_path.file_stem().unwrap_or_default()).with_extension("exr")
    });
    check_output(&output, samples.is_some())?;
    if let Some(n) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
            .map_err(|e| format!("cannot start {n} threads: {e}"))?;
    }

    let t_load = Instant::now();
    if SceneFormat::of_path(&scene_path) != SceneFormat::Gltf {
        for (flag, given) in [
            ("--camera", camera.is_some()),
            ("--environment", environment.is_some()),
        ] {
            if given {
                return Err(format!("{flag} applies to glTF scenes (.gltf, .glb) only"));
            }
        }
    }
    let options = SceneOptions {
        defines,
        gltf: GltfOptions {
            camera,
            resolution,
            environment,
        },
    };
    let mut desc = load_scene(&scene_path, &options).map_err(|e| e.to_string())?;
    if let Some((w, h)) = resolution {
        desc.film.width = w;
        desc.film.height = h;
        desc.film
            .check_size()
            .map_err(|e| format!("--resolution {w}x{h}: {e}"))?;
    }
    if let Some(f) = rfilter {
        desc.film.filter = f;
    }
    if let Some(list) = &aov {
        if desc.integrator.aov.is_some() {
            return Err(format!(
                "--aov: {}: the scene's integrator already is an aov integrator",
                scene_path.display()
            ));
        }
        let outputs = parse_aovs(list).map_err(|e| format!("--aov: {e}"))?;
        desc.integrator.aov = Some(AovDesc {
            outputs,
            beauty_layer: None,
            has_beauty: true,
        });
    }
    if desc.integrator.aov.is_some() {
        // Parts carry only the image's sums; refuse rather than drop the AOVs silently.
        if samples.is_some() {
            return Err(format!(
                "--samples: {}: split renders do not carry AOVs; render AOVs in one piece",
                scene_path.display()
            ));
        }
        if !output
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
        {
            return Err(format!(
                "{}: AOV layers need an OpenEXR output (.exr); PNG holds only the image",
                output.display()
            ));
        }
    }
    // What the parts of a split render must agree on (the film overrides are in `desc`).
    // Reading the files into the typed description, then the acceleration structures: the
    // BVH over the primitives and the light sampler's tree.
    let read_secs = t_load.elapsed().as_secs_f64();
    // Only a part of a split render carries the fingerprint (hashing 10M triangles takes
    // 0.6 s, which a whole render need not spend).
    let fingerprint = samples.map(|_| desc.fingerprint());
    let t_build = Instant::now();
    let mut scene = Scene::build(desc);
    if let Some(kind) = light_sampler {
        scene.set_light_sampler(kind);
    }
    let build_secs = t_build.elapsed().as_secs_f64();
    let load_secs = t_load.elapsed().as_secs_f64();
    let sampler = sampler.unwrap_or(scene.sampler.kind);
    // A time budget without --spp renders as many samples as the time allows.
    let asked = match (spp, time_budget) {
        (Some(n), _) => n,
        (None, Some(_)) => SamplerKind::MAX_SAMPLE_COUNT,
        (None, None) => scene.sampler.sample_count.max(1),
    };
    let rounded = sampler.round_sample_count(asked);
    let adaptive = adaptive
        && {
            let why = if samples.is_some() {
                Some("a part of a split render samples evenly (adaptive sampling needs the whole image's pilot)".to_string())
            } else if spp.is_none() && time_budget.is_some() {
                Some("a time budget without --spp has no average to adapt (give --spp)".to_string())
            } else {
                radia_render::adaptive_unsupported(sampler, rounded)
            };
            if let Some(why) = &why {
                eprintln!("radia: warning: adaptive sampling is off: {why}");
            }
            why.is_none()
        };
    let options = RenderOptions {
        // As Mitsuba's samplers do, round to the nearest count the sampler can stratify.
        spp: rounded,
        seed: seed.unwrap_or(scene.sampler.seed),
        sampler,
        adaptive,
    };
    if options.spp != asked {
        eprintln!(
            "radia: warning: the {} sampler renders {} spp, not {asked} (Mitsuba rounds the same way)",
            sampler.name(),
            options.spp
        );
    }
    let (w, h) = (scene.film.width, scene.film.height);
    eprintln!(
        "radia: loaded {} in {:.3} s (read {:.3} s, BVH and light tree {:.3} s): {} primitives, {} emitters, {}x{} at {} spp ({} sampler)",
        scene_path.display(),
        load_secs,
        read_secs,
        build_secs,
        scene.primitive_count(),
        scene.emitters.len(),
        w,
        h,
        options.spp,
        sampler.name()
    );

    let cancel = Arc::new(AtomicBool::new(false));
    let signal = Arc::new(AtomicI32::new(0));
    handle_signals(cancel.clone(), signal.clone())?;
    let range = samples.unwrap_or(SampleRange::new(0, options.spp));
    let total = w as u64 * h as u64 * range.len() as u64;
    let bar = if quiet {
        ProgressBar::hidden()
    } else if time_budget.is_some() && spp.is_none() {
        ProgressBar::new_spinner()
    } else {
        ProgressBar::new(total)
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% {per_sec} ETA {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let t_render = Instant::now();
    let deadline = time_budget.map(|b| t_render + b);
    // The render time excludes writing the image (validation/benchmark.py reads it).
    // A split render's part (it has the fingerprint), or the whole image.
    let (stats, image, secs) = if let Some(fingerprint) = fingerprint {
        let out = render_part_until(&scene, &options, range, deadline, &cancel, &|done| {
            bar.set_position(done)
        });
        let secs = t_render.elapsed().as_secs_f64();
        let identity = RenderIdentity {
            scene: fingerprint,
            seed: options.seed,
            sampler: sampler.name().to_string(),
            spp: options.spp,
            light_sampler: light_sampler.unwrap_or_default().to_string(),
            width: w,
            height: h,
        };
        let part = Part::new(identity, out.rendered, out.film.into_sums());
        (out.stats, Output::Part(part), secs)
    } else {
        let out = render_until(&scene, &options, deadline, &cancel, &|done| {
            bar.set_position(done)
        });
        let secs = t_render.elapsed().as_secs_f64();
        (out.stats, Output::Image(out.image, out.aovs), secs)
    };
    bar.finish_and_clear();

    let interrupted = match signal.load(Ordering::SeqCst) {
        0 => None,
        sig => Some(sig),
    };
    if stats.spp == 0 {
        let why = interrupted.map_or("stopped", signal_name);
        eprintln!("radia: {why} before the first pass finished: no image written");
        return Ok(ExitCode::from(interrupted.map_or(1, |s| 128 + s) as u8));
    }
    match &image {
        Output::Image(image, aovs) => {
            write_image_with_aovs(image, aovs.as_ref(), Some(stats.spp), &output)
                .map_err(|e| e.to_string())?
        }
        Output::Part(part) => write_part(part, &output).map_err(|e| e.to_string())?,
    }
    if let Some(sig) = interrupted {
        eprintln!(
            "radia: interrupted by {}: wrote {} of {} spp to {}",
            signal_name(sig),
            stats.spp,
            range.len(),
            output.display()
        );
    } else if let Some(budget) = time_budget {
        eprintln!(
            "radia: time budget of {:.3} s: reached {} spp in {secs:.3} s",
            budget.as_secs_f64(),
            stats.spp
        );
    }
    println!(
        "radia: {}x{}, {} spp, {:.3} s render, {:.2} Msamples/s, {:.2} Mrays/s, {} invalid samples dropped -> {}",
        w,
        h,
        stats.spp,
        secs,
        stats.samples as f64 / secs / 1e6,
        stats.rays as f64 / secs / 1e6,
        stats.invalid_samples,
        output.display()
    );
    Ok(match interrupted {
        Some(sig) => ExitCode::from((128 + sig) as u8),
        None => ExitCode::SUCCESS,
    })
}

/// What a render writes: the image, or a partial render (`--samples`) for `radia merge`.
enum Output {
    /// The image and its AOV layers, if any.
    Image(radia_render::Image, Option<radia_render::AovLayers>),
    Part(Part),
}

fn parse_seconds(s: &str) -> Result<Duration, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .and_then(|v| Duration::try_from_secs_f64(v).ok())
        .filter(|d| !d.is_zero())
        .ok_or_else(|| format!("'{s}' is not a positive number of seconds"))
}

fn parse_sampler(s: &str) -> Result<SamplerKind, String> {
    SamplerKind::from_name(s).ok_or_else(|| {
        format!(
            "unknown sampler '{s}' (one of: {})",
            SamplerKind::NAMES.join(", ")
        )
    })
}

fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT with positive integers"))
    };
    match s.split_once(['x', 'X']) {
        Some((w, h)) => Ok((parse(w)?, parse(h)?)),
        None => parse(s).map(|n| (n, n)),
    }
}

fn parse_filter(s: &str) -> Result<FilterDesc, String> {
    match s {
        "box" => Ok(FilterDesc::Box),
        "gaussian" => Ok(FilterDesc::Gaussian { stddev: 0.5 }),
        _ => Err(format!("unknown filter '{s}' (box or gaussian)")),
    }
}
