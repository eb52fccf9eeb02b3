//! The Python package `rangesynth` (python/rangesynth/, docs/python.md): the Rust crate's
//! renderer and verifier on numpy arrays. A thin layer that adds no rendering or scoring of its
//! own: it turns arrays and dicts into the crate's inputs (src/arrays.rs) and its outputs into
//! arrays, releases the GIL while the device works, raises every error as a `rangesynth.Error`
//! carrying the crate's message, and keeps validation's messages for the tests
//! (src/validation.rs).

mod arrays;
mod validation;

use arrays::{array, from_keys, keys_of};
use glam::DMat4;
use numpy::{IntoPyArray, PyArrayMethods, PyReadonlyArray3};
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};
use rangesynth::effects::Effects;
use rangesynth::gpu::{list_devices, ContextOptions};
use rangesynth::io::{read_range_image as read_range_image_file, RangeImage};
use rangesynth::limits::{Ledger, MemoryBudget};
use rangesynth::mesh::{load_model_file, Mesh as CrateMesh};
use rangesynth::render::Raster;
use rangesynth::render_set::{label_map, LabelEntry};
use rangesynth::sensor::Sensor;
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::verify::{
    Hypothesis, Model, Record, SensedImage, Verification, Verifier as CrateVerifier, VerifySettings,
};
use rangesynth::{RenderOutput, Renderer as CrateRenderer, Scene};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

pyo3::create_exception!(
    _rangesynth,
    Error,
    PyException,
    "Every error rangesynth raises: its message is the library's."
);

/// The library's error as a Python exception.
fn raised(e: impl std::fmt::Display) -> PyErr {
    Error::new_err(e.to_string())
}

fn raster_of(raster: Option<&str>) -> PyResult<Raster> {
    raster.map_or(Ok(Raster::Auto), |r| r.parse().map_err(raised))
}

/// A triangle mesh: vertices (V, 3), faces (F, 3) of vertex indices, and each face's surface
/// (1, 2, …; all 1 where not given).
#[pyclass(frozen, module = "rangesynth")]
struct Mesh {
    inner: Arc<CrateMesh>,
}

#[pymethods]
impl Mesh {
    #[new]
    #[pyo3(signature = (vertices, faces, surfaces=None))]
    fn new(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        surfaces: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let vertices = array::<f64, numpy::Ix2>(py, vertices, "float64", "vertices")?;
        let faces = array::<i64, numpy::Ix2>(py, faces, "int64", "faces")?;
        let surfaces = surfaces.map(|s| array::<i64, numpy::Ix1>(py, s, "int64", "surfaces")).transpose()?;
        let (v, f) = (vertices.as_array(), faces.as_array());
        if v.ncols() != 3 || f.ncols() != 3 {
            return Err(raised(format!(
                "vertices must be (V, 3) and faces (F, 3); they are {:?} and {:?}",
                v.shape(),
                f.shape()
            )));
        }
        let positions: Vec<[f64; 3]> = v.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
        let index = |i: i64| u32::try_from(i).map_err(|_| raised(format!("face index {i} is not a vertex index")));
        let triangles = f
            .rows()
            .into_iter()
            .map(|r| Ok([index(r[0])?, index(r[1])?, index(r[2])?]))
            .collect::<PyResult<Vec<_>>>()?;
        let ids: Vec<u32> = match surfaces {
            None => vec![1; triangles.len()],
            Some(s) => s
                .as_array()
                .iter()
                .map(|&i| u32::try_from(i).map_err(|_| raised(format!("surface {i} is not 1 or more"))))
                .collect::<PyResult<_>>()?,
        };
        let count = ids.iter().copied().max().unwrap_or(1);
        let names = (1..=count).map(|s| format!("surface {s}")).collect();
        let mesh = CrateMesh::new("mesh", positions, triangles, ids, names).map_err(raised)?;
        Ok(Self { inner: Arc::new(mesh) })
    }

    /// A model file the command line reads (OBJ, PLY or STL).
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let mesh = load_model_file(&path, &Ledger::default()).map_err(raised)?;
        Ok(Self { inner: Arc::new(mesh) })
    }

    #[getter]
    fn vertex_count(&self) -> usize {
        self.inner.positions.len()
    }

    #[getter]
    fn triangle_count(&self) -> usize {
        self.inner.triangles.len()
    }

    #[getter]
    fn surface_count(&self) -> u32 {
        self.inner.surface_count()
    }
}

