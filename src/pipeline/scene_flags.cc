#include "impactdic/pipeline/scene_flags.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/yaml.h"

namespace impactdic {

const std::vector<SceneFlagAlias>& SceneFlagAliases() {
  static const std::vector<SceneFlagAlias> kAliases = {
      {"correlate", "inputs.frames", "--frames"},
      {"correlate", "dic.subset_size", "--subset"},
      {"correlate", "dic.step", "--step"},
      {"correlate", "dic.roi", "--roi"},
      {"correlate", "dic.mask", "--mask"},
      {"correlate", "dic.interpolation", "--interp"},
      {"correlate", "dic.shape", "--shape"},
      {"correlate", "dic.reference_update", "--reference-update"},
      {"correlate", "dic.mode", "--mode"},
      {"correlate", "dic.first_frame_number", "--first"},
      {"correlate", "dic.last_frame_number", "--last"},
      {"correlate", "dic.threads", "--threads"},
      {"correlate", "dic.keep_warp_gradient", "--warp-gradient", /*is_switch=*/true},
      {"correlate", "dic.search_radius_px", "--search-radius"},
      {"correlate", "dic.min_zncc", "--min-zncc"},
      {"correlate", "dic.max_uncertainty_px", "--max-uncertainty"},
      {"correlate", "dic.continuity_check", "--continuity-check"},
      {"correlate", "dic.continuity_misfit_ratio", "--continuity-misfit-ratio"},
      {"correlate", "dic.continuity_min_misfit", "--continuity-min-misfit"},
      {"correlate", "dic.continuity_max_second_difference_px",
       "--continuity-max-second-difference"},
      {"correlate", "dic.continuity_max_neighbour_difference_px",
       "--continuity-max-neighbour-difference"},
      {"correlate", "dic.continuity_local_ratio", "--continuity-local-ratio"},
      {"correlate", "dic.outlier_check", "--outlier-check"},
      {"correlate", "dic.outlier_threshold", "--outlier-threshold"},
      {"correlate", "dic.outlier_noise_px", "--outlier-noise"},
      {"correlate", "dic.outlier_sigma_factor", "--outlier-sigma-factor"},
      {"analyze", "sensor.cutoff_hz", "--cutoff"},
      {"analyze", "sensor.time_column", "--time-column"},
      {"analyze", "sensor.accel_column", "--accel-column"},
      {"analyze", "sensor.accel_unit", "--accel-unit"},
      {"analyze", "sensor.exposure_column", "--exposure-column"},
      {"analyze", "sensor.quiet_window_s", "--quiet-window"},
      {"analyze", "sensor.offset_reference", "--offset-reference"},
      {"analyze", "sensor.release_time_s", "--release-time"},
      {"analyze", "sensor.impact_threshold_g", "--impact-threshold"},
      {"analyze", "sensor.integrate_from", "--from-release"},  // A flag: integrate_from release.
      {"analyze", "test.impact_velocity_m_s", "--impact-velocity"},
      {"analyze", "inputs.sensor", "--sensor"},
      {"model", "test.mass_kg", "--mass"},
      {"model", "test.drop_height_m", "--height"},
      {"model", "test.impact_velocity_m_s", "--velocity"},
      {"model", "test.width_m", "--width"},
      {"model", "test.depth_m", "--depth"},
      {"model", "test.density_kg_m3", "--rho"},
      {"model", "test.bed_height_m", "--bed-height"},
      {"model", "test.g_m_s2", "--g"},
      {"model", "model.added_mass_kg", "--added-mass"},
      {"model", "model.K", "--K"},
      {"model", "model.n", "--n"},
      {"model", "model.u", "--u"},
      {"model", "model.T_s", "--T"},
      {"model", "model.b_per_s", "--b"},
      {"model", "model.solver", "--solver"},
      {"model", "model.rtol", "--rtol"},
      {"model", "model.atol", "--atol"},
      {"model", "model.error_estimator", "--error-estimate"},
      {"model", "model.ode45_defaults", "--ode45-defaults"},
      {"model", "model.t_max_s", "--t-max"},
      {"render", "outputs.video.codec", "--codec"},
      {"calibrate", "calibration.min_views", "--min-views"},
      {"calibrate", "calibration.max_rms_px", "--max-rms"},
      {"calibrate", "calibration.fix_k3", "--fix-k3", /*is_switch=*/true},
      {"calibrate", "calibration.model", "--model"},
      {"render", "outputs.video.fps", "--fps"},
  };
  return kAliases;
}

std::string SceneFlagNames(const std::string& command, const std::string& key) {
  std::string names = "--" + key;
  for (const SceneFlagAlias& a : SceneFlagAliases())
    if (command == a.command && key == a.key) names += std::string(",") + a.alias;
  return names;
}

std::string SceneFlagShortName(const std::string& command, const std::string& key) {
  for (const SceneFlagAlias& a : SceneFlagAliases())
    if (command == a.command && key == a.key) return a.alias;
  return "--" + key;
}

namespace {

bool InSections(const std::string& section, const std::vector<std::string>& sections) {
  for (const std::string& s : sections)
    if (section == s || section.rfind(s + ".", 0) == 0) return true;
  return false;
}

}  // namespace

std::vector<SceneKeyFlag> SceneKeyFlags(const std::vector<std::string>& sections) {
  Scene defaults;
  std::vector<SceneKeyFlag> flags;
  for (const YamlOptionTable& table : SceneOptionTables(&defaults)) {
    const bool all = InSections(table.section(), sections);
    for (const SceneKeyFlag& f : OptionTableFlags({table}))
      if (all || std::find(sections.begin(), sections.end(), f.key) != sections.end())
        flags.push_back(f);
  }
  return flags;
}

std::vector<SceneKeyFlag> OptionTableFlags(const std::vector<YamlOptionTable>& tables) {
  std::vector<SceneKeyFlag> flags;
  for (const YamlOptionTable& table : tables) {
    for (const YamlOptionTable::Entry& e : table.entries())
      flags.push_back({table.section() + "." + e.key, e.doc + "; " + e.expected, e.default_text});
  }
  return flags;
}

namespace {

// dic.roi as a flag's text "X0,Y0,X1,Y1" (four integers [px]). Error naming `flag` otherwise.
std::array<int, 4> RoiFromText(const std::string& text, const std::string& flag) {
  std::vector<int> v;
  std::stringstream ss(text);
  bool ok = true;
  for (std::string item; std::getline(ss, item, ',');) {
    const std::optional<double> number = ParseNumber(item);
    ok = ok && number && *number == std::floor(*number) && std::abs(*number) < 1e9;
    v.push_back(ok ? static_cast<int>(*number) : 0);
  }
  CheckValue(ok && v.size() == 4, flag, text, "X0,Y0,X1,Y1 (four integers, pixels)");
  CheckValue(v[0] >= 0 && v[1] >= 0 && v[2] > v[0] && v[3] > v[1], flag, text,
             "0 <= X0 < X1 and 0 <= Y0 < Y1");
  return {v[0], v[1], v[2], v[3]};
}

}  // namespace

void SetSceneKey(Scene* scene, const std::string& key, const std::string& value,
                 const std::string& flag) {
  if (key == "dic.roi") {  // Not a field of the tables (ParseScene reads it as a list).
    scene->dic.roi = RoiFromText(value, flag);
    return;
  }
  SetOptionTableKey(SceneOptionTables(scene), key, value, flag);
}

void SetOptionTableKey(const std::vector<YamlOptionTable>& tables, const std::string& key,
                       const std::string& value, const std::string& flag) {
  for (const YamlOptionTable& table : tables) {
    for (const YamlOptionTable::Entry& e : table.entries()) {
      if (table.section() + "." + e.key != key) continue;
      // A number as written, text quoted (as the library's own messages show them).
      CheckValue(e.parse(YAML::Node(value)), flag, ParseNumber(value) ? value : "'" + value + "'",
                 e.expected);
      return;
    }
  }
  throw std::logic_error("SetOptionTableKey: no key " + key);
}

}  // namespace impactdic
