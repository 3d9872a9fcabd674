// OpenCV's image codecs (imgcodecs) and video I/O (videoio), loaded on first use.
//
// Debian's libopencv_imgcodecs and libopencv_videoio pull in about 230 shared libraries (GDAL,
// GDCM, FFmpeg, GStreamer, ...): linked into the binary, the dynamic loader spends ~0.09 s
// resolving them at every process start, most of a one-shot `impactdic correlate` of a pair. So
// no target of ours links them: they live in a small plugin, libimpactdic_opencv_codecs.so, that
// is dlopen()ed the first time an image has to be decoded or encoded by OpenCV or a video is
// opened. Greyscale PNGs (what the DIC reads) are decoded without it (io/png_grey.h).
//
//   cv::Mat image = opencv_codecs::Decode(bytes, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
//   opencv_codecs::VideoCapture video;
//   if (video.Open(path)) while (video.Read(&frame)) ...
//
// The plugin is the file named by the environment variable IMPACTDIC_OPENCV_CODECS if it is set,
// else the first that loads of: next to the running executable; where the build put it. If none
// loads: Error kFileNotFound naming the places tried and what the plugin is needed for.
// cv::Exception thrown by OpenCV passes through unchanged.
#ifndef IMPACTDIC_IO_OPENCV_CODECS_H_
#define IMPACTDIC_IO_OPENCV_CODECS_H_

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace impactdic::opencv_codecs {

// The plugin's file name.
inline constexpr const char* kPluginFileName = "libimpactdic_opencv_codecs.so";

// Loads the plugin now (no-op after the first call). Error as above.
void Load();
// Whether it is loaded (for tests: the correlation of greyscale PNGs must not load it).
bool IsLoaded();

// cv::imdecode / cv::imencode.
cv::Mat Decode(const std::string& bytes, int flags);
bool Encode(const std::string& extension, const cv::Mat& image, std::vector<uchar>* bytes,
            const std::vector<int>& params);

// cv::VideoCapture, with the API preference (cv::CAP_ANY, cv::CAP_FFMPEG, ...).
class VideoCapture {
 public:
  VideoCapture() = default;
  ~VideoCapture();
  VideoCapture(const VideoCapture&) = delete;
  VideoCapture& operator=(const VideoCapture&) = delete;

  bool Open(const std::string& path, int api = 0);
  bool IsOpened() const;
  bool Read(cv::Mat* frame);
  bool Grab();
  double Get(int property) const;

 private:
  void* handle_ = nullptr;  // a cv::VideoCapture owned by the plugin
};

// cv::VideoWriter.
class VideoWriter {
 public:
  VideoWriter() = default;
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  bool Open(const std::string& path, int api, int fourcc, double fps, cv::Size size, bool is_color);
  void Write(const cv::Mat& frame);
  void Release();

  static int Fourcc(char c1, char c2, char c3, char c4);  // no plugin needed

 private:
  void* handle_ = nullptr;  // a cv::VideoWriter owned by the plugin
};

}  // namespace impactdic::opencv_codecs

#endif  // IMPACTDIC_IO_OPENCV_CODECS_H_
