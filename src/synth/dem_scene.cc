// DEM impact scene: reading LAMMPS output, timing, rendering the grains and the accelerometer
// record (docs/validation.md). The truth and the writer are in dem_scene_io.cc.
#include "impactdic/synth/dem_scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/io/input_file.h"
#include "impactdic/synth/checkerboard.h"
#include "lens_render.h"
#include "random.h"

namespace impactdic {
namespace {

using synth_detail::Rng;
using synth_detail::SplitMix64;

// Checked like every input (io/input_file.h: a folder, device or pipe is refused by name); no
// size limit, the dumps are read line by line.
std::ifstream OpenText(const std::string& path) {
  CheckInputFile(path, "a DEM output file", std::numeric_limits<std::uintmax_t>::max());
  std::ifstream in(path);
  if (!in)
    throw Error(ErrorKind::kIo, "", "cannot open it for reading", "a DEM output file")
        .WithFile(path);
  return in;
}

[[noreturn]] void BadLine(const std::string& path, long line, const std::string& found,
                          const std::string& expected) {
  throw Error(ErrorKind::kFileFormat, fmt::format("{}:{}", path, line), found, expected);
}

// Parses whitespace-separated numbers of one line; false if a token is not a number.
bool ParseNumbers(const std::string& text, std::vector<double>* out) {
  out->clear();
  const char* p = text.c_str();
  while (*p) {
    while (*p == ' ' || *p == '\t' || *p == '\r') ++p;
    if (!*p) break;
    char* end = nullptr;
    const double v = std::strtod(p, &end);
    if (end == p) return false;
    out->push_back(v);
    p = end;
  }
  return true;
}

}  // namespace

std::vector<DemSnapshot> ReadLammpsDump(const std::string& path) {
  std::ifstream in = OpenText(path);
  std::vector<DemSnapshot> snapshots;
  std::string line;
  long ln = 0;
  std::vector<double> nums;
  auto next = [&](const std::string& expected) {
    if (!std::getline(in, line)) BadLine(path, ln + 1, "the end of the file", expected);
    ++ln;
  };
  while (std::getline(in, line)) {
    ++ln;
    if (line.empty()) continue;
    if (line.rfind("ITEM: TIMESTEP", 0) != 0) BadLine(path, ln, line, "ITEM: TIMESTEP");
    DemSnapshot snap;
    next("a time step");
    snap.step = std::atoll(line.c_str());
    next("ITEM: NUMBER OF ATOMS");
    next("the number of atoms");
    const long n = std::atol(line.c_str());
    if (n < 0) BadLine(path, ln, line, "a number of atoms >= 0");
    next("ITEM: BOX BOUNDS");
    for (int i = 0; i < 3; ++i) next("a box bound line");
    next("ITEM: ATOMS id x y vx vy ...");
    if (line.rfind("ITEM: ATOMS", 0) != 0) BadLine(path, ln, line, "ITEM: ATOMS ...");
    std::istringstream names(line.substr(11));
    std::map<std::string, int> col;
    std::string name;
    for (int i = 0; names >> name; ++i) col[name] = i;
    for (const char* needed : {"id", "x", "y", "vx", "vy"})
      if (!col.count(needed)) BadLine(path, ln, line, fmt::format("a column '{}'", needed));
    const int cr = col.count("radius") ? col["radius"] : -1;
    const int cm = col.count("mass") ? col["mass"] : -1;
    snap.grains.resize(static_cast<std::size_t>(n));
    for (long i = 0; i < n; ++i) {
      next(fmt::format("{} atom lines", n));
      if (!ParseNumbers(line, &nums) || nums.size() != col.size())
        BadLine(path, ln, line, fmt::format("{} numbers", col.size()));
      DemGrain& g = snap.grains[static_cast<std::size_t>(i)];
      g.id = static_cast<std::int64_t>(nums[col["id"]]);
      g.x_m = nums[col["x"]];
      g.y_m = nums[col["y"]];
      g.vx_m_s = nums[col["vx"]];
      g.vy_m_s = nums[col["vy"]];
      g.radius_m = cr >= 0 ? nums[cr] : 0;
      g.mass_kg = cm >= 0 ? nums[cm] : 0;
    }
    std::sort(snap.grains.begin(), snap.grains.end(),
              [](const DemGrain& a, const DemGrain& b) { return a.id < b.id; });
    snapshots.push_back(std::move(snap));
  }
  return snapshots;
}

std::vector<DemPounderSample> ReadDemPounder(const std::string& path) {
  std::ifstream in = OpenText(path);
  std::vector<DemPounderSample> out;
  std::string line;
  long ln = 0;
  std::vector<double> nums;
  while (std::getline(in, line)) {
    ++ln;
    if (line.empty() || line[0] == '#') continue;
    if (!ParseNumbers(line, &nums) || nums.size() != 5)
      BadLine(path, ln, line, "5 numbers: step, time, y, vy, fy");
    out.push_back({nums[1], nums[2], nums[3], nums[4]});
    if (out.size() > 1 && !(out.back().t_s > out[out.size() - 2].t_s))
      BadLine(path, ln, line, "increasing times");
  }
  return out;
}

DemMeta ReadDemMeta(const std::string& path) {
  std::ifstream in = OpenText(path);
  std::map<std::string, double> kv;
  std::string line;
  long ln = 0;
  while (std::getline(in, line)) {
    ++ln;
    std::istringstream s(line);
    std::string key, value;
    if (!(s >> key >> value)) continue;
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (end == value.c_str()) BadLine(path, ln, line, "key and a number");
    kv[key] = v;
  }
  DemMeta m;
  const std::pair<const char*, double*> fields[] = {
      {"pounder_mass_kg", &m.pounder_mass_kg},
      {"pounder_width_m", &m.pounder_width_m},
      {"depth_m", &m.depth_m},
      {"impact_velocity_m_s", &m.impact_velocity_m_s},
      {"pounder_axis_x_m", &m.pounder_axis_x_m},
      {"pounder_bottom_offset_m", &m.pounder_bottom_offset_m},
      {"bed_top_m", &m.bed_top_m},
      {"box_width_m", &m.box_width_m},
      {"timestep_s", &m.timestep_s},
      {"gravity_m_s2", &m.gravity_m_s2}};
  for (const auto& [key, ptr] : fields) {
    auto it = kv.find(key);
    if (it == kv.end() || !std::isfinite(it->second))
      throw Error(ErrorKind::kFileFormat, path, fmt::format("no '{}'", key),
                  fmt::format("a line '{} VALUE'", key));
    *ptr = it->second;
  }
  for (const auto& [key, ptr] : fields) {
    if (std::string(key) == "bed_top_m" || std::string(key) == "pounder_axis_x_m") continue;
    CheckValue(*ptr > 0, path + ": " + key, fmt::format("{}", *ptr), "> 0");
  }
  // The floor windows: all three or none (a record of impact.in before them has none).
  const std::pair<const char*, double*> windows[] = {
      {"floor_window_width_m", &m.floor_window_width_m},
      {"floor_window_center_x_m", &m.floor_window_center_x_m},
      {"floor_window_offset_x_m", &m.floor_window_offset_x_m}};
  int found = 0;
  for (const auto& [key, ptr] : windows)
    if (auto it = kv.find(key); it != kv.end()) {
      CheckValue(std::isfinite(it->second), path + ": " + key, fmt::format("{}", it->second),
                 "a finite value");
      *ptr = it->second, ++found;
    }
  if (found != 0 && found != 3)
    throw Error(ErrorKind::kFileFormat, path, fmt::format("{} of the 3 floor_window_* keys", found),
                "floor_window_width_m, floor_window_center_x_m and floor_window_offset_x_m");
  if (found == 3)
    CheckValue(m.floor_window_width_m > 0, path + ": floor_window_width_m",
               fmt::format("{}", m.floor_window_width_m), "> 0");
  return m;
}

std::vector<DemFloorSample> ReadDemFloor(const std::string& path) {
  std::ifstream in = OpenText(path);
  std::vector<DemFloorSample> out;
  std::string line;
  long ln = 0;
  std::vector<double> nums;
  while (std::getline(in, line)) {
    ++ln;
    if (line.empty() || line[0] == '#') continue;
    if (!ParseNumbers(line, &nums) || nums.size() != 3)
      BadLine(path, ln, line, "3 numbers: step, the centre window's force, the offset window's");
    out.push_back({static_cast<std::int64_t>(nums[0]), {nums[1], nums[2]}});
    if (out.size() > 1 && !(out.back().step > out[out.size() - 2].step))
      BadLine(path, ln, line, "increasing steps");
  }
  if (out.empty())
    throw Error(ErrorKind::kFileFormat, path, "no samples",
                "step and two forces per line (meta.txt names floor windows)");
  return out;
}

DemPWaveRecord ReadDemPWave(const std::string& dir) {
  DemPWaveRecord r;
  const std::string meta = dir + "/pwave_meta.txt";
  {
    std::ifstream in = OpenText(meta);
    std::string line;
    long ln = 0;
    std::map<std::string, double> kv;
    while (std::getline(in, line)) {
      ++ln;
      std::istringstream s(line);
      std::string key, value;
      if (!(s >> key >> value)) continue;
      char* end = nullptr;
      const double v = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || !std::isfinite(v)) BadLine(meta, ln, line, "key and a number");
      if (key == "layer_depth_m") {
        if (!(v > 0)) BadLine(meta, ln, line, "a layer depth > 0");
        r.layer_depth_m.push_back(v);
      } else {
        kv[key] = v;
      }
    }
    for (const auto& [key, ptr] : {std::pair<const char*, double*>{"timestep_s", &r.timestep_s},
                                   {"pulse_start_s", &r.pulse_start_s},
                                   {"pulse_duration_s", &r.pulse_duration_s},
                                   {"bed_top_m", &r.bed_top_m}}) {
      auto it = kv.find(key);
      if (it == kv.end() || !(it->second > 0))
        throw Error(ErrorKind::kFileFormat, meta, fmt::format("no '{}' > 0", key),
                    fmt::format("a line '{} VALUE'", key));
      *ptr = it->second;
    }
    if (r.layer_depth_m.empty())
      throw Error(ErrorKind::kFileFormat, meta, "no layer_depth_m line", "one per layer");
  }
  // Each file: step, then one mean vy per layer (y up).
  auto read = [&](const std::string& path, std::vector<std::int64_t>* steps) {
    std::ifstream in = OpenText(path);
    std::vector<std::vector<double>> vy(r.layer_depth_m.size());
    std::string line;
    long ln = 0;
    std::vector<double> nums;
    while (std::getline(in, line)) {
      ++ln;
      if (line.empty() || line[0] == '#') continue;
      if (!ParseNumbers(line, &nums) || nums.size() != vy.size() + 1)
        BadLine(path, ln, line, fmt::format("{} numbers: step, each layer's vy", vy.size() + 1));
      steps->push_back(static_cast<std::int64_t>(nums[0]));
      for (std::size_t k = 0; k < vy.size(); ++k) vy[k].push_back(nums[k + 1]);
    }
    return vy;
  };
  std::vector<std::int64_t> rest_steps;
  const std::vector<std::vector<double>> with = read(dir + "/pwave.txt", &r.step);
  const std::vector<std::vector<double>> without = read(dir + "/pwave_rest.txt", &rest_steps);
  if (rest_steps != r.step)
    throw Error(ErrorKind::kFileFormat, dir + "/pwave_rest.txt",
                fmt::format("{} samples", rest_steps.size()),
                fmt::format("the steps of pwave.txt ({} samples)", r.step.size()));
  r.response_m_s.resize(with.size());
  for (std::size_t k = 0; k < with.size(); ++k)
    for (std::size_t i = 0; i < with[k].size(); ++i)
      r.response_m_s[k].push_back(-(with[k][i] - without[k][i]));
  return r;
}

