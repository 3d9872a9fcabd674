#include "impactdic/render/render_results.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <system_error>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/log.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/io/results_io.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/model/model_results.h"
#include "impactdic/momentum/momentum_results.h"
#include "impactdic/render/figures.h"
#include "impactdic/render/wave_figures.h"
#include "impactdic/sensor/sensor_results.h"
#include "impactdic/sensor/wave_results.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace L = results_layout;

void RenderResultsOptions::Check() const {
  CheckValue(animation || !png_frames, "png_frames", "without the animation",
             "PNG frames only together with the animation");
  plot.Check();
  animation_options.Check();
  snapshot_overlay.Check();
  strain_overlay.Check();
}

std::string RenderResultsSummary::BriefReport() const {
  std::string text = "render: " + std::to_string(written.size()) + " file(s) written, " +
                     std::to_string(skipped.size()) + " skipped";
  if (has_animation) {
    text += "; animation " + animation.codec + " " + std::to_string(animation.frames) + " frames";
    if (animation.fell_back) text += " (MJPG fallback)";
  }
  if (has_strain_animation) {
    text += "; strain animation " + strain_animation.codec + " " +
            std::to_string(strain_animation.frames) + " frames";
    if (strain_animation.fell_back) text += " (MJPG fallback)";
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, " in %.2f s", wall_s);
  return text + buf;
}

std::string RenderResultsSummary::FullReport() const {
  std::string text = BriefReport() + "\n";
  for (const auto& w : written) text += "  wrote   " + w + "\n";
  for (const auto& s : skipped) text += "  skipped " + s + "\n";
  if (has_animation) text += "  " + animation.BriefReport() + "\n";
  if (has_strain_animation) text += "  " + strain_animation.BriefReport() + "\n";
  return text;
}

namespace {

std::string Dims2Text(const Dims& d) {
  std::string t = "[";
  for (std::size_t i = 0; i < d.size(); ++i) t += (i ? " x " : "") + std::to_string(d[i]);
  return t + "]";
}

[[noreturn]] void ShapeError(const H5Reader&, const std::string& path, const std::string& file,
                             const Dims& found, const std::string& expected) {
  throw Error(ErrorKind::kFileFormat, "dataset " + path, "shape " + Dims2Text(found), expected)
      .WithFile(file);
}

double NumberAttribute(const H5Reader& r, const std::string& object, const std::string& name) {
  return r.HasAttribute(object, name) ? r.ReadNumberAttribute(object, name) : kNaN;
}

std::vector<double> ReadIf(const H5Reader& r, const std::string& path) {
  return r.Exists(path) ? r.ReadDouble(path) : std::vector<double>{};
}

std::string FormatMs(double t_s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f ms", 1e3 * t_s);
  return buf;
}

}  // namespace

