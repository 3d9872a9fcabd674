#include "impactdic/core/range.h"

#include <fmt/format.h>

#include "impactdic/core/error.h"

namespace impactdic {

std::string ValueRange::Text() const {
  return fmt::format("{}{:g}, {:g}{}{}{}", min_open ? '(' : '[', min, max, max_open ? ')' : ']',
                     unit[0] ? " " : "", unit);
}

void CheckRange(double value, const ValueRange& range, const std::string& where,
                const std::string& what) {
  if (range.Contains(value)) return;
  throw Error(ErrorKind::kInvalidValue, where, fmt::format("{:g}", value),
              what + " in " + range.Text());
}

}  // namespace impactdic