/// A range EXR's arrays, as `render` writes it and `render_scene` returns them: "xyz",
/// "label", and "reason" and "witness" where the file has them, and its "sensor" as a dict of
/// the `[sensor]` keys where its header has one.
#[pyfunction]
fn read_range_image<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let image = py.detach(|| read_range_image_file(&path, &Ledger::default())).map_err(raised)?;
    let xyz: Vec<f32> = (0..image.label.len()).flat_map(|i| [image.x[i], image.y[i], image.z[i]]).collect();
    let reason = image.reason.map(|codes| codes.iter().map(|&r| r as u8).collect());
    let size = (image.width as usize, image.height as usize);
    let dict = image_arrays(py, size, xyz, image.label, reason, image.witness)?;
    if let Some(sensor) = image.sensor {
        dict.set_item("sensor", keys_of(py, &sensor)?)?;
    }
    Ok(dict)
}

/// A range image's arrays: "xyz" (H, W, 3) float32, NaN where no point was measured; "label"
/// (H, W) uint32; and "reason" (H, W) uint8 and "witness" (H, W) uint32 where given.
fn image_arrays<'py>(
    py: Python<'py>,
    (width, height): (usize, usize),
    xyz: Vec<f32>,
    label: Vec<u32>,
    reason: Option<Vec<u8>>,
    witness: Option<Vec<u32>>,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("xyz", xyz.into_pyarray(py).reshape([height, width, 3])?)?;
    dict.set_item("label", label.into_pyarray(py).reshape([height, width])?)?;
    if let Some(reason) = reason {
        dict.set_item("reason", reason.into_pyarray(py).reshape([height, width])?)?;
    }
    if let Some(witness) = witness {
        dict.set_item("witness", witness.into_pyarray(py).reshape([height, width])?)?;
    }
    Ok(dict)
}

/// The arrays of a render (`image_arrays`), its witness bits where the sensor has witnesses,
/// "labels", the scene's labels table as a structured array (`labels_table`), and "sensor",
/// "shadow" and "effects", dicts of the scene's tables: a sensed image that `verify` takes as it
/// is, with the settings it was rendered under.
fn render_arrays<'py>(py: Python<'py>, (labels, out): (Vec<LabelEntry>, RenderOutput)) -> PyResult<Bound<'py, PyDict>> {
    let size = (out.sensor.width() as usize, out.sensor.height() as usize);
    let xyz: Vec<f32> = (0..out.label.len()).flat_map(|i| out.point(i).unwrap_or([f32::NAN; 3])).collect();
    let reason = out.reason.iter().map(|r| r.code() as u8).collect();
    let witness = (!out.sensor.witnesses.is_empty()).then_some(out.witness);
    let dict = image_arrays(py, size, xyz, out.label, Some(reason), witness)?;
    dict.set_item("labels", labels_table(py, &labels)?)?;
    dict.set_item("sensor", keys_of(py, &out.sensor)?)?;
    dict.set_item("shadow", keys_of(py, &out.shadow)?)?;
    dict.set_item("effects", keys_of(py, &out.effects)?)?;
    Ok(dict)
}

/// The labels table as the command line's `labels.json` has it: a numpy structured array of
/// `label`, `object` (the scene file's object, from 0), `model`, `surface` (from 1) and
/// `surface_name`, one row a label.
fn labels_table<'py>(py: Python<'py>, labels: &[LabelEntry]) -> PyResult<Bound<'py, PyAny>> {
    let longest =
        |text: &dyn Fn(&LabelEntry) -> &str| labels.iter().map(|e| text(e).chars().count()).max().unwrap_or(0).max(1);
    let dtype = PyList::new(
        py,
        [
            ("label", "<u4".to_string()),
            ("object", "<u8".to_string()),
            ("model", format!("<U{}", longest(&|e| &e.model))),
            ("surface", "<u4".to_string()),
            ("surface_name", format!("<U{}", longest(&|e| &e.surface_name))),
        ],
    )?;
    let rows = labels
        .iter()
        .map(|e| {
            PyTuple::new(
                py,
                [
                    e.label.into_pyobject(py)?.into_any(),
                    e.object.into_pyobject(py)?.into_any(),
                    e.model.as_str().into_pyobject(py)?.into_any(),
                    e.surface.into_pyobject(py)?.into_any(),
                    e.surface_name.as_str().into_pyobject(py)?.into_any(),
                ],
            )
        })
        .collect::<PyResult<Vec<_>>>()?;
    py.import("numpy")?.call_method1("array", (PyList::new(py, rows)?, dtype))
}

