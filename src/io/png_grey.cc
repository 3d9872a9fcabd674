#include "impactdic/io/png_grey.h"

#include <fmt/format.h>
#include <zlib.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "inflate.h"

namespace impactdic {
namespace {

std::uint32_t BigEndian32(const unsigned char* p) {
  return std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 | std::uint32_t{p[2]} << 8 | p[3];
}

// The Paeth predictor (PNG specification, 2nd ed., section 9.4).
inline unsigned char Paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return static_cast<unsigned char>(a);
  return static_cast<unsigned char>(pb <= pc ? b : c);
}

// Sub, Average and Paeth for one byte per pixel (8-bit grey), the left neighbour carried in a
// register: read back from `out`, each byte waited for the store of the one before (~5 cycles a
// byte, 4 ms for a 2.8 MB frame). Sub, a running sum mod 256, adds 16 bytes at a time where SSE2
// is there: the sums inside the vector by shifted adds, plus the last byte of the one before.
void UnfilterSub1(const unsigned char* in, unsigned char* out, std::size_t bytes) {
  std::size_t i = 0;
#if defined(__SSE2__)
  __m128i carry = _mm_setzero_si128();  // Every byte: out[i - 1].
  for (; i + 16 <= bytes; i += 16) {
    __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i));
    x = _mm_add_epi8(x, _mm_slli_si128(x, 1));
    x = _mm_add_epi8(x, _mm_slli_si128(x, 2));
    x = _mm_add_epi8(x, _mm_slli_si128(x, 4));
    x = _mm_add_epi8(x, _mm_slli_si128(x, 8));
    x = _mm_add_epi8(x, carry);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), x);
    const __m128i high = _mm_unpackhi_epi16(_mm_unpackhi_epi8(x, x), _mm_unpackhi_epi8(x, x));
    carry = _mm_shuffle_epi32(high, 0xFF);  // Byte 15 in every byte.
  }
#endif
  unsigned char left = i > 0 ? out[i - 1] : 0;
  for (; i < bytes; ++i) out[i] = left = static_cast<unsigned char>(in[i] + left);
}

void UnfilterAverage1(const unsigned char* in, unsigned char* out, const unsigned char* prev,
                      std::size_t bytes) {
  int left = 0;
  for (std::size_t i = 0; i < bytes; ++i) {
    left = static_cast<unsigned char>(in[i] + ((left + (prev ? prev[i] : 0)) >> 1));
    out[i] = static_cast<unsigned char>(left);
  }
}

void UnfilterPaeth1(const unsigned char* in, unsigned char* out, const unsigned char* prev,
                    std::size_t bytes) {
  int left = 0, up_left = 0;
  for (std::size_t i = 0; i < bytes; ++i) {
    const int up = prev ? prev[i] : 0;
    left = static_cast<unsigned char>(in[i] + Paeth(left, up, up_left));
    out[i] = static_cast<unsigned char>(left);
    up_left = up;
  }
}

// Reverses the filter of one scanline: the filtered bytes `in` into `out` (which may be `in`
// itself); `prev` is the previous reconstructed line, or null for the first. bpp = bytes per
// pixel. False for an unknown filter type.
bool Unfilter(int type, const unsigned char* in, unsigned char* out, const unsigned char* prev,
              std::size_t bytes, std::size_t bpp) {
  if (bpp == 1 && type == 1) {
    UnfilterSub1(in, out, bytes);
    return true;
  }
  if (bpp == 1 && type == 3) {
    UnfilterAverage1(in, out, prev, bytes);
    return true;
  }
  if (bpp == 1 && type == 4) {
    UnfilterPaeth1(in, out, prev, bytes);
    return true;
  }
  switch (type) {
    case 0:
      if (out != in) std::memcpy(out, in, bytes);
      return true;
    case 1:
      for (std::size_t i = 0; i < bytes; ++i)
        out[i] = static_cast<unsigned char>(in[i] + (i >= bpp ? out[i - bpp] : 0));
      return true;
    case 2:
      for (std::size_t i = 0; i < bytes; ++i)
        out[i] = static_cast<unsigned char>(in[i] + (prev != nullptr ? prev[i] : 0));
      return true;
    case 3:
      for (std::size_t i = 0; i < bytes; ++i) {
        const int left = i >= bpp ? out[i - bpp] : 0, up = prev ? prev[i] : 0;
        out[i] = static_cast<unsigned char>(in[i] + ((left + up) >> 1));
      }
      return true;
    case 4:
      for (std::size_t i = 0; i < bytes; ++i) {
        const int left = i >= bpp ? out[i - bpp] : 0, up = prev ? prev[i] : 0;
        const int up_left = (prev && i >= bpp) ? prev[i - bpp] : 0;
        out[i] = static_cast<unsigned char>(in[i] + Paeth(left, up, up_left));
      }
      return true;
    default: return false;
  }
}