namespace {

// Error kFileFormat naming the first of `paths` the file lacks, as part of `what`.
void RequireDatasets(const H5Reader& r, const std::vector<const char*>& paths,
                     const std::string& what) {
  std::string expected = what + " (";
  for (std::size_t i = 0; i < paths.size(); ++i) {
    expected += i ? ", " : "";
    expected += paths[i];
  }
  expected += ")";
  for (const char* path : paths) {
    if (!r.Exists(path))
      throw Error(ErrorKind::kFileFormat, "dataset " + std::string(path), "missing", expected);
  }
}

// The times, subset positions (moving with /dic/u_px, v_px when stored) and scale of a field whose
// [frames x subsets] dataset `field` has shape `field_dims`.
void ReadFieldGeometry(const H5Reader& r, const char* field, const Dims& field_dims,
                       FieldSequence* seq) {
  const std::string
      file;  // The file name for messages is not exposed by H5Reader; the callers add it.
  Dims dt, dx, dy;
  seq->time_ms = r.ReadDouble(L::kTimeMs, &dt);
  const std::vector<double> x = r.ReadDouble(L::kDicX, &dx);
  const std::vector<double> y = r.ReadDouble(L::kDicY, &dy);
  if (dt.size() != 1) ShapeError(r, L::kTimeMs, file, dt, "[frames]");
  const std::size_t f = dt[0];
  if (field_dims.size() != 2 || field_dims[0] != f) {
    ShapeError(r, field, file, field_dims, "[frames x subsets] with frames = " + std::to_string(f));
  }
  const std::size_t n = field_dims[1];
  const bool fixed = dx.size() == 1 && dx[0] == n;
  const bool moving = dx.size() == 2 && dx[0] == f && dx[1] == n;
  if (!fixed && !moving) {
    ShapeError(r, L::kDicX, file, dx,
               "[subsets] or [frames x subsets] matching " + std::string(field) + " " +
                   Dims2Text(field_dims));
  }
  if (dy != dx) ShapeError(r, L::kDicY, file, dy, "the shape of " + std::string(L::kDicX));
  seq->num_subsets = n;
  seq->x_px = x;
  seq->y_px = y;
  // Lagrangian positions from the accumulated displacement, when stored (read by io
  // ReadDicResults, whatever the layout version).
  if (fixed && r.Exists(L::kDicU) && r.Exists(L::kDicV)) {
    // The displacements only, turned into positions where they are read.
    DicResultsTable dic = ReadDicResults(r, file, DicFields::kDisplacements);
    if (dic.rows != f || dic.subsets != n) {
      ShapeError(r, L::kDicU, file, Dims{dic.rows, dic.subsets},
                 "[frames x subsets] = " + Dims2Text(field_dims));
    }
    seq->x_px = std::move(dic.u_px);
    seq->y_px = std::move(dic.v_px);
    for (std::size_t i = 0; i < f; ++i) {
      for (std::size_t s = 0; s < n; ++s) {
        seq->x_px[i * n + s] = x[s] + seq->x_px[i * n + s];
        seq->y_px[i * n + s] = y[s] + seq->y_px[i * n + s];
      }
    }
  }
  if (r.Exists(L::kKinematicsGroup))
    seq->mm_per_px = NumberAttribute(r, L::kKinematicsGroup, L::kMmPerPxAttr);
}

// The camera frames of /frames/images into seq->frames, scaled to the full frame size; returns
// the rows of /time they belong to (every row, or a preview's).
std::vector<std::size_t> ReadFieldFrames(const H5Reader& r, FieldSequence* seq) {
  const std::string file;
  const std::size_t f = seq->time_ms.size();
  Dims di;
  const std::vector<float> pixels = r.ReadFloat(L::kFrameImages, &di);
  // A preview (`run` outputs.frames: preview) stores some rows, downsampled.
  std::vector<std::size_t> rows;
  if (r.Exists(L::kFrameRows)) {
    for (double row : r.ReadDouble(L::kFrameRows)) {
      if (!(row >= 0 && row < static_cast<double>(f) && row == std::floor(row)))
        ShapeError(r, L::kFrameRows, file, Dims{f}, "row indices below " + std::to_string(f));
      rows.push_back(static_cast<std::size_t>(row));
    }
  } else {
    for (std::size_t i = 0; i < f; ++i) rows.push_back(i);
  }
  if (di.size() != 3 || di[0] != rows.size() || di[1] == 0 || di[2] == 0) {
    ShapeError(r, L::kFrameImages, file, di,
               "[frames x rows x cols] with frames = " + std::to_string(rows.size()));
  }
  float max_value = 0.f;
  bool integral = true;
  for (float p : pixels) {
    if (std::isfinite(p)) max_value = std::max(max_value, p);
    integral = integral && std::isfinite(p) && p >= 0 && p == std::floor(p);
  }
  double bit_depth = NumberAttribute(r, L::kFramesGroup, L::kBitDepthAttr);
  if (std::isnan(bit_depth) && integral)
    bit_depth = max_value <= 255.f ? 8 : max_value <= 65535.f ? 16 : 0;
  const int rows_px = static_cast<int>(di[1]), cols = static_cast<int>(di[2]);
  const std::size_t per_frame = di[1] * di[2];
  const double full_w = NumberAttribute(r, L::kFramesGroup, L::kFrameWidthAttr);
  const double full_h = NumberAttribute(r, L::kFramesGroup, L::kFrameHeightAttr);
  const cv::Size full = std::isfinite(full_w) && std::isfinite(full_h) && full_w >= 1 && full_h >= 1
                            ? cv::Size(static_cast<int>(full_w), static_cast<int>(full_h))
                            : cv::Size(cols, rows_px);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    cv::Mat as_float(rows_px, cols, CV_32F, const_cast<float*>(pixels.data() + i * per_frame));
    cv::Mat frame;
    if (bit_depth == 8) {
      as_float.convertTo(frame, CV_8U);
    } else if (bit_depth == 16) {
      as_float.convertTo(frame, CV_16U);
    } else {
      frame = as_float.clone();
    }
    if (frame.size() != full) cv::resize(frame, frame, full, 0, 0, cv::INTER_LINEAR);
    seq->frames.push_back(frame);
  }
  return rows;
}

}  // namespace

