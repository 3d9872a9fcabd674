#include "impactdic/io/image_io.h"

#include <fmt/format.h>
#include <fnmatch.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
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

// Orders names as a person would: runs of digits compare by value ("f_9" < "f_10").
bool NaturalLess(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) &&
        std::isdigit(static_cast<unsigned char>(b[j]))) {
      std::size_t i1 = i, j1 = j;
      while (i1 < a.size() && a[i1] == '0') ++i1;
      while (j1 < b.size() && b[j1] == '0') ++j1;
      std::size_t i2 = i1, j2 = j1;
      while (i2 < a.size() && std::isdigit(static_cast<unsigned char>(a[i2]))) ++i2;
      while (j2 < b.size() && std::isdigit(static_cast<unsigned char>(b[j2]))) ++j2;
      if (i2 - i1 != j2 - j1) return i2 - i1 < j2 - j1;
      const int c = a.compare(i1, i2 - i1, b, j1, j2 - j1);
      if (c != 0) return c < 0;
      if (i2 - i != j2 - j) return i2 - i < j2 - j;  // "07" before "007": fewer zeros first
      i = i2;
      j = j2;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

// Splits a file name's stem at its last run of digits: prefix, number, suffix. False if the
// stem has no digits.
bool SplitFrameNumber(const std::string& path, std::string* prefix, long long* number,
                      std::string* suffix) {
  const std::string name = fs::path(path).filename().string();
  const std::size_t dot = name.rfind('.');
  const std::string stem = dot == std::string::npos ? name : name.substr(0, dot);
  std::size_t end = stem.size();
  while (end > 0 && !std::isdigit(static_cast<unsigned char>(stem[end - 1]))) --end;
  if (end == 0) return false;
  std::size_t begin = end;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
  if (end - begin > 15) return false;
  *prefix = stem.substr(0, begin);
  *number = std::stoll(stem.substr(begin, end - begin));
  *suffix = name.substr(end);
  return true;
}

}  // namespace

void CheckFrameNumbering(const std::vector<std::string>& files) {
  if (files.size() < 3) return;
  std::vector<long long> numbers;
  std::string prefix0, suffix0;
  for (std::size_t k = 0; k < files.size(); ++k) {
    std::string prefix, suffix;
    long long number = 0;
    // More than 9 digits: a timestamp, not a frame counter; its steps need not be constant.
    if (!SplitFrameNumber(files[k], &prefix, &number, &suffix) || number > 999999999) return;
    if (k == 0) {
      prefix0 = prefix;
      suffix0 = suffix;
    } else if (prefix != prefix0 || suffix != suffix0) {
      return;  // Not one numbered series: nothing to check.
    }
    numbers.push_back(number);
  }
  // The series' step: the most common difference between neighbours (the smallest on a tie).
  std::map<long long, int> counts;
  for (std::size_t k = 1; k < numbers.size(); ++k) ++counts[numbers[k] - numbers[k - 1]];
  long long step = 0;
  int best = 0;
  for (const auto& [d, c] : counts) {
    if (d > 0 && c > best) {
      step = d;
      best = c;
    }
  }
  if (step == 0) step = 1;
  for (std::size_t k = 1; k < numbers.size(); ++k) {
    const long long d = numbers[k] - numbers[k - 1];
    if (d == step) continue;
    const long long missing = d > step && d % step == 0 ? d / step - 1 : 0;
    throw Error(
        ErrorKind::kInvalidValue, "frames",
        fmt::format("the numbering jumps from {} to {} ({})",
                    fs::path(files[k - 1]).filename().string(),
                    fs::path(files[k]).filename().string(),
                    missing > 0 ? fmt::format("{} frame(s) missing", missing)
                                : fmt::format("step {} where the series steps by {}", d, step)),
        fmt::format("consecutively numbered frames (step {}): the frame times are "
                    "counted from the first frame, so a missing frame shifts all later "
                    "ones",
                    step))
        .WithFile(files[k]);
  }
}

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
  // Encoded in memory (OpenCV picks the encoder from the extension) and written with our checked
  // writes: libpng's own file writing reports a full disk only as "libpng error: Write Error".
  const std::string ext = fs::path(path).extension().string();
  std::vector<uchar> bytes;
  bool ok = false;
  try {
    ok = !ext.empty() && cv::imencode(ext, image, bytes);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) {
    throw Error(ErrorKind::kIo, "image", "OpenCV could not encode it",
                "an image extension (.png, .tif, ...)")
        .WithFile(path);
  }
  WriteFileAtomic(path, bytes.data(), bytes.size());
}

bool IsCompletePng(const std::string& path) {
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  // The IEND chunk: length 0, type "IEND", CRC ae 42 60 82.
  static constexpr unsigned char kEnd[12] = {0,   0,   0,    0,    'I',  'E',
                                             'N', 'D', 0xae, 0x42, 0x60, 0x82};
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return false;
  const std::streamoff size = in.tellg();
  if (size < 8 + 12) return false;
  unsigned char head[8] = {}, tail[12] = {};
  in.seekg(0);
  in.read(reinterpret_cast<char*>(head), 8);
  in.seekg(size - 12);
  in.read(reinterpret_cast<char*>(tail), 12);
  return in.good() && std::memcmp(head, kSignature, 8) == 0 && std::memcmp(tail, kEnd, 12) == 0;
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
  std::sort(files.begin(), files.end(), NaturalLess);
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
