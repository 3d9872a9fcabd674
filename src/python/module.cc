// The compiled part of the Python package `impactdic` (src/python/impactdic/__init__.py is the
// interface users call; docs/python.md): a thin layer, like src/cli, over the library functions
// the command-line tool calls. The correlation is pipeline CorrelateSceneInMemory on a scene built
// from scene keys by SetSceneKey (pipeline/scene_flags.h), as `impactdic correlate` builds its
// scene from its flags: the same keys, parsers, ranges and messages.
//
//   _correlate(frames, [("dic.subset_size", "25")], allow_partial=False, time_s=[], progress=None)
//
// `frames` is a list of grey images (numpy arrays: uint8, uint16, float32, float64), a list of
// image files (the first the reference) or one `inputs.frames` setting (a folder, glob, video or
// camera file); `time_s` the arrays' time stamps [s] (one per frame; empty: none); `progress`
// None or a callable progress(done, total). The library runs without the GIL, watched at its stop
// points (core/progress.h) for Ctrl-C and the callback's errors (PythonWatch). Library errors
// become Python exceptions: ErrorKind::kInvalidValue ValueError, kFileNotFound FileNotFoundError,
// kFileFormat and kIo OSError, PartialResultsError impactdic.NothingUsableError, other kNumerical
// impactdic.Error; the message is the library's.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/progress.h"
#include "impactdic/core/version.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/json.h"
#include "impactdic/io/yaml.h"
#include "impactdic/pipeline/correlate_scene.h"
#include "impactdic/pipeline/model_runs.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_flags.h"

namespace py = pybind11;

namespace impactdic::python {
namespace {

// The exception types of the module (created at import, alive as long as the interpreter).
PyObject* g_error = nullptr;           // impactdic.Error (RuntimeError)
PyObject* g_nothing_usable = nullptr;  // impactdic.NothingUsableError (impactdic.Error)

// The scene sections `correlate` takes, as the command's flags (src/cli/correlate_command.cc):
// every key of dic and preprocess, inputs.fps and inputs.calibration, and dic.roi.
const std::vector<std::string>& CorrelateKeys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k;
    for (const SceneKeyFlag& f :
         SceneKeyFlags({"dic", "preprocess", "inputs.fps", "inputs.calibration"}))
      k.push_back(f.key);
    k.push_back("dic.roi");
    return k;
  }();
  return keys;
}

// A key not `known`: "KEY: unknown option (did you mean 'CLOSEST'?); expected EXPECTED", as the
// scene file's "unknown key (did you mean ...)" (the closest key when one is close).
void ApplyKeyCheck(const std::string& key, const std::vector<std::string>& known,
                   const std::string& expected) {
  if (std::find(known.begin(), known.end(), key) != known.end()) return;
  const std::string close = ClosestMatch(key, known);
  throw Error(ErrorKind::kInvalidValue,
              key + ": unknown option" + (close.empty() ? "" : " (did you mean '" + close + "'?)") +
                  "; expected " + expected);
}

// Sets each (key, value text) on `scene` with the key's own parser (ApplyKeyCheck first).
void ApplyKeys(const std::vector<std::pair<std::string, std::string>>& keys,
               const std::vector<std::string>& known, const std::string& expected, Scene* scene) {
  for (const auto& [key, value] : keys) {
    ApplyKeyCheck(key, known, expected);
    SetSceneKey(scene, key, value, key);
  }
}