VelocityFieldSequence ReadVelocityFieldSequence(const H5Reader& r, bool require_frames,
                                                bool read_frames) {
  // The file name for messages is not exposed by H5Reader; the callers add it.
  const std::string file;
  VelocityFieldSequence seq;
  RequireDatasets(r, {L::kTimeMs, L::kDicX, L::kDicY, L::kVx, L::kVy}, "the velocity field data");
  Dims dvx, dvy;
  seq.vx_mm_s = r.ReadDouble(L::kVx, &dvx);
  seq.vy_mm_s = r.ReadDouble(L::kVy, &dvy);
  ReadFieldGeometry(r, L::kVx, dvx, &seq);
  if (dvy != dvx) ShapeError(r, L::kVy, file, dvy, "the shape of " + std::string(L::kVx));
  if (r.HasAttribute(L::kKinematicsGroup, L::kVyDirectionAttr)) {
    const std::string dir = r.ReadStringAttribute(L::kKinematicsGroup, L::kVyDirectionAttr);
    if (dir != "up" && dir != "down") {
      throw Error(ErrorKind::kFileFormat,
                  "attribute " + std::string(L::kVyDirectionAttr) + " of " + L::kKinematicsGroup,
                  dir, "up or down");
    }
    seq.vy_positive_down = dir == "down";
  }
  if (!read_frames) return seq;
  if (!r.Exists(L::kFrameImages)) {
    if (require_frames) {
      throw Error(ErrorKind::kFileFormat, "dataset " + std::string(L::kFrameImages), "missing",
                  "the camera frames [frames x rows x cols]");
    }
    return seq;
  }
  const std::vector<std::size_t> rows = ReadFieldFrames(r, &seq);
  if (rows.size() != seq.time_ms.size()) seq.KeepRows(rows, {&seq.vx_mm_s, &seq.vy_mm_s});
  return seq;
}

StrainFieldSequence ReadStrainFieldSequence(const H5Reader& r, bool read_frames) {
  const std::string file;
  StrainFieldSequence seq;
  RequireDatasets(r, {L::kTimeMs, L::kDicX, L::kDicY, L::kStrainEpsV, L::kStrainGammaMax},
                  "the strain field data");
  Dims de, dg;
  seq.eps_v = r.ReadDouble(L::kStrainEpsV, &de);
  seq.gamma_max = r.ReadDouble(L::kStrainGammaMax, &dg);
  ReadFieldGeometry(r, L::kStrainEpsV, de, &seq);
  if (dg != de) {
    ShapeError(r, L::kStrainGammaMax, file, dg, "the shape of " + std::string(L::kStrainEpsV));
  }
  if (r.Exists(L::kStrainShearBand)) {
    Dims db;
    seq.shear_band = r.ReadDouble(L::kStrainShearBand, &db);
    if (db != de) {
      ShapeError(r, L::kStrainShearBand, file, db, "the shape of " + std::string(L::kStrainEpsV));
    }
  }
  const double full_w = NumberAttribute(r, L::kFramesGroup, L::kFrameWidthAttr);
  const double full_h = NumberAttribute(r, L::kFramesGroup, L::kFrameHeightAttr);
  if (full_w >= 1 && full_h >= 1)
    seq.plain_size = cv::Size(static_cast<int>(full_w), static_cast<int>(full_h));
  if (!read_frames || !r.Exists(L::kFrameImages)) return seq;
  const std::vector<std::size_t> rows = ReadFieldFrames(r, &seq);
  if (rows.size() != seq.time_ms.size()) {
    std::vector<std::vector<double>*> fields = {&seq.eps_v, &seq.gamma_max};
    if (!seq.shear_band.empty()) fields.push_back(&seq.shear_band);
    seq.KeepRows(rows, fields);
  }
  return seq;
}

