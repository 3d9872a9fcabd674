// Process exit under the sanitizers (scripts/test.sh, docs/reliability.md section 8):
// the CLI joins oneTBB's worker threads before it returns from main, so nothing is still
// exiting when LeakSanitizer stops the world; and scripts/lsan_tracer_crashes_only.sh, which
// decides whether the ASan stage of CI re-runs its failed tests once, says yes only when every
// failure is LeakSanitizer's own tracer crash, never for a leak report or a failing test.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

std::string Quote(const fs::path& p) {
  std::string quoted(1, '\'');  // Not "'" + ...: GCC 12 warns wrongly (-Wrestrict) on that.
  quoted.append(p.string());
  quoted.push_back('\'');
  return quoted;
}

// A CTest project of shell tests: one passing, one ending as LeakSanitizer's tracer crash ends a
// process, plus `extra` (more add_test lines). Configured and run; returns the build folder.
fs::path RunMockCtest(const TestDir& dir, const std::string& extra) {
  dir.Write("CMakeLists.txt",
            "cmake_minimum_required(VERSION 3.20)\nproject(mock NONE)\nenable_testing()\n"
            "add_test(NAME Ok.Passes COMMAND sh -c \"echo fine\")\n"
            "add_test(NAME Cli.TracerCrash COMMAND sh -c \"echo 'Tracer caught signal 11: "
            "addr=0x200003260'; echo '==7==LeakSanitizer has encountered a fatal error.'; exit "
            "1\")\n" +
                extra);
  const fs::path build = dir.path() / "build";
  const CliResult configure =
      RunShell("cmake -S " + Quote(dir.path()) + " -B " + Quote(build) + " > /dev/null");
  EXPECT_EQ(configure.exit_code, 0) << configure.output;
  const CliResult ctest = RunShell("cd " + Quote(build) + " && ctest -j2");
  EXPECT_NE(ctest.exit_code, 0) << ctest.output;  // Cli.TracerCrash always fails.
  return build;
}

CliResult Classify(const fs::path& build) {
  return RunShell(
      "bash " +
      Quote(fs::path(impactdic::SourceDir()) / "scripts" / "lsan_tracer_crashes_only.sh") + " " +
      Quote(build));
}

TEST(SanitizerCrashRetry, OnlyTracerCrashesAreRerun) {
  const TestDir dir;
  const CliResult r = Classify(RunMockCtest(dir, ""));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Cli.TracerCrash: LeakSanitizer's tracer crashed"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("Ok.Passes"), std::string::npos) << r.output;
}

TEST(SanitizerCrashRetry, AFailingTestNextToACrashIsNotRerun) {
  const TestDir dir;
  const CliResult r = Classify(RunMockCtest(
      dir, "add_test(NAME Dic.Fails COMMAND sh -c \"echo 'x_test.cc:3: Failure'; exit 1\")\n"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("Dic.Fails: failed on its own"), std::string::npos) << r.output;
}

TEST(SanitizerCrashRetry, ALeakReportIsNotRerun) {
  const TestDir dir;
  const CliResult r = Classify(RunMockCtest(
      dir,
      "add_test(NAME Io.Leaks COMMAND sh -c \"echo '==9==ERROR: LeakSanitizer: detected memory "
      "leaks'; echo '==9==LeakSanitizer has encountered a fatal error.'; exit 1\")\n"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("Io.Leaks: a leak report"), std::string::npos) << r.output;
}

TEST(SanitizerCrashRetry, NoFailedTestListIsNotARetry) {
  const TestDir dir;
  const CliResult r = Classify(dir.path());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("no failed-test list"), std::string::npos) << r.output;
}

// The workers that rendered and correlated are joined before main returns: with -v the CLI
// counts the threads still alive then, which are the main thread and the signal-cleanup thread
// (without the join, oneTBB's workers are among them).
TEST(WorkerThreads, AreJoinedBeforeTheCliExits) {
  const TestDir dir;
  const std::string spec = dir.Write("spec.yaml", "realistic: {frames: 2, seed: 3}\n");
  const fs::path scene = dir.path() / "s";
  const CliResult synth = RunCli("-v synth --realistic " + Quote(spec) + " -o " + Quote(scene));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const CliResult correlate =
      RunCli("-v correlate --reference " + Quote(scene / "frames" / "frame_0000.jpg") +
             " --deformed " + Quote(scene / "frames" / "frame_0001.jpg") +
             " --subset 21 --step 10 --threads 2 -o " + Quote(dir.path() / "c.h5"));
  ASSERT_EQ(correlate.exit_code, 0) << correlate.output;
  // The Gaussian pre-filter runs OpenCV's parallel_for_, in OpenCV's own oneTBB arena: it must
  // not keep the workers from being joined.
  const CliResult filtered =
      RunCli("-v correlate --reference " + Quote(scene / "frames" / "frame_0000.jpg") +
             " --deformed " + Quote(scene / "frames" / "frame_0001.jpg") +
             " --subset 21 --step 10 --threads 2 --gaussian 0.8 -o " + Quote(dir.path() / "g.h5"));
  ASSERT_EQ(filtered.exit_code, 0) << filtered.output;
  for (const CliResult* r : {&synth, &correlate, &filtered}) {
    EXPECT_NE(r->output.find("exit: oneTBB worker threads joined; threads alive: 2"),
              std::string::npos)
        << r->output;
  }
}

}  // namespace
}  // namespace impactdic
