// The campaign's plan: which tests, from a campaign file (scene list, glob, parameter matrix to
// synthesise) or scene files; their unique names and content hashes; shards.
#include <fmt/format.h>
#include <glob.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "campaign_internal.h"
#include "impactdic/core/error.h"
#include "impactdic/core/range.h"
#include "impactdic/core/version.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/yaml.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/pipeline/campaign.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/synth/impact_scene.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace campaign_internal {

void ContentHasher::Add(std::string_view bytes) {
  std::uint64_t h = h_;
  for (const char c : bytes) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;  // Prime.
  h_ = h;
}

std::string ContentHasher::Hex() const { return fmt::format("{:016x}", h_); }

std::string ContentHash(const std::string& bytes) {
  ContentHasher h;
  h.Add(bytes);
  return h.Hex();
}

namespace {

// One input file into the hash: its path, then its size and bytes, or why it cannot be read.
void AddInputFile(const std::string& path, ContentHasher* h) {
  h->Add(path);
  h->Add(std::string_view("\0", 1));
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (!in || ec) {
    h->Add("unreadable\n");
    return;
  }
  h->Add(fmt::format("{} bytes\n", size));
  std::vector<char> buffer(std::size_t{1} << 20);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    h->Add(std::string_view(buffer.data(), static_cast<std::size_t>(in.gcount())));
  }
}

}  // namespace

std::string SceneInputsHash(const Scene& scene) {
  ContentHasher h;
  h.Add("frames\n");
  try {
    // The frames stage reads inputs.frame_files in place of inputs.frames when they are given.
    for (const std::string& frame : scene.inputs.frame_files.empty()
                                        ? FrameSourceFiles(scene.inputs.frames)
                                        : scene.inputs.frame_files)
      AddInputFile(frame, &h);
  } catch (const Error& e) {
    h.Add(std::string("not listed: ") + e.what());
  }
  for (const std::string* input :
       {&scene.inputs.sensor, &scene.inputs.calibration, &scene.inputs.truth, &scene.dic.mask}) {
    h.Add("\ninput\n");
    if (!input->empty()) AddInputFile(*input, &h);
  }
  return h.Hex();
}

std::string ToolVersion() { return fmt::format("{}+{}", Version(), GitRevision()); }

}  // namespace campaign_internal

