// Test helper: the public benchmark data (DIC Challenge samples, real sand footage, Cine files)
// that lives beside the project, never in it (../shared/data/README.md), or a skip or a failure
// when it is not there. Every test that reads that data finds it through this header.
//
//   TEST(Sample12, ...) {
//     IMPACTDIC_SHARED_DATA_OR_SKIP(sample12, "dic-challenge/sample12");
//     ... sample12 / "images" / "oht_cfrp_00.tiff" ...
//   }
//
// The data folder is $IMPACTDIC_SHARED_DATA if set, else ../shared/data beside the project root
// (SourceDir(), tests/core/test_paths.h). When it, or the sub-folder asked for,
// is absent or empty, the test is skipped with a message naming the folder, unless
// IMPACTDIC_REQUIRE_SHARED_DATA is set to anything but "" or "0": then the test fails with that
// message. scripts/test.sh (so CI) sets it to 1: a CI run without the data fails instead of
// passing on skipped tests.
#ifndef IMPACTDIC_TESTS_CORE_SHARED_DATA_H_
#define IMPACTDIC_TESTS_CORE_SHARED_DATA_H_

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

#include "test_paths.h"

namespace impactdic {

// The shared data folder (it may not exist).
inline std::filesystem::path SharedDataRoot() {
  const char* env = std::getenv("IMPACTDIC_SHARED_DATA");
  if (env && *env) return std::filesystem::path(env);
  return (std::filesystem::path(impactdic::SourceDir()) / ".." / "shared" / "data")
      .lexically_normal();
}

// True when a missing shared data folder must fail the test (IMPACTDIC_REQUIRE_SHARED_DATA).
inline bool SharedDataRequired() {
  const char* env = std::getenv("IMPACTDIC_REQUIRE_SHARED_DATA");
  return env && *env && std::string(env) != "0";
}

struct SharedDataLookup {
  std::filesystem::path folder;  // root / sub
  std::string missing;           // empty when the folder exists and holds something
};

// Looks up `sub` (e.g. "dic-challenge/sample3"; "" for the root) below SharedDataRoot().
inline SharedDataLookup FindSharedData(const std::string& sub) {
  SharedDataLookup lookup;
  lookup.folder = sub.empty() ? SharedDataRoot() : SharedDataRoot() / sub;
  std::error_code ec;
  if (!std::filesystem::is_directory(lookup.folder, ec) ||
      std::filesystem::is_empty(lookup.folder, ec)) {
    lookup.missing = "shared benchmark data not found: no folder " + lookup.folder.string() +
                     " (../shared/data beside the project root, see its README.md; or set "
                     "IMPACTDIC_SHARED_DATA=DIR)";
  }
  return lookup;
}

}  // namespace impactdic

// Declares `const std::filesystem::path& var` = the shared data folder `sub`, or ends the test:
// skipped when the folder is absent, failed when IMPACTDIC_REQUIRE_SHARED_DATA is set. Use in a
// test body (or a void function called from one, followed by a check of HasFatalFailure()).
#define IMPACTDIC_SHARED_DATA_OR_SKIP(var, sub)                                          \
  const ::impactdic::SharedDataLookup var##_lookup = ::impactdic::FindSharedData(sub);   \
  if (!var##_lookup.missing.empty()) {                                                   \
    if (::impactdic::SharedDataRequired()) {                                             \
      FAIL() << var##_lookup.missing                                                     \
             << "; IMPACTDIC_REQUIRE_SHARED_DATA is set (scripts/test.sh, CI), so this " \
                "test fails instead of being skipped";                                   \
    }                                                                                    \
    GTEST_SKIP() << var##_lookup.missing;                                                \
  }                                                                                      \
  const std::filesystem::path& var = var##_lookup.folder

#endif  // IMPACTDIC_TESTS_CORE_SHARED_DATA_H_
