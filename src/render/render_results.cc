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
#include "impactdic/io/output_generation.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/render/figures.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace L = results_layout;

void RenderResultsOptions::Check() const {
  plot.Check();
  animation_options.Check();
  snapshot_overlay.Check();
}

std::string RenderResultsSummary::BriefReport() const {
  std::string text = "render: " + std::to_string(written.size()) + " file(s) written, " +
                     std::to_string(skipped.size()) + " skipped";
  if (has_animation) {
    text += "; animation " + animation.codec + " " + std::to_string(animation.frames) + " frames";
    if (animation.fell_back) text += " (MJPG fallback)";
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

// The sequence's data at the given rows only (the frames are set by the caller).
void KeepRows(VelocityFieldSequence& seq, const std::vector<std::size_t>& rows) {
  const std::size_t n = seq.num_subsets;
  auto keep = [&](std::vector<double>& per_row, std::size_t width) {
    std::vector<double> kept;
    for (std::size_t row : rows)
      kept.insert(kept.end(), per_row.begin() + row * width, per_row.begin() + (row + 1) * width);
    per_row = std::move(kept);
  };
  keep(seq.time_ms, 1);
  keep(seq.vx_mm_s, n);
  keep(seq.vy_mm_s, n);
  if (seq.x_px.size() != n) {
    keep(seq.x_px, n);
    keep(seq.y_px, n);
  }
}

}  // namespace

VelocityFieldSequence ReadVelocityFieldSequence(const H5Reader& r, bool require_frames,
                                                bool read_frames) {
  // The file name for messages is not exposed by H5Reader; the callers add it.
  const std::string file;
  VelocityFieldSequence seq;
  for (const char* path : {L::kTimeMs, L::kDicX, L::kDicY, L::kVx, L::kVy}) {
    if (!r.Exists(path)) {
      throw Error(ErrorKind::kFileFormat, "dataset " + std::string(path), "missing",
                  "the velocity field data (" + std::string(L::kTimeMs) + ", " + L::kDicX + ", " +
                      L::kDicY + ", " + L::kVx + ", " + L::kVy + ")");
    }
  }
  Dims dt, dx, dy, dvx, dvy;
  seq.time_ms = r.ReadDouble(L::kTimeMs, &dt);
  const std::vector<double> x = r.ReadDouble(L::kDicX, &dx);
  const std::vector<double> y = r.ReadDouble(L::kDicY, &dy);
  seq.vx_mm_s = r.ReadDouble(L::kVx, &dvx);
  seq.vy_mm_s = r.ReadDouble(L::kVy, &dvy);
  if (dt.size() != 1) ShapeError(r, L::kTimeMs, file, dt, "[frames]");
  const std::size_t f = dt[0];
  if (dvx.size() != 2 || dvx[0] != f) {
    ShapeError(r, L::kVx, file, dvx, "[frames x subsets] with frames = " + std::to_string(f));
  }
  const std::size_t n = dvx[1];
  if (dvy != dvx) ShapeError(r, L::kVy, file, dvy, "the shape of " + std::string(L::kVx));
  const bool fixed = dx.size() == 1 && dx[0] == n;
  const bool moving = dx.size() == 2 && dx[0] == f && dx[1] == n;
  if (!fixed && !moving) {
    ShapeError(
        r, L::kDicX, file, dx,
        "[subsets] or [frames x subsets] matching " + std::string(L::kVx) + " " + Dims2Text(dvx));
  }
  if (dy != dx) ShapeError(r, L::kDicY, file, dy, "the shape of " + std::string(L::kDicX));
  seq.num_subsets = n;
  seq.x_px = x;
  seq.y_px = y;
  // Lagrangian positions from the accumulated displacement, when stored (read by io
  // ReadDicResults, whatever the layout version).
  if (fixed && r.Exists(L::kDicU) && r.Exists(L::kDicV)) {
    // The displacements only, turned into positions where they are read.
    DicResultsTable dic = ReadDicResults(r, file, DicFields::kDisplacements);
    if (dic.rows != f || dic.subsets != n) {
      ShapeError(r, L::kDicU, file, Dims{dic.rows, dic.subsets},
                 "[frames x subsets] = " + Dims2Text(dvx));
    }
    seq.x_px = std::move(dic.u_px);
    seq.y_px = std::move(dic.v_px);
    for (std::size_t i = 0; i < f; ++i) {
      for (std::size_t s = 0; s < n; ++s) {
        seq.x_px[i * n + s] = x[s] + seq.x_px[i * n + s];
        seq.y_px[i * n + s] = y[s] + seq.y_px[i * n + s];
      }
    }
  }
  seq.mm_per_px = NumberAttribute(r, L::kKinematicsGroup, L::kMmPerPxAttr);
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
    seq.frames.push_back(frame);
  }
  if (rows.size() != f) KeepRows(seq, rows);
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
  return {L::kPreviewSnapshotPng, L::kPreviewAnimationName, L::kPreviewAnimationAviName,
          L::kPreviewPngFramesDir, true};
}

// A render's outputs are one generation of the folder; it keeps the other entries of the previous
// generation (a run's results.h5 and summaries, and its frame-based outputs when `names` are the
// preview's) and replaces every figure and animation of its names.
OutputGenerationOptions RenderGenerationOptions(const FrameOutputNames& names, bool force) {
  OutputGenerationOptions o;
  o.command = "impactdic render";
  for (const char* name : {L::kMomentumPng, L::kDecelerationPng, L::kAddedMassPng, names.snapshot,
                           names.animation, names.animation_avi, names.png_frames})
    o.own_names.emplace_back(name);
  for (const char* name : L::kRunOnlyOutputNames) o.known_names.emplace_back(name);
  if (names.preview) {
    for (const char* name :
         {L::kVelocitySnapshotPng, L::kAnimationName, L::kAnimationAviName, L::kPngFramesDir})
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

// The frame of the velocity snapshot: the one nearest t_e, else (no t_e) the one of the largest
// mean speed; *title says which.
std::size_t SnapshotFrame(const VelocityFieldSequence& seq, double t_e_s, std::string* title) {
  if (std::isfinite(t_e_s)) {
    *title = "Velocity field at the end of the peak stage (t_e = " + FormatMs(t_e_s) + ")";
    return FrameNearestTime(seq, 1e3 * t_e_s);
  }
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
    if (seq.num_frames() == 0) {
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
  if (!has_momentum && !has_sensor && !has_model && !has_madd && !has_field) {
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

    if (options.snapshot || options.animation)
      DrawVelocityField(reader, has_field, t_e_s, options, out_dir, names, summary);
  } catch (Error& e) {
    if (e.file().empty() && e.kind() == ErrorKind::kFileFormat)
      e.WithFile(OutputPathForMessages(results_path));
    throw;
  }
}

}  // namespace

}  // namespace impactdic
