// Phantom .cine reader, written from Vision Research's "The Cine File Format" (public document).
//
// Layout (all little-endian):
//   CINEFILEHEADER (44 bytes at 0): "CI", header size, Compression (0 grey, 1 JPEG, 2 raw colour
//     CFA), version, first/total recorded images, FirstImageNo (camera number of the file's first
//     image, negative before the trigger), ImageCount, OffImageHeader, OffSetup,
//     OffImageOffsets, TriggerTime (TIME64).
//   BITMAPINFOHEADER (40 bytes at OffImageHeader): biWidth, biHeight (> 0: rows stored bottom-up),
//     biBitCount (8 or 16 per pixel in the container), biCompression (0 plain, 256 10-bit packed,
//     1024 12-bit packed), biSizeImage.
//   SETUP (at OffSetup, packed to 1 byte): FrameRate16 at 0, "ST" at 140 and the structure's
//     Length at 142, FrameRate (u32) at 768, CFA at 808, RealBPP at 896.
//   Tagged information blocks from OffSetup + Length up to OffImageOffsets: u32 BlockSize
//     (including this 8-byte header), u16 Type, u16 reserved, data. Type 1002 holds one TIME64
//     per image.
//   pImage (ImageCount u64 at OffImageOffsets): each image starts with an annotation block
//     (u32 AnnotationSize including itself, ..., u32 ImageSize as its last 4 bytes), then the
//     pixels.
// TIME64 is 32.32 fixed point: u32 fractions of a second (/ 2^32; its 2 low bits are IRIG flags,
// < 1 ns, left in), then u32 seconds.
// The images of a cine are consecutive camera frames (FirstImageNo, FirstImageNo + 1, ...): the
// format has no save step (SETUP's Decimation is the rate reduction of a Phantom's link to its
// external i3 memory, not of the saved images; a frame rate profile, FRPSteps, changes the rate
// within a recording and shows in the time stamps).
// Checked at open: FrameRate in kCameraFpsRange and within 1 % of the median interval of the
// time stamps (a setup that contradicts them is refused with both rates), and an image size that
// fits in the file (a corrupt biWidth/biHeight is named as such, not as a truncated frame).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/range.h"
#include "impactdic/io/camera_file.h"

namespace impactdic {
namespace {

constexpr std::uint64_t kFileHeaderBytes = 44;
constexpr std::uint64_t kBitmapHeaderBytes = 40;
constexpr std::uint64_t kAnnotationMinBytes = 8;  // AnnotationSize and ImageSize.
constexpr std::uint64_t kSetupMarkOffset = 140;
constexpr std::uint64_t kSetupLengthOffset = 142;
constexpr std::uint64_t kSetupFrameRateOffset = 768;
constexpr std::uint64_t kSetupRealBppOffset = 896;
constexpr std::uint16_t kTagTimeOnly = 1002;
constexpr std::uint32_t kBiPlain = 0;
constexpr std::uint32_t kBiPacked10 = 256;
constexpr std::uint32_t kBiPacked12 = 1024;
constexpr std::uint16_t kCompressionGrey = 0;
constexpr std::uint16_t kCompressionJpeg = 1;
constexpr std::uint16_t kCompressionColourRaw = 2;
// Larger images than this are no camera's: a corrupt header, refused before allocating.
constexpr std::int64_t kMaxSidePx = 1 << 16;
// How far FrameRate may differ from the rate of the time stamps (their median interval): a
// Phantom's clock and its stated integer rate agree far better.
constexpr double kFrameRateTolerance = 0.01;

const char* const kFormat = "Phantom cine";
const char* const kResave =
    "save the cine again from Phantom Camera Control (PCC) as an uncompressed greyscale "
    "(monochrome) cine";

std::uint16_t U16(const std::vector<char>& b, std::uint64_t at) {
  return static_cast<std::uint16_t>(static_cast<unsigned char>(b[at]) |
                                    (static_cast<unsigned char>(b[at + 1]) << 8));
}

std::uint32_t U32(const std::vector<char>& b, std::uint64_t at) {
  return static_cast<std::uint32_t>(U16(b, at)) |
         (static_cast<std::uint32_t>(U16(b, at + 2)) << 16);
}

std::int32_t I32(const std::vector<char>& b, std::uint64_t at) {
  return static_cast<std::int32_t>(U32(b, at));
}

std::uint64_t U64(const std::vector<char>& b, std::uint64_t at) {
  return static_cast<std::uint64_t>(U32(b, at)) |
         (static_cast<std::uint64_t>(U32(b, at + 4)) << 32);
}

// TIME64 at `at` minus `origin` (both TIME64) [s].
double Time64Difference(const std::vector<char>& b, std::uint64_t at,
                        std::uint32_t origin_fractions, std::uint32_t origin_seconds) {
  const double seconds = static_cast<double>(static_cast<std::int64_t>(U32(b, at + 4)) -
                                             static_cast<std::int64_t>(origin_seconds));
  const double fractions = static_cast<double>(static_cast<std::int64_t>(U32(b, at)) -
                                               static_cast<std::int64_t>(origin_fractions));
  return seconds + fractions / 4294967296.0;
}

// What the header says of the pixels.
struct PixelLayout {
  int width_px = 0;
  int height_px = 0;
  bool bottom_up = true;          // Rows stored last row first (positive biHeight).
  int container_bits = 8;         // 8 or 16 for plain data; 10 or 12 for packed.
  bool packed = false;            // 10 or 12-bit packed stream, most significant bits first.
  std::uint64_t row_bytes = 0;    // Plain data: bytes per stored row.
  std::uint64_t frame_bytes = 0;  // Bytes of one image's pixels.
};

class CineFile final : public CameraFileReader {
 public:
  explicit CineFile(const std::string& path);
  const CameraFileInfo& info() const override { return info_; }
  cv::Mat ReadFrame(long long index) override;

