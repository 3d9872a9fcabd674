#include "impactdic/io/png_grey.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

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

// Reverses the filter of one scanline in place (`prev` is the previous reconstructed line, or
// null for the first). bpp = bytes per pixel. False for an unknown filter type.
bool Unfilter(int type, unsigned char* line, const unsigned char* prev, std::size_t bytes,
              std::size_t bpp) {
  switch (type) {
    case 0: return true;
    case 1:
      for (std::size_t i = bpp; i < bytes; ++i) line[i] = line[i] + line[i - bpp];
      return true;
    case 2:
      if (prev != nullptr)
        for (std::size_t i = 0; i < bytes; ++i) line[i] = line[i] + prev[i];
      return true;
    case 3:
      for (std::size_t i = 0; i < bytes; ++i) {
        const int left = i >= bpp ? line[i - bpp] : 0, up = prev ? prev[i] : 0;
        line[i] = static_cast<unsigned char>(line[i] + ((left + up) >> 1));
      }
      return true;
    case 4:
      for (std::size_t i = 0; i < bytes; ++i) {
        const int left = i >= bpp ? line[i - bpp] : 0, up = prev ? prev[i] : 0;
        const int up_left = (prev && i >= bpp) ? prev[i - bpp] : 0;
        line[i] = static_cast<unsigned char>(line[i] + Paeth(left, up, up_left));
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

}  // namespace

bool DecodeGreyPng(const std::string& bytes, cv::Mat* image) {
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t size = bytes.size();
  if (size < 8 + 25 || std::memcmp(data, kSignature, 8) != 0) return false;

  std::size_t width = 0, height = 0, bpp = 0, row_bytes = 0;
  std::vector<unsigned char> raw;  // filter byte + row_bytes per line
  Inflater inflater;
  if (!inflater.ok) return false;
  bool header = false, stream_end = false, end = false;
  for (std::size_t at = 8; at + 12 <= size && !end;) {
    const std::uint32_t length = BigEndian32(data + at);
    if (length > size - at - 12) return false;
    const unsigned char* type = data + at + 4;
    const unsigned char* body = data + at + 8;
    const std::uint32_t crc = BigEndian32(body + length);
    if (crc32(crc32(0L, Z_NULL, 0), type, length + 4) != crc) return false;
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
      raw.resize(height * (row_bytes + 1));
      inflater.z.next_out = raw.data();
      inflater.z.avail_out = static_cast<uInt>(raw.size());
      header = true;
    } else if (std::memcmp(type, "IDAT", 4) == 0) {
      if (stream_end) continue;  // trailing empty IDATs are allowed; extra data is ignored
      inflater.z.next_in = const_cast<unsigned char*>(body);
      inflater.z.avail_in = length;
      while (inflater.z.avail_in > 0) {
        const uInt before = inflater.z.avail_in;
        const int r = inflate(&inflater.z, Z_NO_FLUSH);
        if (r == Z_STREAM_END) {
          stream_end = true;
          break;
        }
        if (r != Z_OK) return false;                                                   // damaged
        if (inflater.z.avail_in == before && inflater.z.avail_out == 0) return false;  // too long
      }
    } else if (std::memcmp(type, "IEND", 4) == 0) {
      end = true;
    } else if ((type[0] & 0x20) == 0 || std::memcmp(type, "tRNS", 4) == 0) {
      return false;  // a critical chunk (PLTE, or one we do not know), or transparency
    }
  }
  if (!end || !stream_end || inflater.z.avail_out != 0) return false;

  cv::Mat out(static_cast<int>(height), static_cast<int>(width), bpp == 1 ? CV_8UC1 : CV_16UC1);
  const unsigned char* prev = nullptr;
  for (std::size_t y = 0; y < height; ++y) {
    unsigned char* line = raw.data() + y * (row_bytes + 1);
    if (!Unfilter(line[0], line + 1, prev, row_bytes, bpp)) return false;
    prev = line + 1;
  }
  for (std::size_t y = 0; y < height; ++y) {
    const unsigned char* line = raw.data() + y * (row_bytes + 1) + 1;
    if (bpp == 1) {
      std::memcpy(out.ptr<unsigned char>(static_cast<int>(y)), line, row_bytes);
    } else {
      auto* dst = out.ptr<std::uint16_t>(static_cast<int>(y));
      for (std::size_t x = 0; x < width; ++x)
        dst[x] = static_cast<std::uint16_t>(line[2 * x] << 8 | line[2 * x + 1]);
    }
  }
  *image = out;
  return true;
}

}  // namespace impactdic
