//! `radia._native`: the Rust side of the `radia` Python package (`python/radia/` re-exports it
//! and adds `radia.distributed`). The signatures and their documentation for type checkers are
//! in `python/radia/_native.pyi`.
//!
//! The renderer runs on a thread of its own with the GIL released; the calling thread wakes
//! every 50 ms, takes the GIL just long enough for `PyErr_CheckSignals`, and on Ctrl-C asks the
//! renderer to stop (it abandons the current pass) and raises `KeyboardInterrupt`.

use numpy::ndarray::Array3;
use numpy::{PyArray3, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict};
use radia_formats::load_mitsuba_xml_with_warnings;
use radia_render::aov::AovFilm;
use radia_render::film::develop_pixel;
use radia_render::part::{self, Part, PartError, RenderIdentity};
use radia_render::{
    image_io, render_part_with_aovs, AovLayers, FilmOutput, Image, RenderOptions, RenderStats,
    SampleRange,
};
use radia_sampling::SamplerKind;
use radia_scene::{parse_aovs, AovDesc, FilterDesc, LightSamplerKind, Scene};
use std::ffi::CString;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

create_exception!(
    radia,
    LoadError,
    PyValueError,
    "A scene or a file it references could not be loaded. Attributes: `file` (str), `line` \
     and `column` (int or None, 1-based), `message` (str, without the location)."
);
create_exception!(
    radia,
    MergeError,
    PyValueError,
    "Parts that cannot be merged: of different scenes, seeds, samplers or sample counts, or \
     sharing samples. The message names both parts and what differs."
);

/// A loaded scene, ready to render (from :func:`load_file`).
#[pyclass(name = "Scene", module = "radia", frozen)]
struct PyScene {
    scene: Arc<Scene>,
    fingerprint: u64,
    path: String,
}

#[pymethods]
impl PyScene {
    /// (width, height) of the film in pixels.
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        (self.scene.film.width, self.scene.film.height)
    }
    /// Film width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.scene.film.width
    }
    /// Film height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.scene.film.height
    }
    /// Samples per pixel the scene's sampler asks for.
    #[getter]
    fn spp(&self) -> u32 {
        self.scene.sampler.sample_count
    }
    /// The sample count :func:`render` renders for ``spp`` (default: the scene's): rounded
    /// as the sampler requires (a square for ``stratified``, …).
    #[pyo3(signature = (spp=None))]
    fn render_spp(&self, spp: Option<u32>) -> u32 {
        let asked = spp.unwrap_or(self.scene.sampler.sample_count).max(1);
        self.scene.sampler.kind.round_sample_count(asked)
    }
    /// The scene's sampler (``"independent"``, ``"sobol"``, …).
    #[getter]
    fn sampler(&self) -> &'static str {
        self.scene.sampler.kind.name()
    }
    /// Number of emitters, area lights included.
    #[getter]
    fn emitters(&self) -> usize {
        self.scene.emitters.len()
    }
    /// Number of shapes.
    #[getter]
    fn shapes(&self) -> usize {
        self.scene.shapes.len()
    }
    /// Number of primitives in the BVH (triangles and analytic shapes).
    #[getter]
    fn primitives(&self) -> usize {
        self.scene.primitive_count()
    }
    /// The file it was loaded from.
    #[getter]
    fn path(&self) -> &str {
        &self.path
    }
    /// Hash of the scene's content (16 hex digits): the parts of a split render must agree on it.
    #[getter]
    fn fingerprint(&self) -> String {
        format!("{:016x}", self.fingerprint)
    }
    fn __repr__(&self) -> String {
        let (w, h) = self.resolution();
        format!(
            "<radia.Scene '{}': {w}x{h}, {} spp ({}), {} shapes, {} emitters>",
            self.path,
            self.spp(),
            self.sampler(),
            self.shapes(),
            self.emitters()
        )
    }
}

