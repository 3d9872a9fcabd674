#include "impactdic/io/image_io.h"

#include <fmt/format.h>
#include <fnmatch.h>
#include <sys/stat.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>  // flags only: the codecs are in the plugin (io/opencv_codecs.h)
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>  // property ids only
#include <optional>
#include <system_error>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/input_file.h"
#include "impactdic/io/opencv_codecs.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/io/png_grey.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace {

bool IsImageFile(const fs::path& p) {
  static const char* kExt[] = {".tif", ".tiff", ".png", ".bmp", ".jpg", ".jpeg", ".pgm", ".jp2"};
  const std::string ext = ToLower(p.extension().string());
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

constexpr const char* kImageWhat = "an 8- or 16-bit TIFF/PNG/BMP/JPEG image";

std::uint32_t BigEndian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

// Image dimensions from the file header, without decoding. Knows PNG, TIFF, BMP and JPEG (the
// camera formats); false for anything else, which OpenCV then decodes under its own limits.
class HeaderReader {
 public:
  explicit HeaderReader(const std::string& bytes)
      : p_(reinterpret_cast<const unsigned char*>(bytes.data())), n_(bytes.size()) {}

  bool Size(long long* width, long long* height) const {
    if (n_ >= 24 && std::memcmp(p_, "\x89PNG\r\n\x1a\n", 8) == 0 &&
        std::memcmp(p_ + 12, "IHDR", 4) == 0) {
      *width = BigEndian32(p_ + 16);
      *height = BigEndian32(p_ + 20);
      return true;
    }
    if (n_ >= 26 && p_[0] == 'B' && p_[1] == 'M') {
      // Signed; a negative height means rows stored top-down.
      *width = std::llabs(static_cast<long long>(static_cast<std::int32_t>(Little(18, 4))));
      *height = std::llabs(static_cast<long long>(static_cast<std::int32_t>(Little(22, 4))));
      return true;
    }
    if (n_ >= 8 && ((p_[0] == 'I' && p_[1] == 'I') || (p_[0] == 'M' && p_[1] == 'M')))
      return TiffSize(width, height);
    if (n_ >= 4 && p_[0] == 0xFF && p_[1] == 0xD8) return JpegSize(width, height);
    return false;
  }

  // Whether the file is a palette (indexed colour) TIFF: PhotometricInterpretation (262) = 3 in
  // its first image file directory. `grey` tells whether every entry of its ColorMap (320; all
  // red values, then all green, then all blue, 16 bits each) has red = green = blue.
  bool TiffPalette(bool* grey) const {
    if (n_ < 8 || !((p_[0] == 'I' && p_[1] == 'I') || (p_[0] == 'M' && p_[1] == 'M'))) return false;
    const bool le = p_[0] == 'I';
    if (Read(2, 2, le) != 42) return false;
    const std::uint64_t ifd = Read(4, 4, le);
    if (ifd + 2 > n_) return false;
    const std::uint64_t entries = Read(ifd, 2, le);
    bool palette = false;
    std::uint64_t map_at = 0, map_count = 0;
    for (std::uint64_t e = 0; e < entries && ifd + 2 + 12 * (e + 1) <= n_; ++e) {
      const std::size_t at = ifd + 2 + 12 * e;
      const std::uint64_t tag = Read(at, 2, le), type = Read(at + 2, 2, le);
      if (tag == 262) palette = (type == 3 ? Read(at + 8, 2, le) : Read(at + 8, 4, le)) == 3;
      if (tag == 320 && type == 3) {
        map_count = Read(at + 4, 4, le);
        map_at = Read(at + 8, 4, le);
      }
    }
    if (!palette) return false;
    // A ColorMap that is missing or lies outside the file: not grey (OpenCV refuses it anyway).
    const std::uint64_t colours = map_count / 3;
    *grey = colours > 0 && map_count % 3 == 0 && map_at + 2 * map_count <= n_;
    for (std::uint64_t i = 0; *grey && i < colours; ++i) {
      const std::uint64_t r = Read(map_at + 2 * i, 2, le);
      *grey = r == Read(map_at + 2 * (colours + i), 2, le) &&
              r == Read(map_at + 2 * (2 * colours + i), 2, le);
    }
    return true;
  }

 private:
  std::uint64_t Read(std::size_t at, int bytes, bool little) const {
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) {
      const std::uint64_t b = p_[at + static_cast<std::size_t>(i)];
      v |= little ? b << (8 * i) : b << (8 * (bytes - 1 - i));
    }
    return v;
  }
  std::uint64_t Little(std::size_t at, int bytes) const { return Read(at, bytes, true); }

  // The first image file directory's ImageWidth (256) and ImageLength (257) tags.
  bool TiffSize(long long* width, long long* height) const {
    const bool le = p_[0] == 'I';
    if (Read(2, 2, le) != 42) return false;  // BigTIFF (43) and others: left to OpenCV.
    const std::uint64_t ifd = Read(4, 4, le);
    if (ifd + 2 > n_) return false;
    const std::uint64_t entries = Read(ifd, 2, le);
    bool w = false, h = false;
    for (std::uint64_t e = 0; e < entries && ifd + 2 + 12 * (e + 1) <= n_; ++e) {
      const std::size_t at = ifd + 2 + 12 * e;
      const std::uint64_t tag = Read(at, 2, le), type = Read(at + 2, 2, le);
      if (tag != 256 && tag != 257) continue;
      const auto value =
          static_cast<long long>(type == 3 ? Read(at + 8, 2, le) : Read(at + 8, 4, le));
      if (tag == 256) {
        *width = value;
        w = true;
      } else {
        *height = value;
        h = true;
      }
    }
    return w && h;
  }

  // The first start-of-frame marker (SOF0..SOF15 except DHT, JPG and DAC).
  bool JpegSize(long long* width, long long* height) const {
    std::size_t at = 2;
    while (at + 9 <= n_) {
      if (p_[at] != 0xFF) return false;
      const unsigned char marker = p_[at + 1];
      if (marker == 0xFF) {
        ++at;
        continue;
      }
      const auto length = static_cast<std::size_t>(Read(at + 2, 2, false));
      if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
        *height = static_cast<long long>(Read(at + 5, 2, false));
        *width = static_cast<long long>(Read(at + 7, 2, false));
        return true;
      }
      at += 2 + length;
    }
    return false;
  }

  const unsigned char* p_;
  std::size_t n_;
};