void DemPWaveOptions::Check() const {
  CheckValue(
      min_depth_fraction >= 0 && min_depth_fraction < max_depth_fraction && max_depth_fraction <= 1,
      "min/max_depth_fraction", fmt::format("{}/{}", min_depth_fraction, max_depth_fraction),
      "0 <= min < max <= 1");
}

DemPWave MeasurePWave(const DemPWaveRecord& record, const DemPWaveOptions& options) {
  options.Check();
  const double min_depth_fraction = options.min_depth_fraction;
  const double max_depth_fraction = options.max_depth_fraction;
  DemPWave w;
  const std::size_t L = record.layer_depth_m.size(), n = record.step.size();
  w.layer_depth_m = record.layer_depth_m;
  w.half_peak_s.assign(L, kNaN);
  w.peak_s.assign(L, kNaN);
  w.peak_m_s.assign(L, kNaN);
  w.in_fit.assign(L, 0);
  std::vector<double> t(n);
  for (std::size_t i = 0; i < n; ++i)
    t[i] = static_cast<double>(record.step[i]) * record.timestep_s - record.pulse_start_s;
  std::vector<double> zf, thf, tpf;
  for (std::size_t k = 0; k < L; ++k) {
    const std::vector<double>& v = record.response_m_s[k];
    std::size_t ip = n;
    for (std::size_t i = 0; i < n; ++i)
      if (t[i] > 0 && (ip == n || v[i] > v[ip])) ip = i;
    if (ip == n || !(v[ip] > 0)) continue;
    double tp = t[ip];
    if (ip > 0 && ip + 1 < n && t[ip - 1] > 0) {  // Parabola through the peak and its neighbours.
      const double a = v[ip - 1], b = v[ip], c = v[ip + 1], den = a - 2 * b + c;
      if (den < 0) tp += 0.5 * (a - c) / den * (t[ip + 1] - t[ip]);
    }
    std::size_t j = ip;
    while (j > 0 && v[j] > 0.5 * v[ip]) --j;
    if (v[j] > 0.5 * v[ip]) continue;
    w.half_peak_s[k] = t[j] + (0.5 * v[ip] - v[j]) / (v[j + 1] - v[j]) * (t[j + 1] - t[j]);
    w.peak_s[k] = tp;
    w.peak_m_s[k] = v[ip];
    const double depth = record.layer_depth_m[k], H = record.bed_top_m;
    // A peak at the record's last sample may lie beyond it.
    if (depth >= min_depth_fraction * H && depth <= max_depth_fraction * H && ip + 1 < n) {
      w.in_fit[k] = 1;
      zf.push_back(depth), thf.push_back(w.half_peak_s[k]), tpf.push_back(tp);
    }
  }
  if (zf.size() < 3) {
    w.problem = fmt::format("{} layers with a pulse between {} and {} of the bed depth (need 3)",
                            zf.size(), min_depth_fraction, max_depth_fraction);
    return w;
  }
  // depth = z0 + c t: c and its standard error.
  auto fit = [&](const std::vector<double>& x, double* c, double* sigma, double* rms_t) {
    const double m = static_cast<double>(x.size());
    double mx = 0, mz = 0;
    for (std::size_t i = 0; i < x.size(); ++i) mx += x[i] / m, mz += zf[i] / m;
    double sxx = 0, sxz = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
      sxx += (x[i] - mx) * (x[i] - mx), sxz += (x[i] - mx) * (zf[i] - mz);
    *c = sxz / sxx;
    double ss = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double r = zf[i] - (mz + *c * (x[i] - mx));
      ss += r * r;
    }
    *sigma = std::sqrt(ss / (m - 2) / sxx);
    if (rms_t) *rms_t = std::sqrt(ss / m) / std::abs(*c);
  };
  fit(thf, &w.speed_m_s, &w.speed_sigma_m_s, &w.rms_residual_s);
  fit(tpf, &w.speed_peak_m_s, &w.speed_peak_sigma_m_s, nullptr);
  return w;
}