 private:
  Error FormatError(const std::string& found, const std::string& expected) const {
    return Error(ErrorKind::kFileFormat, info_.path, found, expected);
  }
  // `bytes` bytes at `offset`, or an error naming `what` when the file ends before them.
  std::vector<char> ReadAt(std::uint64_t offset, std::uint64_t bytes, const std::string& what);
  Error Truncated(long long index) const;
  void ReadFileHeader();
  void ReadBitmapHeader();
  void ReadSetup();
  void ReadTimeStamps();
  // Error naming both rates when FrameRate differs from the rate of the time stamps.
  void CheckRateAgainstTimeStamps() const;
  void ReadImageOffsets();
  cv::Mat Decode(const std::vector<char>& pixels) const;

  CameraFileInfo info_;
  std::ifstream file_;
  std::uint64_t file_bytes_ = 0;
  std::vector<char> header_;  // CINEFILEHEADER.
  PixelLayout layout_;
  std::uint64_t setup_offset_ = 0;
  std::uint64_t setup_length_ = 0;  // 0 when the setup carries no "ST" mark and length.
  std::uint64_t offsets_offset_ = 0;
  std::vector<std::uint64_t> image_offsets_;
};

CineFile::CineFile(const std::string& path) {
  info_.path = path;
  info_.format = kFormat;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw Error(ErrorKind::kFileNotFound, path, "no such file", "a Phantom .cine file");
  }
  file_bytes_ = std::filesystem::file_size(path, ec);
  if (ec) throw Error(ErrorKind::kIo, path, ec.message(), "a readable file");
  file_.open(path, std::ios::binary);
  if (!file_) throw Error(ErrorKind::kIo, path, "cannot open for reading", "a readable file");
  ReadFileHeader();
  ReadBitmapHeader();
  ReadSetup();
  ReadImageOffsets();
  ReadTimeStamps();
}

std::vector<char> CineFile::ReadAt(std::uint64_t offset, std::uint64_t bytes,
                                   const std::string& what) {
  if (offset > file_bytes_ || bytes > file_bytes_ - offset) {
    throw FormatError(what + " at byte " + std::to_string(offset) + " (" + std::to_string(bytes) +
                          " bytes) past the end of the " + std::to_string(file_bytes_) +
                          "-byte file",
                      "a complete cine file (is the file truncated? copy or save it again)");
  }
  std::vector<char> buffer(bytes);
  file_.clear();
  file_.seekg(static_cast<std::streamoff>(offset));
  file_.read(buffer.data(), static_cast<std::streamsize>(bytes));
  if (!file_) {
    throw Error(ErrorKind::kIo, info_.path, "reading " + what + " failed", "a readable file");
  }
  return buffer;
}

void CineFile::ReadFileHeader() {
  if (file_bytes_ < kFileHeaderBytes) {
    throw FormatError(std::to_string(file_bytes_) + " bytes",
                      "a Phantom cine file (at least its 44-byte header)");
  }
  header_ = ReadAt(0, kFileHeaderBytes, "the file header");
  if (header_[0] != 'C' || header_[1] != 'I') {
    throw FormatError("no \"CI\" at its start", "a Phantom .cine file (it starts with \"CI\")");
  }
  const std::uint16_t compression = U16(header_, 4);
  if (compression == kCompressionColourRaw) {
    throw FormatError("a colour recording (raw colour-filter-array / Bayer pixels)",
                      "greyscale data: " + std::string(kResave));
  }
  if (compression == kCompressionJpeg) {
    throw FormatError("JPEG-compressed images", "uncompressed images: " + std::string(kResave));
  }
  if (compression != kCompressionGrey) {
    throw FormatError("unknown Compression code " + std::to_string(compression),
                      "0 (uncompressed): " + std::string(kResave));
  }
  const std::uint32_t image_count = U32(header_, 20);
  if (image_count == 0) throw FormatError("ImageCount 0", "a recording of at least one image");
  info_.frame_count = image_count;
  info_.first_frame_number = I32(header_, 16);
  setup_offset_ = U32(header_, 28);
  offsets_offset_ = U32(header_, 32);
}

void CineFile::ReadBitmapHeader() {
  const std::vector<char> bi = ReadAt(U32(header_, 24), kBitmapHeaderBytes, "the image header");
  const std::int64_t width = I32(bi, 4);
  const std::int64_t height = I32(bi, 8);
  const std::uint16_t bit_count = U16(bi, 14);
  const std::uint32_t compression = U32(bi, 16);
  const std::int64_t abs_height = height < 0 ? -height : height;
  if (width <= 0 || width > kMaxSidePx || abs_height == 0 || abs_height > kMaxSidePx) {
    throw FormatError("image size " + std::to_string(width) + " x " + std::to_string(height),
                      "1 .. 65536 pixels a side");
  }
  if (bit_count == 24 || bit_count == 48) {
    throw FormatError("a colour recording (" + std::to_string(bit_count) + "-bit RGB pixels)",
                      "greyscale data: " + std::string(kResave));
  }
  PixelLayout& l = layout_;
  l.width_px = static_cast<int>(width);
  l.height_px = static_cast<int>(abs_height);
  l.bottom_up = height > 0;
  const auto pixels = static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(abs_height);
  if (compression == kBiPlain && (bit_count == 8 || bit_count == 16)) {
    l.container_bits = bit_count;
    l.row_bytes = static_cast<std::uint64_t>(width) * (bit_count / 8);
    l.frame_bytes = l.row_bytes * static_cast<std::uint64_t>(abs_height);
  } else if (compression == kBiPacked10 || compression == kBiPacked12) {
    // Packed images are one bit stream over the whole frame, rows top-down (as Phantom's own
    // software and the published readers treat them).
    l.packed = true;
    l.bottom_up = false;
    l.container_bits = compression == kBiPacked10 ? 10 : 12;
    l.frame_bytes = (pixels * static_cast<std::uint64_t>(l.container_bits) + 7) / 8;
  } else {
    throw FormatError(
        "biCompression " + std::to_string(compression) + " with " + std::to_string(bit_count) +
            " bits per pixel",
        "uncompressed 8 or 16-bit, or 10 or 12-bit packed pixels: " + std::string(kResave));
  }
  info_.width_px = l.width_px;
  info_.height_px = l.height_px;
  info_.data_bits = l.container_bits;
}

void CineFile::ReadSetup() {
  // The setup's fixed start (up to its Length field), then as much of it as it says it has.
  const std::vector<char> start = ReadAt(setup_offset_, kSetupLengthOffset + 2, "the camera setup");
  double fps = U16(start, 0);  // FrameRate16, replaced by FrameRate where present.
  const char* fps_field = "FrameRate16";
  if (start[kSetupMarkOffset] == 'S' && start[kSetupMarkOffset + 1] == 'T') {
    setup_length_ = U16(start, kSetupLengthOffset);
    const std::vector<char> setup = ReadAt(setup_offset_, setup_length_, "the camera setup");
    if (setup_length_ >= kSetupFrameRateOffset + 4 && U32(setup, kSetupFrameRateOffset) > 0) {
      fps = U32(setup, kSetupFrameRateOffset);
      fps_field = "FrameRate";
    }
    if (setup_length_ >= kSetupRealBppOffset + 4) {
      const std::uint32_t real_bpp = U32(setup, kSetupRealBppOffset);
      // Only a depth that fits the container: 8-bit data holds 8, 16-bit data 9 .. 16, packed
      // data its packing.
      const bool fits = layout_.packed
                            ? real_bpp == static_cast<std::uint32_t>(layout_.container_bits)
                        : layout_.container_bits == 8 ? real_bpp == 8
                                                      : real_bpp >= 9 && real_bpp <= 16;
      if (fits) info_.data_bits = static_cast<int>(real_bpp);
    }
  }
  if (!kCameraFpsRange.Contains(fps)) {
    throw Error(ErrorKind::kFileFormat, fps_field, fmt::format("{:g} frames/s", fps),
                ExpectedText("a recording frame rate", kCameraFpsRange) + " in the camera setup")
        .WithFile(info_.path);
  }
  info_.fps = fps;
}

void CineFile::ReadImageOffsets() {
  const auto count = static_cast<std::uint64_t>(info_.frame_count);
  if (count > (file_bytes_ - std::min(file_bytes_, offsets_offset_)) / 8) {
    throw FormatError("ImageCount " + std::to_string(count) + " image offsets at byte " +
                          std::to_string(offsets_offset_) + " past the end of the " +
                          std::to_string(file_bytes_) + "-byte file",
                      "a complete cine file (is it truncated? copy or save it again)");
  }
  const std::vector<char> table = ReadAt(offsets_offset_, count * 8, "the image offsets");
  image_offsets_.resize(count);
  for (std::uint64_t i = 0; i < count; ++i) image_offsets_[i] = U64(table, i * 8);
  // Images closer together than the image header's size, or larger than the whole file: a corrupt
  // biWidth/biHeight, not a truncated file (whose images lie where they should, up to its end).
  const std::uint64_t image_bytes = kAnnotationMinBytes + layout_.frame_bytes;
  const std::uint64_t spacing = count >= 2 && image_offsets_[1] > image_offsets_[0]
                                    ? image_offsets_[1] - image_offsets_[0]
                                    : 0;
  if ((spacing > 0 && spacing < image_bytes) || image_bytes > file_bytes_) {
    throw FormatError(
        fmt::format("biWidth x biHeight {} x {} pixels of {} bits: {} bytes a frame, {}",
                    layout_.width_px, layout_.height_px, layout_.container_bits,
                    layout_.frame_bytes,
                    spacing > 0 && spacing < image_bytes
                        ? fmt::format("while the file's images are {} bytes apart", spacing)
                        : fmt::format("more than the whole {}-byte file", file_bytes_)),
        "image dimensions of the frames the file holds (a corrupt image header; save the cine "
        "again from Phantom Camera Control)");
  }
  for (std::uint64_t i = 0; i < count; ++i) {
    if (image_offsets_[i] > file_bytes_ || image_bytes > file_bytes_ - image_offsets_[i]) {
      throw Truncated(static_cast<long long>(i));
    }
  }
}

Error CineFile::Truncated(long long index) const {
  return FormatError("the file (" + std::to_string(file_bytes_) + " bytes) ends inside frame " +
                         std::to_string(index) + " (camera frame " +
                         std::to_string(info_.first_frame_number + index) + ")",
                     "a complete cine file: it is truncated (an interrupted copy or save?); copy "
                     "it again or save it again from the camera software");
}

void CineFile::CheckRateAgainstTimeStamps() const {
  const std::vector<double>& t = info_.time_s;
  if (t.size() < 2) return;
  std::vector<double> dt(t.size() - 1);
  for (std::size_t i = 0; i + 1 < t.size(); ++i) dt[i] = t[i + 1] - t[i];
  const auto middle = dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2);
  std::nth_element(dt.begin(), middle, dt.end());
  const double median_s = *middle;
  if (std::abs(median_s * info_.fps - 1) <= kFrameRateTolerance) return;
  throw Error(ErrorKind::kFileFormat, "FrameRate",
              fmt::format("{:g} frames/s, while the time stamps say {:.6g} frames/s (median "
                          "interval {:.6g} s of {} intervals)",
                          info_.fps, 1 / median_s, median_s, dt.size()),
              fmt::format("a frame rate within {:g} % of the time stamps' (the camera setup "
                          "contradicts the time stamps: save the cine again from Phantom Camera "
                          "Control)",
                          100 * kFrameRateTolerance))
      .WithFile(info_.path);
}