// A PNG's chunk structure: every chunk complete with a correct CRC, up to IEND. libpng would
// print "libpng error: ..." to stderr (through OpenCV, which keeps libpng's default handler) for
// a truncated or corrupted file before our own message; checking first keeps the output to one
// clear message. Returns "" when the structure is sound, else what is wrong.
std::string PngStructureProblem(const std::string& bytes) {
  // zlib's CRC-32 (ISO 3309, the PNG chunks'): 2x as fast as a table sliced by 8 bytes.
  const auto crc = [](const unsigned char* data, std::size_t n) {
    return static_cast<std::uint32_t>(crc32(crc32(0L, Z_NULL, 0), data, static_cast<uInt>(n)));
  };
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t n = bytes.size();
  std::size_t at = 8;
  while (at + 8 <= n) {
    const std::size_t length = BigEndian32(p + at);
    const std::string type(bytes, at + 4, 4);
    if (length > 0x7FFFFFFFu) return fmt::format("a corrupt chunk length at byte {}", at);
    if (at + 12 + length > n) {
      return fmt::format(
          "a truncated PNG: the file ends at byte {}, inside its '{}' chunk, which ends at "
          "byte {}",
          n, type, at + 12 + length);
    }
    if (crc(p + at + 4, length + 4) != BigEndian32(p + at + 8 + length))
      return fmt::format("a corrupt PNG: CRC error in its '{}' chunk at byte {}", type, at);
    if (type == "IEND") return "";
    at += 12 + length;
  }
  return fmt::format("a truncated PNG: the file ends at byte {} before its IEND chunk", n);
}