// A grey image of a numpy array, in a buffer of its own (the library works on its own frames):
// 2-D; uint8, uint16 with any bit depth of the data (the frames image files give), float32 or
// float64 grey levels as they are (the correlator's float images: any range, the contrast limits
// relative to the reference's largest value; float64 becomes float32, the precision the
// correlator computes in). Error naming `what` otherwise, and for a float that is not finite.
cv::Mat ImageOfArray(const py::array& array, const std::string& what) {
  const py::dtype dtype = array.dtype();
  const std::string dtype_name = py::str(static_cast<py::handle>(dtype)).cast<std::string>();
  const bool bits8 = dtype.is(py::dtype::of<std::uint8_t>());
  const bool bits16 = dtype.is(py::dtype::of<std::uint16_t>());
  const bool float32 = dtype.is(py::dtype::of<float>());
  const bool float64 = dtype.is(py::dtype::of<double>());
  CheckValue(bits8 || bits16 || float32 || float64, what, "dtype " + dtype_name,
             "uint8 or uint16 (8- or 16-bit frames, as image files hold them) or float32 or "
             "float64 (grey levels as they are)");
  CheckValue(array.ndim() == 2, what, std::to_string(array.ndim()) + "-D array",
             "a 2-D grey image (rows, columns)");
  const int rows = static_cast<int>(array.shape(0)), cols = static_cast<int>(array.shape(1));
  CheckValue(rows > 0 && cols > 0, what, std::to_string(rows) + "x" + std::to_string(cols),
             "a non-empty image");
  cv::Mat image(rows, cols, bits8 ? CV_8U : bits16 ? CV_16U : CV_32F);
  const auto n = static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols);
  const auto copy = [&](auto tag, auto* out) {
    using T = decltype(tag);
    const auto a = py::array_t<T, py::array::c_style>::ensure(array);
    const T* in = a.data();
    using Out = std::remove_pointer_t<decltype(out)>;
    if constexpr (std::is_floating_point_v<T>) {
      const T* bad = std::find_if(in, in + n, [](T v) { return !std::isfinite(v); });
      if (bad != in + n) {
        const auto k = static_cast<std::size_t>(bad - in);
        throw Error(ErrorKind::kInvalidValue, what,
                    std::string(std::isnan(*bad) ? "NaN" : "infinity") + " at row " +
                        std::to_string(k / static_cast<std::size_t>(cols)) + ", column " +
                        std::to_string(k % static_cast<std::size_t>(cols)),
                    "finite grey levels");
      }
    }
    std::transform(in, in + n, out, [](T v) { return static_cast<Out>(v); });
  };
  if (bits8) {
    copy(std::uint8_t{}, image.ptr<std::uint8_t>());
  } else if (bits16) {
    copy(std::uint16_t{}, image.ptr<std::uint16_t>());
  } else if (float32) {
    copy(float{}, image.ptr<float>());
  } else {
    copy(double{}, image.ptr<float>());
  }
  return image;
}

// numpy array over `data` (shape `shape`), owned by `owner` (no copy); an empty vector: None.
template <typename T>
py::object ArrayOf(const std::vector<T>& data, std::vector<py::ssize_t> shape,
                   const py::object& owner) {
  if (data.empty()) return py::none();
  return py::array_t<T>(std::move(shape), data.data(), owner);
}

// The table's arrays (numpy views of it, the table kept alive by them) and attributes.
py::dict TableDict(std::shared_ptr<DicResultsTable> table) {
  const DicResultsTable& t = *table;
  // One capsule owns the table for every array over it.
  auto* holder = new std::shared_ptr<DicResultsTable>(std::move(table));
  const py::capsule owner(
      holder, [](void* p) { delete static_cast<std::shared_ptr<DicResultsTable>*>(p); });
  const auto rows = static_cast<py::ssize_t>(t.rows), n = static_cast<py::ssize_t>(t.subsets);
  py::dict d;
  d["x"] = ArrayOf(t.x_px, {n}, owner);
  d["y"] = ArrayOf(t.y_px, {n}, owner);
  d["u"] = ArrayOf(t.u_px, {rows, n}, owner);
  d["v"] = ArrayOf(t.v_px, {rows, n}, owner);
  d["status"] = ArrayOf(t.status, {rows, n}, owner);
  d["iterations"] = ArrayOf(t.iterations, {rows, n}, owner);
  d["zncc"] = ArrayOf(t.zncc, {rows, n}, owner);
  d["sigma_u"] = ArrayOf(t.sigma_u_px, {rows, n}, owner);
  d["sigma_v"] = ArrayOf(t.sigma_v_px, {rows, n}, owner);
  d["sigma"] = ArrayOf(t.sigma_px, {rows, n}, owner);
  d["dudx_warp"] = ArrayOf(t.dudx_warp, {rows, n}, owner);
  d["dudy_warp"] = ArrayOf(t.dudy_warp, {rows, n}, owner);
  d["dvdx_warp"] = ArrayOf(t.dvdx_warp, {rows, n}, owner);
  d["dvdy_warp"] = ArrayOf(t.dvdy_warp, {rows, n}, owner);
  d["frame"] = ArrayOf(t.frame, {rows}, owner);
  d["reference_frame"] = ArrayOf(t.reference_frame, {rows}, owner);
  d["frame_number"] = ArrayOf(t.frame_number, {rows}, owner);
  d["time_s"] = ArrayOf(t.time_s, {rows}, owner);
  d["status_codes"] = t.status_codes;
  py::dict attributes;
  for (const auto& [name, value] : t.number_attributes) attributes[py::str(name)] = value;
  for (const auto& [name, value] : t.text_attributes) attributes[py::str(name)] = value;
  d["attributes"] = attributes;
  return d;
}

