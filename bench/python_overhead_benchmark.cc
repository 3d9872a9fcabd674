// The library call the Python module's `correlate` makes, timed in C++ (bench/python_overhead.py
// compares the module against it, docs/python.md "Speed"): pipeline CorrelateSceneInMemory on two
// grey images decoded once, with the scene keys given, as `impactdic correlate` builds its scene
// from its flags. It waits on stdin: each line "run" correlates once and prints the wall seconds
// of the call, its CPU seconds (the process's, every thread's: user + system), its minor page
// faults and the number of subsets; end of input ends it. So the Python script keeps one warm
// process and takes turns with it. Messages below warnings are off, as in the module.
//
//   python_overhead_benchmark REF.png DEF.png [KEY=VALUE ...]     e.g. dic.threads=2
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <iostream>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/log.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/correlate_scene.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_flags.h"

namespace {

// CPU seconds of the process so far (every thread, user + system) and its minor page faults.
std::pair<double, long> ProcessCpu() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  return {seconds(usage.ru_utime) + seconds(usage.ru_stime), usage.ru_minflt};
}

}  // namespace

int main(int argc, char** argv) {
  using impactdic::Scene;
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s REF DEF [KEY=VALUE ...]\n", argv[0]);
    return 2;
  }
  impactdic::SetLogLevel(impactdic::LogLevel::kWarning);  // As the Python module's default.
  try {
    const std::vector<cv::Mat> images = {impactdic::ReadGreyImage(argv[1]),
                                         impactdic::ReadGreyImage(argv[2])};
    Scene scene;
    for (int k = 3; k < argc; ++k) {
      const std::string setting = argv[k];
      const std::size_t equals = setting.find('=');
      const std::string key = setting.substr(0, equals);
      impactdic::SetSceneKey(&scene, key, setting.substr(equals + 1), key);
    }
    std::string line;
    while (std::getline(std::cin, line)) {
      if (line != "run") continue;
      const auto [cpu_start, faults_start] = ProcessCpu();
      const auto start = std::chrono::steady_clock::now();
      const impactdic::SceneCorrelation result =
          impactdic::CorrelateSceneInMemory(scene, impactdic::MakeMemoryFrameSource(images));
      const std::chrono::duration<double> seconds = std::chrono::steady_clock::now() - start;
      const auto [cpu_end, faults_end] = ProcessCpu();
      std::cout << seconds.count() << " " << cpu_end - cpu_start << " " << faults_end - faults_start
                << " " << result.dic.subsets << std::endl;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "python_overhead_benchmark: %s\n", e.what());
    return 1;
  }
  return 0;
}