/// Renders a scene file, its inputs charged to an account of the renderer's budget for this
/// call alone: a renderer kept for many calls would otherwise hold every scene it ever loaded
/// against its budget, and refuse one in the end. With the scene's labels table.
fn render_file(renderer: &CrateRenderer, path: &Path) -> rangesynth::Result<(Vec<LabelEntry>, RenderOutput)> {
    let scene = Scene::from_file(path, &Ledger::new(renderer.memory_budget()))?;
    Ok((label_map(&scene)?, renderer.render(&scene)?))
}

/// A renderer on one device, made once and reused: `render(scene_path)` gives a scene's
/// arrays. Usable from several threads; the GIL is released while it renders.
#[pyclass(frozen, module = "rangesynth")]
struct Renderer {
    inner: Arc<CrateRenderer>,
}

fn context_options(device: Option<&str>) -> ContextOptions {
    let mut options = ContextOptions::from_env();
    if let Some(device) = device {
        options.device = Some(device.to_string());
    }
    options
}

/// A renderer on `device` (an index or a UUID from `devices()`, or a name or part of one) with a memory
/// budget as the command line takes it ("4G") and a rasterizer ("auto", "graphics",
/// "compute"); the GIL released while the device starts.
fn new_renderer(
    py: Python<'_>,
    device: Option<&Bound<'_, PyAny>>,
    memory_budget: Option<String>,
    raster: Option<&str>,
) -> PyResult<CrateRenderer> {
    let raster = raster_of(raster)?;
    let budget = memory_budget
        .map(|b| MemoryBudget::parse_setting(&b, "memory_budget"))
        .transpose()
        .map_err(raised)?
        .unwrap_or_default();
    // An index or a UUID from devices(), or a name: the library matches its text.
    let device = device.map(|d| d.str().map(|text| text.to_string())).transpose()?;
    let renderer = py.detach(|| CrateRenderer::new(&context_options(device.as_deref()))).map_err(raised)?;
    Ok(validation::watched(renderer.with_raster(raster).with_memory_budget(budget)))
}

#[pymethods]
impl Renderer {
    /// `device`: an index or a UUID from `devices()`, or a name (or part of one); `memory_budget` as the
    /// command line takes it ("4G"); `raster`: "auto", "graphics" or "compute".
    #[new]
    #[pyo3(signature = (device=None, memory_budget=None, raster=None))]
    fn new(
        py: Python<'_>,
        device: Option<&Bound<'_, PyAny>>,
        memory_budget: Option<String>,
        raster: Option<&str>,
    ) -> PyResult<Self> {
        let renderer = new_renderer(py, device, memory_budget, raster)?;
        Ok(Self { inner: Arc::new(renderer) })
    }

    /// Renders a scene file: a dict of numpy arrays (see `render_scene`).
    fn render<'py>(&self, py: Python<'py>, scene: PathBuf) -> PyResult<Bound<'py, PyDict>> {
        let out = py.detach(|| render_file(&self.inner, &scene));
        render_arrays(py, out.map_err(raised)?)
    }

    #[getter]
    fn device_name(&self) -> String {
        self.inner.context().device_name().to_string()
    }

    /// Whether Vulkan validation is on (RANGESYNTH_VALIDATION=1 where the renderer was made).
    #[getter]
    fn validation_enabled(&self) -> bool {
        self.inner.context().validation_enabled()
    }
}

/// Verifiers kept for the module-level functions, one per rasterizer choice: made on first
/// use, so that a script calling `verify` in a loop builds the pipelines once.
fn shared_verifier(raster: Raster) -> PyResult<Arc<CrateVerifier>> {
    static VERIFIERS: OnceLock<Mutex<HashMap<Raster, Arc<CrateVerifier>>>> = OnceLock::new();
    let mut kept = VERIFIERS.get_or_init(Default::default).lock().unwrap_or_else(|p| p.into_inner());
    if let Some(v) = kept.get(&raster) {
        return Ok(v.clone());
    }
    let renderer =
        validation::watched(CrateRenderer::new(&ContextOptions::from_env()).map_err(raised)?.with_raster(raster));
    let verifier = Arc::new(CrateVerifier::new(renderer).map_err(raised)?);
    kept.insert(raster, verifier.clone());
    Ok(verifier)
}

