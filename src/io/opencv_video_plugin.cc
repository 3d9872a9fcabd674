// The OpenCV video plugin: the only code of ours linked against opencv_videoio (see
// include/impactdic/io/opencv_codecs.h for why).
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>
#include <string>

#include "opencv_codecs_api.h"

namespace impactdic::io_internal {
namespace {

cv::VideoCapture* Capture(void* p) { return static_cast<cv::VideoCapture*>(p); }
const cv::VideoCapture* Capture(const void* p) { return static_cast<const cv::VideoCapture*>(p); }
cv::VideoWriter* Writer(void* p) { return static_cast<cv::VideoWriter*>(p); }

OpenCvVideoApi MakeApi() {
  OpenCvVideoApi api;
  api.has_backend = [](int backend) {
    return cv::videoio_registry::hasBackend(static_cast<cv::VideoCaptureAPIs>(backend));
  };
  api.capture_new = []() -> void* { return new cv::VideoCapture(); };
  api.capture_delete = [](void* c) { delete Capture(c); };
  api.capture_open = [](void* c, const std::string& path, int pref) {
    return Capture(c)->open(path, pref);
  };
  api.capture_is_opened = [](const void* c) { return Capture(c)->isOpened(); };
  api.capture_read = [](void* c, cv::Mat* frame) { return Capture(c)->read(*frame); };
  api.capture_grab = [](void* c) { return Capture(c)->grab(); };
  api.capture_get = [](const void* c, int property) { return Capture(c)->get(property); };
  api.writer_new = []() -> void* { return new cv::VideoWriter(); };
  api.writer_delete = [](void* w) { delete Writer(w); };
  api.writer_open = [](void* w, const std::string& path, int pref, int fourcc, double fps,
                       cv::Size size, bool is_color) {
    return Writer(w)->open(path, pref, fourcc, fps, size, is_color);
  };
  api.writer_write = [](void* w, const cv::Mat& frame) { Writer(w)->write(frame); };
  api.writer_release = [](void* w) { Writer(w)->release(); };
  return api;
}

}  // namespace
}  // namespace impactdic::io_internal

extern "C" __attribute__((visibility("default"))) const impactdic::io_internal::OpenCvVideoApi*
ImpactdicOpenCvVideoApi() {
  static const impactdic::io_internal::OpenCvVideoApi api = impactdic::io_internal::MakeApi();
  return &api;
}