/// Loads a Mitsuba 3 XML scene. Keyword arguments define or override the scene's
/// ``<default>`` parameters, as Mitsuba's ``-D`` (``radia.load_file("cbox.xml", res=64)``),
/// except ``resolution`` and ``rfilter``, which override the scene's film as ``radia render
/// --resolution`` and ``--rfilter`` do: ``resolution`` an int (a square) or ``(width,
/// height)``, ``rfilter`` ``"box"`` or ``"gaussian"`` (stddev 0.5). Raises
/// :class:`LoadError` (with ``file``, ``line``, ``column``, ``message``), and ``ValueError``
/// for a bad override.
#[pyfunction]
#[pyo3(signature = (path, *, resolution=None, rfilter=None, **defines))]
fn load_file(
    py: Python<'_>,
    path: PathBuf,
    resolution: Option<&Bound<'_, PyAny>>,
    rfilter: Option<&str>,
    defines: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyScene> {
    let resolution = resolution.map(film_size).transpose()?;
    let filter = match rfilter {
        None => None,
        Some("box") => Some(FilterDesc::Box),
        // As `radia render --rfilter gaussian`: Mitsuba's default gaussian.
        Some("gaussian") => Some(FilterDesc::Gaussian { stddev: 0.5 }),
        Some(other) => {
            return Err(PyValueError::new_err(format!(
                "rfilter={other:?}: unknown filter (box or gaussian)"
            )))
        }
    };
    let mut defs = Vec::new();
    for (k, v) in defines.into_iter().flat_map(|d| d.iter()) {
        let value = if v.is_instance_of::<PyBool>() {
            if v.is_truthy()? { "true" } else { "false" }.to_string()
        } else {
            v.str()?.to_string()
        };
        defs.push((k.str()?.to_string(), value));
    }
    let loaded = py.detach(|| {
        load_mitsuba_xml_with_warnings(&path, &defs).map(|(mut desc, warnings)| {
            // The overrides as the CLI applies them, before the fingerprint, so that the parts
            // of a render at another resolution are told apart.
            if let Some((w, h)) = resolution {
                desc.film.width = w;
                desc.film.height = h;
            }
            if let Some(f) = filter {
                desc.film.filter = f;
            }
            let size = match resolution {
                Some(_) => desc.film.check_size(),
                None => Ok(()),
            };
            let fingerprint = desc.fingerprint();
            size.map(|()| (Scene::build(desc), fingerprint, warnings))
        })
    });
    match loaded {
        Ok(Err(size)) => {
            let (w, h) = resolution.unwrap_or_default();
            Err(PyValueError::new_err(format!(
                "resolution=({w}, {h}): {size}"
            )))
        }
        Ok(Ok((scene, fingerprint, warnings))) => {
            for w in warnings {
                warn(py, &w)?;
            }
            Ok(PyScene {
                scene: Arc::new(scene),
                fingerprint,
                path: path.display().to_string(),
            })
        }
        Err(e) => {
            let err = LoadError::new_err(e.to_string());
            let value = err.value(py);
            value.setattr("file", e.file.display().to_string())?;
            value.setattr("line", e.line)?;
            value.setattr("column", e.col)?;
            value.setattr("message", &e.message)?;
            Err(err)
        }
    }
}

/// ``resolution=``: an int (a square film) or a ``(width, height)`` pair, each at least 1.
fn film_size(value: &Bound<'_, PyAny>) -> PyResult<(u32, u32)> {
    let (w, h) = match value.extract::<u32>() {
        Ok(n) => (n, n),
        Err(_) => value.extract::<(u32, u32)>().map_err(|_| {
            PyValueError::new_err(format!(
                "resolution={value}: expected an int or a (width, height) pair of ints"
            ))
        })?,
    };
    if w == 0 || h == 0 {
        return Err(PyValueError::new_err(format!(
            "resolution=({w}, {h}): width and height must be at least 1"
        )));
    }
    Ok((w, h))
}

fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let message = CString::new(message.replace('\0', " ")).unwrap_or_default();
    PyErr::warn(py, &py.get_type::<PyUserWarning>(), &message, 1)
}