DemRecord ReadDemRecord(const std::string& dir) {
  DemRecord r;
  r.meta = ReadDemMeta(dir + "/meta.txt");
  r.frames = ReadLammpsDump(dir + "/grains.dump");
  std::ifstream near(dir + "/near.dump");
  if (near) r.near = ReadLammpsDump(dir + "/near.dump");
  r.pounder = ReadDemPounder(dir + "/pounder.txt");
  if (std::isfinite(r.meta.floor_window_width_m)) r.floor = ReadDemFloor(dir + "/floor.txt");
  if (std::ifstream pw(dir + "/pwave_meta.txt"); pw) r.pwave = ReadDemPWave(dir);
  return r;
}

void DemSceneOptions::Check() const {
  CheckValue(velocity_tolerance > 0 && velocity_tolerance <= 0.5, "velocity_tolerance",
             fmt::format("{}", velocity_tolerance), "in (0, 0.5]");
  CheckValue(grain_level_min >= 0 && grain_level_min <= grain_level_max && grain_level_max <= 1,
             "grain_level_min/max", fmt::format("{}/{}", grain_level_min, grain_level_max),
             "0 <= min <= max <= 1");
  CheckValue(pore_level >= 0 && pore_level <= 1, "pore_level", fmt::format("{}", pore_level),
             "in [0, 1]");
}