struct Inflater {
  z_stream z{};
  bool ok = false;
  Inflater() { ok = inflateInit(&z) == Z_OK; }
  ~Inflater() {
    if (ok) inflateEnd(&z);
  }
};

// Samples per pixel of a PNG colour type (0 grey, 2 RGB, 3 palette, 4 grey + alpha, 6 RGBA);
// 0 for an invalid type.
int PngChannels(int colour) {
  switch (colour) {
    case 0:
    case 3: return 1;
    case 2: return 3;
    case 4: return 2;
    case 6: return 4;
    default: return 0;
  }
}

// The bit depths the PNG specification (section 11.2.2) allows for a colour type.
bool PngDepthAllowed(int colour, int depth) {
  if (colour == 0) return depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16;
  if (colour == 3) return depth == 1 || depth == 2 || depth == 4 || depth == 8;
  return depth == 8 || depth == 16;
}

// The filtered rows of a PNG's image data in order: (rows, bytes per row without the filter
// byte) of the whole image, or of each non-empty Adam7 pass when interlaced (section 8.2).
std::vector<std::pair<std::size_t, std::size_t>> PngRowLayout(std::size_t width, std::size_t height,
                                                              std::size_t bits_per_pixel,
                                                              bool interlaced) {
  if (!interlaced) return {{height, (width * bits_per_pixel + 7) / 8}};
  static constexpr std::size_t kX0[7] = {0, 4, 0, 2, 0, 1, 0}, kY0[7] = {0, 0, 4, 0, 2, 0, 1};
  static constexpr std::size_t kDx[7] = {8, 8, 4, 4, 2, 2, 1}, kDy[7] = {8, 8, 8, 4, 4, 2, 2};
  std::vector<std::pair<std::size_t, std::size_t>> passes;
  for (int p = 0; p < 7; ++p) {
    const std::size_t w = width > kX0[p] ? (width - kX0[p] + kDx[p] - 1) / kDx[p] : 0;
    const std::size_t h = height > kY0[p] ? (height - kY0[p] + kDy[p] - 1) / kDy[p] : 0;
    if (w > 0 && h > 0) passes.emplace_back(h, (w * bits_per_pixel + 7) / 8);
  }
  return passes;
}

// Follows the inflated image data byte by byte through the rows of PngRowLayout and checks each
// row's filter type.
class PngRowWalk {
 public:
  explicit PngRowWalk(std::vector<std::pair<std::size_t, std::size_t>> passes)
      : passes_(std::move(passes)) {}

  bool done() const { return pass_ >= passes_.size(); }
  std::size_t bytes_seen() const { return seen_; }
  // Where the data stops: "row 12" or "row 3 of interlace pass 5".
  std::string Where() const {
    return passes_.size() > 1 ? fmt::format("row {} of interlace pass {}", row_, pass_ + 1)
                              : fmt::format("row {}", row_);
  }

  // Takes the next `n` bytes (those past the last row are ignored); "" or the problem.
  std::string Feed(const unsigned char* data, std::size_t n) {
    std::size_t i = 0;
    while (i < n && !done()) {
      const std::size_t row_bytes = passes_[pass_].second;
      if (in_row_ == 0 && data[i] > 4) {
        return fmt::format("a corrupt PNG: {} has filter type {}; the PNG filter types are 0-4",
                           Where(), data[i]);
      }
      const std::size_t take = std::min(n - i, row_bytes + 1 - in_row_);
      i += take;
      seen_ += take;
      in_row_ += take;
      if (in_row_ == row_bytes + 1) {
        in_row_ = 0;
        if (++row_ == passes_[pass_].first) {
          row_ = 0;
          ++pass_;
        }
      }
    }
    return "";
  }