namespace {
using campaign_internal::ContentHash;

constexpr const char* kWhat = "a campaign file (YAML)";

// Error for a node of the campaign file: "FILE:LINE: KEY: got ...; expected ...".
[[noreturn]] void Fail(const std::string& file, const YAML::Node& node, const std::string& key,
                       const std::string& found, const std::string& expected) {
  Error e(ErrorKind::kInvalidValue, key, found, expected);
  if (node.IsDefined() && node.Mark().line >= 0) {
    e.WithFile(file, node.Mark().line + 1, node.Mark().column + 1);
  } else {
    e.WithFile(file);
  }
  throw e;
}

// A path or a non-empty list of paths at `key` (absent or null: none).
std::vector<std::string> ReadPaths(YamlSection& section, const std::string& key) {
  const YAML::Node node = section.Get(key);
  if (!node.IsDefined() || node.IsNull()) return {};
  if (node.IsScalar() && !node.Scalar().empty()) return {node.Scalar()};
  if (!node.IsSequence() || node.size() == 0) {
    section.Problem(key, fmt::format("got {}; expected a path or a non-empty list of paths",
                                     DescribeYaml(node)));
    return {};
  }
  std::vector<std::string> out;
  for (std::size_t i = 0; i < node.size(); ++i) {
    if (node[i].IsScalar() && !node[i].Scalar().empty()) {
      out.push_back(node[i].Scalar());
    } else {
      section.problems()->Add(node[i], fmt::format("{}[{}]", section.PathOf(key), i),
                              fmt::format("got {}; expected a path", DescribeYaml(node[i])));
    }
  }
  return out;
}

// A non-empty list of positive numbers at `key`, stored in *out when every element is valid
// (absent or null: *out unchanged).
void ReadPositiveList(YamlSection& section, const std::string& key, std::vector<double>* out) {
  const YAML::Node node = section.Get(key);
  if (!node.IsDefined() || node.IsNull()) return;
  if (!node.IsSequence() || node.size() == 0) {
    section.Problem(key, fmt::format("got {}; expected a non-empty list of positive numbers",
                                     DescribeYaml(node)));
    return;
  }
  std::vector<double> values;
  for (std::size_t i = 0; i < node.size(); ++i) {
    double v = 0;
    if (node[i].IsScalar() && YAML::convert<double>::decode(node[i], v) && v > 0 &&
        std::isfinite(v)) {
      values.push_back(v);
    } else {
      section.problems()->Add(
          node[i], fmt::format("{}[{}]", section.PathOf(key), i),
          fmt::format("got {}; expected a positive number", DescribeYaml(node[i])));
    }
  }
  if (values.size() == node.size()) *out = std::move(values);
}

// The keys of `synthesise:` (lists left out: Table 1).
struct MatrixKeys {
  std::vector<double> masses{7, 10, 13}, heights{0.2, 0.7, 1.2}, widths{0.10, 0.15, 0.20};
  double noise = 0.05;  // sd of ln(M / Eq. 4)
  std::uint64_t seed = 1;
  YAML::Node spec;  // synth spec keys shared by the tests (undefined: the campaign default)
  YAML::Node node;  // the section, for the line of later errors
};

MatrixKeys ReadMatrixKeys(YamlSection& top) {
  MatrixKeys k;
  k.node = top.Get("synthesise");
  YamlSection s = top.Sub("synthesise");
  ReadPositiveList(s, "mass_kg", &k.masses);
  ReadPositiveList(s, "drop_height_m", &k.heights);
  ReadPositiveList(s, "width_m", &k.widths);
  s.Read("added_mass_noise", &k.noise, ValueRange{0, 1, "", false, true},
         "a standard deviation of ln(M / Eq. 4)");
  s.Read("seed", &k.seed);
  k.spec = s.Get("spec");
  if (k.spec.IsDefined() && !k.spec.IsNull() && !k.spec.IsMap()) {
    s.Problem("spec", fmt::format("got {}; expected a map of synth keys", DescribeYaml(k.spec)));
  }
  s.Finish();
  return k;
}

// `outputs:` {animation, figures}: overrides of every test's scene outputs.
struct OutputOverrides {
  std::optional<bool> animation, figures;
};

OutputOverrides ReadOutputOverrides(YamlSection& top) {
  OutputOverrides o;
  YamlSection s = top.Sub("outputs");
  bool v = false;
  if (s.Read("animation", &v)) o.animation = v;
  if (s.Read("figures", &v)) o.figures = v;
  s.Finish();
  return o;
}

std::string Resolve(const std::string& file, const std::string& path) {
  const fs::path p(path);
  if (p.is_absolute() || file.empty()) return path;
  return (fs::path(file).parent_path() / p).lexically_normal().string();
}

CampaignTest SceneFileTest(const std::string& path, const std::string& where,
                           const std::string& campaign_file) {
  Scene scene;
  try {
    scene = LoadScene(path);
  } catch (const Error& e) {
    if (campaign_file.empty()) throw;
    throw Error(e.kind(), where, e.what(), "a scene file that loads").WithFile(campaign_file);
  }
  CampaignTest t;
  t.scene_path = path;
  t.source = path;
  t.name = scene.name;
  t.hash_hex = ContentHash(scene.yaml_text);
  return t;
}

std::vector<std::string> GlobPaths(const std::string& file, const YAML::Node& node,
                                   const std::string& key, const std::string& pattern) {
  glob_t g{};
  const int rc = glob(Resolve(file, pattern).c_str(), 0, nullptr, &g);
  std::vector<std::string> out;
  for (std::size_t i = 0; rc == 0 && i < g.gl_pathc; ++i) out.push_back(g.gl_pathv[i]);
  globfree(&g);
  if (out.empty())
    Fail(file, node, key, "'" + pattern + "' (matches no file)", "a pattern matching scene files");
  std::sort(out.begin(), out.end());
  return out;
}

// Two independent standard normal numbers per call from a portable generator (Box-Muller on
// mt19937_64's raw output: the same on every standard library, unlike normal_distribution).
double StandardNormal(std::mt19937_64& rng) {
  const double u1 = (static_cast<double>(rng() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
  const double u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;          // [0, 1)
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

// Overlays `over` onto `base` (maps merged key by key, anything else replaced).
void Overlay(YAML::Node base, const YAML::Node& over) {
  for (const auto& kv : over) {
    const std::string key = kv.first.as<std::string>();
    if (kv.second.IsMap() && base[key].IsMap()) {
      Overlay(base[key], kv.second);
    } else {
      base[key] = kv.second;
    }
  }
}

// The synthesised tests' shared spec: the campaign default (docs/campaign.md: the tiny preset,
// frames until the pounder stops, a 4 x 4 momentum grid), or `preset:`, with the keys of
// synthesise.spec over it, read by the synth spec reader (its errors name the key path).
ImpactSceneSpec SharedSpec(const std::string& file, const YAML::Node& node) {
  ImpactSceneSpec base = ImpactScenePreset("tiny");
  base.frames = 0;
  base.grid_cols = 4;
  base.grid_rows = 4;
  if (!node.IsDefined() || node.IsNull()) return base;
  YAML::Node over = YAML::Clone(node);
  if (over["preset"]) {
    base = ImpactScenePreset(over["preset"].as<std::string>());
    over.remove("preset");
  }
  YAML::Node merged = YAML::Load(ImpactSceneSpecToYaml(base));
  Overlay(merged, over);
  YAML::Emitter out;
  out << merged;
  return ParseImpactSceneSpec(out.c_str(), file + " (synthesise.spec)");
}

// Panel scale that makes the momentum grid's soil mass rho_d (cols rows step^2 s^2) t_z equal M:
// the synthetic soil field makes the measured m_add,max equal that grid mass (docs/synth.md), so
// the measured m_add,max follows the M the test is given.
double GridScaleMmPerPx(const ImpactSceneSpec& s, double added_mass_kg) {
  const double area_m2 = added_mass_kg / (s.density_kg_m3 * s.depth_m);
  return 1e3 * std::sqrt(area_m2 / (s.grid_cols * s.grid_rows)) / s.step;
}

std::vector<CampaignTest> MatrixTests(const std::string& file, const MatrixKeys& keys) {
  const YAML::Node& node = keys.node;
  const std::vector<double>&masses = keys.masses, &heights = keys.heights, &widths = keys.widths;
  const double noise = keys.noise;
  const std::uint64_t seed = keys.seed;
  const ImpactSceneSpec shared = SharedSpec(file, keys.spec);
  std::mt19937_64 rng(seed);
  std::vector<CampaignTest> tests;
  for (double m : masses) {
    for (double h : heights) {
      for (double d : widths) {
        CampaignTest t;
        t.synthesise = true;
        t.spec = shared;
        t.spec.name = t.name = fmt::format("m{}_h{}_D{}", m, h, d);
        t.spec.pounder_mass_kg = m;
        t.spec.drop_height_m = h;
        t.spec.impact_velocity_m_s = std::numeric_limits<double>::quiet_NaN();
        t.spec.width_m = d;
        const double eq4 = AddedMassMaxEq4(m, t.spec.ImpactVelocity(), d * t.spec.depth_m);
        t.spec.added_mass = SceneAddedMass::kGiven;
        t.spec.added_mass_kg = eq4 * std::exp(noise * StandardNormal(rng));
        t.spec.mm_per_px = GridScaleMmPerPx(t.spec, t.spec.added_mass_kg);
        t.spec.seed = shared.seed + tests.size();
        const double grid_span_m = (t.spec.grid_cols - 1) * t.spec.step * t.spec.mm_per_px * 1e-3;
        if (grid_span_m > d) {
          Fail(file, node, "synthesise (test " + t.name + ")",
               fmt::format("a momentum grid {:.1f} mm wide under a {:.0f} mm pounder",
                           grid_span_m * 1e3, d * 1e3),
               "a grid beneath the pounder: more momentum.grid_rows or fewer grid_cols in "
               "synthesise.spec");
        }
        t.spec.Check();
        t.source = "synthesised";
        t.hash_hex = ContentHash(ImpactSceneSpecToYaml(t.spec));
        tests.push_back(std::move(t));
      }
    }
  }
  return tests;
}

// The `outputs:` overrides applied to every test (part of its hash).
void ApplyOutputs(const OutputOverrides& o, std::vector<CampaignTest>* tests) {
  const std::optional<bool>&animation = o.animation, &figures = o.figures;
  for (auto& t : *tests) {
    t.animation = animation;
    t.figures = figures;
    t.hash_hex = ContentHash(t.hash_hex + fmt::format(" animation {} figures {}",
                                                      animation ? int(*animation) : -1,
                                                      figures ? int(*figures) : -1));
  }
}

// A name usable as a folder: [A-Za-z0-9._-], not starting with '.', not a campaign file's name.
std::string FolderName(const std::string& name) {
  std::string out;
  for (char c : name)
    out +=
        (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.') ? c : '_';
  if (out.empty() || out[0] == '.') out = "test" + out;
  const auto reserved = campaign_internal::CampaignFileNames();
  if (std::find(reserved.begin(), reserved.end(), out) != reserved.end()) out += "-test";
  return out;
}

// Unique folder names: a name shared by several tests (two scene.yaml in different folders both
// called "scene") gets "-" and 8 hex digits of the hash of its source (path or spec) appended.
void AssignNamesAndIndices(std::vector<CampaignTest>* tests, const std::string& file) {
  std::map<std::string, int> count;
  for (auto& t : *tests) ++count[t.name = FolderName(t.name)];
  std::map<std::string, const CampaignTest*> seen;
  for (std::size_t i = 0; i < tests->size(); ++i) {
    CampaignTest& t = (*tests)[i];
    t.index = static_cast<int>(i) + 1;
    if (count[t.name] > 1) {
      const std::string key =
          t.synthesise ? t.hash_hex : fs::absolute(t.scene_path).lexically_normal().string();
      t.name += "-" + ContentHash(key).substr(0, 8);
    }
    if (seen.count(t.name)) {
      throw Error(ErrorKind::kInvalidValue, "scenes", "'" + t.source + "' listed twice",
                  "each test once")
          .WithFile(file.empty() ? t.source : file);
    }
    seen[t.name] = &t;
  }
}

}  // namespace

std::string CampaignShard::ToString() const { return fmt::format("{}/{}", index, count); }

CampaignShard ParseShard(const std::string& text, const std::string& where) {
  CampaignShard s;
  char slash = 0, extra = 0;
  const int n = std::sscanf(text.c_str(), "%d%c%d%c", &s.index, &slash, &s.count, &extra);
  if (n != 3 || slash != '/' || s.count < 1 || s.index < 1 || s.index > s.count) {
    throw Error(ErrorKind::kInvalidValue, where, "'" + text + "'",
                "I/N with 1 <= I <= N (shard I of N: tests I, I+N, I+2N, ...)");
  }
  return s;
}

bool IsCampaignFile(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path, "a campaign or scene file (YAML)");
  return root.IsMap() && !root["inputs"] &&
         (root["scenes"] || root["scene_glob"] || root["synthesise"]);
}

CampaignPlan LoadCampaignFile(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path, kWhat);
  YamlProblems problems(path);
  YamlSection top(root, "", &problems);
  const std::vector<std::string> files = ReadPaths(top, "scenes");
  const std::vector<std::string> patterns = ReadPaths(top, "scene_glob");
  const bool synthesise = top.Get("synthesise").IsDefined();  // null: Table 1 defaults
  const MatrixKeys matrix = ReadMatrixKeys(top);
  const bool has_outputs = top.Get("outputs").IsDefined();
  const OutputOverrides outputs = ReadOutputOverrides(top);
  top.Finish();
  problems.ThrowIfAny(kWhat);

  CampaignPlan plan;
  plan.path = path;
  std::ifstream in(path);
  plan.yaml_text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  for (std::size_t i = 0; i < files.size(); ++i) {
    plan.tests.push_back(
        SceneFileTest(Resolve(path, files[i]), fmt::format("scenes[{}]", i), path));
  }
  for (const auto& pattern : patterns) {
    for (const auto& f : GlobPaths(path, root["scene_glob"], "scene_glob", pattern))
      plan.tests.push_back(SceneFileTest(f, "scene_glob '" + pattern + "'", path));
  }
  if (synthesise) {
    for (auto& t : MatrixTests(path, matrix)) plan.tests.push_back(std::move(t));
  }
  if (plan.tests.empty()) {
    Fail(path, root, "scenes / scene_glob / synthesise", "no test",
         "at least one scene file, glob match or synthesised test");
  }
  if (has_outputs) ApplyOutputs(outputs, &plan.tests);
  AssignNamesAndIndices(&plan.tests, path);
  return plan;
}

CampaignPlan PlanFromSceneFiles(const std::vector<std::string>& scene_paths) {
  if (scene_paths.empty())
    throw Error(ErrorKind::kInvalidValue, "scenes", "none", "at least one scene file");
  CampaignPlan plan;
  for (const auto& p : scene_paths) plan.tests.push_back(SceneFileTest(p, p, ""));
  AssignNamesAndIndices(&plan.tests, "");
  return plan;
}

}  // namespace impactdic
