#include "impactdic/io/camera_file.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
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
  throw Error(ErrorKind::kFileFormat, path, "got '" + ext + "'",
              "a camera file: a Phantom .cine or a Photron .mraw with its .cih/.cihx");
}

}  // namespace impactdic