py::dict SummaryDict(const SceneCorrelation& c) {
  const DicSummary& s = c.dic;
  py::dict d;
  d["subsets"] = s.subsets;
  d["frames"] = s.frames;
  d["valid_fraction"] = s.valid_fraction;
  d["mean_iterations"] = s.mean_iterations;
  d["reference_updates"] = s.reference_updates;
  d["data_bits"] = s.data_bits;
  py::dict counts;
  for (int k = 0; k < kSubsetStatusCount; ++k)
    counts[py::str(ToString(static_cast<SubsetStatus>(k)))] = s.status_counts[std::size_t(k)];
  d["status_counts"] = counts;
  d["seconds"] = s.seconds_total;
  d["subsets_per_s"] = s.SubsetsPerSecond();
  d["usable"] = s.IsUsable();
  d["brief_report"] = s.BriefReport();
  d["full_report"] = s.FullReport();
  d["warnings"] = c.summary.warnings;
  return d;
}

// Watches a library call made without the GIL on the calling thread (core/progress.h): each step
// of the "correlate" loop calls `progress(done, total)`, taking the GIL for just that, and on
// Python's main thread (the only one that runs signal handlers) a stop point at least
// kSignalCheck after the last check runs Python's signal handlers (Ctrl-C: KeyboardInterrupt), so
// the GIL is taken at most 20 times a second: a busy Python thread holding it delays the library
// little. A Python error either raises stops the call at the next stop point; it stays set in the
// thread's error indicator, raised when the call has unwound (Interruptible). Made, and used, on
// the calling thread.
class PythonWatch : public ProgressObserver {
 public:
  // With the GIL held.
  explicit PythonWatch(py::object progress)
      : progress_(std::move(progress)), main_thread_(IsMainThread()) {}
  void Advanced(const std::string& label, std::size_t done, std::size_t total) override {
    if (label != "correlate" || progress_.is_none() || stop_) return;
    const py::gil_scoped_acquire gil;
    try {
      progress_(done, total);
    } catch (py::error_already_set& e) {
      e.restore();
      stop_ = true;
    }
  }
  bool ShouldStop() override {
    if (stop_ || !main_thread_) return stop_;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_check_ < kSignalCheck) return false;
    last_check_ = now;
    const py::gil_scoped_acquire gil;
    stop_ = PyErr_CheckSignals() != 0;
    return stop_;
  }

 private:
  static bool IsMainThread() {
    const py::module_ threading = py::module_::import("threading");
    return threading.attr("current_thread")().is(threading.attr("main_thread")());
  }

  static constexpr std::chrono::milliseconds kSignalCheck{50};
  py::object progress_;
  bool main_thread_;
  bool stop_ = false;  // A Python error is set: stop.
  std::chrono::steady_clock::time_point last_check_;
};

