// AdviseHugePages: a hint that leaves every buffer's contents and usability as they were.
#include "impactdic/core/memory.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <numeric>
#include <vector>

namespace impactdic {
namespace {

TEST(Memory, AdvisedBuffersKeepTheirValues) {
  for (const std::size_t floats : {std::size_t{0}, std::size_t{100}, std::size_t{3} << 20}) {
    std::vector<float> buffer(floats);
    AdviseHugePages(buffer.data(), buffer.size() * sizeof(float));
    std::iota(buffer.begin(), buffer.end(), 0.0f);
    for (std::size_t i = 0; i < floats; i += 4099) EXPECT_EQ(buffer[i], static_cast<float>(i));
  }
  AdviseHugePages(nullptr, std::size_t{64} << 20);  // Nothing to advise: no effect.
}

}  // namespace
}  // namespace impactdic