// A JPEG's marker structure (ITU-T T.81, annex B): marker segments, each scan's entropy-coded
// data up to the next marker, until the end-of-image marker FF D9. libjpeg decodes a JPEG that
// stops early with the missing blocks flat grey and only a warning on stderr ("Premature end of
// JPEG file") that OpenCV does not pass on; walking the markers first finds the truncation.
// Bytes after FF D9 are not looked at (cameras append their own data there). Returns "" when
// the structure is sound, else what is wrong.
std::string JpegStructureProblem(const std::string& bytes) {
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t n = bytes.size();
  const auto truncated = [n](const std::string& where) {
    return fmt::format(
        "a truncated JPEG: the file ends at byte {}, {}, before its end-of-image marker (FF D9)", n,
        where);
  };
  int scans = 0;
  std::size_t at = 2;  // after the start-of-image marker FF D8
  while (true) {
    if (at >= n) return truncated("after its last complete segment");
    if (p[at] != 0xFF) {
      return fmt::format("a corrupt JPEG: byte {} should start a marker (FF) but is {:02X}", at,
                         p[at]);
    }
    while (at + 1 < n && p[at + 1] == 0xFF) ++at;  // fill bytes
    if (at + 1 >= n) return truncated("inside a marker");
    const unsigned char marker = p[at + 1];
    if (marker == 0xD9) return "";
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {  // TEM, RSTn: no length
      at += 2;
      continue;
    }
    if (at + 4 > n) return truncated(fmt::format("inside the marker FF {:02X}", marker));
    const std::size_t length = std::size_t{p[at + 2]} << 8 | p[at + 3];
    if (length < 2)
      return fmt::format("a corrupt JPEG: the segment at byte {} has length {}", at, length);
    if (at + 2 + length > n) {
      return truncated(fmt::format("inside the segment FF {:02X} at byte {}, which ends at byte {}",
                                   marker, at, at + 2 + length));
    }
    at += 2 + length;
    if (marker != 0xDA) continue;
    // Start of scan: its entropy-coded data run to the next marker other than a stuffed zero
    // byte (FF 00) or a restart marker (FF D0..D7).
    ++scans;
    while (at + 1 < n && !(p[at] == 0xFF && p[at + 1] != 0x00 && p[at + 1] != 0xFF &&
                           (p[at + 1] < 0xD0 || p[at + 1] > 0xD7))) {
      ++at;
    }
    if (at + 1 >= n) {
      return truncated(fmt::format("inside the compressed image data of its scan {}", scans));
    }
  }
}

// What can be told of an image file before decoding it: Error naming the file when it is
// empty, when its header claims more than the size limits (image_io.h), or when a PNG's chunks or
// a JPEG's markers show it truncated or corrupt.
void CheckImageBytes(const std::string& path, const std::string& bytes) {
  if (bytes.empty()) {
    throw Error(ErrorKind::kFileFormat, fmt::format("is empty (0 bytes); expected {}", kImageWhat))
        .WithFile(path);
  }
  long long width = 0, height = 0;
  if (HeaderReader(bytes).Size(&width, &height) &&
      (width < 1 || height < 1 || width > kMaxImageSidePx || height > kMaxImageSidePx ||
       width * height > kMaxImagePixels)) {
    throw Error(ErrorKind::kFileFormat, "image size",
                fmt::format("{}x{} px in its header", width, height),
                fmt::format("at most {} px a side and {} pixels in all (e.g. 16384x16384)",
                            kMaxImageSidePx, kMaxImagePixels))
        .WithFile(path);
  }
  if (bytes.rfind("\x89PNG", 0) == 0) {
    const std::string problem = PngStructureProblem(bytes);
    if (!problem.empty())
      throw Error(ErrorKind::kFileFormat, "image", problem, "a complete PNG file").WithFile(path);
  }
  if (bytes.rfind("\xFF\xD8", 0) == 0) {
    const std::string problem = JpegStructureProblem(bytes);
    if (!problem.empty()) {
      throw Error(ErrorKind::kFileFormat, "image", problem,
                  "a complete JPEG file (data after its end-of-image marker are ignored)")
          .WithFile(path);
    }
  }
}

// The path of a directory entry that is to be a frame (its name has an image extension or
// matches the frames glob): Error naming it and what it is when it is not a regular file (a
// folder, a dangling symbolic link, a FIFO, a device), which would otherwise be left out of the
// list and reported as a missing frame. Judged by stat(), so a FIFO is never opened.
std::string CheckedFrame(const fs::directory_entry& entry) {
  std::string path = entry.path().string();
  std::error_code ec;
  if (!entry.is_regular_file(ec)) CheckImageFileExists(path);
  return path;
}

