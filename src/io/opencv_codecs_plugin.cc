// The OpenCV images plugin: the only code of ours linked against opencv_imgcodecs (see
// include/impactdic/io/opencv_codecs.h for why).
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "opencv_codecs_api.h"

namespace impactdic::io_internal {
namespace {

OpenCvImagesApi MakeApi() {
  OpenCvImagesApi api;
  api.decode = [](const cv::Mat& buffer, int flags) { return cv::imdecode(buffer, flags); };
  api.encode = [](const std::string& ext, const cv::Mat& image, std::vector<uchar>* bytes,
                  const std::vector<int>& params) {
    return cv::imencode(ext, image, *bytes, params);
  };
  return api;
}

}  // namespace
}  // namespace impactdic::io_internal

extern "C" __attribute__((visibility("default"))) const impactdic::io_internal::OpenCvImagesApi*
ImpactdicOpenCvImagesApi() {
  static const impactdic::io_internal::OpenCvImagesApi api = impactdic::io_internal::MakeApi();
  return &api;
}
