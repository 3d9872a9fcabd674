// The OpenCV images plugin: the only code of ours linked against opencv_imgcodecs (see
// include/impactdic/io/opencv_codecs.h for why).
#include <iostream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <streambuf>
#include <string>
#include <vector>

#include "opencv_codecs_api.h"

namespace impactdic::io_internal {
namespace {

// Where std::cerr's output of the current thread goes while it decodes; null: to the terminal.
thread_local std::string* t_captured = nullptr;

// std::cerr's buffer while the plugin is loaded: unbuffered, it hands each write to the calling
// thread's capture if that thread is decoding, else to the original buffer (stderr). Stateless
// besides the original buffer, so threads that write at the same time do not interfere.
class PerThreadCapture : public std::streambuf {
 public:
  explicit PerThreadCapture(std::streambuf* original) : original_(original) {}

 protected:
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    if (t_captured == nullptr) return original_->sputc(traits_type::to_char_type(c));
    t_captured->push_back(traits_type::to_char_type(c));
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (t_captured == nullptr) return original_->sputn(s, n);
    t_captured->append(s, static_cast<std::size_t>(n));
    return n;
  }
  int sync() override { return t_captured == nullptr ? original_->pubsync() : 0; }

 private:
  std::streambuf* original_;
};

cv::Mat Decode(const cv::Mat& buffer, int flags, std::string* messages) {
  // Installed once, for the life of the process (the plugin is never unloaded).
  static PerThreadCapture* capture = [] {
    auto* c = new PerThreadCapture(std::cerr.rdbuf());
    std::cerr.rdbuf(c);
    return c;
  }();
  static_cast<void>(capture);
  std::string captured;
  t_captured = &captured;
  cv::Mat image;
  try {
    image = cv::imdecode(buffer, flags);
  } catch (...) {
    t_captured = nullptr;
    throw;
  }
  t_captured = nullptr;
  if (messages != nullptr) *messages = captured;
  return image;
}

OpenCvImagesApi MakeApi() {
  OpenCvImagesApi api;
  api.decode = Decode;
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
