// Linked into every test program (impactdic_add_test): a GoogleTest environment that holds
// oneTBB's worker threads for the whole run and joins them when the tests are over, before
// main returns, as the CLI's main does (core/threads.h, WorkerThreadsJoinedAtExit). A test that
// leaves them unjoinable (an arena or a thread still attached, as OpenCV's arena did) fails here
// every time, instead of now and then under LeakSanitizer (docs/reliability.md, section 8).
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "impactdic/core/threads.h"

namespace impactdic {
namespace {

class WorkerThreadsEnvironment : public ::testing::Environment {
 public:
  void SetUp() override { workers_ = std::make_unique<WorkerThreadsJoinedAtExit>(); }
  void TearDown() override {
    EXPECT_TRUE(workers_->Join())
        << "oneTBB's worker threads could not be joined after the tests: an arena or a thread "
           "is still attached to oneTBB";
    workers_.reset();
  }

 private:
  std::unique_ptr<WorkerThreadsJoinedAtExit> workers_;
};

// GoogleTest owns and deletes the environment.
[[maybe_unused]] ::testing::Environment* const kEnvironment =
    ::testing::AddGlobalTestEnvironment(new WorkerThreadsEnvironment);

}  // namespace
}  // namespace impactdic