/// Renders ``scene``. Without ``samples``: the image as a float32 array (height, width, 3),
/// linear RGB. With ``samples=(a, b)``: only the sample indices a..b (b excluded) of the
/// ``spp`` of every pixel, as a :class:`Part` to :func:`merge` with the other ranges.
///
/// With AOVs (``aovs="dd.y:depth,nn:sh_normal"``, Mitsuba's ``aov`` integrator string, as
/// ``radia render --aov``; or a scene whose integrator is ``aov``): ``(image, layers)``, the
/// image as above and a dict of float32 arrays (height, width, C), one per layer of the EXR
/// the CLI writes, in its order and with its values, keyed by the channels' prefix: the
/// nested integrator's layer (R, G, B, A) if the scene names one, then each AOV (``depth``:
/// T; ``position``, normals, ``dp_du``, ``dp_dv``: X, Y, Z; ``uv``: U, V; ``albedo``: R, G,
/// B; ids: I). AOVs are not split: ``samples`` is refused with them.
///
/// ``spp`` defaults to the scene's (rounded as its sampler requires, with a warning);
/// ``seed`` is the seed of the sample sequences (0, as ``mi.render``); ``threads`` defaults to
/// all cores; ``sampler`` overrides the scene's sampler by name, as ``radia render
/// --sampler``; ``adaptive=True`` spends ``spp`` as an average, where a pilot pass found
/// noise, as ``radia render --adaptive`` (independent or sobol sampler only; else a warning
/// and even sampling). With ``stats=True`` the result comes as ``(result, RenderStats)``: the rays,
/// samples and dropped NaN/Inf samples the CLI reports. The GIL is released while rendering;
/// Ctrl-C stops the render and raises ``KeyboardInterrupt``.
#[pyfunction]
#[pyo3(signature = (scene, spp=None, seed=0, threads=None, samples=None, aovs=None, sampler=None, stats=false, adaptive=false))]
#[allow(clippy::too_many_arguments)] // Python's keyword arguments, each optional
fn render(
    py: Python<'_>,
    scene: &PyScene,
    spp: Option<u32>,
    seed: u64,
    threads: Option<usize>,
    samples: Option<(u32, u32)>,
    aovs: Option<&str>,
    sampler: Option<&str>,
    stats: bool,
    adaptive: bool,
) -> PyResult<Py<PyAny>> {
    let result = render_result(
        py, scene, spp, seed, threads, samples, aovs, sampler, adaptive,
    )?;
    if !stats {
        return Ok(result.value);
    }
    let stats = PyRenderStats {
        spp: result.stats.spp,
        samples: result.stats.samples,
        rays: result.stats.rays,
        invalid_samples: result.stats.invalid_samples,
        seconds: result.seconds,
    };
    Ok((result.value, stats).into_pyobject(py)?.into_any().unbind())
}

/// What [`render`] returns, with the statistics it returns on request.
struct Rendered {
    value: Py<PyAny>,
    stats: RenderStats,
    seconds: f64,
}

