// The interrupt cleanup (core/interrupt.h), in forked children: SIGTERM removes the registered
// paths and exits with 143; a swap inside DeferInterrupts finishes first; a signal ignored at start
// stays ignored.
#include "impactdic/core/interrupt.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <thread>

namespace impactdic {
namespace {

namespace fs = std::filesystem;

fs::path Scratch(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("impactdic_interrupt_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Runs `body` in a child process (which must end itself) and returns its wait status.
int InChild(const std::function<void()>& body) {
  const pid_t child = fork();
  if (child == 0) {
    body();
    _exit(0);
  }
  int status = 0;
  waitpid(child, &status, 0);
  return status;
}

// The one "is this path in that folder" test (staging folders, registered temporaries): whole
// path components only.
TEST(Interrupt, IsSameOrInsideComparesWholeComponents) {
  EXPECT_TRUE(IsSameOrInside("/w/out", "/w/out"));
  EXPECT_TRUE(IsSameOrInside("/w/out/results.h5", "/w/out"));
  EXPECT_TRUE(IsSameOrInside("/w/out/a/b", "/w/out"));
  EXPECT_FALSE(IsSameOrInside("/w/output/results.h5", "/w/out"));
  EXPECT_FALSE(IsSameOrInside("/w/ou", "/w/out"));
  EXPECT_FALSE(IsSameOrInside("/w", "/w/out"));
}

TEST(Interrupt, SigtermRemovesRegisteredPathsAndExitsWith143) {
  const fs::path dir = Scratch("term");
  const fs::path staging = dir / "staging", kept = dir / "kept.txt", released = dir / "done.txt";
  const int status = InChild([&] {
    InstallInterruptCleanup();
    fs::create_directories(staging / "sub");
    std::ofstream(staging / "sub" / "file") << "x";
    std::ofstream(kept) << "not registered";
    std::ofstream(released) << "registered, then released (renamed into place)";
    RemoveOnInterrupt guard(staging.string());
    RemoveOnInterrupt done(released.string());
    done.Release();
    kill(getpid(), SIGTERM);
    WaitIfInterrupted();
    for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
  });
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM);
  EXPECT_FALSE(fs::exists(staging));
  EXPECT_TRUE(fs::exists(kept));
  EXPECT_TRUE(fs::exists(released));
  fs::remove_all(dir);
}

TEST(Interrupt, ASwapInProgressFinishesBeforeTheCleanup) {
  const fs::path dir = Scratch("swap");
  const fs::path staging = dir / "staging", final_name = dir / "final";
  const int status = InChild([&] {
    InstallInterruptCleanup();
    fs::create_directories(staging);
    RemoveOnInterrupt guard(staging.string());
    {
      DeferInterrupts swap;
      kill(getpid(), SIGINT);
      // Without the deferral the cleanup would remove `staging` now and the rename would fail.
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      fs::rename(staging, final_name);
    }
    WaitIfInterrupted();
    _exit(0);
  });
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGINT);
  EXPECT_TRUE(fs::is_directory(final_name));
  EXPECT_FALSE(fs::exists(staging));
  fs::remove_all(dir);
}

TEST(Interrupt, ASignalIgnoredAtStartStaysIgnored) {
  const int status = InChild([] {
    signal(SIGINT, SIG_IGN);  // As for `impactdic ... &` in a script, or under nohup (SIGHUP).
    InstallInterruptCleanup();
    kill(getpid(), SIGINT);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    _exit(Interrupted() ? 1 : 0);
  });
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

}  // namespace
}  // namespace impactdic
