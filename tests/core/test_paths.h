// Test helper: where the tests find the project's files and the built command-line tool.
//
// The paths are compiled into one object (test_paths.cc, linked into every test program by
// impactdic_add_test), not into each test file: a test file's compile command then holds no path
// of the checkout, so a compiler cache (scripts/test.sh) reuses its object in another clone.
#ifndef IMPACTDIC_TESTS_CORE_TEST_PATHS_H_
#define IMPACTDIC_TESTS_CORE_TEST_PATHS_H_

namespace impactdic {

// The project's root folder (the one with CMakeLists.txt, sample_frames/, docs/).
const char* SourceDir();

// The built `impactdic` program of this build tree.
const char* CliPath();

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_CORE_TEST_PATHS_H_