namespace {

// The figures of a results file drawn into a folder holding another results file would not match
// it: refuse (the folder of RESULTS itself, or one without a results file, is fine).
void RefuseOtherResults(const std::string& out_dir, const std::string& results_path) {
  const fs::path other = fs::path(out_dir) / L::kResultsFile;
  std::error_code ec;
  if (!fs::exists(other, ec) || fs::equivalent(other, results_path, ec)) return;
  throw Error(ErrorKind::kInvalidValue, "output folder",
              "a folder holding another results file (" + other.string() + ")",
              "the folder of " + results_path +
                  " or one without a results.h5 (the figures would not match it)")
      .WithFile(out_dir);
}

// The names of the outputs drawn from the camera frames.
struct FrameOutputNames {
  const char* snapshot = L::kVelocitySnapshotPng;
  const char* animation = L::kAnimationName;
  const char* animation_avi = L::kAnimationAviName;
  const char* png_frames = L::kPngFramesDir;
  const char* strain_te = L::kStrainTePng;
  const char* strain_end = L::kStrainEndPng;
  const char* strain_animation = L::kStrainAnimationName;
  const char* strain_animation_avi = L::kStrainAnimationAviName;
  const char* strain_png_frames = L::kStrainPngFramesDir;
  bool preview = false;
};

// The preview names (RenderResultsOptions::frame_loader's comment) when `out_dir` is the folder of
// the results file and that stores a preview of the frames; the usual names otherwise.
FrameOutputNames FrameOutputsOf(const H5Reader& r, const std::string& results_path,
                                const std::string& out_dir, const RenderResultsOptions& options) {
  std::error_code ec;
  if (options.frame_loader || !r.Exists(L::kFrameRows) || !r.Exists(L::kTimeMs) ||
      !fs::equivalent(fs::path(out_dir) / L::kResultsFile, results_path, ec)) {
    return {};
  }
  const std::size_t stored = r.Dimensions(L::kFrameRows)[0], analysed = r.Dimensions(L::kTimeMs)[0];
  const double downsample = NumberAttribute(r, L::kFramesGroup, L::kDownsampleAttr);
  if (stored >= analysed && !(downsample > 1)) return {};
  LogInfo(
      "render: {} stores a preview of the frames ({} of {}, downsampled {}x): the velocity "
      "snapshot and animation drawn from it are {} and {}; the run's {} and {} (every frame, "
      "full size) are kept",
      results_path, stored, analysed, std::isfinite(downsample) ? downsample : 1.0,
      L::kPreviewSnapshotPng, L::kPreviewAnimationName, L::kVelocitySnapshotPng, L::kAnimationName);
  return {L::kPreviewSnapshotPng,         L::kPreviewAnimationName,
          L::kPreviewAnimationAviName,    L::kPreviewPngFramesDir,
          L::kStrainTePreviewPng,         L::kStrainEndPreviewPng,
          L::kStrainPreviewAnimationName, L::kStrainPreviewAnimationAviName,
          L::kStrainPreviewPngFramesDir,  true};
}

// A render's outputs are one generation of the folder; it keeps the other entries of the previous
// generation (a run's results.h5 and summaries, and its frame-based outputs when `names` are the
// preview's) and replaces every figure and animation of its names.
OutputGenerationOptions RenderGenerationOptions(const FrameOutputNames& names, bool force) {
  OutputGenerationOptions o;
  o.command = "impactdic render";
  for (const char* name :
       {L::kMomentumPng, L::kDecelerationPng, L::kAddedMassPng, names.snapshot, names.animation,
        names.animation_avi, names.png_frames, names.strain_te, names.strain_end,
        names.strain_animation, names.strain_animation_avi, names.strain_png_frames})
    o.own_names.emplace_back(name);
  for (const char* name : L::kRunOnlyOutputNames) o.known_names.emplace_back(name);
  if (names.preview) {
    for (const char* name :
         {L::kVelocitySnapshotPng, L::kAnimationName, L::kAnimationAviName, L::kPngFramesDir,
          L::kStrainTePng, L::kStrainEndPng, L::kStrainAnimationName, L::kStrainAnimationAviName,
          L::kStrainPngFramesDir})
      o.known_names.emplace_back(name);
  }
  o.keep_other_entries = true;
  o.replaces_kinds = {"run"};  // Its figures, beside the run's results.h5 (RefuseOtherResults).
  o.force = force;
  return o;
}

void RenderInto(const H5Reader& reader, const std::string& results_path, const std::string& out_dir,
                const RenderResultsOptions& options, const FrameOutputNames& names,
                RenderResultsSummary& summary);

}  // namespace

