#include "impactdic/pipeline/scene_template.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/yaml.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

// An input the scene must give (CheckScene and the stages' rules), marked `# REQUIRED`; `value`
// (YAML) replaces the default when not empty.
struct RequiredKey {
  const char* key;
  const char* value;
  const char* note;
};

const std::vector<RequiredKey>& RequiredKeys() {
  static const std::vector<RequiredKey> kKeys = {
      {"inputs.frames", "\"frames/*.png\"",
       "REQUIRED: your recording (a folder, a glob, a video or a camera file)"},
      {"inputs.fps", "",
       "REQUIRED for images and videos: your camera's frame rate (a camera file states its own: "
       "then delete this line)"},
      {"inputs.calibration", "",
       "REQUIRED: the scale, from this calibration (impactdic calibrate) or inputs.mm_per_px"},
      {"inputs.mm_per_px", "",
       "REQUIRED unless the calibration has a plane scale: the image scale [mm/px]"},
      {"momentum.pounder_center_x_px", "",
       "REQUIRED with inputs.sensor (the momentum stage), or momentum.rect_mm"},
      {"momentum.surface_y_px", "",
       "REQUIRED with inputs.sensor (the momentum stage), or momentum.rect_mm"},
  };
  return kKeys;
}

const RequiredKey* FindRequired(const std::string& key_path) {
  for (const RequiredKey& r : RequiredKeys())
    if (key_path == r.key) return &r;
  return nullptr;
}

// `text` as a YAML scalar: plain when YAML reads it back as the same text, else double-quoted.
std::string YamlScalar(const std::string& text) {
  if (!text.empty()) {
    try {
      const YAML::Node n = YAML::Load(text);
      if (n.IsScalar() && n.Scalar() == text) return text;
    } catch (const std::exception&) {
      // Not plain YAML: quoted below.
    }
  }
  YAML::Emitter out;
  out << YAML::DoubleQuoted << text;
  return out.c_str();
}

// Whether `value` (YAML) for entry `index` of table `table` leaves the key at its default: the
// key parses and the bound field shows the same default text afterwards.
bool KeepsDefault(std::size_t table, std::size_t index, const std::string& value) {
  Scene scene;
  const std::vector<YamlOptionTable> tables = SceneOptionTables(&scene);
  const YamlOptionTable::Entry& entry = tables[table].entries()[index];
  try {
    if (!entry.parse(YAML::Load(value))) return false;
  } catch (const std::exception&) {
    return false;
  }
  return SceneOptionTables(&scene)[table].entries()[index].default_text == entry.default_text;
}

// The lines of one key: its meaning and expected values as a comment, then `key: value`. A
// default that is no value of the key ("unset", "Eq. 4") is written as an empty value (YAML null:
// the key is not set).
std::string KeyLines(const std::string& indent, const std::string& section, std::size_t table,
                     std::size_t index, const YamlOptionTable::Entry& e) {
  const std::string path = section + "." + e.key;
  std::string text = fmt::format("{}# {}. Expected: {}.\n", indent, e.doc, e.expected);
  const RequiredKey* required = FindRequired(path);
  std::string value = required && *required->value ? required->value : YamlScalar(e.default_text);
  std::string note;
  if (!(required && *required->value) && !KeepsDefault(table, index, value)) {
    value.clear();
    note = fmt::format("empty: the default ({})", e.default_text.empty() ? "none" : e.default_text);
  }
  if (required) note = required->note + (note.empty() ? "" : "; " + note);
  text += fmt::format("{}{}:{}{}\n", indent, e.key, value.empty() ? "" : " " + value,
                      note.empty() ? "" : "  # " + note);
  return text;
}

// The keys of a section that are not one field (ParseScene reads them itself), as comments.
std::string ExtraKeyLines(const std::string& section, const std::string& indent) {
  if (section == "dic") {
    return indent +
           "# roi: [x0, y0, x1, y1]  Region of interest [px] in the first frame; not set (the "
           "default): the whole image less margins.\n" +
           indent +
           "# roi_polygon: [[x, y], [x, y], [x, y]]  Polygon region of interest [px], >= 3 "
           "vertices; not set (the default): none.\n";
  }
  if (section == "momentum") {
    return indent +
           "# rect_mm: [x0, y0, x1, y1]  Momentum grid rectangle [mm] instead of the pounder's "
           "position; not set (the default): from the position.\n";
  }
  return "";
}

// "preprocess.gaussian" -> {"preprocess", "gaussian"}.
std::vector<std::string> SectionPath(const std::string& section) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  for (std::size_t dot = section.find('.'); dot != std::string::npos;
       begin = dot + 1, dot = section.find('.', begin))
    parts.push_back(section.substr(begin, dot - begin));
  parts.push_back(section.substr(begin));
  return parts;
}

std::string Header() {
  return fmt::format(
      "# impactdic scene file, written by `impactdic init`.\n"
      "# Every key below holds the library's default. Fill in the lines marked REQUIRED, set the\n"
      "# test (pounder, soil: the defaults are the paper's sample test) and whatever else your\n"
      "# test needs, then run:\n"
      "#   impactdic run scene.yaml\n"
      "# Relative paths resolve against this file's folder. Every key and the format:\n"
      "# docs/scene_keys.md. A key left empty (or deleted) keeps its default.\n"
      "\n"
      "# name: my_test  Free-form name; not set (the default): the file's stem.\n"
      "# stages: [{}]  Stages to run; not set (the default): all whose inputs exist.\n",
      Join(AllSceneStages()));
}

}  // namespace

std::string SceneTemplate() {
  Scene scene;
  const std::vector<YamlOptionTable> tables = SceneOptionTables(&scene);
  std::string text = Header();
  std::vector<std::string> open;  // The section path written last ("preprocess", "gaussian").
  for (std::size_t t = 0; t < tables.size(); ++t) {
    const std::vector<std::string> parts = SectionPath(tables[t].section());
    std::size_t common = 0;
    while (common < open.size() && common < parts.size() && open[common] == parts[common]) ++common;
    for (std::size_t d = common; d < parts.size(); ++d)
      text += fmt::format("{}{:{}}{}:\n", d == 0 ? "\n" : "", "", 2 * d, parts[d]);
    open = parts;
    const std::string indent(2 * parts.size(), ' ');
    const std::vector<YamlOptionTable::Entry>& entries = tables[t].entries();
    for (std::size_t i = 0; i < entries.size(); ++i)
      text += KeyLines(indent, tables[t].section(), t, i, entries[i]);
    text += ExtraKeyLines(tables[t].section(), indent);
  }
  return text;
}

std::string WriteSceneTemplate(const std::string& folder, bool force) {
  std::error_code ec;
  MakeFolders(folder, ec);
  if (ec) throw Error(ErrorKind::kIo, folder + ": cannot create the folder: " + ec.message());
  std::string path = (std::filesystem::path(folder) / "scene.yaml").string();
  if (!force && std::filesystem::exists(path)) {
    throw Error(ErrorKind::kInvalidValue,
                path + " exists; `impactdic init --force` overwrites it, or give another folder");
  }
  WriteTextFileAtomic(path, SceneTemplate());
  return path;
}

}  // namespace impactdic
