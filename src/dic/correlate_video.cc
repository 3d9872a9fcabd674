#include <fmt/format.h>

#include <numeric>

#include "impactdic/core/error.h"
#include "impactdic/dic/dic_io.h"
#include "impactdic/io/image_io.h"

namespace impactdic {

DicResult CorrelateVideo(const std::string& path, const DicOptions& options) {
  options.Check();
  std::string truncated;
  const std::vector<cv::Mat> frames = ReadVideoFrames(path, /*max_frames=*/0, &truncated);
  CheckValue(frames.size() >= 2, "--frames",
             fmt::format("{} ({} decodable frame)", path, frames.size()),
             "a video of at least two frames (the first is the reference)");
  DicResult result = CorrelateSequence(frames, options);
  result.frame_numbers.resize(frames.size());
  std::iota(result.frame_numbers.begin(), result.frame_numbers.end(), 0LL);
  if (!truncated.empty()) result.warnings.push_back(truncated);
  return result;
}

}  // namespace impactdic