void CineFile::ReadTimeStamps() {
  const auto count = static_cast<std::size_t>(info_.frame_count);
  info_.time_s.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    info_.time_s[i] =
        static_cast<double>(info_.first_frame_number + static_cast<long long>(i)) / info_.fps;
  }
  if (setup_length_ == 0) return;
  std::uint64_t at = setup_offset_ + setup_length_;
  const std::uint64_t end = std::min(offsets_offset_, file_bytes_);
  while (at + 8 <= end) {
    const std::vector<char> block_header = ReadAt(at, 8, "a tagged information block");
    const std::uint64_t block_bytes = U32(block_header, 0);
    if (block_bytes < 8 || block_bytes > end - at) return;  // Not (or no longer) tagged blocks.
    if (U16(block_header, 4) == kTagTimeOnly && (block_bytes - 8) / 8 >= count) {
      const std::vector<char> stamps = ReadAt(at + 8, 8 * count, "the image time stamps");
      const std::uint32_t trigger_fractions = U32(header_, 36);
      const std::uint32_t trigger_seconds = U32(header_, 40);
      for (std::size_t i = 0; i < count; ++i) {
        info_.time_s[i] = Time64Difference(stamps, 8 * i, trigger_fractions, trigger_seconds);
      }
      CheckRateAgainstTimeStamps();
      return;
    }
    at += block_bytes;
  }
}