// Error when two names of a frame sequence are the same file (a symbolic or hard link, e.g.
// one made to fill a gap in the numbering): the repeated image would read as no motion over that
// frame interval.
void CheckDistinctFiles(const std::vector<std::string>& files) {
  const auto repeated = FirstRepeatedFile(files);
  if (!repeated) return;
  throw Error(
      ErrorKind::kInvalidValue, "frames",
      fmt::format("the same file as {} (a symbolic or hard link to it)", files[repeated->first]),
      "each frame of a sequence its own image: a repeated image reads as no motion "
      "over one frame interval")
      .WithFile(files[repeated->second]);
}

// The reason in what OpenCV's imgcodecs printed about a file it could not decode, e.g.
// "imdecode_(''): can't read data: OpenCV(4.6.0) .../bitstrm.cpp:102: error: (-2:Unspecified
// error) Unexpected end of input stream in function 'readBlock'" -> "Unexpected end of input
// stream in function 'readBlock'"; "" when it printed nothing.
std::string DecoderReason(const std::string& messages) {
  std::string text = messages;
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  const std::size_t line = text.rfind('\n');
  if (line != std::string::npos) text = text.substr(line + 1);
  const std::size_t error = text.find("error: (");
  const std::size_t end = error == std::string::npos ? error : text.find(") ", error);
  if (end != std::string::npos) return text.substr(end + 2);
  const std::size_t colon = text.find("): ");
  return colon == std::string::npos ? text : text.substr(colon + 3);
}

// A palette TIFF whose palette is not grey: converted to grey like a colour frame, with one
// warning per process (a sequence of such frames would otherwise repeat it for every frame).
void WarnColourPalette(const std::string& path) {
  static std::atomic<bool> warned{false};
  if (warned.exchange(true)) return;
  LogWarning(
      "{} is a palette (indexed colour) TIFF whose palette is not grey: its colours are converted "
      "to grey (0.299 R + 0.587 G + 0.114 B), as for colour frames; further such images are not "
      "listed",
      path);
}

}  // namespace

std::vector<long long> FrameNumbers(const std::vector<std::string>& files) {
  std::vector<long long> numbers;
  std::string prefix0, suffix0;
  for (std::size_t k = 0; k < files.size(); ++k) {
    std::string prefix, suffix;
    long long number = 0;
    // More than 9 digits: a timestamp, not a frame counter.
    if (!SplitFrameNumber(files[k], &prefix, &number, &suffix) || number > 999999999) return {};
    if (k == 0) {
      prefix0 = prefix;
      suffix0 = suffix;
    } else if (prefix != prefix0 || suffix != suffix0) {
      return {};  // Not one numbered series.
    }
    numbers.push_back(number);
  }
  return numbers;
}

void CheckFrameNumbering(const std::vector<std::string>& files) {
  if (files.size() < 3) return;
  // Timestamps and names that are not one numbered series: nothing to check.
  const std::vector<long long> numbers = FrameNumbers(files);
  if (numbers.empty()) return;
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
  CheckInputFile(path, kImageWhat, kMaxImageFileBytes);
}

