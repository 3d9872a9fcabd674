#include "impactdic/io/camera_file.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>
#include <vector>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

[[noreturn]] void ThrowNotACameraFile(const std::string& path, const std::string& ext) {
  throw Error(ErrorKind::kFileFormat, path, "got '" + ext + "'",
              "a camera file: a Phantom .cine or a Photron .mraw with its .cih/.cihx");
}

}  // namespace

bool IsCameraFile(const std::string& path) {
  const std::string ext = LowerExtension(path);
  return ext == ".cine" || ext == ".mraw" || ext == ".cih" || ext == ".cihx";
}

std::unique_ptr<CameraFileReader> OpenCameraFile(const std::string& path) {
  const std::string ext = LowerExtension(path);
  if (ext == ".cine") return OpenCineFile(path);
  if (ext == ".mraw" || ext == ".cih" || ext == ".cihx") return OpenMrawFile(path);
  ThrowNotACameraFile(path, ext);
}

std::vector<std::string> CameraFileParts(const std::string& path) {
  const std::string ext = LowerExtension(path);
  if (ext == ".cine") return {path};
  if (ext == ".mraw" || ext == ".cih" || ext == ".cihx") return MrawFileParts(path);
  ThrowNotACameraFile(path, ext);
}

}  // namespace impactdic
