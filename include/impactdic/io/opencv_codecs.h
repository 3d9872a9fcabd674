// OpenCV's image codecs (imgcodecs) and video I/O (videoio), loaded on first use.
//
// Debian's libopencv_imgcodecs pulls in about 140 shared libraries (GDAL, GDCM, OpenEXR, ...) and
// libopencv_videoio about 100 more (FFmpeg, GStreamer, ...): linked into the binary, the dynamic
// loader spends ~0.09 s resolving them at every process start, most of a one-shot `impactdic
// correlate` of a pair. So no target of ours links them: they live in two small plugins,
// dlopen()ed the first time they are needed:
//  - libimpactdic_opencv_codecs.so (imgcodecs): an image decoded or encoded by OpenCV;
//  - libimpactdic_opencv_video.so (videoio): a video opened for reading or writing.
// Greyscale PNGs (what the DIC reads) are decoded without either (io/png_grey.h), and a TIFF or
// JPEG sequence loads the images plugin alone (dlopen ~0.05 s instead of ~0.07 s for both).
//
//   cv::Mat image = opencv_codecs::Decode(bytes, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
//   opencv_codecs::VideoCapture video;
//   if (video.Open(path)) while (video.Read(&frame)) ...
//
// A plugin is the file named by its environment variable if it is set (IMPACTDIC_OPENCV_CODECS
// for the images plugin, IMPACTDIC_OPENCV_VIDEO for the video plugin), else the first that loads
// of: next to the running executable; where the build put it. If none loads: Error
// kFileNotFound naming the plugin, what it is needed for, its variable and the places tried.
// cv::Exception thrown by OpenCV passes through unchanged.
#ifndef IMPACTDIC_IO_OPENCV_CODECS_H_
#define IMPACTDIC_IO_OPENCV_CODECS_H_

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace impactdic::opencv_codecs {

// The plugins' file names.
inline constexpr const char* kPluginFileName = "libimpactdic_opencv_codecs.so";  // images
inline constexpr const char* kVideoPluginFileName = "libimpactdic_opencv_video.so";

// cv::imdecode / cv::imencode (the images plugin). What OpenCV writes to std::cerr while this
// thread decodes (imgcodecs prints a decoder's exception there instead of throwing it, e.g.
// "imdecode_(''): can't read data: ... Unexpected end of input stream") is kept from the terminal
// and returned in `messages` if given, for the caller's own error.
cv::Mat Decode(const std::string& bytes, int flags, std::string* messages = nullptr);
bool Encode(const std::string& extension, const cv::Mat& image, std::vector<uchar>* bytes,
            const std::vector<int>& params);

// Whether OpenCV was built with the video backend `api` (cv::CAP_FFMPEG, ...); loads the video
// plugin.
bool HasVideoBackend(int api);

// cv::VideoCapture (the video plugin), with the API preference (cv::CAP_ANY, cv::CAP_FFMPEG, ...).
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

// cv::VideoWriter (the video plugin).
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