cv::Mat CineFile::ReadFrame(long long index) {
  if (index < 0 || index >= info_.frame_count) {
    throw Error(ErrorKind::kInvalidValue, info_.path, "frame index " + std::to_string(index),
                "0 .. " + std::to_string(info_.frame_count - 1) + " (camera frames " +
                    std::to_string(info_.first_frame_number) + " .. " +
                    std::to_string(info_.first_frame_number + info_.frame_count - 1) + ")");
  }
  const std::uint64_t offset = image_offsets_[static_cast<std::size_t>(index)];
  const std::vector<char> size_field = ReadAt(offset, 4, "an image's annotation");
  const std::uint64_t annotation_bytes = U32(size_field, 0);
  if (annotation_bytes < kAnnotationMinBytes) {
    throw FormatError("annotation size " + std::to_string(annotation_bytes) + " of frame " +
                          std::to_string(index),
                      "at least 8 bytes");
  }
  if (annotation_bytes > file_bytes_ - offset ||
      layout_.frame_bytes > file_bytes_ - offset - annotation_bytes) {
    throw Truncated(index);
  }
  const std::vector<char> pixels =
      ReadAt(offset + annotation_bytes, layout_.frame_bytes, "frame " + std::to_string(index));
  return Decode(pixels);
}

cv::Mat CineFile::Decode(const std::vector<char>& pixels) const {
  const PixelLayout& l = layout_;
  const auto* bytes = reinterpret_cast<const unsigned char*>(pixels.data());
  if (l.container_bits == 8) {
    cv::Mat frame(l.height_px, l.width_px, CV_8UC1);
    for (int r = 0; r < l.height_px; ++r) {
      const int out_row = l.bottom_up ? l.height_px - 1 - r : r;
      std::copy_n(bytes + static_cast<std::uint64_t>(r) * l.row_bytes, l.width_px,
                  frame.ptr<unsigned char>(out_row));
    }
    return frame;
  }
  cv::Mat frame(l.height_px, l.width_px, CV_16UC1);
  if (!l.packed) {
    for (int r = 0; r < l.height_px; ++r) {
      const unsigned char* in = bytes + static_cast<std::uint64_t>(r) * l.row_bytes;
      auto* out = frame.ptr<std::uint16_t>(l.bottom_up ? l.height_px - 1 - r : r);
      for (std::ptrdiff_t c = 0; c < l.width_px; ++c) {
        out[c] = static_cast<std::uint16_t>(in[2 * c] | (in[2 * c + 1] << 8));
      }
    }
    return frame;
  }
  // Packed: pixel k occupies bits [k * bits, (k + 1) * bits) of the stream, most significant bit
  // first (10-bit: 4 pixels in 5 bytes; 12-bit: 2 pixels in 3 bytes).
  const auto bits = static_cast<std::uint64_t>(l.container_bits);
  const std::uint32_t mask = (1U << bits) - 1U;
  std::uint64_t bit = 0;
  for (int r = 0; r < l.height_px; ++r) {
    auto* out = frame.ptr<std::uint16_t>(r);
    for (int c = 0; c < l.width_px; ++c, bit += bits) {
      const std::uint64_t byte = bit / 8;
      // Three bytes hold any 10 or 12-bit field; the last byte may be the stream's end.
      std::uint32_t window = static_cast<std::uint32_t>(bytes[byte]) << 16;
      if (byte + 1 < pixels.size()) window |= static_cast<std::uint32_t>(bytes[byte + 1]) << 8;
      if (byte + 2 < pixels.size()) window |= bytes[byte + 2];
      const auto shift = static_cast<unsigned>(24 - (bit % 8) - bits);
      out[c] = static_cast<std::uint16_t>((window >> shift) & mask);
    }
  }
  return frame;
}

}  // namespace

std::unique_ptr<CameraFileReader> OpenCineFile(const std::string& path) {
  return std::make_unique<CineFile>(path);
}

}  // namespace impactdic