namespace {

// Bulk density [kg/m^3] of the bed under the footprint: grain mass per slab volume of the box
// |X| <= D/2, Y in [5, 105] mm below the surface (grain centres inside).
double BulkDensity(const DemSnapshot& snap, const DemMeta& m, double surface_y_m) {
  const double half = m.pounder_width_m / 2, y_top = surface_y_m - 0.005, y_bot = y_top - 0.1;
  double mass = 0;
  for (const DemGrain& g : snap.grains)
    if (std::abs(g.x_m - m.pounder_axis_x_m) <= half && g.y_m <= y_top && g.y_m > y_bot)
      mass += g.mass_kg;
  return mass / (2 * half * 0.1 * m.depth_m);
}

}  // namespace

DemScene::DemScene(DemRecord record, ImpactSceneSpec spec, DemSceneOptions options)
    : record_(std::move(record)), spec_(std::move(spec)), options_(options) {
  options_.Check();
  const DemMeta& m = record_.meta;
  const auto& P = record_.pounder;
  CheckValue(P.size() >= 4, "pounder.txt", fmt::format("{} samples", P.size()),
             "at least 4 pounder samples");
  CheckValue(record_.frames.size() >= 4, "grains.dump",
             fmt::format("{} snapshots", record_.frames.size()), "at least 4 snapshots");
  for (const DemSnapshot& s : record_.frames) {
    CheckValue(
        s.grains.size() == record_.frames[0].grains.size() && !s.grains.empty(), "grains.dump",
        fmt::format("a snapshot of {} grains at step {}", s.grains.size(), s.step),
        fmt::format("the same {} grains in every snapshot", record_.frames[0].grains.size()));
    for (const DemGrain& g : s.grains)
      CheckValue(g.radius_m > 0 && g.mass_kg > 0, "grains.dump", fmt::format("grain {}", g.id),
                 "radius and mass columns > 0");
  }
  const double dt_frame = (record_.frames[1].step - record_.frames[0].step) * m.timestep_s;
  CheckValue(
      std::abs(dt_frame * spec_.fps - 1) < 1e-6, "camera.fps", fmt::format("{}", spec_.fps),
      fmt::format("the DEM's frame rate {:.9g} (dump every {:.9g} s)", 1 / dt_frame, dt_frame));

  // Contact: the last sample without a contact force (the force is -m g exactly in free fall).
  const double mg = m.pounder_mass_kg * m.gravity_m_s2;
  std::size_t ic = P.size();
  for (std::size_t i = 0; i < P.size(); ++i)
    if (P[i].fy_N + mg > 1e-6 * mg) {
      ic = i;
      break;
    }
  CheckValue(ic >= 1 && ic < P.size(), "pounder.txt", "no contact force after the first sample",
             "a record that starts in free fall and hits the bed");
  t_contact_s_ = P[ic - 1].t_s;
  surface_y_m_ = P[ic - 1].yc_m - m.pounder_bottom_offset_m;
  v_start_m_s_ = -P[0].vy_m_s;
  release_time_s_ = P[0].t_s - v_start_m_s_ / m.gravity_m_s2 - t_contact_s_;

  // Frames the DAQ record covers with their exposure pulse.
  const double t_rec_end = P.back().t_s - t_contact_s_ - 1 / spec_.sensor.rate_hz;
  while (record_.frames.size() > 4 &&
         FrameTime(frame_count() - 1) + spec_.sensor.exposure_s > t_rec_end)
    record_.frames.pop_back();
  int before = 0;
  while (before < frame_count() && FrameTime(before) < 0) ++before;
  CheckValue(before >= 1 && before + 2 <= frame_count(), "grains.dump",
             fmt::format("{} of {} frames before the contact", before, frame_count()),
             "at least one frame before and two after the contact");

  // The test comes from the DEM; the scene's rho_d is the bed's bulk density.
  spec_.pounder_mass_kg = m.pounder_mass_kg;
  spec_.width_m = m.pounder_width_m;
  spec_.depth_m = m.depth_m;
  spec_.g_m_s2 = m.gravity_m_s2;
  spec_.impact_velocity_m_s = -P[ic - 1].vy_m_s;
  spec_.density_kg_m3 =
      BulkDensity(record_.frames[static_cast<std::size_t>(before - 1)], m, surface_y_m_);
  spec_.added_mass = SceneAddedMass::kEq4;
  spec_.frames = frame_count();
  spec_.frames_before_impact = before;
  spec_.impact_phase = std::clamp(-FrameTime(before - 1) * spec_.fps, 1e-6, 1.0);
  if (!record_.floor.empty()) SetUpFloorSensors();
  base_ = std::make_unique<ImpactScene>(spec_);

  const SynthCamera& cam = base_->camera();
  corner_map_.assign(static_cast<std::size_t>(spec_.width + 1) * (spec_.height + 1), {});
  for (int r = 0; r <= spec_.height; ++r)
    for (int c = 0; c <= spec_.width; ++c) {
      cv::Point2d n;
      if (!cam.Undistort({c - 0.5, r - 0.5}, &n))
        throw Error(ErrorKind::kNumerical, "camera", "distortion",
                    "an invertible distortion over the image");
      corner_map_[static_cast<std::size_t>(r) * (spec_.width + 1) + c] = cam.Pinhole(n);
    }
  // DAQ clock: starts pre_release before the release, shifted so frame 0 falls on a sample.
  const double nominal = release_time_s_ - spec_.sensor.pre_release_s;
  const double t0 = FrameTime(0);
  daq_origin_s_ =
      t0 - std::ceil((t0 - nominal) * spec_.sensor.rate_hz - 1e-9) / spec_.sensor.rate_hz;
  ComputeTruth();
}

