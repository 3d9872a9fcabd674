// Bindings of synthetic scene spec keys (impact_scene_io.cc, realistic_io.cc): a spec key holds
// any value of its type; the spec's Check() judges the value and names the key.
#ifndef IMPACTDIC_SRC_SYNTH_SPEC_KEYS_H_
#define IMPACTDIC_SRC_SYNTH_SPEC_KEYS_H_

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/io/yaml.h"

namespace impactdic::synth_detail {

inline void Number(YamlOptionTable& t, const std::string& key, double* field) {
  t.AddCustom(
      key, "a number", fmt::format("{}", *field),
      [field](const YAML::Node& n) {
        double v = 0;
        if (!n.IsScalar() || !YAML::convert<double>::decode(n, v) || !std::isfinite(v))
          return false;
        *field = v;
        return true;
      },
      "");
}

inline void Integer(YamlOptionTable& t, const std::string& key, int* field) {
  t.AddCustom(
      key, "an integer", std::to_string(*field),
      [field](const YAML::Node& n) {
        return n.IsScalar() && YAML::convert<int>::decode(n, *field);
      },
      "");
}

inline void Seed(YamlOptionTable& t, const std::string& key, std::uint64_t* field) {
  t.AddCustom(
      key, "a non-negative integer", std::to_string(*field),
      [field](const YAML::Node& n) {
        unsigned long long v = 0;
        if (!n.IsScalar() || !YAML::convert<unsigned long long>::decode(n, v)) return false;
        *field = v;
        return true;
      },
      "");
}

// A YAML list of names (any length).
inline void TextList(YamlOptionTable& t, const std::string& key, std::vector<std::string>* field) {
  t.AddCustom(
      key, "a list of names", "[]",
      [field](const YAML::Node& n) {
        if (!n.IsSequence()) return false;
        std::vector<std::string> v;
        for (const YAML::Node& c : n) {
          if (!c.IsScalar() || c.Scalar().empty()) return false;
          v.push_back(c.Scalar());
        }
        *field = std::move(v);
        return true;
      },
      "");
}

// A YAML list of finite numbers (any length).
inline void NumberList(YamlOptionTable& t, const std::string& key, std::vector<double>* field) {
  t.AddCustom(
      key, "a list of numbers", "[]",
      [field](const YAML::Node& n) {
        if (!n.IsSequence()) return false;
        std::vector<double> v;
        for (const YAML::Node& c : n) {
          double x = 0;
          if (!c.IsScalar() || !YAML::convert<double>::decode(c, x) || !std::isfinite(x))
            return false;
          v.push_back(x);
        }
        *field = std::move(v);
        return true;
      },
      "");
}

}  // namespace impactdic::synth_detail

#endif  // IMPACTDIC_SRC_SYNTH_SPEC_KEYS_H_