 private:
  std::vector<std::pair<std::size_t, std::size_t>> passes_;
  std::size_t pass_ = 0, row_ = 0, in_row_ = 0, seen_ = 0;
};

// The PNG's IHDR checked as libpng does; "" when valid, else the problem. Sets the row layout.
std::string PngHeaderProblem(const unsigned char* data, std::size_t size,
                             std::vector<std::pair<std::size_t, std::size_t>>* passes) {
  if (size < 8 + 25 || BigEndian32(data + 8) != 13 || std::memcmp(data + 12, "IHDR", 4) != 0)
    return "a corrupt PNG: its first chunk is not a 13-byte IHDR header";
  const unsigned char* h = data + 16;
  const std::size_t width = BigEndian32(h), height = BigEndian32(h + 4);
  const int depth = h[8], colour = h[9], channels = PngChannels(colour);
  if (width == 0 || height == 0 || width > 0x7FFFFFFFu || height > 0x7FFFFFFFu || channels == 0 ||
      !PngDepthAllowed(colour, depth) || h[10] != 0 || h[11] != 0 || h[12] > 1) {
    return fmt::format(
        "an invalid PNG header (IHDR: {}x{} px, bit depth {}, colour type {}, compression {}, "
        "filter method {}, interlace {})",
        width, height, depth, colour, h[10], h[11], h[12]);
  }
  *passes = PngRowLayout(width, height,
                         static_cast<std::size_t>(channels) * static_cast<std::size_t>(depth),
                         h[12] == 1);
  return "";
}

}  // namespace

std::string PngImageDataProblem(const std::string& bytes) {
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t size = bytes.size();
  if (size < 8 || std::memcmp(data, kSignature, 8) != 0) return "";
  std::vector<std::pair<std::size_t, std::size_t>> passes;
  std::string header = PngHeaderProblem(data, size, &passes);
  if (!header.empty()) return header;
  std::size_t needed = 0;
  for (const auto& [rows, row_bytes] : passes) needed += rows * (row_bytes + 1);
  PngRowWalk walk(passes);
  Inflater inflater;
  if (!inflater.ok) return "";
  std::vector<unsigned char> out(std::size_t{1} << 16);
  bool stream_end = false;
  for (std::size_t at = 8; at + 12 <= size && !walk.done() && !stream_end;) {
    const std::uint32_t length = BigEndian32(data + at);
    if (length > size - at - 12) break;  // the chunk check (image_io.cc) names this
    const unsigned char* type = data + at + 4;
    inflater.z.next_in = const_cast<unsigned char*>(data + at + 8);
    inflater.z.avail_in = length;
    at += 12 + std::size_t{length};
    if (std::memcmp(type, "IEND", 4) == 0) break;
    if (std::memcmp(type, "IDAT", 4) != 0) continue;
    while (inflater.z.avail_in > 0 && !walk.done() && !stream_end) {
      inflater.z.next_out = out.data();
      inflater.z.avail_out = static_cast<uInt>(out.size());
      const int r = inflate(&inflater.z, Z_NO_FLUSH);
      std::string problem = walk.Feed(out.data(), out.size() - inflater.z.avail_out);
      if (!problem.empty()) return problem;
      stream_end = r == Z_STREAM_END;
      if (r != Z_OK && r != Z_STREAM_END && !walk.done()) {
        return fmt::format("a corrupt PNG: its compressed image data are damaged in {} (zlib: {})",
                           walk.Where(), inflater.z.msg ? inflater.z.msg : "error");
      }
    }
  }
  if (walk.done()) return "";
  return fmt::format(
      "a corrupt PNG: its image data end in {}, after {} of the {} bytes its header needs",
      walk.Where(), walk.bytes_seen(), needed);
}

