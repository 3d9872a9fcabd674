#include "impactdic/core/range.h"

#include <fmt/format.h>

#include "impactdic/core/error.h"

namespace impactdic {

std::string ValueRange::Text() const {
  return fmt::format("{}{:g}, {:g}{}{}{}", min_open ? '(' : '[', min, max, max_open ? ')' : ']',
                     unit[0] ? " " : "", unit);
}

std::string ExpectedText(const std::string& what, const ValueRange& range) {
  constexpr double kUnbounded = 1e300;
  const std::string unit = range.unit[0] ? std::string(" ") + range.unit : "";
  if (range.max < kUnbounded) return what + " in " + range.Text();
  if (range.min <= -kUnbounded) return what + (unit.empty() ? "" : " [" + unit.substr(1) + "]");
  return fmt::format("{} {} {:g}{}", what, range.min_open ? ">" : ">=", range.min, unit);
}

void CheckRange(double value, const ValueRange& range, const std::string& where,
                const std::string& what) {
  if (range.Contains(value)) return;
  throw Error(ErrorKind::kInvalidValue, where, fmt::format("{:g}", value),
              ExpectedText(what, range));
}

}  // namespace impactdic