RenderResultsSummary RenderResults(const std::string& results_path,
                                   const RenderResultsOptions& options) {
  options.Check();
  std::error_code ec;
  if (!fs::is_regular_file(results_path, ec))
    throw Error(ErrorKind::kFileNotFound, "results file", results_path,
                "an existing results .h5 file");
  const H5Reader reader(results_path);
  return RenderResults(reader, results_path, options);
}

RenderResultsSummary RenderResults(const H5Reader& reader, const std::string& results_path,
                                   const RenderResultsOptions& options) {
  WallTimer wall;
  options.Check();
  RenderResultsSummary summary;
  std::string out_dir = options.output_dir;
  if (out_dir.empty()) {
    out_dir = fs::path(results_path).parent_path().string();
    if (out_dir.empty()) out_dir = ".";
  }
  if (options.new_generation) {
    RefuseOtherResults(out_dir, results_path);
    const FrameOutputNames names = FrameOutputsOf(reader, results_path, out_dir, options);
    OutputGeneration generation(out_dir, RenderGenerationOptions(names, options.force));
    RenderInto(reader, results_path, generation.staging_folder(), options, names, summary);
    generation.Commit();
    for (auto& w : summary.written) w = generation.FinalPath(w);
    summary.animation.path = generation.FinalPath(summary.animation.path);
    summary.strain_animation.path = generation.FinalPath(summary.strain_animation.path);
  } else {
    std::error_code ec;
    MakeFolders(out_dir, ec);
    if (!fs::is_directory(out_dir, ec)) {
      throw Error(ErrorKind::kIo, "output folder", OutputPathForMessages(out_dir),
                  "a folder that exists or can be created");
    }
    if (access(out_dir.c_str(), W_OK) != 0) {
      throw Error(ErrorKind::kIo, "output folder",
                  OutputPathForMessages(out_dir) + " is not writable", "a writable folder");
    }
    RenderInto(reader, results_path, out_dir, options, FrameOutputNames{}, summary);
  }
  summary.wall_s = wall.ElapsedSeconds();
  LogInfo("{}", summary.BriefReport());
  return summary;
}