/// The sensed image and its sensor: an EXR path (its header gives the sensor, shadow and
/// effects), or a dict of "xyz" (H, W, 3) and "label" (H, W) arrays with "sensor" (a dict of
/// the `[sensor]` keys) and, where given, "shadow" and "effects" (dicts of those tables' keys),
/// as a render's dict has them.
fn sensed_of(py: Python<'_>, sensed: &Bound<'_, PyAny>) -> PyResult<RangeImage> {
    if let Ok(dict) = sensed.cast::<PyDict>() {
        let get = |key: &str| dict.get_item(key)?.ok_or_else(|| raised(format!("the sensed dict has no {key:?}")));
        let xyz = array::<f32, numpy::Ix3>(py, &get("xyz")?, "float32", "sensed \"xyz\"")?;
        let label = array::<u32, numpy::Ix2>(py, &get("label")?, "uint32", "sensed \"label\"")?;
        let (xyz, label) = (xyz.as_array(), label.as_array());
        let (height, width) = (label.nrows(), label.ncols());
        if xyz.shape() != [height, width, 3] {
            return Err(raised(format!(
                "sensed \"xyz\" is {:?}; with a {height}×{width} label it must be ({height}, {width}, 3)",
                xyz.shape()
            )));
        }
        let sensor: Sensor = from_keys(py, &get("sensor")?, "sensed \"sensor\"")?;
        let shadow = dict.get_item("shadow")?.map(|k| from_keys(py, &k, "sensed \"shadow\"")).transpose()?;
        let effects = dict.get_item("effects")?.map(|k| from_keys(py, &k, "sensed \"effects\"")).transpose()?;
        let channel = |k: usize| xyz.index_axis(numpy::ndarray::Axis(2), k).iter().copied().collect::<Vec<f32>>();
        let size = |n: usize| u32::try_from(n).map_err(|_| raised(format!("a side of {n} pixels is too large")));
        return Ok(RangeImage {
            width: size(width)?,
            height: size(height)?,
            x: channel(0),
            y: channel(1),
            z: channel(2),
            label: label.iter().copied().collect(),
            reason: None,
            witness: None,
            sensor: Some(sensor),
            shadow,
            effects,
        });
    }
    let path: PathBuf = sensed
        .extract()
        .map_err(|_| raised("sensed must be an EXR path or a dict of \"xyz\", \"label\" and \"sensor\""))?;
    read_range_image_file(&path, &Ledger::default()).map_err(raised)
}

/// The poses of an (N, 4, 4) float64 array, row-major as numpy holds them.
fn poses_of(poses: &PyReadonlyArray3<'_, f64>) -> PyResult<Vec<DMat4>> {
    let a = poses.as_array();
    if a.shape()[1..] != [4, 4] {
        return Err(raised(format!("poses must be (N, 4, 4); they are {:?}", a.shape())));
    }
    Ok(a.outer_iter()
        .map(|m| DMat4::from_cols_array_2d(&std::array::from_fn(|c| std::array::from_fn(|r| m[[r, c]]))))
        .collect())
}

/// A verification's model as Python gave it: a Mesh, or a path or `builtin:` name.
enum ModelArg {
    Mesh(Arc<CrateMesh>),
    Reference(String),
}

impl ModelArg {
    fn of(model: &Bound<'_, PyAny>) -> PyResult<Self> {
        if let Ok(mesh) = model.cast::<Mesh>() {
            return Ok(Self::Mesh(mesh.get().inner.clone()));
        }
        let reference = model.extract().map_err(|_| raised("model must be a Mesh, a file path or a builtin: name"))?;
        Ok(Self::Reference(reference))
    }

    /// The model loaded (a reference once, then kept) and uploaded: with the GIL released.
    fn load(self, verifier: &CrateVerifier) -> rangesynth::Result<Arc<Model>> {
        match self {
            Self::Mesh(mesh) => verifier.model_of_mesh(mesh),
            Self::Reference(reference) => verifier.model(&reference, Path::new(".")),
        }
    }
}