// `work()` without the GIL, watched by a PythonWatch; a stop raises the Python error that asked
// for it (KeyboardInterrupt, the progress callback's exception).
template <typename Work>
auto Interruptible(const py::object& progress, Work work) {
  PythonWatch watch(progress);
  try {
    const py::gil_scoped_release release;
    const ScopedProgressObserver watching(&watch);
    return work();
  } catch (const Stopped&) {  // The GIL is held again here.
    if (PyErr_Occurred() != nullptr) throw py::error_already_set();
    throw;
  }
}

// _correlate(frames, keys, allow_partial): see the file comment. Returns (table dict, summary
// dict). The library computes without the GIL.
py::tuple Correlate(const py::object& frames,
                    const std::vector<std::pair<std::string, std::string>>& keys,
                    bool allow_partial, std::vector<double> time_s, const py::object& progress) {
  Scene scene;
  ApplyKeys(keys, CorrelateKeys(),
            "a key of the scene's dic or preprocess section, inputs.fps or inputs.calibration",
            &scene);
  std::unique_ptr<FrameSource> source;
  if (py::isinstance<py::str>(frames)) {
    CheckValue(time_s.empty(), "time_s", "given with " + frames.cast<std::string>(),
               "time stamps of frames given as arrays only (files and cameras have their own)");
    scene.inputs.frames = frames.cast<std::string>();
  } else {
    const auto list = frames.cast<py::list>();
    bool arrays = false, files = false;
    for (const py::handle item : list) (py::isinstance<py::str>(item) ? files : arrays) = true;
    CheckValue(!(arrays && files), "frames", "arrays and file names", "one or the other");
    CheckValue(!files || time_s.empty(), "time_s", "given with image files",
               "time stamps of frames given as arrays only (files and cameras have their own)");
    if (files) {
      scene.inputs.frame_files = list.cast<std::vector<std::string>>();
    } else {
      std::vector<cv::Mat> images;
      for (std::size_t k = 0; k < list.size(); ++k) {
        const std::string what = k == 0 ? "reference" : "frame " + std::to_string(k);
        images.push_back(ImageOfArray(py::array::ensure(list[k]), what));
        const cv::Mat& first = images.front();
        CheckValue(images.back().size() == first.size() && images.back().type() == first.type(),
                   what,
                   std::to_string(images.back().rows) + "x" + std::to_string(images.back().cols) +
                       " " + py::str(list[k].attr("dtype")).cast<std::string>(),
                   std::to_string(first.rows) + "x" + std::to_string(first.cols) + " " +
                       py::str(list[0].attr("dtype")).cast<std::string>() +
                       " like the reference (rows x columns, dtype)");
      }
      CheckValue(images.size() >= 2, "frames", std::to_string(images.size()) + " image(s)",
                 "a reference and at least one deformed image");
      source = MakeMemoryFrameSource(std::move(images), std::move(time_s));
    }
  }
  const auto result = Interruptible(progress, [&] {
    return std::make_shared<SceneCorrelation>(CorrelateSceneInMemory(
        scene, std::move(source), allow_partial, {"reference", "deformed", "reference"}));
  });
  py::dict summary = SummaryDict(*result);
  auto table = std::make_shared<DicResultsTable>(std::move(result->table));
  return py::make_tuple(TableDict(std::move(table)), summary);
}

// The attributes of a group or dataset: name -> str or float.
py::dict Attributes(const H5Reader& in, const std::string& path) {
  py::dict d;
  for (const std::string& name : in.AttributeNames(path)) {
    if (in.IsTextAttribute(path, name)) {
      d[py::str(name)] = in.ReadStringAttribute(path, name);
    } else {
      d[py::str(name)] = in.ReadNumberAttribute(path, name);
    }
  }
  return d;
}

