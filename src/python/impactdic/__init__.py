"""impactdic from Python: subset DIC of numpy arrays or image files (docs/python.md).

    import impactdic
    r = impactdic.correlate(reference, deformed, dic={"subset_size": 25})
    r.u, r.v          # [frames, subsets] displacements [px], row 0 the reference
    r.status_name(r.status)

The options are the scene file's keys (docs/scene_keys.md) of the dic and preprocess sections and
inputs.fps / inputs.calibration, nested (dic={"subset_size": 25}) or dotted
(**{"dic.subset_size": 25}), read by the same parsers as the scene file and the command line.
The computation is the library's (the one `impactdic correlate` runs), without the GIL.
"""

import os as _os

import numpy as _np

# OpenCV's image and video plugins (io/opencv_codecs.h: TIFF, JPEG, video) installed beside the
# module, unless their variables name others; in the build tree the library finds them itself.
for _variable, _plugin in (("IMPACTDIC_OPENCV_CODECS", "libimpactdic_opencv_codecs.so"),
                           ("IMPACTDIC_OPENCV_VIDEO", "libimpactdic_opencv_video.so")):
    _path = _os.path.join(_os.path.dirname(_os.path.abspath(__file__)), _plugin)
    if not _os.environ.get(_variable) and _os.path.exists(_path):
        _os.environ[_variable] = _path

from ._impactdic import (  # noqa: F401 (the package's interface)
    Error,
    NothingUsableError,
    __version__,
    _correlate,
    _model,
    _read_h5,
    _run,
    correlate_keys,
    run_keys,
    set_log_level,
)

__all__ = ["correlate", "CorrelationResult", "run", "model", "read_results", "Results", "Group", "Error",
           "NothingUsableError", "set_log_level", "correlate_keys", "run_keys", "__version__"]

# The library's progress and notes stay off the notebook unless asked for (set_log_level("info")).
set_log_level("warning")

_SECTIONS = ("dic", "preprocess", "inputs")


