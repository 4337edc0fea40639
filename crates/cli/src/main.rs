//! `radia`: renders Mitsuba 3 XML scenes.
//!
//! ```text
//! radia render scenes/cornell-box.xml -o cornell.exr --spp 256 --threads 2 --seed 0
//! ```

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use radia_render::{image_io::write_image, render_until, RenderOptions};
use radia_sampling::SamplerKind;
use radia_scene::{load_mitsuba_xml, FilterDesc, LightSamplerKind, Scene};
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
    /// Render a Mitsuba 3 XML scene to an EXR (linear float32 RGB) or PNG (sRGB 8-bit) image.
    Render {
        /// The scene file.
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
        /// Film size (overrides the scene's film): WIDTHxHEIGHT, or one number for a square.
        #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
        resolution: Option<(u32, u32)>,
        /// Reconstruction filter (overrides the scene's film): box, or gaussian (stddev 0.5).
        #[arg(long, value_name = "box|gaussian", value_parser = parse_filter)]
        rfilter: Option<FilterDesc>,
        /// How next-event estimation chooses a light: uniform (Mitsuba's choice), power, or
        /// bvh (a light BVH that accounts for distance and orientation; the default).
        #[arg(long, value_name = "uniform|power|bvh")]
        light_sampler: Option<LightSamplerKind>,
        /// Render passes of 16 spp until the next one would end after SECONDS, then write
        /// the image (up to --spp if given, else without a sample limit).
        #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
        time_budget: Option<Duration>,
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
                eprintln!("\nradia: {} again: exiting without writing", signal_name(sig));
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
        resolution,
        rfilter,
        time_budget,
    } = cli.command;
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
    match output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("exr") | Some("png") => {}
        _ => {
            return Err(format!(
                "{}: output must end in .exr or .png",
                output.display()
            ))
        }
    }
    if let Some(n) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
            .map_err(|e| format!("cannot start {n} threads: {e}"))?;
    }

    let t_load = Instant::now();
    let desc = load_mitsuba_xml(&scene_path, &defines).map_err(|e| e.to_string())?;
    let mut desc = desc;
    if let Some((w, h)) = resolution {
        desc.film.width = w;
        desc.film.height = h;
        desc.film.check_size().map_err(|e| format!("--resolution {w}x{h}: {e}"))?;
    }
    if let Some(f) = rfilter {
        desc.film.filter = f;
    }
    let mut scene = Scene::build(desc);
    if let Some(kind) = light_sampler {
        scene.set_light_sampler(kind);
    }
    let load_secs = t_load.elapsed().as_secs_f64();
    let sampler = sampler.unwrap_or(scene.sampler.kind);
    // A time budget without --spp renders as many samples as the time allows.
    let asked = match (spp, time_budget) {
        (Some(n), _) => n,
        (None, Some(_)) => SamplerKind::MAX_SAMPLE_COUNT,
        (None, None) => scene.sampler.sample_count.max(1),
    };
    let options = RenderOptions {
        // As Mitsuba's samplers do, round to the nearest count the sampler can stratify.
        spp: sampler.round_sample_count(asked),
        seed: seed.unwrap_or(scene.sampler.seed),
        sampler,
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
        "radia: loaded {} in {:.3} s: {} primitives, {} emitters, {}x{} at {} spp ({} sampler)",
        scene_path.display(),
        load_secs,
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
    let total = w as u64 * h as u64 * options.spp as u64;
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
    let out = render_until(&scene, &options, deadline, &cancel, &|done| {
        bar.set_position(done)
    });
    let secs = t_render.elapsed().as_secs_f64();
    bar.finish_and_clear();

    let interrupted = match signal.load(Ordering::SeqCst) {
        0 => None,
        sig => Some(sig),
    };
    if out.stats.spp == 0 {
        let why = interrupted.map_or("stopped", signal_name);
        eprintln!("radia: {why} before the first pass finished: no image written");
        return Ok(ExitCode::from(interrupted.map_or(1, |s| 128 + s) as u8));
    }
    write_image(&out.image, &output).map_err(|e| e.to_string())?;
    if let Some(sig) = interrupted {
        eprintln!(
            "radia: interrupted by {}: wrote {} of {} spp to {}",
            signal_name(sig),
            out.stats.spp,
            options.spp,
            output.display()
        );
    } else if let Some(budget) = time_budget {
        eprintln!(
            "radia: time budget of {:.3} s: reached {} spp in {secs:.3} s",
            budget.as_secs_f64(),
            out.stats.spp
        );
    }
    println!(
        "radia: {}x{}, {} spp, {:.3} s render, {:.2} Msamples/s, {:.2} Mrays/s, {} invalid samples dropped -> {}",
        w,
        h,
        out.stats.spp,
        secs,
        out.stats.samples as f64 / secs / 1e6,
        out.stats.rays as f64 / secs / 1e6,
        out.stats.invalid_samples,
        output.display()
    );
    Ok(match interrupted {
        Some(sig) => ExitCode::from((128 + sig) as u8),
        None => ExitCode::SUCCESS,
    })
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
