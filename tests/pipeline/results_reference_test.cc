// docs/results.md, the results reference, is generated from a results.h5 that `impactdic run`
// writes: every group, dataset and attribute the writers make, each dataset with its shape (in
// the layout's symbols), type and the `units` and `description` attributes its writer gave it. The
// run is the small synthesised scene with every optional group on (strain, the XDMF views, the
// preview frames), so the page lists everything a run can write. Run with IMPACTDIC_UPDATE_DOCS=1
// to rewrite the page after changing a writer.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cstddef>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "impactdic/io/results_layout.h"
#include "small_scene_spec.h"

namespace impactdic {
namespace {

namespace L = results_layout;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// One object of the file: a group or a dataset, its attributes' names, and for a dataset its
// dimensions, type and the values of its `units` and `description` attributes.
struct Object {
  bool dataset = false;
  std::vector<hsize_t> dims;
  std::string type, units, description;
  std::set<std::string> attributes;  // Besides units and description.
};

std::string StringAttribute(hid_t object, const char* name) {
  if (H5Aexists(object, name) <= 0) return "";
  const hid_t attr = H5Aopen(object, name, H5P_DEFAULT);
  const hid_t type = H5Aget_type(attr);
  std::string value;
  if (H5Tget_class(type) == H5T_STRING) {
    if (H5Tis_variable_str(type) > 0) {
      char* text = nullptr;
      const hid_t memory = H5Tcopy(H5T_C_S1);
      H5Tset_size(memory, H5T_VARIABLE);
      H5Tset_cset(memory, H5Tget_cset(type));  // HDF5 converts no ASCII to UTF-8 or back.
      if (H5Aread(attr, memory, &text) >= 0 && text != nullptr) value = text;
      H5free_memory(text);
      H5Tclose(memory);
    } else {
      std::vector<char> buffer(H5Tget_size(type) + 1, 0);
      H5Aread(attr, type, buffer.data());
      value = buffer.data();
    }
  }
  H5Tclose(type);
  H5Aclose(attr);
  return value;
}

std::string TypeName(hid_t dataset) {
  const hid_t type = H5Dget_type(dataset);
  std::string name;
  const std::size_t bits = 8 * H5Tget_size(type);
  switch (H5Tget_class(type)) {
    case H5T_FLOAT: name = "float" + std::to_string(bits); break;
    case H5T_INTEGER:
      name = (H5Tget_sign(type) == H5T_SGN_NONE ? "uint" : "int") + std::to_string(bits);
      break;
    case H5T_STRING: name = "string"; break;
    default: name = "other";
  }
  H5Tclose(type);
  return name;
}

herr_t AttributeName(hid_t, const char* name, const H5A_info_t*, void* data) {
  static_cast<std::set<std::string>*>(data)->insert(name);
  return 0;
}

herr_t Visit(hid_t file, const char* name, const H5O_info_t* info, void* data) {
  auto& objects = *static_cast<std::map<std::string, Object>*>(data);
  const std::string path = std::string(name) == "." ? "/" : "/" + std::string(name);
  Object o;
  const hid_t object = H5Oopen(file, name, H5P_DEFAULT);
  hsize_t index = 0;
  H5Aiterate2(object, H5_INDEX_NAME, H5_ITER_INC, &index, AttributeName, &o.attributes);
  if (info->type == H5O_TYPE_DATASET) {
    o.dataset = true;
    const hid_t space = H5Dget_space(object);
    o.dims.resize(H5Sget_simple_extent_ndims(space));
    H5Sget_simple_extent_dims(space, o.dims.data(), nullptr);
    H5Sclose(space);
    o.type = TypeName(object);
    o.units = StringAttribute(object, "units");
    o.description = StringAttribute(object, "description");
    o.attributes.erase("units");
    o.attributes.erase("description");
  }
  H5Oclose(object);
  objects[path] = o;
  return 0;
}

// Every object of the file by path (H5Ovisit, names in order).
std::map<std::string, Object> Objects(const std::string& path) {
  std::map<std::string, Object> objects;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(file, 0) << path;
  if (file < 0) return objects;
#if H5_VERSION_GE(1, 12, 0)
  H5Ovisit(file, H5_INDEX_NAME, H5_ITER_INC, Visit, &objects, H5O_INFO_BASIC);
#else
  H5Ovisit(file, H5_INDEX_NAME, H5_ITER_INC, Visit, &objects);
#endif
  H5Fclose(file);
  return objects;
}

std::string Join(const std::set<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "`" : ", `") + n + "`";
  return text;
}

// The page: the layout's symbols for the dimensions of this file (each must be a different
// number, else the shapes would be ambiguous), then one section per top-level group.
std::string Reference(const std::map<std::string, Object>& all) {
  const auto length = [&](const char* path, std::size_t axis = 0) {
    return all.count(path) ? static_cast<hsize_t>(all.at(path).dims.at(axis)) : hsize_t{0};
  };
  const std::vector<std::pair<std::string, hsize_t>> symbols = {
      {"F", length(L::kTimeMs)},
      {"N", length(L::kDicX)},
      {"K", length("/sensor/t_s")},
      {"K_a", length("/momentum/added_mass_daq/t_s")},
      {"K_m", length("/model/t_s")},
      {"P", length("/frames/images")},
      {"R'", length("/frames/images", 1)},
      {"C'", length("/frames/images", 2)},
      {"G", length("/momentum/grid_subset_ids")},
      {"C", length("/wave/depth_mm")},
  };
  std::map<hsize_t, std::string> symbol_of;
  for (const auto& [symbol, n] : symbols) {
    EXPECT_GT(n, 0u) << symbol << ": the run wrote no such dataset";
    EXPECT_TRUE(symbol_of.emplace(n, symbol).second)
        << symbol << " and " << symbol_of[n] << " are both " << n << ": choose another scene";
  }
  // The per-frame groups of /xdmf are one entry: /xdmf/frame_FFFFFF.
  static const std::regex kFrameGroup("frame_[0-9]{6}");
  static const std::regex kRow("row [0-9]+ of");
  std::map<std::string, std::map<std::string, Object>> groups;  // top-level group -> objects
  for (const auto& [path, object] : all) {
    const std::string shown = std::regex_replace(path, kFrameGroup, "frame_FFFFFF");
    const std::size_t slash = shown.find('/', 1);
    Object o = object;
    o.description = std::regex_replace(o.description, kRow, "row f of");
    groups[shown.substr(0, slash)][shown] = o;
  }
  std::string text;
  for (const auto& [group, objects] : groups) {
    text += "\n## " + group + "\n\n";
    std::string table;
    for (const auto& [path, o] : objects) {
      if (!o.dataset) {
        if (!o.attributes.empty()) {
          text += "Attributes of `" + path + "`: " + Join(o.attributes) + ".\n\n";
        }
        continue;
      }
      std::string shape;
      for (const hsize_t d : o.dims) {
        shape += (shape.empty() ? "" : " x ") +
                 (symbol_of.count(d) ? symbol_of.at(d) : std::to_string(d));
      }
      table += "| `" + path + "` | " + shape + " | " + o.type + " | " + o.units + " | " +
               o.description +
               (o.attributes.empty() ? "" : " (attributes " + Join(o.attributes) + ")") + " |\n";
    }
    if (table.empty()) {
      text.pop_back();  // One blank line before the next section.
    } else {
      text += "| dataset | shape | type | units | description |\n|---|---|---|---|---|\n" + table;
    }
  }
  return text;
}

// Four base force sensors (a number no other dimension of the file has), so that /wave is written.
constexpr const char* kBaseSensors =
    "base_sensors:\n  columns: [base_a_N, base_b_N, base_c_N, base_d_N]\n"
    "  offsets_mm: [0, 100, 200, 300]\n  depths_mm: [600, 600, 600, 600]\n"
    "  areas_mm2: [2000, 2000, 2000, 2000]\n";

TEST(ResultsReference, IsGeneratedFromTheFileARunWrites) {
  TestDir dir("ResultsReference");
  // 30 frames: more than the preview stores, so P and F differ.
  const CliResult synth =
      RunCli("-q synth " + dir.Write("spec.yaml", SmallSceneSpec({.frames = 30}) + kBaseSensors) +
             " -o " + dir.File("scene"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  // Every optional group on; the figures off (not part of results.h5).
  const CliResult run = RunCli("-q run " + dir.File("scene/scene.yaml") + " -o " + dir.File("out") +
                               " --strain.enabled true --outputs.xdmf true --outputs.frames preview"
                               " --outputs.figures false --outputs.animation false");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::map<std::string, Object> objects = Objects(dir.File("out/results.h5"));
  for (const char* group : {L::kTimeGroup, L::kDicGroup, "/sensor", "/kinematics", "/momentum",
                            "/model", "/strain", "/frames", "/xdmf", "/wave"}) {
    EXPECT_TRUE(objects.count(group)) << group << " not written";
  }
  // Every dataset says what it holds.
  for (const auto& [path, o] : objects) {
    if (o.dataset && path.rfind("/xdmf/", 0) != 0) {
      EXPECT_FALSE(o.description.empty()) << path << " has no description attribute";
    }
  }
  const std::string expected =
      "# Results reference: results.h5\n\n"
      "<!-- Generated from the results.h5 that `impactdic run` writes (a small synthesised scene "
      "with\nstrain, XDMF views, preview frames and four base force sensors on) by\n"
      "`IMPACTDIC_UPDATE_DOCS=1 build/release/tests/pipeline/pipeline_results_reference_test`;\n"
      "the test fails when this page is out of date. -->\n\n"
      "`impactdic run` writes one HDF5 file, `results.h5`, with a group per stage; `correlate -o "
      "X.h5`\nwrites the same `/dic`, `model -o X.h5` the same `/model`. Plain HDF5, row-major "
      "(MATLAB's `h5read`\nshows the dimensions reversed); every dataset carries the `units` and "
      "`description` below;\ndatasets of 4096 values or more are chunked and deflate-compressed. "
      "Names are declared once, in\n`include/impactdic/io/results_layout.h` and the owner of each "
      "group (`io/dic_results.h`,\n`sensor/sensor_results.h`, `kinematics/kinematics_results.h`, "
      "`momentum/momentum_results.h`,\n`model/model_results.h`, `strain/strain_results.h`, "
      "`sensor/frame_timeline.h`,\n`sensor/wave_results.h`). Reading it in Python, ParaView or "
      "VisIt: [python.md](python.md).\n\n"
      "Shapes: F = analysed frames (row 0 is the reference: the last frame before the impact, or 4 "
      "before it with base channels), N = "
      "subsets,\nK = DAQ samples, K_a = DAQ samples of the peak stage's added mass, K_m = steps "
      "of the model's output,\nP = stored preview frames of R' x C' pixels, G = subsets of the "
      "momentum grid, C = base force\nsensors. A group or dataset that a scene does not ask for is "
      "absent: `/sensor` and `/momentum` need\na sensor record, `/wave` base force channels "
      "(`sensor.base_columns`, docs/wave.md), `/strain`\n`strain.enabled`, `/xdmf` `outputs.xdmf`, "
      "`/frames` `outputs.frames` other than `none`. The key\nfigures are also in `summary.json` "
      "and `summary.csv` (a figure that could not be measured is null,\nwith the reason); wall "
      "times in `timing.json`.\n" +
      Reference(objects);
  const std::string path = std::string(impactdic::SourceDir()) + "/docs/results.md";
  if (std::getenv("IMPACTDIC_UPDATE_DOCS")) std::ofstream(path) << expected;
  EXPECT_EQ(ReadText(path), expected) << "docs/results.md is out of date; regenerate it:\n"
                                      << "IMPACTDIC_UPDATE_DOCS=1 build/release/tests/pipeline/"
                                         "pipeline_results_reference_test";
}

}  // namespace
}  // namespace impactdic
