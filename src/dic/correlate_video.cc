#include <fmt/format.h>

#include <algorithm>
#include <cstddef>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/progress.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/dic_io.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/image_io.h"

namespace impactdic {

DicResult CorrelateVideo(const std::string& path, const DicOptions& options,
                         const ImageFilter& filter) {
  options.Check();
  VideoReader video(path);
  cv::Mat reference, frame;
  const bool first = video.Read(&reference);
  if (!first || !video.Read(&frame)) {
    throw Error(ErrorKind::kInvalidValue, "frames video",
                fmt::format("{} decodable frame(s)", first ? 1 : 0),
                "a video of at least two frames (the first is the reference)")
        .WithFile(path);
  }
  auto prepared = [&filter](const cv::Mat& image) {
    return filter.apply ? filter.apply(image) : image;
  };
  Correlator correlator(options);
  correlator.SetReference(prepared(reference));
  DicResult result;
  result.preprocess = filter.apply ? filter.description : "";
  result.positions = correlator.positions();
  // One frame decoded at a time: memory does not grow with the length of the video.
  const double declared = video.declared_frames();
  ProgressBar bar("correlate", declared > 1 ? static_cast<std::size_t>(declared) - 1 : 1);
  do {
    CheckSameSize({reference, frame},
                  {path + " frame 0", fmt::format("{} frame {}", path, video.frames_read() - 1)});
    result.frames.push_back(correlator.Correlate(prepared(frame)));
    bar.Advance();
  } while (video.Read(&frame));
  bar.Finish();
  result.summary = correlator.summary();
  for (long long k = 0; k < video.frames_read(); ++k) result.frame_numbers.push_back(k);
  const std::string truncated = video.Finish();
  if (!truncated.empty()) result.warnings.push_back(truncated);
  return result;
}

}  // namespace impactdic
