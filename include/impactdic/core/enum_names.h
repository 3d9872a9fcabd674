// The written names of an enum's values, defined once beside the enum: its ToString and
// FromString, the scene's choice keys (YamlOptionTable::AddChoice) and the messages read them.
//
//   inline constexpr EnumNames<Shape, 2> kShapeNames{{{{Shape::kAffine, "affine"},
//                                                       {Shape::kQuadratic, "quadratic"}}}};
//   kShapeNames.Name(Shape::kAffine)          -> "affine"
//   kShapeNames.Parse("cubic", "dic.shape")   -> Error "dic.shape: ... expected one of affine,
//                                                quadratic"
#ifndef IMPACTDIC_CORE_ENUM_NAMES_H_
#define IMPACTDIC_CORE_ENUM_NAMES_H_

#include <algorithm>
#include <array>  // IWYU pragma: export (EnumNames::entries)
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/strings.h"

namespace impactdic {

template <typename E>
struct EnumName {
  E value;
  const char* name;          // As written in scenes and on the command line, and as printed.
  const char* aliases = "";  // Other accepted spellings, separated by spaces ("m_s2 m/s2").
};

template <typename E, std::size_t N>
struct EnumNames {
  std::array<EnumName<E>, N> entries;
  bool ignore_case = false;  // "G" is "g".

  // The name of `value` ("?" for a value without one, which is a programming error).
  const char* Name(E value) const {
    for (const EnumName<E>& e : entries) {
      if (e.value == value) return e.name;
    }
    return "?";
  }
  std::vector<std::string> Names() const {
    std::vector<std::string> names;
    for (const EnumName<E>& e : entries) names.emplace_back(e.name);
    return names;
  }
  // "one of affine, quadratic".
  std::string Expected() const { return "one of " + Join(Names()); }
  // The value named (or aliased) `text`; Error(kInvalidValue, where, 'text', Expected())
  // otherwise.
  E Parse(const std::string& text, const std::string& where) const {
    const std::string t = ignore_case ? ToLower(text) : text;
    for (const EnumName<E>& e : entries) {
      if (t == e.name) return e.value;
      std::string_view aliases = e.aliases;
      while (!aliases.empty()) {
        const std::size_t end = std::min(aliases.find(' '), aliases.size());
        if (end > 0 && t == aliases.substr(0, end)) return e.value;
        aliases.remove_prefix(std::min(end + 1, aliases.size()));
      }
    }
    throw Error(ErrorKind::kInvalidValue, where, "'" + text + "'", Expected());
  }
};

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_ENUM_NAMES_H_