#[allow(clippy::too_many_arguments)]
fn render_result(
    py: Python<'_>,
    scene: &PyScene,
    spp: Option<u32>,
    seed: u64,
    threads: Option<usize>,
    samples: Option<(u32, u32)>,
    aovs: Option<&str>,
    sampler: Option<&str>,
    adaptive: bool,
) -> PyResult<Rendered> {
    let aov = match (aovs, &scene.scene.integrator.aov) {
        (None, own) => own.clone(),
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err(format!(
                "aovs: {}: the scene's integrator already is an aov integrator",
                scene.path
            )))
        }
        (Some(list), None) => Some(AovDesc {
            outputs: parse_aovs(list).map_err(|e| PyValueError::new_err(format!("aovs: {e}")))?,
            beauty_layer: None,
            has_beauty: true,
        }),
    };
    if aov.is_some() && samples.is_some() {
        // Parts carry only the image's sums; refuse rather than drop the AOVs silently.
        return Err(PyValueError::new_err(format!(
            "samples: {}: split renders do not carry AOVs; render AOVs in one piece",
            scene.path
        )));
    }
    let sampler = match sampler {
        None => scene.scene.sampler.kind,
        Some(name) => SamplerKind::from_name(name).ok_or_else(|| {
            PyValueError::new_err(format!(
                "sampler={name:?}: unknown sampler (one of: {})",
                SamplerKind::NAMES.join(", ")
            ))
        })?,
    };
    let asked = spp.unwrap_or(scene.scene.sampler.sample_count).max(1);
    let rounded = sampler.round_sample_count(asked);
    let why_not = if samples.is_some() {
        Some("a part of a split render samples evenly".to_string())
    } else {
        radia_render::adaptive_unsupported(sampler, rounded)
    };
    if let (true, Some(why)) = (adaptive, &why_not) {
        warn(py, &format!("adaptive sampling is off: {why}"))?;
    }
    let options = RenderOptions {
        spp: rounded,
        seed,
        sampler,
        adaptive: adaptive && why_not.is_none(),
    };
    if options.spp != asked {
        warn(
            py,
            &format!(
                "the {} sampler renders {} spp, not {asked} (Mitsuba rounds the same way)",
                sampler.name(),
                options.spp
            ),
        )?;
    }
    let range = match samples {
        None => SampleRange::new(0, options.spp),
        Some((a, b)) if a < b && b <= options.spp => SampleRange::new(a, b),
        Some((a, b)) => {
            return Err(PyValueError::new_err(format!(
                "samples=({a}, {b}) is not a non-empty range within the render's {} spp",
                options.spp
            )))
        }
    };
    let pool = match threads {
        None => None,
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .build()
                .map_err(|e| PyRuntimeError::new_err(format!("cannot start {n} threads: {e}")))?,
        ),
    };
    let t_render = Instant::now();
    let out = render_interruptibly(py, scene.scene.clone(), options, range, aov.clone(), pool)?;
    let seconds = t_render.elapsed().as_secs_f64();
    let stats = out.stats;
    let rendered = |value: Py<PyAny>| Rendered {
        value,
        stats,
        seconds,
    };
    let (w, h) = (scene.scene.film.width, scene.scene.film.height);
    if samples.is_none() {
        let image = image_array(py, out.film.sums(), w, h)?;
        return match (&aov, &out.aovs) {
            (Some(desc), Some(film)) => {
                let layers = aov_dict(py, desc, film, &out.film.develop())?;
                Ok(rendered(
                    (image, layers).into_pyobject(py)?.into_any().unbind(),
                ))
            }
            _ => Ok(rendered(image.into_any().unbind())),
        };
    }
    let identity = RenderIdentity {
        scene: scene.fingerprint,
        seed,
        sampler: sampler.name().to_string(),
        spp: options.spp,
        light_sampler: LightSamplerKind::default().to_string(),
        width: w,
        height: h,
    };
    let part = Part::new(identity, out.rendered, out.film.into_sums());
    Ok(rendered(Py::new(py, PyPart { part })?.into_any()))
}

/// What a render did (``render(..., stats=True)``): the figures `radia render` prints.
#[pyclass(name = "RenderStats", module = "radia", frozen, get_all)]
struct PyRenderStats {
    /// Samples per pixel rendered (of the range asked for, with ``samples=``).
    spp: u32,
    /// Camera samples traced (pixels × spp).
    samples: u64,
    /// Rays traced, shadow rays included.
    rays: u64,
    /// Samples whose radiance came out NaN or infinite: dropped, as the CLI's "invalid samples
    /// dropped".
    invalid_samples: u64,
    /// Wall time of the render in seconds (the scene was loaded before).
    seconds: f64,
}