/// The arrays of a batch's verifications of a model of `surfaces` surfaces: the scores, and
/// the counts as the command line's JSON lines have them (`Record`): the scalars, and
/// "surface_population" (N, surfaces) and "overlaps", each pose's (K, 3) array of
/// [scene label, model surface, pixels].
fn verification_arrays<'py>(
    py: Python<'py>,
    verified: &[Verification],
    sensed: &SensedImage,
    surfaces: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    let scores = [("s", 6usize), ("s1", 0), ("s2", 1), ("s3", 2), ("s4", 3), ("s5", 4), ("s6", 5)];
    for (name, k) in scores {
        let column: Vec<f64> = verified
            .iter()
            .map(|v| {
                let s = &v.scores;
                [s.s1, s.s2, s.s3, s.s4, s.s5, s.s6, s.s][k]
            })
            .collect();
        dict.set_item(name, column.into_pyarray(py))?;
    }
    let records: Vec<Record<'_>> = verified.iter().map(|v| Record::new(v, sensed)).collect();
    let counts: Vec<_> = records.iter().map(|r| &r.scores.counts).collect();
    let scalar =
        |of: &dyn Fn(&rangesynth::verify::CountsRecord) -> u64| counts.iter().map(|&c| of(c)).collect::<Vec<u64>>();
    dict.set_item("n1_plus", scalar(&|c| c.n1_plus).into_pyarray(py))?;
    dict.set_item("n1_minus", scalar(&|c| c.n1_minus).into_pyarray(py))?;
    dict.set_item("n0", scalar(&|c| c.n0).into_pyarray(py))?;
    dict.set_item("n1", scalar(&|c| c.n1).into_pyarray(py))?;
    dict.set_item("n_s", scalar(&|c| c.n_s).into_pyarray(py))?;
    dict.set_item("n_i", scalar(&|c| c.n_i).into_pyarray(py))?;
    let population: Vec<u64> = counts.iter().flat_map(|c| c.surface_population.iter().copied()).collect();
    dict.set_item("surface_population", population.into_pyarray(py).reshape([verified.len(), surfaces])?)?;
    let numpy = py.import("numpy")?;
    let overlaps = numpy.call_method1("empty", (verified.len(), "O"))?;
    for (i, c) in counts.iter().enumerate() {
        let rows: Vec<u64> = c.overlaps.iter().flatten().copied().collect();
        overlaps.set_item(i, rows.into_pyarray(py).reshape([c.overlaps.len(), 3])?)?;
    }
    dict.set_item("overlaps", overlaps)?;
    let rejected: Vec<String> = verified.iter().map(|v| v.scores.rejected.clone().unwrap_or_default()).collect();
    dict.set_item("rejected", numpy.call_method1("array", (PyList::new(py, rejected)?, PyString::new(py, "U")))?)?;
    Ok(dict)
}

/// A verification's arguments as Python gave them.
struct VerifyCall<'a, 'py> {
    sensed: &'a Bound<'py, PyAny>,
    model: &'a Bound<'py, PyAny>,
    poses: &'a Bound<'py, PyAny>,
    bindings: Vec<(u32, u32)>,
    shadow: Option<&'a Bound<'py, PyAny>>,
    effects: Option<&'a Bound<'py, PyAny>>,
    tolerance: f64,
    /// Called with the number of poses done after each chunk.
    progress: Option<&'a Bound<'py, PyAny>>,
}