cv::Mat ReadGreyImage(const std::string& path, int* file_channels) {
  const std::string bytes = ReadInputFile(path, kImageWhat, kMaxImageFileBytes);
  CheckImageBytes(path, bytes);
  cv::Mat image;
  std::string messages;  // what OpenCV's decoder printed instead of throwing
  try {
    // Greyscale PNGs without OpenCV's codecs (loading them costs more than decoding a frame).
    // Any other PNG's image data are checked first, so that libpng has nothing to complain of.
    // CheckImageBytes has checked a PNG's chunk CRCs.
    if (!DecodeGreyPng(bytes, &image, PngChunkCrcs::kCheckedByCaller)) {
      const std::string problem = PngImageDataProblem(bytes);
      if (!problem.empty())
        throw Error(ErrorKind::kFileFormat, "image", problem, "a valid PNG file").WithFile(path);
      image = opencv_codecs::Decode(bytes, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR, &messages);
    }
  } catch (const cv::Exception& e) {
    throw Error(ErrorKind::kFileFormat, "image", "a file OpenCV cannot decode: " + e.err,
                kImageWhat)
        .WithFile(path);
  }
  if (image.empty()) {
    const std::string why = DecoderReason(messages);
    throw Error(ErrorKind::kFileFormat, "image",
                why.empty() ? "a file OpenCV cannot decode (corrupt or truncated?)"
                            : "a file OpenCV cannot decode: " + why,
                kImageWhat)
        .WithFile(path);
  }
  // OpenCV expands a palette TIFF into BGR colour. A grey palette (red = green = blue) gives three
  // equal channels, so the conversion below returns exactly the palette's grey values: the file
  // is a greyscale image. Any other palette is a colour image, converted like one.
  bool grey_palette = false;
  if (HeaderReader(bytes).TiffPalette(&grey_palette) && !grey_palette) WarnColourPalette(path);
  if (file_channels) *file_channels = grey_palette ? 1 : image.channels();
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

int DataBits(const cv::Mat& image) {
  if (image.depth() == CV_8U) return 8;
  if (image.depth() != CV_16U) return 0;
  double max_value = 0;
  cv::minMaxLoc(image.reshape(1), nullptr, &max_value);
  return max_value <= 4095 ? 12 : 16;
}

std::string DepthName(const cv::Mat& image) {
  switch (image.depth()) {
    case CV_8U: return "8-bit";
    case CV_16U: return "16-bit";
    case CV_32F: return "32-bit float";
    default: return "depth code " + std::to_string(image.depth());
  }
}

std::string SequenceColourCheck::Check(const std::string& path, int file_channels) {
  if (first_path_.empty()) {
    first_path_ = path;
    first_channels_ = file_channels;
    return "";
  }
  if (file_channels == first_channels_) return "";
  ++mismatches_;
  if (mismatches_ > kListed) return "";
  auto layout = [](int c) {
    return c == 1 ? std::string("greyscale") : fmt::format("{}-channel colour", c);
  };
  std::string text =
      fmt::format("{} is a {} image in a sequence whose first image {} is {}: converted to grey{}",
                  path, layout(file_channels), first_path_, layout(first_channels_),
                  file_channels > 1 ? " (0.299 R + 0.587 G + 0.114 B)" : "");
  if (mismatches_ == kListed) text += "; further images that differ are not listed";
  LogWarning("{}", text);
  return text;
}

void WriteImage(const std::string& path, const cv::Mat& image, const std::vector<int>& params) {
  // Encoded in memory (OpenCV picks the encoder from the extension) and written with our checked
  // writes: libpng's own file writing reports a full disk only as "libpng error: Write Error".
  const std::string ext = fs::path(path).extension().string();
  std::vector<uchar> bytes;
  bool ok = false;
  try {
    ok = !ext.empty() && opencv_codecs::Encode(ext, image, &bytes, params);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) {
    throw Error(ErrorKind::kIo, "image", "OpenCV could not encode it",
                "an image extension (.png, .tif, ...)")
        .WithFile(OutputPathForMessages(path));
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
      if (IsImageFile(entry.path())) files.push_back(CheckedFrame(entry));
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
      if (fnmatch(name_pattern.c_str(), entry.path().filename().c_str(), 0) != 0) continue;
      if (entry.is_regular_file(ec) || IsImageFile(entry.path()))
        files.push_back(CheckedFrame(entry));
    }
  } else if (fs::is_regular_file(source, ec)) {
    files.push_back(source);
  } else if (fs::exists(fs::symlink_status(source, ec))) {
    CheckImageFileExists(source);  // a dangling link, a FIFO, a device: named as such
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

std::optional<std::pair<std::size_t, std::size_t>> FirstRepeatedFile(
    const std::vector<std::string>& paths) {
  std::map<std::pair<dev_t, ino_t>, std::size_t> seen;
  for (std::size_t k = 0; k < paths.size(); ++k) {
    struct stat info {};
    if (stat(paths[k].c_str(), &info) != 0) continue;
    const auto [it, added] = seen.emplace(std::make_pair(info.st_dev, info.st_ino), k);
    if (!added) return std::make_pair(it->second, k);
  }
  return std::nullopt;
}

std::vector<std::string> ListFrameSequence(const std::string& source) {
  std::vector<std::string> files = ListFrames(source);
  CheckFrameNumbering(files);
  CheckDistinctFiles(files);
  return files;
}

bool IsVideoFile(const std::string& path) {
  const std::string ext = ToLower(fs::path(path).extension().string());
  return ext == ".mp4" || ext == ".avi" || ext == ".mov" || ext == ".mkv";
}

struct VideoReader::Impl {
  opencv_codecs::VideoCapture capture;
  cv::Mat frame;
};

VideoReader::VideoReader(const std::string& path) : impl_(std::make_unique<Impl>()), path_(path) {
  static constexpr const char* kVideoWhat = "a video file OpenCV can decode (.mp4, .avi, ...)";
  CheckInputFile(path, kVideoWhat, std::numeric_limits<std::uintmax_t>::max());
  // An empty file: FFmpeg and GStreamer would each try it and fail with messages of their own.
  std::error_code ec;
  if (fs::file_size(path, ec) == 0 && !ec) {
    throw Error(ErrorKind::kFileFormat, fmt::format("is empty (0 bytes); expected {}", kVideoWhat))
        .WithFile(path);
  }
  // FFmpeg alone where OpenCV has it (the animation is written with it too): with any backend,
  // a file FFmpeg cannot open goes on to the others, GStreamer printing its own warnings and an
  // assertion ("uridecodebin"), and LeakSanitizer finding libusb device lists left behind.
  const int api =
      opencv_codecs::HasVideoBackend(cv::CAP_FFMPEG) ? int{cv::CAP_FFMPEG} : int{cv::CAP_ANY};
  if (!impl_->capture.Open(path, api)) {
    throw Error(ErrorKind::kFileFormat, "video", "a file OpenCV cannot open",
                "a video OpenCV can decode (.mp4, .avi, ...)")
        .WithFile(path);
  }
  declared_ = impl_->capture.Get(cv::CAP_PROP_FRAME_COUNT);
}

VideoReader::~VideoReader() = default;

bool VideoReader::Read(cv::Mat* grey) {
  if (!impl_->capture.Read(&impl_->frame)) return false;
  // A new buffer for every frame: the caller may keep the previous one.
  cv::Mat out;
  if (impl_->frame.channels() == 3) {
    cv::cvtColor(impl_->frame, out, cv::COLOR_BGR2GRAY);
  } else {
    out = impl_->frame.clone();
  }
  *grey = out;
  ++frames_read_;
  return true;
}

std::string VideoReader::Finish(int max_frames) const {
  const auto wanted = static_cast<long long>(
      max_frames > 0 ? std::min(declared_, static_cast<double>(max_frames)) : declared_);
  if (declared_ <= 0 || frames_read_ >= wanted) return "";
  std::string text = fmt::format(
      "{}: decoded {} frames but the container declares {}: the video is truncated or "
      "damaged; the sequence ends after frame {}",
      path_, frames_read_, static_cast<long long>(declared_), frames_read_ - 1);
  LogWarning("{}", text);
  return text;
}

std::vector<cv::Mat> ReadVideoFrames(const std::string& path, int max_frames,
                                     std::string* warning) {
  VideoReader video(path);
  std::vector<cv::Mat> frames;
  cv::Mat frame;
  while ((max_frames <= 0 || static_cast<int>(frames.size()) < max_frames) && video.Read(&frame))
    frames.push_back(frame);
  if (frames.empty()) {
    throw Error(ErrorKind::kFileFormat, "video", "no decodable frames", "at least one frame")
        .WithFile(path);
  }
  const std::string text = video.Finish(max_frames);
  if (warning && !text.empty()) *warning = text;
  return frames;
}

void CheckSameSize(const std::vector<cv::Mat>& images, const std::vector<std::string>& names) {
  for (std::size_t i = 1; i < images.size(); ++i) {
    if (images[i].size() != images[0].size() || images[i].depth() != images[0].depth()) {
      const std::string name = i < names.size() ? names[i] : "frame " + std::to_string(i);
      throw Error(ErrorKind::kFileFormat, "image size",
                  std::to_string(images[i].cols) + "x" + std::to_string(images[i].rows) + " " +
                      DepthName(images[i]),
                  std::to_string(images[0].cols) + "x" + std::to_string(images[0].rows) + " " +
                      DepthName(images[0]) + " like the first image")
          .WithFile(name);
    }
  }
}

}  // namespace impactdic