#[pymethods]
impl PyRenderStats {
    fn __repr__(&self) -> String {
        format!(
            "<radia.RenderStats: {} spp, {} samples, {} rays, {} invalid samples, {:.3} s>",
            self.spp, self.samples, self.rays, self.invalid_samples, self.seconds
        )
    }
}

/// The AOV layers ``render`` returns: one (height, width, C) array per layer of
/// [`AovLayers`] (the channels `NAME.SUFFIX` grouped by NAME, in their order).
fn aov_dict<'py>(
    py: Python<'py>,
    desc: &AovDesc,
    film: &AovFilm,
    developed: &Image,
) -> PyResult<Bound<'py, PyDict>> {
    let layers = AovLayers::new(desc, film, developed);
    let (w, h) = (developed.width as usize, developed.height as usize);
    let mut groups: Vec<(&str, Vec<&[f32]>)> = Vec::new();
    for (name, plane) in layers.names.iter().zip(&layers.planes) {
        let layer = name.rsplit_once('.').map_or(name.as_str(), |(l, _)| l);
        match groups.iter_mut().find(|(l, _)| *l == layer) {
            Some((_, planes)) => planes.push(plane),
            None => groups.push((layer, vec![plane])),
        }
    }
    let dict = PyDict::new(py);
    for (layer, planes) in groups {
        let c = planes.len();
        let mut data = vec![0.0f32; w * h * c];
        for (k, plane) in planes.iter().enumerate() {
            for (i, v) in plane.iter().enumerate() {
                data[i * c + k] = *v;
            }
        }
        let array = Array3::from_shape_vec((h, w, c), data)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        dict.set_item(layer, PyArray3::from_owned_array(py, array))?;
    }
    Ok(dict)
}

/// Runs the renderer on a thread of its own, the GIL released, checking for signals between
/// waits (see the module comment).
fn render_interruptibly(
    py: Python<'_>,
    scene: Arc<Scene>,
    options: RenderOptions,
    range: SampleRange,
    aov: Option<AovDesc>,
    pool: Option<rayon::ThreadPool>,
) -> PyResult<FilmOutput> {
    let cancel = Arc::new(AtomicBool::new(false));
    let (tx, mut rx) = mpsc::channel();
    {
        let cancel = cancel.clone();
        std::thread::spawn(move || {
            let run = || {
                let aov = aov.as_ref();
                render_part_with_aovs(&scene, &options, aov, range, None, &cancel, &|_| {})
            };
            let out = match pool {
                Some(pool) => pool.install(run),
                None => run(),
            };
            let _ = tx.send(out);
        });
    }
    loop {
        let (got, back) = py.detach(move || (rx.recv_timeout(Duration::from_millis(50)), rx));
        rx = back;
        match got {
            Ok(out) => return Ok(out),
            Err(mpsc::RecvTimeoutError::Timeout) => {
                if let Err(interrupt) = py.check_signals() {
                    cancel.store(true, Ordering::SeqCst);
                    // The renderer stops within one tile row; wait so no thread outlives us.
                    let _ = py.detach(move || rx.recv());
                    return Err(interrupt);
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err("the render thread panicked"))
            }
        }
    }
}

/// Develops accumulations into a new (height, width, 3) float32 array: the one copy of the
/// film; the vector becomes the array's buffer as it is.
fn image_array<'py>(
    py: Python<'py>,
    sums: &[[f32; 4]],
    w: u32,
    h: u32,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let mut rgb = Vec::with_capacity(sums.len() * 3);
    for &p in sums {
        rgb.extend_from_slice(&develop_pixel(p).to_array());
    }
    let array = Array3::from_shape_vec((h as usize, w as usize, 3), rgb)
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok(PyArray3::from_owned_array(py, array))
}