def _key_text(value):
    """A Python value as the text of a scene key's value (parsed as in a scene file)."""
    if isinstance(value, (bool, _np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (list, tuple, _np.ndarray)):  # dic.roi: X0,Y0,X1,Y1
        return ",".join(_key_text(v) for v in value)
    if isinstance(value, (float, _np.floating)):
        return repr(float(value))
    if isinstance(value, _np.integer):
        return str(int(value))
    if isinstance(value, _os.PathLike):
        return _os.fspath(value)
    return str(value)


def _flatten(prefix, value, out):
    if isinstance(value, dict):
        for name, v in value.items():
            _flatten(prefix + "." + str(name), v, out)
    else:
        out.append((prefix, _key_text(value)))


def _scene_keys(options, sections=_SECTIONS):
    """The keyword options as (scene key, value text) pairs, in the order given.

    `threads` is dic.threads (the command line's --threads); a section given as a dict is
    expanded (dic={"subset_size": 25} is dic.subset_size)."""
    keys = []
    for name, value in options.items():
        if name == "threads":
            name = "dic.threads"
        if name in sections and not isinstance(value, dict):
            raise ValueError(f"{name}: invalid value (got {value!r}); expected a dict of its keys")
        _flatten(name, value, keys)
    seen = set()
    for key, _ in keys:
        if key in seen:
            raise ValueError(f"{key}: given twice; expected it once")
        seen.add(key)
    return keys


def _is_path(x):
    return isinstance(x, (str, bytes, _os.PathLike))


def _frames(reference, deformed):
    """The frames argument of _correlate: one inputs.frames setting, image files, or arrays."""
    if deformed is None:
        if _is_path(reference):  # A folder, glob, video or camera file.
            return _os.fsdecode(reference)
        if isinstance(reference, _np.ndarray):
            if reference.ndim != 3:
                raise ValueError(
                    f"reference: invalid value (got a {reference.ndim}-D array and no deformed "
                    "frames); expected a 3-D array (frames, rows, columns) of a sequence")
            return list(reference)
        return list(reference)  # A list of images or files, the first the reference.
    if isinstance(deformed, (list, tuple)) or (
            isinstance(deformed, _np.ndarray) and deformed.ndim == 3):
        rest = list(deformed)
    else:
        rest = [deformed]
    frames = [reference] + rest
    return [_os.fsdecode(f) if _is_path(f) else f for f in frames]


class CorrelationResult:
    """The correlation's results, as `impactdic correlate -o X.h5` writes its /dic group.

    Row 0 of the [frames, subsets] arrays is the reference (zero displacement where valid).
      x, y             subset centres in the reference [px] (subsets)
      u, v             accumulated displacement [px], NaN where the subset failed
      sigma_u, sigma_v estimated standard deviation of u, v [px]
      zncc, iterations, status (codes; status_names maps them to names, valid: status == 0)
      frame            row -> index in the input sequence; frame_number the source's numbers;
                       time_s the source's time stamps [s] (a camera file's, or the time_s
                       given with arrays; None when there are none)
      summary          the correlation's summary (valid fraction, status counts, reports)
      attributes       the /dic group's attributes (options, preprocessing)
    """

    def __init__(self, table, summary):
        self._table = table
        for name in ("x", "y", "u", "v", "sigma_u", "sigma_v", "sigma", "zncc", "status",
                     "iterations", "frame", "reference_frame", "frame_number", "time_s",
                     "dudx_warp", "dudy_warp", "dvdx_warp", "dvdy_warp"):
            setattr(self, name, table[name])
        self.attributes = table["attributes"]
        self.summary = summary
        self.status_names = {}
        for item in table["status_codes"].split(","):
            if "=" in item:
                code, name = item.split("=", 1)
                self.status_names[int(code)] = name.strip()

    @property
    def valid(self):
        """[frames, subsets]: True where the subset converged (status 0, finite u and v)."""
        return (self.status == 0) & _np.isfinite(self.u) & _np.isfinite(self.v)

    def status_name(self, status):
        """The name of a status code, or an array of names for an array of codes."""
        if _np.ndim(status) == 0:
            return self.status_names[int(status)]
        return _np.vectorize(self.status_names.__getitem__, otypes=[object])(status)

    def __repr__(self):
        return (f"<impactdic.CorrelationResult: {self.u.shape[0]} frames x {self.u.shape[1]} "
                f"subsets, {100 * self.summary['valid_fraction']:.1f} % valid>")


def correlate(reference, deformed=None, *, allow_partial=False, time_s=None, progress=None,
              **options):
    """Subset DIC of `deformed` against `reference`; the CorrelationResult.

    reference, deformed: 2-D numpy arrays (grey: uint8, or uint16 with any bit depth of the data,
      as image files hold them; or float32 / float64 grey levels as they are, any range, finite),
      image files, or lists of either; deformed may be a 3-D array (frames, rows, columns) or a
      list. Or `reference` alone: a 3-D array or list (the first frame the reference), or a
      folder, glob, video or camera file (the scene's inputs.frames). Every array of one call
      has the reference's shape and dtype.
    options: scene keys (dic={"subset_size": 25}, **{"dic.subset_size": 25}, preprocess={...},
      inputs={"fps": 5000}); threads=N is dic.threads (0: all cores).
    allow_partial: return results with no valid subset instead of raising NothingUsableError.
    time_s: the time stamps [s] of frames given as arrays, one per frame (the result's time_s).
    progress: a callable, called as progress(done, total) after each deformed frame (done of the
      total deformed frames); an exception it raises stops the correlation and is raised here.

    Ctrl-C (KeyboardInterrupt) stops the correlation within a fraction of a second.

    Raises ValueError for a bad option or input (the scene file's message), OSError for files,
    NothingUsableError when no subset is valid in any deformed frame.
    """
    times = [] if time_s is None else [float(t) for t in time_s]
    if progress is not None and not callable(progress):
        raise ValueError(f"progress: invalid value (got {progress!r}); expected a callable "
                         "progress(done, total) or None")
    table, summary = _correlate(_frames(reference, deformed), _scene_keys(options),
                                bool(allow_partial), times, progress)
    return CorrelationResult(table, summary)


class Group:
    """A group of an HDF5 file: its datasets as numpy arrays and its subgroups, as attributes
    (`group.u_px`, `group.added_mass_daq.t_s`); `attrs` the group's own attributes; `units`,
    `descriptions` and `dataset_attrs` the datasets' attributes by name."""

    def __init__(self, path):
        self.path = path
        self.attrs = {}
        self.units = {}
        self.descriptions = {}
        self.dataset_attrs = {}
        self.datasets = []  # Names of the datasets, in the file's order.
        self.groups = []  # Names of the subgroups.

    def __getitem__(self, name):
        node = self
        for part in name.strip("/").split("/"):
            node = getattr(node, part)
        return node

    def __repr__(self):
        return (f"<impactdic.Group {self.path}: datasets {', '.join(self.datasets) or '-'}; "
                f"groups {', '.join(self.groups) or '-'}>")


class Results(Group):
    """A results file read whole (read_results): the root group, with the file's name in `file`."""

    def __init__(self, file):
        super().__init__("/")
        self.file = file

    def to_xarray(self):
        """The per-frame, per-subset fields as an xarray.Dataset (python3-xarray).

        Dimensions (frame, subset): every [F x N] dataset of /dic, /kinematics and /strain, named
        GROUP_NAME (dic_u_px, kinematics_vx_mm_s); coordinates x_px, y_px (and x_mm, y_mm with
        kinematics) per subset, frame_number and t_ms (time since the impact, with /time) per
        frame; each variable's units and description in its attributes."""
        import xarray

        dic = self.dic
        frames, subsets = dic.u_px.shape
        coords = {"x_px": ("subset", dic.x_px, {"units": "px"}),
                  "y_px": ("subset", dic.y_px, {"units": "px"})}
        if "kinematics" in self.groups and "x_mm" in self.kinematics.datasets:
            coords["x_mm"] = ("subset", self.kinematics.x_mm, {"units": "mm"})
            coords["y_mm"] = ("subset", self.kinematics.y_mm, {"units": "mm"})
        if "frame_number" in dic.datasets:
            coords["frame_number"] = ("frame", dic.frame_number, {"units": "1"})
        if "time" in self.groups and "t_ms" in self.time.datasets:
            coords["t_ms"] = ("frame", self.time.t_ms,
                              {"units": "ms", "description": self.time.descriptions.get("t_ms", "")})
        variables = {}
        for group_name in ("dic", "kinematics", "strain"):
            if group_name not in self.groups:
                continue
            group = getattr(self, group_name)
            for name in group.datasets:
                data = getattr(group, name)
                if data.shape != (frames, subsets):
                    continue
                attrs = {"units": group.units.get(name, ""),
                         "description": group.descriptions.get(name, "")}
                variables[f"{group_name}_{name}"] = (("frame", "subset"), data, attrs)
        attrs = {k: v for k, v in self.attrs.items()}
        attrs["file"] = self.file
        return xarray.Dataset(variables, coords=coords, attrs=attrs)

    def __repr__(self):
        return f"<impactdic.Results {self.file}: groups {', '.join(self.groups)}>"


def read_results(path):
    """Every group and numeric dataset of a results file (results.h5 of `impactdic run`, or the
    output of `impactdic correlate -o X.h5`) as a Results: groups as attributes, datasets as numpy
    arrays (float32 and float64 as stored, integers as int32 up to int32 and uint16, wider ones as
    float64), their units and descriptions in each group's
    `units` and `descriptions`. Text datasets are left out (their paths in `skipped`).
    OSError when the file is missing or not HDF5."""
    raw = _read_h5(_os.fspath(path))
    root = Results(_os.fspath(path))
    root.skipped = list(raw["skipped"])
    nodes = {"/": root}

    def group_of(group_path):
        if group_path not in nodes:
            parent_path, name = group_path.rsplit("/", 1)
            parent = group_of(parent_path or "/")
            node = Group(group_path)
            setattr(parent, name, node)
            parent.groups.append(name)
            nodes[group_path] = node
        return nodes[group_path]

    for group_path, attrs in sorted(raw["groups"].items()):
        group_of(group_path).attrs = dict(attrs)
    for path, (array, attrs) in raw["datasets"].items():
        parent_path, name = path.rsplit("/", 1)
        group = group_of(parent_path or "/")
        setattr(group, name, array)
        group.datasets.append(name)
        group.dataset_attrs[name] = dict(attrs)
        group.units[name] = attrs.get("units", "")
        group.descriptions[name] = attrs.get("description", "")
    return root


_RUN_SECTIONS = ("test", "preprocess", "dic", "sensor", "momentum", "model", "strain", "outputs")


def run(scene, output=None, *, allow_partial=False, force=False, **overrides):
    """Runs a scene as `impactdic run` does; (summary, results).

    summary: a dict with summary.json's keys (the same values as the file).
    results: the results.h5 it wrote, as read_results gives it (None when the scene writes no
      HDF5 file: outputs.hdf5 false).

    scene: a scene file, or a dict of its sections (relative paths against the working folder).
    output: the output folder (default: the scene's outputs.folder).
    overrides: scene keys of the test, preprocess, dic, sensor, momentum, model, strain and
      outputs sections (dic={"subset_size": 25}, **{"outputs.figures": False}); threads=N is
      dic.threads.
    allow_partial, force: as the command's --allow-partial and --force.
    Raises ValueError for a bad key or value, OSError for files, NothingUsableError when a stage
    produced nothing usable (unless allow_partial); Ctrl-C (KeyboardInterrupt) stops the run, its
    output folder as it was.
    """
    import json

    if isinstance(scene, dict):
        scene_file, scene_text = "", json.dumps(scene)
    else:
        scene_file, scene_text = _os.fspath(scene), ""
    keys = _scene_keys(overrides, _RUN_SECTIONS)
    summary_text, outputs = _run(scene_file, scene_text,
                                 "" if output is None else _os.fspath(output), keys,
                                 bool(allow_partial), bool(force))
    summary = json.loads(summary_text)
    results_file = next((f for f in outputs if _os.path.basename(f) == "results.h5"), None)
    return summary, (None if results_file is None else read_results(results_file))


def model(output=None, **keys):
    """The added-mass impact model (Eq. 9, docs/model.md) of one test, as `impactdic model
    --format json`: its summary (a dict: the solve's figures and the solver's report).

    keys: the scene's test and model keys, nested (test={"mass_kg": 10, "width_m": 0.15,
      "drop_height_m": 0.7}) or dotted (**{"model.K": 2.0e6}); test.mass_kg, test.width_m and one
      of test.drop_height_m / test.impact_velocity_m_s are required; model.solver and
      model.error_estimator take their names, model.ode45_defaults True or False.
    output: also write the time series (.csv or .h5; read_results reads the .h5).
    Raises ValueError for a bad key or value, impactdic.Error when the solve does not reach the
    end of the motion.
    """
    import json

    numbers, texts, ode45_defaults = {}, {"model.solver": "", "model.error_estimator": ""}, False
    for key, text in _scene_keys(keys, ("test", "model")):
        value = keys.get(key)
        if value is None:  # Given nested: find the value again.
            section, name = key.split(".", 1)
            value = keys[section][name]
        if key in texts:
            texts[key] = str(value)
        elif key == "model.ode45_defaults":
            if not isinstance(value, (bool, _np.bool_)):
                raise ValueError(f"{key}: invalid value (got {value!r}); expected True or False")
            ode45_defaults = bool(value)
        else:
            try:
                numbers[key] = float(value)
            except (TypeError, ValueError):
                raise ValueError(
                    f"{key}: invalid value (got {value!r}); expected a number") from None
    summary = _model(numbers, texts["model.solver"], texts["model.error_estimator"],
                     ode45_defaults, "" if output is None else _os.fspath(output))
    return json.loads(summary)