/// Scores the call's poses of its model against its sensed image.
fn verify_with<'py>(
    py: Python<'py>,
    verifier: &Arc<CrateVerifier>,
    call: VerifyCall<'_, 'py>,
) -> PyResult<Bound<'py, PyDict>> {
    let VerifyCall { sensed, model, poses, bindings, shadow, effects, tolerance, progress } = call;
    let image = sensed_of(py, sensed)?;
    let sensor = image.sensor.clone().ok_or_else(|| raised("the sensed image has no sensor header"))?;
    let shadow = match shadow {
        None => image.shadow.unwrap_or_default(),
        Some(s) => match s.extract::<String>() {
            Ok(mode) => ShadowSettings::of(from_keys::<ShadowMode>(py, s, &format!("shadow {mode:?}"))?),
            Err(_) => from_keys(py, s, "shadow")?,
        },
    };
    let effects: Effects = match effects {
        None => image.effects.unwrap_or_default(),
        Some(e) => from_keys(py, e, "effects")?,
    };
    let sensed = SensedImage::new(&image, &sensor).map_err(raised)?;
    let model = ModelArg::of(model)?;
    let model = py.detach(|| model.load(verifier)).map_err(raised)?;
    // The call's poses, held to the budget before any is copied.
    let count = pose_count(py, poses)?;
    let surfaces = model.mesh.surface_count() as usize;
    let ledger = verifier.renderer().ledger();
    let pose_bytes = (count as u64).saturating_mul(held_bytes_a_pose(bindings.len(), surfaces));
    let _held = ledger.hold(format_args!("{count} poses"), pose_bytes).map_err(raised)?;
    let poses = array::<f64, numpy::Ix3>(py, poses, "float64", "poses")?;
    let hypotheses: Vec<Hypothesis> = poses_of(&poses)?
        .into_iter()
        .enumerate()
        .map(|(i, pose)| Hypothesis { id: i.to_string(), model: model.clone(), pose, bindings: bindings.clone() })
        .collect();
    let settings = VerifySettings { sensor, shadow, effects, tolerance, compare_shadow: false, chunk_size: 1024 };
    let verifier = verifier.clone();
    // Chunk by chunk, the GIL taken back to tell the callback how many are done.
    let callback = progress.map(|callback| callback.clone().unbind());
    let done = py
        .detach(|| {
            verifier.verify_until(&sensed, &settings, &hypotheses, &mut |count| match &callback {
                None => Ok(()),
                Some(callback) => Python::attach(|py| callback.call1(py, (count,)).map(|_| ()))
                    .map_err(|e| rangesynth::Error::Scene(format!("the progress callback raised: {e}"))),
            })
        })
        .map_err(raised)?;
    // Held again while the arrays are made from them: the crate gave its hold back.
    let held: u64 = done.iter().map(Verification::held_bytes).sum();
    let _verifications = ledger.hold(format_args!("the verifications of {count} poses"), held).map_err(raised)?;
    verification_arrays(py, &done, &sensed, surfaces)
}

/// How many poses an array-like holds (its first dimension), read before it is converted.
fn pose_count(py: Python<'_>, poses: &Bound<'_, PyAny>) -> PyResult<usize> {
    let shape: Vec<usize> = py
        .import("numpy")?
        .call_method1("shape", (poses,))
        .and_then(|shape| shape.extract())
        .map_err(|e| raised(format!("poses is not an array of float64: {e}")))?;
    Ok(shape.first().copied().unwrap_or(0))
}

/// Host bytes a pose of a call takes besides its verification (which the crate holds while it
/// verifies, and this call after): the pose as float64 (where it is converted) and as the
/// crate's matrix, its hypothesis (its id, its `bindings`), and its row of the output arrays
/// as they are made (thirteen numbers; a count a surface of the model's `surfaces`, twice: the
/// record's copy and the array's; its overlaps' array and its rejection's text, each at least
/// a Python object).
fn held_bytes_a_pose(bindings: usize, surfaces: usize) -> u64 {
    const PYTHON_OBJECT: usize = 64;
    let id = u64::MAX.to_string().len();
    let hypothesis = size_of::<Hypothesis>() + id + bindings * size_of::<(u32, u32)>();
    let row = (13 + 2 * surfaces) * size_of::<u64>() + 2 * PYTHON_OBJECT;
    (2 * size_of::<DMat4>() + hypothesis + row) as u64
}

/// A verifier on one device, made once and reused; usable from several threads, the GIL
/// released while it verifies.
#[pyclass(frozen, module = "rangesynth")]
struct Verifier {
    inner: Arc<CrateVerifier>,
}

#[pymethods]
impl Verifier {
    #[new]
    #[pyo3(signature = (device=None, memory_budget=None, raster=None))]
    fn new(
        py: Python<'_>,
        device: Option<&Bound<'_, PyAny>>,
        memory_budget: Option<String>,
        raster: Option<&str>,
    ) -> PyResult<Self> {
        let renderer = new_renderer(py, device, memory_budget, raster)?;
        let verifier = py.detach(|| CrateVerifier::new(renderer));
        Ok(Self { inner: Arc::new(verifier.map_err(raised)?) })
    }

    #[getter]
    fn device_name(&self) -> String {
        self.inner.renderer().context().device_name().to_string()
    }

