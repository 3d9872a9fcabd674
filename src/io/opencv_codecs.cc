#include "impactdic/io/opencv_codecs.h"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <opencv2/core/utils/logger.hpp>
#include <system_error>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "opencv_codecs_api.h"

namespace impactdic::opencv_codecs {
namespace {

using io_internal::OpenCvImagesApi;
using io_internal::OpenCvVideoApi;

// What tells one plugin apart (see the header).
struct Plugin {
  const char* file_name;
  const char* environment;  // the variable naming its file instead
  const char* entry;        // its one exported symbol
  const char* needed_for;   // for the error when it cannot be loaded
};

const Plugin kImagesPlugin{kPluginFileName, "IMPACTDIC_OPENCV_CODECS", "ImpactdicOpenCvImagesApi",
                           "needed to read images other than greyscale PNGs and to write images"};
const Plugin kVideoPlugin{kVideoPluginFileName, "IMPACTDIC_OPENCV_VIDEO", "ImpactdicOpenCvVideoApi",
                          "needed to read or write videos"};

// The places a plugin is looked for, in order (see the header).
std::vector<std::string> Candidates(const Plugin& plugin, const char* build_path) {
  std::vector<std::string> paths;
  if (const char* env = std::getenv(plugin.environment); env != nullptr && *env != '\0')
    return {env};  // the user's choice, and only it
  char exe[4096];
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n > 0) {
    exe[n] = '\0';
    paths.push_back((std::filesystem::path(exe).parent_path() / plugin.file_name).string());
  }
  paths.emplace_back(build_path);
  return paths;
}

// OpenCV's log and FFmpeg's (through OpenCV's FFmpeg backend) go to stderr beside our own
// message about the same file: a video that cannot be opened gave "[mov,mp4,...] moov atom not
// found", "[ WARN:0@0.16] ... GStreamer warning: ..." and "[ERROR:0@0.16] ... raised OpenCV
// exception" before ours. Both are silenced before the first plugin is loaded, unless the user
// asks for them: impactdic --verbose, or their own OPENCV_LOG_LEVEL / OPENCV_FFMPEG_LOGLEVEL.
void QuietLibraries() {
  if (GetLogLevel() <= LogLevel::kDebug) return;
  if (std::getenv("OPENCV_LOG_LEVEL") == nullptr)
    cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  // Read by OpenCV's FFmpeg backend when it first opens a file; -8 is AV_LOG_QUIET.
  setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", /*overwrite=*/0);
}

// Loads the plugin and returns its table (of type Api, checked against `version`). Each plugin
// is loaded once, its table kept for the whole process (*loaded, guarded by g_mutex).
std::mutex g_mutex;

template <typename Api>
const Api& LoadPlugin(const Plugin& plugin, const char* build_path, int version,
                      const Api** loaded) {
  std::lock_guard<std::mutex> lock(g_mutex);
  if (*loaded != nullptr) return **loaded;
  static bool quiet = false;  // guarded by g_mutex
  if (!quiet) {
    QuietLibraries();
    quiet = true;
  }
  std::string tried;
  for (const auto& path : Candidates(plugin, build_path)) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
      tried += "\n  " + path + ": no such file";
      continue;
    }
    // Never closed: OpenCV's libraries keep threads and static state.
    void* library = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) {
      const char* why = dlerror();
      tried += "\n  " + path + ": " + (why ? why : "dlopen failed");
      continue;
    }
    using Entry = const Api* (*)();
    auto entry = reinterpret_cast<Entry>(dlsym(library, plugin.entry));
    const Api* api = entry ? entry() : nullptr;
    if (api == nullptr || api->version != version) {
      tried += "\n  " + path + ": not a plugin of this build (rebuild impactdic)";
      continue;
    }
    LogDebug("OpenCV plugin loaded from {}", path);
    *loaded = api;
    return *api;
  }
  throw Error(ErrorKind::kFileNotFound, std::string("the OpenCV plugin ") + plugin.file_name +
                                            " (" + plugin.needed_for +
                                            ") could not be loaded; set " + plugin.environment +
                                            " to its path. Tried:" + tried);
}

const OpenCvImagesApi* g_images = nullptr;  // guarded by g_mutex; never reset once set
const OpenCvVideoApi* g_video = nullptr;    // guarded by g_mutex; never reset once set

const OpenCvImagesApi& Images() {
  return LoadPlugin(kImagesPlugin, IMPACTDIC_OPENCV_CODECS_BUILD_PATH,
                    io_internal::kOpenCvImagesApiVersion, &g_images);
}

const OpenCvVideoApi& Video() {
  return LoadPlugin(kVideoPlugin, IMPACTDIC_OPENCV_VIDEO_BUILD_PATH,
                    io_internal::kOpenCvVideoApiVersion, &g_video);
}

}  // namespace

cv::Mat Decode(const std::string& bytes, int flags, std::string* messages) {
  const auto& api = Images();
  const cv::Mat buffer(1, static_cast<int>(bytes.size()), CV_8U, const_cast<char*>(bytes.data()));
  std::string captured;
  cv::Mat image = api.decode(buffer, flags, &captured);
  if (messages != nullptr) *messages = std::move(captured);
  return image;
}

bool Encode(const std::string& extension, const cv::Mat& image, std::vector<uchar>* bytes,
            const std::vector<int>& params) {
  return Images().encode(extension, image, bytes, params);
}

bool HasVideoBackend(int api) { return Video().has_backend(api); }

VideoCapture::~VideoCapture() {
  if (handle_ != nullptr) Video().capture_delete(handle_);
}

bool VideoCapture::Open(const std::string& path, int api) {
  const auto& table = Video();
  if (handle_ == nullptr) handle_ = table.capture_new();
  return table.capture_open(handle_, path, api);
}

bool VideoCapture::IsOpened() const {
  return handle_ != nullptr && Video().capture_is_opened(handle_);
}

bool VideoCapture::Read(cv::Mat* frame) {
  return handle_ != nullptr && Video().capture_read(handle_, frame);
}

bool VideoCapture::Grab() { return handle_ != nullptr && Video().capture_grab(handle_); }

double VideoCapture::Get(int property) const {
  return handle_ != nullptr ? Video().capture_get(handle_, property) : 0.0;
}

VideoWriter::~VideoWriter() {
  if (handle_ != nullptr) Video().writer_delete(handle_);
}

bool VideoWriter::Open(const std::string& path, int api, int fourcc, double fps, cv::Size size,
                       bool is_color) {
  const auto& table = Video();
  if (handle_ == nullptr) handle_ = table.writer_new();
  return table.writer_open(handle_, path, api, fourcc, fps, size, is_color);
}

void VideoWriter::Write(const cv::Mat& frame) {
  if (handle_ != nullptr) Video().writer_write(handle_, frame);
}

void VideoWriter::Release() {
  if (handle_ != nullptr) Video().writer_release(handle_);
}

// cv::VideoWriter::fourcc, without the plugin.
int VideoWriter::Fourcc(char c1, char c2, char c3, char c4) {
  return (c1 & 255) + ((c2 & 255) << 8) + ((c3 & 255) << 16) + ((c4 & 255) << 24);
}

}  // namespace impactdic::opencv_codecs