bool DecodeGreyPng(const std::string& bytes, cv::Mat* image, PngChunkCrcs crcs) {
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t size = bytes.size();
  if (size < 8 + 25 || std::memcmp(data, kSignature, 8) != 0) return false;

  std::size_t width = 0, height = 0, bpp = 0, row_bytes = 0;
  // The image data: the IDAT chunks' bodies, one zlib stream.
  std::vector<std::pair<const unsigned char*, std::size_t>> pieces;
  std::size_t data_bytes = 0;
  bool header = false, end = false;
  for (std::size_t at = 8; at + 12 <= size && !end;) {
    const std::uint32_t length = BigEndian32(data + at);
    if (length > size - at - 12) return false;
    const unsigned char* type = data + at + 4;
    const unsigned char* body = data + at + 8;
    const std::uint32_t crc = BigEndian32(body + length);
    if (crcs == PngChunkCrcs::kCheck && crc32(crc32(0L, Z_NULL, 0), type, length + 4) != crc)
      return false;
    at += 12 + std::size_t{length};
    if (!header) {  // IHDR must come first
      if (std::memcmp(type, "IHDR", 4) != 0 || length != 13) return false;
      width = BigEndian32(body);
      height = BigEndian32(body + 4);
      const int depth = body[8], colour = body[9];
      if (colour != 0 || (depth != 8 && depth != 16) || body[10] != 0 || body[11] != 0 ||
          body[12] != 0)
        return false;
      if (width == 0 || height == 0 || width > (1u << 20) || height > (1u << 20) ||
          width * height > (std::size_t{1} << 30))
        return false;
      bpp = depth / 8;
      row_bytes = width * bpp;
      header = true;
    } else if (std::memcmp(type, "IDAT", 4) == 0) {
      if (length > 0) pieces.emplace_back(body, length);
      data_bytes += length;
    } else if (std::memcmp(type, "IEND", 4) == 0) {
      end = true;
    } else if ((type[0] & 0x20) == 0 || std::memcmp(type, "tRNS", 4) == 0) {
      return false;  // a critical chunk (PLTE, or one we do not know), or transparency
    }
  }
  if (!end || data_bytes < 2) return false;
  // One contiguous stream (a copy when the encoder split it into several chunks).
  std::vector<unsigned char> joined;
  const unsigned char* stream = pieces.front().first;
  if (pieces.size() > 1) {
    joined.reserve(data_bytes);
    for (const auto& [piece, length] : pieces) joined.insert(joined.end(), piece, piece + length);
    stream = joined.data();
  }
  // The zlib header (RFC 1950, 2.2): deflate, a window of at most 32 KiB, no preset dictionary,
  // the check bits right. Then raw deflate data, inflated by our decoder (inflate.h); the
  // Adler-32 after them is not checked: the chunks' CRC-32s cover the same bytes.
  const int cmf = stream[0], flg = stream[1];
  if ((cmf & 0x0F) != 8 || (cmf >> 4) > 7 || (flg & 0x20) != 0 || (cmf * 256 + flg) % 31 != 0)
    return false;
  // Filter byte + row_bytes per line, every byte written by the inflation (not zeroed first).
  // Deflate expands at most ~1032:1 (258 bytes per 2-bit code): a header claiming more than the
  // data can hold is refused before its buffer is allocated.
  const std::size_t raw_size = height * (row_bytes + 1);
  if (raw_size / 1032 > data_bytes) return false;
  std::unique_ptr<unsigned char[]> raw(new unsigned char[raw_size]);  // NOLINT(*-owning-memory)
  if (!InflateRaw(stream + 2, data_bytes - 2, raw.get(), raw_size)) return false;

  cv::Mat out(static_cast<int>(height), static_cast<int>(width), bpp == 1 ? CV_8UC1 : CV_16UC1);
  const unsigned char* prev = nullptr;
  for (std::size_t y = 0; y < height; ++y) {
    unsigned char* line = raw.get() + y * (row_bytes + 1);
    if (bpp == 1) {  // Straight into the image.
      unsigned char* row = out.ptr<unsigned char>(static_cast<int>(y));
      if (!Unfilter(line[0], line + 1, row, prev, row_bytes, bpp)) return false;
      prev = row;
    } else {  // In place, then the big-endian samples into the image.
      if (!Unfilter(line[0], line + 1, line + 1, prev, row_bytes, bpp)) return false;
      prev = line + 1;
      auto* dst = out.ptr<std::uint16_t>(static_cast<int>(y));
      for (std::size_t x = 0; x < width; ++x)
        dst[x] = static_cast<std::uint16_t>(line[1 + 2 * x] << 8 | line[2 + 2 * x]);
    }
  }
  *image = out;
  return true;
}

}  // namespace impactdic
