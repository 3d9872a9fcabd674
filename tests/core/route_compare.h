// Test helper: compares the outputs of two routes to the same numbers (`run` against `analyze`
// of its results, or of `correlate`'s): HDF5 datasets listed recursively, and JSON/YAML trees
// whose numbers agree to kTolerance (relative).
#ifndef IMPACTDIC_TESTS_CORE_ROUTE_COMPARE_H_
#define IMPACTDIC_TESTS_CORE_ROUTE_COMPARE_H_

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/io/hdf5_store.h"

namespace impactdic {

inline constexpr double kTolerance = 1e-12;  // Relative; the same stages on the same rows.

inline bool Equal(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return std::abs(a - b) <= kTolerance * std::max({1e-300, std::abs(a), std::abs(b)});
}

// Every dataset below `group` (recursively), as paths.
inline void Datasets(const H5Reader& in, const std::string& group, std::vector<std::string>* out) {
  for (const std::string& name : in.List(group)) {
    const std::string path = std::string(group).append("/").append(name);
    bool dataset = true;
    try {
      in.Dimensions(path);
    } catch (const Error&) {
      dataset = false;  // A group.
    }
    if (dataset) {
      out->push_back(path);
    } else {
      Datasets(in, path, out);
    }
  }
}

// The differences between two JSON values (numbers to kTolerance), each naming its key path.
inline void Compare(const YAML::Node& a, const YAML::Node& b, const std::string& path,
                    std::vector<std::string>* differences) {
  if (a.Type() != b.Type()) {
    differences->push_back(path + ": of another type");
  } else if (a.IsMap()) {
    for (const auto& entry : b) {
      const std::string key = entry.first.as<std::string>();
      const std::string at = std::string(path).append(".").append(key);
      if (!a[key]) {
        differences->push_back(at + ": missing");
      } else {
        Compare(a[key], entry.second, at, differences);
      }
    }
    if (a.size() != b.size()) differences->push_back(path + ": other keys");
  } else if (a.IsSequence()) {
    if (a.size() != b.size()) {
      differences->push_back(path + ": another length");
      return;
    }
    for (std::size_t i = 0; i < a.size(); ++i)
      Compare(a[i], b[i], path + "[" + std::to_string(i) + "]", differences);
  } else if (a.IsScalar()) {
    double x = 0, y = 0;
    const bool numbers = a.Tag() != "!" && b.Tag() != "!" && YAML::convert<double>::decode(a, x) &&
                         YAML::convert<double>::decode(b, y);
    if (numbers ? !Equal(x, y) : a.Scalar() != b.Scalar())
      differences->push_back(path + ": " + a.Scalar() + " vs " + b.Scalar());
  }
}

// The differences between two JSON trees, one line each ("" when none).
inline std::string Differences(const YAML::Node& a, const YAML::Node& b, const std::string& root) {
  std::vector<std::string> differences;
  Compare(a, b, root, &differences);
  std::string listed;
  for (const std::string& d : differences) listed += "  " + d + "\n";
  return listed;
}

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_CORE_ROUTE_COMPARE_H_