// The base force sensors of the scene are the floor windows: at the floor (its depth below the
// surface), offset from the pounder axis, sensing area window width x t_z. The impulse series
// integrates floor.txt's interval averages, so any interval's average comes back exactly.
void DemScene::SetUpFloorSensors() {
  const DemMeta& m = record_.meta;
  const std::vector<DemFloorSample>& F = record_.floor;
  const std::size_t W = F[0].force_N.size();
  floor_t_s_.assign(1, 0.0);
  floor_impulse_Ns_.assign(W, std::vector<double>(1, 0.0));
  std::int64_t prev = 0;
  for (const DemFloorSample& s : F) {
    CheckValue(s.step > prev, "floor.txt", fmt::format("step {}", s.step),
               "increasing steps after step 0");
    const double dt = static_cast<double>(s.step - prev) * m.timestep_s;
    floor_t_s_.push_back(static_cast<double>(s.step) * m.timestep_s);
    for (std::size_t w = 0; w < W; ++w)
      floor_impulse_Ns_[w].push_back(floor_impulse_Ns_[w].back() + s.force_N[w] * dt);
    prev = s.step;
  }
  CheckValue(floor_t_s_[1] < t_contact_s_ && floor_t_s_.back() > t_contact_s_, "floor.txt",
             fmt::format("DEM times {:.6g} to {:.6g} s", floor_t_s_[1], floor_t_s_.back()),
             fmt::format("a record spanning the contact at {:.6g} s", t_contact_s_));
  floor_static_N_.assign(W, 0.0);
  auto impulse_at = [&](std::size_t w, double tau) {
    const auto it = std::upper_bound(floor_t_s_.begin(), floor_t_s_.end(), tau);
    const auto i = static_cast<std::size_t>(it - floor_t_s_.begin());
    const double a = floor_t_s_[i - 1], b = floor_t_s_[i];
    return floor_impulse_Ns_[w][i - 1] +
           (tau - a) / (b - a) * (floor_impulse_Ns_[w][i] - floor_impulse_Ns_[w][i - 1]);
  };
  for (std::size_t w = 0; w < W; ++w)
    floor_static_N_[w] = impulse_at(w, t_contact_s_) / t_contact_s_;
  SceneBaseSensorOptions& b = spec_.base_sensors;
  b.columns = {"base_center_N", "base_offset_N"};
  b.offset_mm = {(m.floor_window_center_x_m - m.pounder_axis_x_m) * 1000,
                 (m.floor_window_offset_x_m - m.pounder_axis_x_m) * 1000};
  b.depth_mm.assign(W, surface_y_m_ * 1000);  // The floor is y = 0.
  b.area_mm2.assign(W, m.floor_window_width_m * m.depth_m * 1e6);
}

