// String helpers shared by the modules (file extensions, case-insensitive names, lists in
// messages).
#ifndef IMPACTDIC_CORE_STRINGS_H_
#define IMPACTDIC_CORE_STRINGS_H_

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace impactdic {

// ASCII lower case ("Accel_G" -> "accel_g"); other bytes unchanged.
std::string ToLower(std::string_view text);

bool StartsWith(std::string_view text, std::string_view prefix);
bool EndsWith(std::string_view text, std::string_view suffix);
// EndsWith after ASCII lower-casing text; suffix must be given in lower case (".h5").
bool EndsWithIgnoreCase(std::string_view text, std::string_view suffix);

// The number the whole of `text` spells ("0.25", "1e-3"; std::stod's syntax), or nullopt (empty,
// trailing characters, out of range). NaN and infinities are returned as spelt; callers check
// the range.
std::optional<double> ParseNumber(const std::string& text);

// The items separated by `separator`: {"a", "b", "c"} -> "a, b, c".
std::string Join(const std::vector<std::string>& items, std::string_view separator = ", ");

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_STRINGS_H_