/// Writes a (height, width, 3) float32 linear RGB array as OpenEXR (float32) or PNG (sRGB,
/// 8 bit), chosen by the extension of ``path``.
#[pyfunction]
fn write_image(py: Python<'_>, array: PyReadonlyArray3<'_, f32>, path: PathBuf) -> PyResult<()> {
    let shape = array.shape();
    if shape[2] != 3 {
        return Err(PyValueError::new_err(format!(
            "write_image expects an array of shape (height, width, 3), got {shape:?}"
        )));
    }
    let view = array.as_array();
    let pixels = view
        .outer_iter()
        .flat_map(|row| {
            row.outer_iter()
                .map(|p| radia_math::Spectrum::new(p[0], p[1], p[2]))
                .collect::<Vec<_>>()
        })
        .collect();
    let image = Image {
        width: shape[1] as u32,
        height: shape[0] as u32,
        pixels,
    };
    py.detach(|| image_io::write_image(&image, &path))
        .map_err(|e| PyOSError::new_err(e.to_string()))
}

/// The accumulated film of some sample ranges of a render: what ``render(..., samples=(a, b))``
/// returns, :func:`merge` adds up and :meth:`develop` turns into the image. Picklable.
#[pyclass(name = "Part", module = "radia", frozen)]
struct PyPart {
    part: Part,
}

#[pymethods]
impl PyPart {
    /// The sample ranges it holds, as [(a, b), …] (b excluded), sorted.
    #[getter]
    fn samples(&self) -> Vec<(u32, u32)> {
        self.part.samples.iter().map(|r| (r.start, r.end)).collect()
    }
    /// Samples per pixel it holds.
    #[getter]
    fn sample_count(&self) -> u32 {
        self.part.sample_count()
    }
    /// The whole render's samples per pixel (what the sampler is stratified over).
    #[getter]
    fn spp(&self) -> u32 {
        self.part.identity.spp
    }
    #[getter]
    fn seed(&self) -> u64 {
        self.part.identity.seed
    }
    #[getter]
    fn sampler(&self) -> &str {
        &self.part.identity.sampler
    }
    /// The scene's fingerprint (16 hex digits).
    #[getter]
    fn scene(&self) -> String {
        format!("{:016x}", self.part.identity.scene)
    }
    /// (width, height) in pixels.
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        (self.part.identity.width, self.part.identity.height)
    }
    /// The ranges of [0, spp) it does not hold, as [(a, b), …].
    fn gaps(&self) -> Vec<(u32, u32)> {
        self.part.gaps().iter().map(|r| (r.start, r.end)).collect()
    }
    /// The image of its samples: a float32 array (height, width, 3).
    fn develop<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let (w, h) = self.resolution();
        image_array(py, &self.part.sums, w, h)
    }
    /// Its sums: a float32 array (height, width, 4) of (Σw·r, Σw·g, Σw·b, Σw).
    fn sums<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let (w, h) = self.resolution();
        let flat: Vec<f32> = self.part.sums.iter().flatten().copied().collect();
        let array = Array3::from_shape_vec((h as usize, w as usize, 4), flat)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        Ok(PyArray3::from_owned_array(py, array))
    }
    /// Writes it as a partial EXR (what ``radia merge`` reads).
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| part::write_part(&self.part, &path))
            .map_err(part_error)
    }
    fn __repr__(&self) -> String {
        let ranges: Vec<String> = self.part.samples.iter().map(|r| r.to_string()).collect();
        format!(
            "<radia.Part samples {} of {} spp, {}x{}, seed {}, scene {}>",
            ranges.join(","),
            self.spp(),
            self.part.identity.width,
            self.part.identity.height,
            self.seed(),
            self.scene()
        )
    }
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Py<PyAny>)> {
        let id = &self.part.identity;
        let bytes: Vec<u8> = self
            .part
            .sums
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let state = (
            id.scene,
            id.seed,
            id.sampler.clone(),
            id.spp,
            id.light_sampler.clone(),
            (id.width, id.height),
            self.samples(),
            PyBytes::new(py, &bytes),
        );
        let ctor = py.import("radia._native")?.getattr("_part_from_state")?;
        Ok((ctor, (state,).into_pyobject(py)?.into_any().unbind()))
    }
}