double DemScene::FloorDynamicForce(std::size_t w, double t0_s, double t1_s) const {
  const std::vector<double>& T = floor_t_s_;
  const std::vector<double>& I = floor_impulse_Ns_[w];
  const double s = floor_static_N_[w];
  // Impulse since DEM time 0 at DEM time tau: the static load before the record, the last
  // force after it.
  auto impulse = [&](double tau) {
    if (tau <= 0) return s * tau;
    if (tau >= T.back()) {
      const double last = (I.back() - I[I.size() - 2]) / (T.back() - T[T.size() - 2]);
      return I.back() + last * (tau - T.back());
    }
    const auto i = static_cast<std::size_t>(std::upper_bound(T.begin(), T.end(), tau) - T.begin());
    return I[i - 1] + (tau - T[i - 1]) / (T[i] - T[i - 1]) * (I[i] - I[i - 1]);
  };
  const double a = t0_s + t_contact_s_, b = t1_s + t_contact_s_;
  return (impulse(b) - impulse(a)) / (b - a) - s;
}

double DemScene::FrameTime(int k) const {
  return record_.frames[static_cast<std::size_t>(k)].step * record_.meta.timestep_s - t_contact_s_;
}

cv::Point2d DemScene::PanelFromDem(double x_m, double y_m) const {
  return {(x_m - record_.meta.pounder_axis_x_m) * 1000, (surface_y_m_ - y_m) * 1000};
}

PounderState DemScene::Pounder(double t_s) const {
  const auto& P = record_.pounder;
  const double off = record_.meta.pounder_bottom_offset_m, g = record_.meta.gravity_m_s2;
  const double tau = t_s + t_contact_s_;  // DEM time
  const double z0 = surface_y_m_ - (P[0].yc_m - off);
  if (tau <= P[0].t_s) {
    const double tr = release_time_s_ + t_contact_s_;
    const double s = std::max(tau, tr) - P[0].t_s;
    return {z0 + v_start_m_s_ * s + 0.5 * g * s * s, std::max(0.0, v_start_m_s_ + g * s)};
  }
  if (tau >= P.back().t_s) return {surface_y_m_ - (P.back().yc_m - off), -P.back().vy_m_s};
  const auto it = std::upper_bound(P.begin(), P.end(), tau,
                                   [](double t, const DemPounderSample& s) { return t < s.t_s; });
  const DemPounderSample& b = *it;
  const DemPounderSample& a = *(it - 1);
  const double w = (tau - a.t_s) / (b.t_s - a.t_s);
  const double yc = a.yc_m + w * (b.yc_m - a.yc_m), vy = a.vy_m_s + w * (b.vy_m_s - a.vy_m_s);
  return {surface_y_m_ - (yc - off), -vy};
}