// A numeric dataset as a numpy array of its shape: float32 and float64 as stored, integers of up
// to 4 bytes as int32, wider ones as float64.
py::array Dataset(const H5Reader& in, const std::string& path) {
  const H5Reader::NumberType type = in.Type(path);
  Dims dims;
  const auto array = [&dims](auto values) {
    using T = typename decltype(values)::value_type;
    auto* owned = new std::vector<T>(std::move(values));
    const py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
    const std::vector<py::ssize_t> shape(dims.begin(), dims.end());
    return py::array_t<T>(shape, owned->data(), owner);
  };
  if (type.kind == H5Reader::NumberKind::kFloat && type.bytes == 4)
    return array(in.ReadFloat(path, &dims));
  if (type.kind != H5Reader::NumberKind::kFloat && type.bytes <= 4 &&
      !(type.kind == H5Reader::NumberKind::kUInt && type.bytes == 4))
    return array(in.ReadInt(path, &dims));
  return array(in.ReadDouble(path, &dims));
}

// _read_h5(path): every group of the file ("/dic": its attributes) and every numeric dataset
// ("/dic/u_px": (array, attributes)); the paths of the others (text) in "skipped".
py::dict ReadH5(const std::string& file) {
  const H5Reader in(file);
  py::dict groups, datasets;
  py::list skipped;
  std::vector<std::string> pending = {"/"};
  while (!pending.empty()) {
    const std::string group = pending.back();
    pending.pop_back();
    groups[py::str(group)] = Attributes(in, group);
    for (const std::string& name : in.List(group)) {
      const std::string path = (group == "/" ? "" : group) + "/" + name;
      if (in.IsGroup(path)) {
        pending.push_back(path);
        continue;
      }
      try {
        datasets[py::str(path)] = py::make_tuple(Dataset(in, path), Attributes(in, path));
      } catch (const Error& e) {
        if (e.found() != "not numeric") throw;
        skipped.append(path);
      }
    }
  }
  py::dict d;
  d["groups"] = groups;
  d["datasets"] = datasets;
  d["skipped"] = skipped;
  return d;
}

// The scene keys `run` takes: those of `impactdic run`'s flags.
const std::vector<std::string>& RunKeys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k;
    for (const SceneKeyFlag& f : SceneKeyFlags(
             {"test", "preprocess", "dic", "sensor", "momentum", "model", "strain", "outputs"}))
      k.push_back(f.key);
    k.push_back("dic.roi");
    return k;
  }();
  return keys;
}

// _run(scene_file, scene_text, output, keys, allow_partial, force): RunScene on the scene file,
// or on `scene_text` (YAML or JSON; relative paths against the working folder) when scene_file
// is empty, with `keys` set on it as `impactdic run`'s flags set them; `output` the output folder
// ("" = the scene's outputs.folder). Returns (summary.json's text, the files written).
py::tuple Run(const std::string& scene_file, const std::string& scene_text,
              const std::string& output,
              const std::vector<std::pair<std::string, std::string>>& keys, bool allow_partial,
              bool force) {
  // A dict's text is one line of JSON: messages name "(scene dict):1" and the key path.
  Scene scene = scene_file.empty() ? ParseScene(scene_text, "(scene dict)") : LoadScene(scene_file);
  ApplyKeys(keys, RunKeys(),
            "a key of the scene's test, preprocess, dic, sensor, momentum, "
            "model, strain or outputs section",
            &scene);
  MakeSensorOptions(scene);  // The keys' values checked together, as the scene file's.
  PipelineOptions options;
  options.output_folder = output;
  options.allow_partial = allow_partial;
  options.force = force;
  const PipelineSummary summary =
      Interruptible(py::none(), [&] { return RunScene(scene, options); });
  return py::make_tuple(summary.ToJson().Dump(), summary.outputs);
}

