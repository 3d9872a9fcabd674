// tests/core/shared_data.h: where the shared benchmark data is looked for, and when its absence
// fails a test instead of skipping it.
#include "shared_data.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "test_paths.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// Sets an environment variable for the scope (unset or restored after).
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    const char* old = std::getenv(name);
    had_ = old != nullptr;
    if (had_) old_ = old;
    if (value) {
      setenv(name, value, 1);
    } else {
      unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (had_) {
      setenv(name_, old_.c_str(), 1);
    } else {
      unsetenv(name_);
    }
  }

 private:
  const char* name_;
  bool had_ = false;
  std::string old_;
};

TEST(SharedData, DefaultsToTheFolderBesideTheProjectRoot) {
  const ScopedEnv env("IMPACTDIC_SHARED_DATA", nullptr);
  EXPECT_EQ(SharedDataRoot(),
            (fs::path(impactdic::SourceDir()) / ".." / "shared" / "data").lexically_normal());
}

TEST(SharedData, AnAbsentOrEmptyFolderIsNamed) {
  const fs::path dir =
      fs::temp_directory_path() / ("impactdic_shared_data_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "empty");
  fs::create_directories(dir / "full");
  { std::ofstream(dir / "full" / "a.txt") << "x"; }
  const ScopedEnv env("IMPACTDIC_SHARED_DATA", dir.c_str());
  EXPECT_EQ(FindSharedData("full").missing, "");
  EXPECT_EQ(FindSharedData("full").folder, dir / "full");
  EXPECT_NE(FindSharedData("empty").missing.find((dir / "empty").string()), std::string::npos);
  EXPECT_NE(FindSharedData("absent").missing.find("no folder " + (dir / "absent").string()),
            std::string::npos);
  fs::remove_all(dir);
}

TEST(SharedData, RequiredWhenTheVariableIsSetToAnythingButZero) {
  {
    const ScopedEnv env("IMPACTDIC_REQUIRE_SHARED_DATA", nullptr);
    EXPECT_FALSE(SharedDataRequired());
  }
  {
    const ScopedEnv env("IMPACTDIC_REQUIRE_SHARED_DATA", "0");
    EXPECT_FALSE(SharedDataRequired());
  }
  {
    const ScopedEnv env("IMPACTDIC_REQUIRE_SHARED_DATA", "1");
    EXPECT_TRUE(SharedDataRequired());
  }
}

}  // namespace
}  // namespace impactdic