namespace {

// The stored frame nearest t_e and the title of `what` drawn there: "at the end of the peak stage
// (t_e = ...)" when the frame's time reads as t_e, else the frame's own time and that it is the
// frame nearest t_e (a preview stores every few frames only, so the nearest may be far from t_e).
std::size_t FrameAtTe(const FieldSequence& seq, double t_e_s, const std::string& what,
                      std::string* title) {
  const std::size_t frame = FrameNearestTime(seq, 1e3 * t_e_s);
  const std::string at_te = FormatMs(t_e_s);
  const std::string at_frame =
      frame < seq.time_ms.size() ? FormatMs(1e-3 * seq.time_ms[frame]) : at_te;
  if (at_frame == at_te) {
    *title = what + " at the end of the peak stage (t_e = " + at_te + ")";
  } else {
    *title = what + " at t = " + at_frame + ", the stored frame nearest t_e = " + at_te;
    LogInfo("render: no stored frame at t_e = {}: the {} is drawn at the nearest, t = {}", at_te,
            ToLower(what), at_frame);
  }
  return frame;
}

// The frame of the velocity snapshot: the one nearest t_e, else (no t_e) the one of the largest
// mean speed; *title says which.
std::size_t SnapshotFrame(const VelocityFieldSequence& seq, double t_e_s, std::string* title) {
  if (std::isfinite(t_e_s)) return FrameAtTe(seq, t_e_s, "Velocity field", title);
  std::size_t frame = 0;
  double best = -1;
  for (std::size_t i = 0; i < seq.num_frames(); ++i) {
    double sum = 0;
    std::size_t count = 0;
    for (std::size_t s = 0; s < seq.num_subsets; ++s) {
      const double v =
          std::hypot(seq.vx_mm_s[i * seq.num_subsets + s], seq.vy_mm_s[i * seq.num_subsets + s]);
      if (std::isfinite(v)) sum += v, ++count;
    }
    if (count > 0 && sum / count > best) best = sum / count, frame = i;
  }
  LogInfo(
      "render: no {} attribute on {}; the snapshot shows the frame of the largest mean speed ({})",
      L::kTeAttr, L::kMomentumGroup, frame);
  *title = "Velocity field at the largest mean speed";
  return frame;
}

// The velocity snapshot and the animation (or why they are skipped).
void DrawVelocityField(const H5Reader& reader, bool has_field, double t_e_s,
                       const RenderResultsOptions& options, const std::string& out_dir,
                       const FrameOutputNames& names, RenderResultsSummary& summary) {
  auto out = [&](const char* name) { return (fs::path(out_dir) / name).string(); };
  auto skip = [&](const std::string& output, const std::string& reason) {
    LogInfo("render: skipping {}: {}", output, reason);
    summary.skipped.push_back(output + ": " + reason);
  };
  if (!has_field) {
    const std::string reason = std::string("no velocity field (") + L::kTimeMs + ", " + L::kDicX +
                               ", " + L::kDicY + ", " + L::kVx + ", " + L::kVy + ")";
    if (options.snapshot) skip(names.snapshot, reason);
    if (options.animation) skip(names.animation, reason);
  } else {
    const bool loaded = static_cast<bool>(options.frame_loader);
    VelocityFieldSequence seq =
        ReadVelocityFieldSequence(reader, /*require_frames=*/false, /*read_frames=*/!loaded);
    if (loaded) {
      seq.frame_count = seq.time_ms.size();
      seq.load_frame = options.frame_loader;
    }
    if (!seq.has_images()) {
      const std::string reason = std::string("no camera frames (") + L::kFrameImages + ")";
      if (options.snapshot) skip(names.snapshot, reason);
      if (options.animation) skip(names.animation, reason);
    } else {
      if (options.snapshot) {
        std::string title;
        const std::size_t frame = SnapshotFrame(seq, t_e_s, &title);
        RenderVelocitySnapshot(seq, frame, out(names.snapshot), options.snapshot_overlay, title);
        summary.written.push_back(out(names.snapshot));
      }
      if (options.animation) {
        AnimationOptions a = options.animation_options;
        if (options.png_frames) a.png_frames_dir = out(names.png_frames);
        summary.animation = WriteVelocityAnimation(seq, out(names.animation), a);
        summary.has_animation = true;
        summary.written.push_back(summary.animation.path);
      }
    }
  }
}

// The wave figures, when the file has /wave (else nothing: a run without base channels asks for
// none); each figure whose data is missing is skipped with the reason.
void DrawWaveFigures(const H5Reader& reader, const std::string& results_path,
                     const RenderResultsOptions& options, const std::string& out_dir,
                     RenderResultsSummary& summary) {
  if (!reader.Exists(L::kWaveGroup)) return;
  auto out = [&](const char* name) { return (fs::path(out_dir) / name).string(); };
  auto skip = [&](const char* output, const std::string& reason) {
    LogInfo("render: skipping {}: {}", output, reason);
    summary.skipped.push_back(std::string(output) + ": " + reason);
  };
  const std::string file = OutputPathForMessages(results_path);
  const WaveResult wave = ReadWaveResults(reader, file);
  if (!wave.front.space_time.time_s.empty()) {
    summary.written.push_back(PlotSpaceTime(wave, out(L::kWaveSpaceTimePng), options.plot).path);
  } else {
    skip(L::kWaveSpaceTimePng,
         "no space-time data (/wave/front: " +
             (wave.front.problem.empty() ? std::string("the front was not computed")
                                         : wave.front.problem) +
             ")");
  }
  if (reader.Exists(L::kSensorT) && !wave.channels.empty()) {
    std::size_t n = kAnyLength;
    const std::vector<double> t_s = ReadSeries(reader, L::kSensorT, file, &n);
    const std::vector<BaseForceRecord> records = ReadBaseForceRecords(reader, file, wave);
    summary.written.push_back(
        PlotBaseForce(t_s, records, wave, out(L::kWaveBaseForcePng), options.plot).path);
  } else {
    skip(L::kWaveBaseForcePng, std::string("no ") + L::kSensorT + " or no base channel");
  }
  const auto has_profile = [](const DepthDecayFit& d) {
    return std::any_of(d.profile_value.begin(), d.profile_value.end(),
                       [](double v) { return v > 0; });
  };
  if (has_profile(wave.front.displacement_te) || has_profile(wave.front.displacement_end)) {
    summary.written.push_back(
        PlotDepthProfile(wave.front, out(L::kWaveDepthProfilePng), options.plot).path);
  } else {
    skip(L::kWaveDepthProfilePng, "no downward displacement on the centre line below the pounder");
  }
}

// The strain maps at t_e and at the last frame and the strain animation, when the file has
// /strain (else nothing, and no entry in the summary: a run without strain asks for none).
void DrawStrainField(const H5Reader& reader, double t_e_s, const RenderResultsOptions& options,
                     const std::string& out_dir, const FrameOutputNames& names,
                     RenderResultsSummary& summary) {
  if (!reader.Exists(L::kStrainGroup)) return;
  auto out = [&](const char* name) { return (fs::path(out_dir) / name).string(); };
  const bool loaded = static_cast<bool>(options.frame_loader);
  StrainFieldSequence seq = ReadStrainFieldSequence(reader, /*read_frames=*/!loaded);
  if (loaded) {
    seq.frame_count = seq.time_ms.size();
    seq.load_frame = options.frame_loader;
  }
  if (!seq.has_images()) {
    LogInfo("render: no camera frames ({}); the strain is drawn on a plain background",
            L::kFrameImages);
  }
  const StrainFieldRenderer renderer(seq, options.strain_overlay);
  if (options.snapshot) {
    auto write = [&](std::size_t frame, const char* name, const std::string& title) {
      WriteImage(out(name), renderer.RenderFrame(frame, title));
      summary.written.push_back(out(name));
    };
    if (std::isfinite(t_e_s)) {
      std::string title;
      const std::size_t frame = FrameAtTe(seq, t_e_s, "Strain", &title);
      write(frame, names.strain_te, title);
    } else {
      const std::string reason = std::string("no ") + L::kTeAttr + " attribute on " +
                                 L::kMomentumGroup + " (only the last frame is drawn)";
      LogInfo("render: skipping {}: {}", names.strain_te, reason);
      summary.skipped.push_back(std::string(names.strain_te) + ": " + reason);
    }
    const std::size_t last = seq.num_frames() - 1;
    write(last, names.strain_end,
          "Strain at the last analysed frame (t = " + FormatMs(1e-3 * seq.time_ms[last]) + ")");
  }
  if (options.animation) {
    VideoFrameSource source;
    source.count = seq.num_frames();
    source.size = renderer.canvas_size();
    source.render = [&renderer](std::size_t i) { return renderer.RenderFrame(i); };
    AnimationOptions a = options.animation_options;
    a.png_frames_dir = options.png_frames ? out(names.strain_png_frames) : "";
    summary.strain_animation = WriteAnimation(source, out(names.strain_animation), a);
    summary.has_strain_animation = true;
    summary.written.push_back(summary.strain_animation.path);
  }
}

void RenderInto(const H5Reader& reader, const std::string& results_path, const std::string& out_dir,
                const RenderResultsOptions& options, const FrameOutputNames& names,
                RenderResultsSummary& summary) {
  auto out = [&](const char* name) { return (fs::path(out_dir) / name).string(); };
  auto skip = [&](const std::string& output, const std::string& reason) {
    LogInfo("render: skipping {}: {}", output, reason);
    summary.skipped.push_back(output + ": " + reason);
  };

  // What the file has.
  const bool has_momentum_t = reader.Exists(L::kMomentumT);
  const bool has_momentum =
      has_momentum_t &&
      (reader.Exists(L::kPPounder) || reader.Exists(L::kPGran) || reader.Exists(L::kPTotal));
  const bool has_sensor = reader.Exists(L::kSensorT) && reader.Exists(L::kSensorDecel);
  const bool has_model = reader.Exists(L::kModelT) && reader.Exists(L::kModelDecel);
  const bool has_madd = has_momentum_t && reader.Exists(L::kMAdd);
  const bool has_field = reader.Exists(L::kTimeMs) && reader.Exists(L::kDicX) &&
                         reader.Exists(L::kDicY) && reader.Exists(L::kVx) && reader.Exists(L::kVy);
  const bool has_strain = reader.Exists(L::kStrainGroup);
  if (!has_momentum && !has_sensor && !has_model && !has_madd && !has_field && !has_strain) {
    throw Error(ErrorKind::kFileFormat, "results file", "none of the datasets render draws from",
                std::string("at least one of: ") + L::kMomentumT + " with " + L::kPPounder + "/" +
                    L::kPGran + "/" + L::kPTotal + "; " + L::kSensorT + " + " + L::kSensorDecel +
                    "; " + L::kModelT + " + " + L::kModelDecel + "; " + L::kMAdd + "; " +
                    L::kTimeMs + " + " + L::kDicX + " + " + L::kDicY + " + " + L::kVx + " + " +
                    L::kVy + " (+ " + L::kFrameImages + ")")
        .WithFile(OutputPathForMessages(results_path));
  }
  const double t_e_s = reader.Exists(L::kMomentumGroup)
                           ? NumberAttribute(reader, L::kMomentumGroup, L::kTeAttr)
                           : kNaN;

  try {
    if (options.figures) {
      if (has_momentum) {
        MomentumFigureData d;
        d.t_s = reader.ReadDouble(L::kMomentumT);
        d.p_pounder_Ns = ReadIf(reader, L::kPPounder);
        d.p_gran_Ns = ReadIf(reader, L::kPGran);
        d.p_total_Ns = ReadIf(reader, L::kPTotal);
        d.p_gran_u_Ns = ReadIf(reader, L::kPGranU);
        d.p_total_u_Ns = ReadIf(reader, L::kPTotalU);
        d.p_max_Ns = NumberAttribute(reader, L::kMomentumGroup, L::kPMaxAttr);
        d.t_e_s = t_e_s;
        summary.written.push_back(PlotMomentum(d, out(L::kMomentumPng), options.plot).path);
      } else {
        skip(L::kMomentumPng, std::string("no ") + L::kMomentumT + " with " + L::kPPounder + "/" +
                                  L::kPGran + "/" + L::kPTotal);
      }
      if (has_sensor || has_model) {
        DecelerationFigureData d;
        if (has_sensor) {
          d.measured_t_s = reader.ReadDouble(L::kSensorT);
          d.measured_decel_g = reader.ReadDouble(L::kSensorDecel);
        } else {
          LogInfo("render: no {}; the deceleration figure shows the model only", L::kSensorDecel);
        }
        if (has_model) {
          d.model_t_s = reader.ReadDouble(L::kModelT);
          d.model_decel_g = reader.ReadDouble(L::kModelDecel);
        } else {
          LogInfo("render: no {}; the deceleration figure shows the measurement only",
                  L::kModelDecel);
        }
        d.t_e_s = t_e_s;
        summary.written.push_back(PlotDeceleration(d, out(L::kDecelerationPng), options.plot).path);
      } else {
        skip(L::kDecelerationPng, std::string("neither ") + L::kSensorDecel + " nor " +
                                      L::kModelDecel + " (with their t_s)");
      }
      if (has_madd) {
        AddedMassFigureData d;
        d.t_s = reader.ReadDouble(L::kMomentumT);
        d.m_add_kg = reader.ReadDouble(L::kMAdd);
        d.m_add_u_kg = ReadIf(reader, L::kMAddU);
        d.sigmoid_M_kg = NumberAttribute(reader, L::kMomentumGroup, L::kSigmoidMAttr);
        d.sigmoid_b_per_s = NumberAttribute(reader, L::kMomentumGroup, L::kSigmoidBAttr);
        d.sigmoid_T_s = NumberAttribute(reader, L::kMomentumGroup, L::kSigmoidTAttr);
        d.t_e_s = t_e_s;
        if (std::none_of(d.m_add_kg.begin(), d.m_add_kg.end(),
                         [](double v) { return std::isfinite(v); })) {
          // A run whose momentum stage could not measure t_e (`run --allow-partial`).
          skip(L::kAddedMassPng,
               std::string("no finite value in ") + L::kMAdd + " (t_e was not measured)");
        } else {
          if (std::isnan(d.sigmoid_M_kg)) {
            LogInfo("render: no sigmoid attributes on {}; m_add drawn without its fit",
                    L::kMomentumGroup);
          }
          summary.written.push_back(PlotAddedMass(d, out(L::kAddedMassPng), options.plot).path);
        }
      } else {
        skip(L::kAddedMassPng, std::string("no ") + L::kMAdd + " with " + L::kMomentumT);
      }
    }

    if (options.figures) DrawWaveFigures(reader, results_path, options, out_dir, summary);
    if (options.snapshot || options.animation) {
      DrawVelocityField(reader, has_field, t_e_s, options, out_dir, names, summary);
      DrawStrainField(reader, t_e_s, options, out_dir, names, summary);
    }
  } catch (Error& e) {
    if (e.file().empty() && e.kind() == ErrorKind::kFileFormat)
      e.WithFile(OutputPathForMessages(results_path));
    throw;
  }
}

}  // namespace

}  // namespace impactdic
