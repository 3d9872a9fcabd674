#include "impactdic/io/image_io.h"

#include <fnmatch.h>

#include <algorithm>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "impactdic/core/error.h"
#include "impactdic/io/atomic_file.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool IsImageFile(const fs::path& p) {
  static const char* kExt[] = {".tif", ".tiff", ".png", ".bmp", ".jpg", ".jpeg", ".pgm", ".jp2"};
  const std::string ext = Lower(p.extension().string());
  return std::any_of(std::begin(kExt), std::end(kExt), [&](const char* e) { return ext == e; });
}

}  // namespace

void CheckImageFileExists(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw Error(ErrorKind::kFileNotFound, "image", "", "an existing image file").WithFile(path);
  }
}

cv::Mat ReadGreyImage(const std::string& path) {
  CheckImageFileExists(path);
  cv::Mat image = cv::imread(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  if (image.empty()) {
    throw Error(ErrorKind::kFileFormat, "image",
                "a file OpenCV cannot decode (corrupt or truncated?)",
                "an 8- or 16-bit TIFF/PNG/BMP/JPEG image")
        .WithFile(path);
  }
  if (image.channels() == 3) {
    cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, image, cv::COLOR_BGRA2GRAY);
  }
  if (image.depth() != CV_8U && image.depth() != CV_16U) {
    throw Error(ErrorKind::kFileFormat, "image", "pixel depth other than 8 or 16 bit",
                "an 8- or 16-bit greyscale image")
        .WithFile(path);
  }
  return image;
}

void WriteImage(const std::string& path, const cv::Mat& image) {
  AtomicFile file(path);
  // OpenCV picks the encoder from the extension, so the temporary name keeps it.
  const std::string temp = file.temp_path() + fs::path(path).extension().string();
  bool ok = false;
  try {
    ok = cv::imwrite(temp, image);
  } catch (const cv::Exception& e) {
    ok = false;
  }
  if (!ok) {
    std::error_code ec;
    fs::remove(temp, ec);
    throw Error(ErrorKind::kIo, "image", "OpenCV could not write it",
                "a writable path with an image extension")
        .WithFile(path);
  }
  std::error_code ec;
  fs::rename(temp, file.temp_path(), ec);
  file.Commit();
}

std::vector<std::string> ListFrames(const std::string& source) {
  std::vector<std::string> files;
  std::error_code ec;
  if (fs::is_directory(source, ec)) {
    for (const auto& entry : fs::directory_iterator(source)) {
      if (entry.is_regular_file() && IsImageFile(entry.path()))
        files.push_back(entry.path().string());
    }
  } else if (source.find_first_of("*?[") != std::string::npos) {
    const fs::path pattern(source);
    fs::path folder = pattern.parent_path();
    if (folder.empty()) folder = ".";
    if (!fs::is_directory(folder, ec)) {
      throw Error(ErrorKind::kFileNotFound, "frames",
                  "folder " + folder.string() + " does not exist", "a folder, glob or image file")
          .WithFile(source);
    }
    const std::string name_pattern = pattern.filename().string();
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (entry.is_regular_file() &&
          fnmatch(name_pattern.c_str(), entry.path().filename().c_str(), 0) == 0) {
        files.push_back(entry.path().string());
      }
    }
  } else if (fs::is_regular_file(source, ec)) {
    files.push_back(source);
  } else {
    throw Error(ErrorKind::kFileNotFound, "frames", "", "an existing folder, glob or image file")
        .WithFile(source);
  }
  if (files.empty()) {
    throw Error(ErrorKind::kFileNotFound, "frames", "no image files match",
                "at least one .tif/.png/.bmp/.jpg frame")
        .WithFile(source);
  }
  std::sort(files.begin(), files.end());
  return files;
}

bool IsVideoFile(const std::string& path) {
  const std::string ext = Lower(fs::path(path).extension().string());
  return ext == ".mp4" || ext == ".avi" || ext == ".mov" || ext == ".mkv";
}

std::vector<cv::Mat> ReadVideoFrames(const std::string& path, int max_frames) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw Error(ErrorKind::kFileNotFound, "video", "", "an existing video file").WithFile(path);
  }
  cv::VideoCapture capture(path);
  if (!capture.isOpened()) {
    throw Error(ErrorKind::kFileFormat, "video", "a file OpenCV cannot open",
                "a video OpenCV can decode (.mp4, .avi, ...)")
        .WithFile(path);
  }
  std::vector<cv::Mat> frames;
  cv::Mat frame;
  while ((max_frames <= 0 || static_cast<int>(frames.size()) < max_frames) && capture.read(frame)) {
    cv::Mat grey;
    if (frame.channels() == 3) {
      cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
    } else {
      grey = frame.clone();
    }
    frames.push_back(grey);
  }
  if (frames.empty()) {
    throw Error(ErrorKind::kFileFormat, "video", "no decodable frames", "at least one frame")
        .WithFile(path);
  }
  return frames;
}

void CheckSameSize(const std::vector<cv::Mat>& images, const std::vector<std::string>& names) {
  for (std::size_t i = 1; i < images.size(); ++i) {
    if (images[i].size() != images[0].size() || images[i].depth() != images[0].depth()) {
      const std::string name = i < names.size() ? names[i] : "frame " + std::to_string(i);
      throw Error(ErrorKind::kFileFormat, "image size",
                  std::to_string(images[i].cols) + "x" + std::to_string(images[i].rows) +
                      (images[i].depth() == CV_16U ? " 16-bit" : " 8-bit"),
                  std::to_string(images[0].cols) + "x" + std::to_string(images[0].rows) +
                      (images[0].depth() == CV_16U ? " 16-bit" : " 8-bit") +
                      " like the first image")
          .WithFile(name);
    }
  }
}

}  // namespace impactdic
