// Realistic synthetic scene: spec YAML and writing the scene (frames as JPEG, truth.h5).
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/input_file.h"
#include "impactdic/io/yaml.h"
#include "impactdic/synth/realistic.h"
#include "spec_keys.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;
using synth_detail::Integer;
using synth_detail::Number;
using synth_detail::Seed;

constexpr const char* kWhat = "a realistic synthetic scene spec (YAML)";

// The one binding of every key of the `realistic:` section.
YamlOptionTable RealisticKeys(RealisticSceneSpec* s) {
  YamlOptionTable t("realistic");
  t.Add("name", &s->name, "");
  Integer(t, "width", &s->width);
  Integer(t, "height", &s->height);
  Integer(t, "frames", &s->frames);
  Number(t, "fps", &s->fps);
  Number(t, "exposure_s", &s->exposure_s);
  Integer(t, "blur_samples", &s->blur_samples);
  Integer(t, "supersampling", &s->supersampling);
  Number(t, "noise_sigma", &s->noise_sigma);
  Integer(t, "jpeg_quality", &s->jpeg_quality);
  Number(t, "grain_radius_px", &s->grain_radius_px);
  Number(t, "grain_radius_spread", &s->grain_radius_spread);
  Number(t, "grain_coverage", &s->grain_coverage);
  Number(t, "light_falloff", &s->light_falloff);
  Number(t, "light_drift_per_frame", &s->light_drift_per_frame);
  Number(t, "glare_level", &s->glare_level);
  Number(t, "glare_radius_px", &s->glare_radius_px);
  Number(t, "glare_x", &s->glare_x);
  Number(t, "glare_y", &s->glare_y);
  Number(t, "surface_fraction", &s->surface_fraction);
  Number(t, "pounder_width_fraction", &s->pounder_width_fraction);
  Number(t, "penetration_px_per_frame", &s->penetration_px_per_frame);
  Number(t, "shear_band_width_px", &s->shear_band_width_px);
  Number(t, "core_decay_px", &s->core_decay_px);
  Number(t, "heave_ratio", &s->heave_ratio);
  Number(t, "heave_decay_px", &s->heave_decay_px);
  Integer(t, "subset_size", &s->subset_size);
  Integer(t, "step", &s->step);
  Seed(t, "seed", &s->seed);
  return t;
}

std::string FrameName(const RealisticSceneSpec& spec, int k) {
  return fmt::format("frame_{:04d}.{}", k, spec.jpeg_quality > 0 ? "jpg" : "png");
}

}  // namespace

RealisticSceneSpec ParseRealisticSceneSpec(const std::string& yaml_text, const std::string& path) {
  const YAML::Node root = LoadYaml(yaml_text, path, kWhat);
  YamlProblems problems(path);
  YamlSection top(root, "", &problems);
  RealisticSceneSpec spec;
  const YamlOptionTable table = RealisticKeys(&spec);
  YamlSection section = top.Sub(table.section());
  table.Read(section);
  section.Finish();
  top.Finish();
  problems.ThrowIfAny("realistic synthetic scene spec");
  try {
    spec.Check();
  } catch (Error& e) {
    throw e.WithFile(path);
  }
  return spec;
}

RealisticSceneSpec LoadRealisticSceneSpec(const std::string& path) {
  return ParseRealisticSceneSpec(ReadInputFile(path, kWhat, kMaxTextFileBytes), path);
}

std::string RealisticSceneSpecToYaml(const RealisticSceneSpec& spec) {
  RealisticSceneSpec copy = spec;
  std::ostringstream o;
  o << "# impactdic synth: realistic footage spec (keys: docs/synth.md, \"Realistic mode\")\n"
       "realistic:\n";
  const YamlOptionTable table = RealisticKeys(&copy);
  for (const auto& entry : table.entries())
    o << "  " << entry.key << ": " << entry.default_text << "\n";
  return o.str();
}

RealisticSceneReport WriteRealisticScene(const RealisticScene& scene, const std::string& out_dir) {
  const RealisticSceneSpec& spec = scene.spec();
  const fs::path dir(out_dir);
  std::error_code ec;
  fs::create_directories(dir / "frames", ec);
  if (ec) throw Error(ErrorKind::kIo, fmt::format("{}: cannot create: {}", out_dir, ec.message()));
  WallTimer timer;
  RealisticSceneReport report;
  report.out_dir = out_dir;
  int cols = 0, rows = 0;
  const std::vector<cv::Point2d> grid = scene.GridPoints(&cols, &rows);
  const std::size_t n = grid.size();
  const auto frames = static_cast<std::size_t>(spec.frames);
  std::vector<double> u(frames * n), v(frames * n);
  std::vector<std::int32_t> edge(frames * n), band(frames * n), glare(frames * n);
  for (int k = 0; k < spec.frames; ++k) {
    const cv::Mat image = scene.RenderFrame(k);
    std::vector<int> params;
    if (spec.jpeg_quality > 0) params = {cv::IMWRITE_JPEG_QUALITY, spec.jpeg_quality};
    WriteImage((dir / "frames" / FrameName(spec, k)).string(), image, params);
    const RealisticTruth t =
        scene.Truth(grid, k, 0.5 * (spec.subset_size - 1));  // half-width, odd size
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = k * n + i;
      u[j] = t.u_px[i];
      v[j] = t.v_px[i];
      edge[j] = t.straddles_edge[i];
      band[j] = t.straddles_shear_band[i];
      glare[j] = t.in_glare[i];
    }
    LogInfo("realistic frame {}/{} rendered", k + 1, spec.frames);
  }
  report.render_seconds = timer.ElapsedSeconds();
  const std::string yaml = RealisticSceneSpecToYaml(spec);
  WriteTextFileAtomic((dir / "spec.yaml").string(), yaml);
  report.truth_h5 = (dir / "truth.h5").string();
  H5Writer out(report.truth_h5);
  out.WriteProvenance(yaml);
  std::vector<double> gx, gy;
  for (const auto& p : grid) {
    gx.push_back(p.x);
    gy.push_back(p.y);
  }
  const Dims grid_dims{static_cast<std::size_t>(rows), static_cast<std::size_t>(cols)};
  const Dims dims{frames, grid_dims[0], grid_dims[1]};
  out.Write("grid/x_px", gx, grid_dims, "px", "subset centre x in frame 0 (correlator layout)");
  out.Write("grid/y_px", gy, grid_dims, "px", "subset centre y in frame 0");
  out.Write("truth/u_px", u, dims, "px", "displacement since frame 0, x right (exposure mean)");
  out.Write("truth/v_px", v, dims, "px", "displacement since frame 0, y down (exposure mean)");
  out.Write("truth/straddles_edge", edge, dims, "",
            "1: the pounder edge or the sand surface lies in the subset");
  out.Write("truth/straddles_shear_band", band, dims, "", "1: a shear band crosses the subset");
  out.Write("truth/in_glare", glare, dims, "", "1: glare adds >= 0.2 full scale in the subset");
  out.SetAttribute("truth", "subset_size_px", spec.subset_size);
  out.SetAttribute("truth", "step_px", spec.step);
  out.SetAttribute("truth", "pounder_axis_px", scene.axis_px());
  out.SetAttribute("truth", "surface_px", scene.surface_px());
  out.SetAttribute("truth", "pounder_half_width_px", scene.half_width_px());
  out.Commit();
  report.frames = spec.frames;
  return report;
}

}  // namespace impactdic
