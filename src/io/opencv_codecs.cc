#include "impactdic/io/opencv_codecs.h"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <system_error>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "opencv_codecs_api.h"

namespace impactdic::opencv_codecs {
namespace {

using io_internal::OpenCvCodecsApi;

// The places the plugin is looked for, in order (see the header).
std::vector<std::string> Candidates() {
  std::vector<std::string> paths;
  if (const char* env = std::getenv("IMPACTDIC_OPENCV_CODECS"); env != nullptr && *env != '\0')
    return {env};  // the user's choice, and only it
  char exe[4096];
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n > 0) {
    exe[n] = '\0';
    paths.push_back((std::filesystem::path(exe).parent_path() / kPluginFileName).string());
  }
#ifdef IMPACTDIC_OPENCV_CODECS_BUILD_PATH
  paths.emplace_back(IMPACTDIC_OPENCV_CODECS_BUILD_PATH);
#endif
  return paths;
}

std::mutex g_mutex;
const OpenCvCodecsApi* g_api = nullptr;  // guarded by g_mutex; never reset once set

const OpenCvCodecsApi& Api() {
  std::lock_guard<std::mutex> lock(g_mutex);
  if (g_api != nullptr) return *g_api;
  std::string tried;
  for (const auto& path : Candidates()) {
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
    using Entry = const OpenCvCodecsApi* (*)();
    auto entry = reinterpret_cast<Entry>(dlsym(library, "ImpactdicOpenCvCodecsApi"));
    const OpenCvCodecsApi* api = entry ? entry() : nullptr;
    if (api == nullptr || api->version != io_internal::kOpenCvCodecsApiVersion) {
      tried += "\n  " + path + ": not a plugin of this build (rebuild impactdic)";
      continue;
    }
    LogDebug("OpenCV codecs loaded from {}", path);
    g_api = api;
    return *g_api;
  }
  throw Error(ErrorKind::kFileNotFound,
              std::string("the OpenCV codecs plugin ") + kPluginFileName +
                  " (needed to read images other than greyscale PNGs, to write images and to "
                  "read or write videos) could not be loaded; set IMPACTDIC_OPENCV_CODECS to "
                  "its path. Tried:" +
                  tried);
}

}  // namespace

void Load() { Api(); }

bool IsLoaded() {
  std::lock_guard<std::mutex> lock(g_mutex);
  return g_api != nullptr;
}

cv::Mat Decode(const std::string& bytes, int flags) {
  const auto& api = Api();
  const cv::Mat buffer(1, static_cast<int>(bytes.size()), CV_8U, const_cast<char*>(bytes.data()));
  return api.decode(buffer, flags);
}

bool Encode(const std::string& extension, const cv::Mat& image, std::vector<uchar>* bytes,
            const std::vector<int>& params) {
  return Api().encode(extension, image, bytes, params);
}

VideoCapture::~VideoCapture() {
  if (handle_ != nullptr) Api().capture_delete(handle_);
}

bool VideoCapture::Open(const std::string& path, int api) {
  const auto& table = Api();
  if (handle_ == nullptr) handle_ = table.capture_new();
  return table.capture_open(handle_, path, api);
}

bool VideoCapture::IsOpened() const {
  return handle_ != nullptr && Api().capture_is_opened(handle_);
}

bool VideoCapture::Read(cv::Mat* frame) {
  return handle_ != nullptr && Api().capture_read(handle_, frame);
}

bool VideoCapture::Grab() { return handle_ != nullptr && Api().capture_grab(handle_); }

double VideoCapture::Get(int property) const {
  return handle_ != nullptr ? Api().capture_get(handle_, property) : 0.0;
}

VideoWriter::~VideoWriter() {
  if (handle_ != nullptr) Api().writer_delete(handle_);
}

bool VideoWriter::Open(const std::string& path, int api, int fourcc, double fps, cv::Size size,
                       bool is_color) {
  const auto& table = Api();
  if (handle_ == nullptr) handle_ = table.writer_new();
  return table.writer_open(handle_, path, api, fourcc, fps, size, is_color);
}

void VideoWriter::Write(const cv::Mat& frame) {
  if (handle_ != nullptr) Api().writer_write(handle_, frame);
}

void VideoWriter::Release() {
  if (handle_ != nullptr) Api().writer_release(handle_);
}

// cv::VideoWriter::fourcc, without the plugin.
int VideoWriter::Fourcc(char c1, char c2, char c3, char c4) {
  return (c1 & 255) + ((c2 & 255) << 8) + ((c3 & 255) << 16) + ((c4 & 255) << 24);
}

}  // namespace impactdic::opencv_codecs
