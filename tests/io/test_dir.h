// A fresh temporary folder per test (and per process: CTest runs tests in parallel processes),
// removed afterwards.
#ifndef IMPACTDIC_TESTS_IO_TEST_DIR_H_
#define IMPACTDIC_TESTS_IO_TEST_DIR_H_

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace impactdic {

class TestDir {
 public:
  // Named after the running test; `name` is needed where no test runs (SetUpTestSuite).
  explicit TestDir(const std::string& name = "") {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::string stem =
        !name.empty() ? name : std::string(info->test_suite_name()) + "_" + info->name();
    path_ = std::filesystem::temp_directory_path() /
            ("impactdic_" + stem + "_" + std::to_string(getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TestDir() { std::filesystem::remove_all(path_); }
  std::string File(const std::string& name) const { return (path_ / name).string(); }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(File(name)) << text;
    return File(name);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_IO_TEST_DIR_H_