// _model(numbers, solver, error_estimator, ode45_defaults, output): `impactdic model` of one test
// (pipeline RunModelRequest) with the test.* and model.* keys given: the numbers by key, the
// solver's names ("" = default) and the switch. Returns the summary's JSON text (ImpactSummary
// ToJson); writes the series to `output` (.csv, .h5; "" = none).
std::string Model(const std::map<std::string, double>& numbers, const std::string& solver,
                  const std::string& error_estimator, bool ode45_defaults,
                  const std::string& output) {
  std::vector<std::string> known;
  for (const SceneKeyFlag& f : SceneKeyFlags({"test", "model"})) known.push_back(f.key);
  ModelRequest request;
  for (const auto& [key, value] : numbers) {
    ApplyKeyCheck(key, known, "a key of the scene's test or model section");
    request.keys[key] = value;
  }
  if (!solver.empty()) request.solver = solver;
  if (!error_estimator.empty()) request.error_estimator = error_estimator;
  request.ode45_defaults = ode45_defaults;
  request.format = "json";
  request.output = output;
  std::ostringstream out;
  {
    const py::gil_scoped_release release;
    RunModelRequest(request, out);
  }
  return out.str();
}

// The library's messages at `level` and above ("debug", "info", "warning", "error", "off").
void SetLogLevelByName(const std::string& level) {
  static const std::vector<std::pair<std::string, LogLevel>> kLevels = {
      {"debug", LogLevel::kDebug},
      {"info", LogLevel::kInfo},
      {"warning", LogLevel::kWarning},
      {"error", LogLevel::kError},
      {"off", LogLevel::kOff}};
  for (const auto& [name, value] : kLevels) {
    if (name == level) {
      SetLogLevel(value);
      return;
    }
  }
  throw Error(ErrorKind::kInvalidValue, "log level", "'" + level + "'",
              "debug, info, warning, error or off");
}

// An impactdic::Error as the Python exception of its kind (file comment).
// pybind11 hands the exception by value (py::register_exception_translator's signature).
void Translate(std::exception_ptr p) {  // NOLINT(performance-unnecessary-value-param)
  try {
    if (p) std::rethrow_exception(p);
  } catch (const PartialResultsError& e) {
    PyErr_SetString(g_nothing_usable, e.what());
  } catch (const Error& e) {
    switch (e.kind()) {
      case ErrorKind::kInvalidValue: PyErr_SetString(PyExc_ValueError, e.what()); break;
      case ErrorKind::kFileNotFound: PyErr_SetString(PyExc_FileNotFoundError, e.what()); break;
      case ErrorKind::kFileFormat:
      case ErrorKind::kIo: PyErr_SetString(PyExc_OSError, e.what()); break;
      case ErrorKind::kNumerical: PyErr_SetString(g_error, e.what()); break;
    }
  }
}

}  // namespace
}  // namespace impactdic::python

PYBIND11_MODULE(_impactdic, m) {
  using namespace impactdic::python;  // NOLINT(google-build-using-namespace): the module's own.
  m.doc() = "The compiled part of impactdic (use the package impactdic)";
  g_error = PyErr_NewException("impactdic.Error", PyExc_RuntimeError, nullptr);
  g_nothing_usable = PyErr_NewException("impactdic.NothingUsableError", g_error, nullptr);
  m.add_object("Error", py::handle(g_error));
  m.add_object("NothingUsableError", py::handle(g_nothing_usable));
  py::register_exception_translator(&Translate);
  m.attr("__version__") = impactdic::Version();
  m.attr("git_revision") = impactdic::GitRevision();
  m.attr("correlate_keys") = CorrelateKeys();
  m.def("_correlate", &Correlate, py::arg("frames"), py::arg("keys"), py::arg("allow_partial"),
        py::arg("time_s"), py::arg("progress"));
  m.def("_read_h5", &ReadH5, py::arg("path"));
  m.def("_run", &Run, py::arg("scene_file"), py::arg("scene_text"), py::arg("output"),
        py::arg("keys"), py::arg("allow_partial"), py::arg("force"));
  m.attr("run_keys") = RunKeys();
  m.def("_model", &Model, py::arg("numbers"), py::arg("solver"), py::arg("error_estimator"),
        py::arg("ode45_defaults"), py::arg("output"));
  m.def("set_log_level", &SetLogLevelByName, py::arg("level"),
        "Shows the library's messages at `level` and above: debug, info, warning, error or off");
}