type PartState = (
    u64,
    u64,
    String,
    u32,
    String,
    (u32, u32),
    Vec<(u32, u32)>,
    Vec<u8>,
);

/// Rebuilds a pickled :class:`Part`.
#[pyfunction]
fn _part_from_state(state: PartState) -> PyResult<PyPart> {
    let (scene, seed, sampler, spp, light_sampler, (width, height), samples, bytes) = state;
    let n = width as usize * height as usize;
    if bytes.len() != n * 16 || samples.is_empty() {
        return Err(PyValueError::new_err("corrupt pickled radia.Part"));
    }
    let sums = bytes
        .chunks_exact(16)
        .map(|c| {
            std::array::from_fn(|i| f32::from_le_bytes(c[4 * i..4 * i + 4].try_into().unwrap()))
        })
        .collect();
    let identity = RenderIdentity {
        scene,
        seed,
        sampler,
        spp,
        light_sampler,
        width,
        height,
    };
    let mut part = Part::new(identity, SampleRange::new(samples[0].0, samples[0].1), sums);
    part.samples = samples
        .iter()
        .map(|&(a, b)| SampleRange::new(a, b))
        .collect();
    Ok(PyPart { part })
}

fn part_error(e: PartError) -> PyErr {
    match e {
        PartError::Io { .. } => PyOSError::new_err(e.to_string()),
        PartError::NotAPart { .. } => PyValueError::new_err(e.to_string()),
        PartError::Mismatch { .. } | PartError::Overlap { .. } | PartError::Empty => {
            MergeError::new_err(e.to_string())
        }
    }
}

/// Reads a partial EXR (``radia render --samples`` or :meth:`Part.write`).
#[pyfunction]
fn read_part(py: Python<'_>, path: PathBuf) -> PyResult<PyPart> {
    py.detach(|| part::read_part(&path))
        .map(|part| PyPart { part })
        .map_err(part_error)
}

/// Adds up parts of one render (in ascending order of their first sample, whatever the order
/// given, so the result has the same bits every time). Raises :class:`MergeError` for parts of
/// different renders or sharing samples. ``names`` (default ``part 0``, ``part 1``, … with
/// their ranges) name the parts in errors.
#[pyfunction]
#[pyo3(signature = (parts, names=None))]
fn _merge(
    py: Python<'_>,
    parts: Vec<PyRef<'_, PyPart>>,
    names: Option<Vec<String>>,
) -> PyResult<PyPart> {
    let named: Vec<(Part, String)> = parts
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let name = names
                .as_ref()
                .and_then(|n| n.get(i).cloned())
                .unwrap_or_else(|| {
                    let ranges: Vec<String> =
                        p.part.samples.iter().map(|r| r.to_string()).collect();
                    format!("part {i} (samples {})", ranges.join(","))
                });
            (p.part.clone(), name)
        })
        .collect();
    py.detach(|| part::merge(named))
        .map(|part| PyPart { part })
        .map_err(part_error)
}

#[pymodule]
#[pyo3(name = "_native")]
fn native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("LoadError", py.get_type::<LoadError>())?;
    m.add("MergeError", py.get_type::<MergeError>())?;
    m.add_class::<PyScene>()?;
    m.add_class::<PyPart>()?;
    m.add_class::<PyRenderStats>()?;
    m.add_function(wrap_pyfunction!(load_file, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(write_image, m)?)?;
    m.add_function(wrap_pyfunction!(read_part, m)?)?;
    m.add_function(wrap_pyfunction!(_merge, m)?)?;
    m.add_function(wrap_pyfunction!(_part_from_state, m)?)?;
    Ok(())
}
