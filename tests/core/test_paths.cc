// The paths of tests/core/test_paths.h, given by CMake to this file alone
// (tests/core/CMakeLists.txt).
#include "test_paths.h"

namespace impactdic {

const char* SourceDir() { return IMPACTDIC_TEST_SOURCE_DIR; }

const char* CliPath() { return IMPACTDIC_TEST_CLI_PATH; }

}  // namespace impactdic
