#include "impactdic/core/threads.h"

#include "impactdic/core/error.h"

namespace impactdic {

void CheckThreadCount(int threads, const std::string& where) {
  CheckValue(IsValidThreadCount(threads), where, std::to_string(threads), kThreadCountExpected);
}

}  // namespace impactdic