namespace {

// Grains of one snapshot binned on a square grid in panel mm, for point-in-grain look-ups.
class GrainIndex {
 public:
  GrainIndex(const std::vector<cv::Point2d>& centre_mm, const std::vector<double>& radius_mm)
      : centre_(centre_mm), radius_(radius_mm) {
    double rmax = 0;
    x0_ = y0_ = std::numeric_limits<double>::max();
    double x1 = -x0_, y1 = -y0_;
    for (std::size_t i = 0; i < centre_.size(); ++i) {
      rmax = std::max(rmax, radius_[i]);
      x0_ = std::min(x0_, centre_[i].x), y0_ = std::min(y0_, centre_[i].y);
      x1 = std::max(x1, centre_[i].x), y1 = std::max(y1, centre_[i].y);
    }
    cell_ = std::max(2 * rmax, 1e-6);
    x0_ -= cell_, y0_ -= cell_;
    nx_ = static_cast<int>((x1 - x0_) / cell_) + 3;
    ny_ = static_cast<int>((y1 - y0_) / cell_) + 3;
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    std::vector<std::size_t> key(centre_.size());
    for (std::size_t i = 0; i < centre_.size(); ++i) {
      key[i] = Key(centre_[i].x, centre_[i].y);
      ++start_[key[i] + 1];
    }
    for (std::size_t k = 1; k < start_.size(); ++k) start_[k] += start_[k - 1];
    items_.resize(centre_.size());
    std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < centre_.size(); ++i) items_[fill[key[i]]++] = i;
  }
  // The grain containing (x, y) [mm] (the nearest centre if discs overlap), or -1.
  long Find(double x, double y, double* rho_over_r) const {
    const int cx = static_cast<int>(std::floor((x - x0_) / cell_));
    const int cy = static_cast<int>(std::floor((y - y0_) / cell_));
    long best = -1;
    double best_q = 1;
    for (int j = std::max(cy - 1, 0); j <= std::min(cy + 1, ny_ - 1); ++j)
      for (int i = std::max(cx - 1, 0); i <= std::min(cx + 1, nx_ - 1); ++i) {
        const std::size_t k = static_cast<std::size_t>(j) * nx_ + i;
        for (std::size_t s = start_[k]; s < start_[k + 1]; ++s) {
          const std::size_t g = items_[s];
          const double dx = x - centre_[g].x, dy = y - centre_[g].y;
          const double q = std::sqrt(dx * dx + dy * dy) / radius_[g];
          if (q < best_q) best_q = q, best = static_cast<long>(g);
        }
      }
    *rho_over_r = best_q;
    return best;
  }

 private:
  std::size_t Key(double x, double y) const {
    const int i = std::clamp(static_cast<int>(std::floor((x - x0_) / cell_)), 0, nx_ - 1);
    const int j = std::clamp(static_cast<int>(std::floor((y - y0_) / cell_)), 0, ny_ - 1);
    return static_cast<std::size_t>(j) * nx_ + i;
  }
  const std::vector<cv::Point2d>& centre_;
  const std::vector<double>& radius_;
  double x0_ = 0, y0_ = 0, cell_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<std::size_t> start_, items_;
};

}  // namespace

