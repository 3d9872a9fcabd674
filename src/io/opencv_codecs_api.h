// The tables of functions the two OpenCV plugins hand to the loader (opencv_codecs.cc):
//  - the images plugin (opencv_codecs_plugin.cc, libimpactdic_opencv_codecs.so): imgcodecs;
//  - the video plugin (opencv_video_plugin.cc, libimpactdic_opencv_video.so): videoio.
// They are two so that decoding a TIFF or JPEG does not load FFmpeg and GStreamer (videoio's
// ~100 further libraries) as well. Both sides are built from this header in the same build, so
// the layouts match; the versions guard against a stale plugin file from another build.
#ifndef IMPACTDIC_SRC_IO_OPENCV_CODECS_API_H_
#define IMPACTDIC_SRC_IO_OPENCV_CODECS_API_H_

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace impactdic::io_internal {

inline constexpr int kOpenCvImagesApiVersion = 3;
inline constexpr int kOpenCvVideoApiVersion = 3;

struct OpenCvImagesApi {
  int version = kOpenCvImagesApiVersion;
  // cv::imdecode; what OpenCV writes to std::cerr meanwhile on this thread (its imgcodecs print
  // a decoder's exception there, "imdecode_(''): can't read data: ...") goes to `messages`
  // instead of the terminal.
  cv::Mat (*decode)(const cv::Mat& buffer, int flags, std::string* messages) = nullptr;
  bool (*encode)(const std::string& ext, const cv::Mat& image, std::vector<uchar>* bytes,
                 const std::vector<int>& params) = nullptr;
};

struct OpenCvVideoApi {
  int version = kOpenCvVideoApiVersion;
  bool (*has_backend)(int api) = nullptr;  // cv::videoio_registry::hasBackend
  void* (*capture_new)() = nullptr;
  void (*capture_delete)(void* capture) = nullptr;
  bool (*capture_open)(void* capture, const std::string& path, int api) = nullptr;
  bool (*capture_is_opened)(const void* capture) = nullptr;
  bool (*capture_read)(void* capture, cv::Mat* frame) = nullptr;
  bool (*capture_grab)(void* capture) = nullptr;
  double (*capture_get)(const void* capture, int property) = nullptr;
  void* (*writer_new)() = nullptr;
  void (*writer_delete)(void* writer) = nullptr;
  bool (*writer_open)(void* writer, const std::string& path, int api, int fourcc, double fps,
                      cv::Size size, bool is_color) = nullptr;
  void (*writer_write)(void* writer, const cv::Mat& frame) = nullptr;
  void (*writer_release)(void* writer) = nullptr;
};

}  // namespace impactdic::io_internal

// Each plugin's one exported symbol.
extern "C" const impactdic::io_internal::OpenCvImagesApi* ImpactdicOpenCvImagesApi();
extern "C" const impactdic::io_internal::OpenCvVideoApi* ImpactdicOpenCvVideoApi();

#endif  // IMPACTDIC_SRC_IO_OPENCV_CODECS_API_H_