    /// Whether Vulkan validation is on (RANGESYNTH_VALIDATION=1 where the verifier was made).
    #[getter]
    fn validation_enabled(&self) -> bool {
        self.inner.renderer().context().validation_enabled()
    }

    /// As the module's `verify`, with `progress` called with the number of poses done after
    /// each chunk.
    #[pyo3(signature = (sensed, model, poses, bindings, shadow=None, effects=None, tolerance=0.1, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn verify<'py>(
        &self,
        py: Python<'py>,
        sensed: &Bound<'py, PyAny>,
        model: &Bound<'py, PyAny>,
        poses: &Bound<'py, PyAny>,
        bindings: Vec<(u32, u32)>,
        shadow: Option<&Bound<'py, PyAny>>,
        effects: Option<&Bound<'py, PyAny>>,
        tolerance: f64,
        progress: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let call = VerifyCall { sensed, model, poses, bindings, shadow, effects, tolerance, progress };
        verify_with(py, &self.inner, call)
    }
}

/// Renders a scene file: a dict of numpy arrays, "xyz" (H, W, 3) float32 (NaN where nothing was
/// measured), "label" (H, W) uint32, "reason" (H, W) uint8 and, where the sensor has witnesses,
/// "witness" (H, W) uint32 (bit k: witness k did not see the point); with "labels", the labels
/// table, and "sensor", the scene's `[sensor]` keys, so that `verify` takes it as a sensed image.
#[pyfunction]
#[pyo3(signature = (path, raster=None))]
fn render_scene<'py>(py: Python<'py>, path: PathBuf, raster: Option<&str>) -> PyResult<Bound<'py, PyDict>> {
    // The renderer of the verifier kept for this rasterizer: its pipelines are built once.
    let verifier = shared_verifier(raster_of(raster)?)?;
    let out = py.detach(|| render_file(verifier.renderer(), &path));
    render_arrays(py, out.map_err(raised)?)
}

/// Scores each pose of `model` against the sensed image: a dict of arrays, one element a pose:
/// "s", "s1" … "s6" float64; the counts "n1_plus", "n1_minus", "n0", "n1", "n_s", "n_i" uint64,
/// "surface_population" (N, the model's surfaces) uint64 and "overlaps" (each pose's (K, 3)
/// array of [scene label, model surface, pixels]); and "rejected" (str, empty where the pose
/// was not rejected).
#[pyfunction]
#[pyo3(signature = (sensed, model, poses, bindings, shadow=None, effects=None, tolerance=0.1, raster=None))]
#[allow(clippy::too_many_arguments)]
fn verify<'py>(
    py: Python<'py>,
    sensed: &Bound<'py, PyAny>,
    model: &Bound<'py, PyAny>,
    poses: &Bound<'py, PyAny>,
    bindings: Vec<(u32, u32)>,
    shadow: Option<&Bound<'py, PyAny>>,
    effects: Option<&Bound<'py, PyAny>>,
    tolerance: f64,
    raster: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let verifier = shared_verifier(raster_of(raster)?)?;
    let call = VerifyCall { sensed, model, poses, bindings, shadow, effects, tolerance, progress: None };
    verify_with(py, &verifier, call)
}

/// The Vulkan devices the loader lists: dicts of "index", "name", "uuid" and "kind".
#[pyfunction]
fn devices<'py>(py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let listed = py.detach(list_devices).map_err(raised)?;
    listed
        .into_iter()
        .map(|d| {
            let dict = PyDict::new(py);
            dict.set_item("index", d.index)?;
            dict.set_item("name", d.name)?;
            dict.set_item("uuid", d.uuid)?;
            dict.set_item("kind", d.kind)?;
            Ok(dict)
        })
        .collect()
}

#[pymodule]
fn _rangesynth(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("Error", m.py().get_type::<Error>())?;
    m.add_class::<Mesh>()?;
    m.add_class::<Renderer>()?;
    m.add_class::<Verifier>()?;
    m.add_function(wrap_pyfunction!(render_scene, m)?)?;
    m.add_function(wrap_pyfunction!(verify, m)?)?;
    m.add_function(wrap_pyfunction!(devices, m)?)?;
    m.add_function(wrap_pyfunction!(read_range_image, m)?)?;
    m.add_function(wrap_pyfunction!(validation::validation_messages, m)?)?;
    Ok(())
}