// Each pixel: ss x ss samples of its undistorted quadrilateral (as ImpactScene). A sample on the
// pounder (a dark block of the DEM pounder's width and height with a lighter rim) shows it; on a
// grain, the grain's own grey level (random per grain id, fixed over time) shaded darker towards
// its rim; else the pore level. The texture is the grains themselves.
cv::Mat DemScene::RenderFrame(int k, bool with_noise) const {
  CheckValue(k >= 0 && k < frame_count(), "frame index", std::to_string(k),
             fmt::format("in [0, {})", frame_count()));
  const DemSnapshot& snap = record_.frames[static_cast<std::size_t>(k)];
  std::vector<cv::Point2d> centre(snap.grains.size());
  std::vector<double> radius(snap.grains.size()), level(snap.grains.size());
  const double span = options_.grain_level_max - options_.grain_level_min;
  for (std::size_t i = 0; i < snap.grains.size(); ++i) {
    const DemGrain& g = snap.grains[i];
    centre[i] = PanelFromDem(g.x_m, g.y_m);
    radius[i] = g.radius_m * 1000;
    const std::uint64_t h = SplitMix64(static_cast<std::uint64_t>(g.id) ^ (spec_.seed * 0x9E37ull));
    level[i] = options_.grain_level_min + span * ((h >> 11) * (1.0 / 9007199254740992.0));
  }
  const GrainIndex index(centre, radius);
  const double z_mm = Pounder(FrameTime(k)).z_m * 1000;
  const double a_mm = spec_.width_m * 500,
               block_mm = 2 * record_.meta.pounder_bottom_offset_m * 1000;
  const double rim_mm = std::max(1.5 * std::max(base_->sx_mm_per_px(), base_->sy_mm_per_px()),
                                 0.02 * spec_.width_m * 1000);
  const double shaft_mm = 0.15 * spec_.width_m * 1000;
  auto pounder_at = [&](double x, double y) {
    const double ax = std::abs(x);
    if (y > z_mm) return -1.0;
    if (y >= z_mm - block_mm) {
      if (ax > a_mm) return -1.0;
      const bool rim = ax >= a_mm - rim_mm || y >= z_mm - rim_mm;
      return rim ? spec_.pounder_level + 0.12 : spec_.pounder_level;
    }
    return ax <= shaft_mm ? spec_.pounder_level + 0.06 : -1.0;
  };
  const std::uint64_t noise_seed = spec_.seed * 7919 + 1000003ull * static_cast<std::uint64_t>(k);
  return synth_detail::RenderThroughLens(
      spec_, corner_map_, noise_seed, with_noise, [&](const cv::Point2d& q) {
        const cv::Point2d p = base_->PanelFromIdeal(q);
        const double pl = pounder_at(p.x, p.y);
        if (pl >= 0) return pl;
        double rho = 1;
        const long g = index.Find(p.x, p.y, &rho);
        return g >= 0 ? level[static_cast<std::size_t>(g)] * (1 - 0.35 * rho * rho)
                      : options_.pore_level;
      });
}

// As ImpactScene::MakeSensorRecord: sample i reads the cell average 1 - (v(t + dt/2) -
// v(t - dt/2)) / (g dt) of the pounder's motion (axis up: 0 g in free fall, 1 g held), here from
// the DEM's pounder velocity (sampled at the half-sample points), plus offset and noise. The
// record ends with the DEM.
ImpactScene::SensorRecord DemScene::MakeSensorRecord() const {
  ImpactScene::SensorRecord rec;
  const SceneSensorOptions& so = spec_.sensor;
  const double dt = 1 / so.rate_hz, g = spec_.g_m_s2;
  const double t_end = record_.pounder.back().t_s - t_contact_s_;
  const auto n = static_cast<std::size_t>(std::floor((t_end - daq_origin_s_) / dt - 0.5 + 1e-9));
  rec.frame0_daq_time_s = FrameTime(0) - daq_origin_s_;
  rec.impact_daq_time_s = -daq_origin_s_;
  rec.release_daq_time_s = release_time_s_ - daq_origin_s_;
  Rng noise(SplitMix64(spec_.seed) ^ 0x5EB50Bull);
  rec.time_s.resize(n);
  rec.accel_g.resize(n);
  rec.accel_true_g.resize(n);
  rec.exposure.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double daq = static_cast<double>(i) * dt, t = daq_origin_s_ + daq;
    rec.time_s[i] = daq;
    rec.accel_true_g[i] = 1 - (Pounder(t + dt / 2).v_m_s - Pounder(t - dt / 2).v_m_s) / (g * dt);
    rec.accel_g[i] = rec.accel_true_g[i] + so.offset_g + so.noise_g * noise.Normal();
    const double k = std::floor((t - FrameTime(0)) * spec_.fps + 1e-9);
    double e = 0;
    if (k >= 0 && k < frame_count()) {
      const double since = t - FrameTime(static_cast<int>(k));
      e = (since > -1e-12 && since < so.exposure_s) ? 1.0 : 0.0;
    }
    rec.exposure[i] = e;
  }
  const SceneBaseSensorOptions& b = spec_.base_sensors;
  for (std::size_t w = 0; w < floor_windows(); ++w) {
    std::vector<double> truth(n), written(n);
    Rng base_noise(SplitMix64(spec_.seed + 17 * (w + 1)) ^ 0xBA5E5E45ull);
    for (std::size_t i = 0; i < n; ++i) {
      const double t = daq_origin_s_ + static_cast<double>(i) * dt;
      truth[i] = FloorDynamicForce(w, t - dt / 2, t + dt / 2);
      written[i] = floor_static_N_[w] + truth[i] + b.offset_n + b.noise_n * base_noise.Normal();
    }
    rec.base_force_true_n.push_back(std::move(truth));
    rec.base_force_n.push_back(std::move(written));
  }
  return rec;
}

}  // namespace impactdic
