// Writes minimal Phantom .cine files from the published layout ("The Cine File Format", see
// src/io/cine_file.cc), independently of the reader: the headers, the setup with its frame rate
// and RealBPP, optionally a TIME64 tagged block (type 1002) of per-image time stamps, the image
// offsets and each image behind an 8-byte annotation.
#ifndef IMPACTDIC_TESTS_IO_CINE_TEST_WRITER_H_
#define IMPACTDIC_TESTS_IO_CINE_TEST_WRITER_H_

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace impactdic::test {

// A minimal cine: `images` already in the file's encoding.
struct SyntheticCine {
  int width = 4, height = 3;
  int bi_height = 3;  // Negative: rows stored top-down.
  std::uint16_t bit_count = 16;
  std::uint32_t bi_compression = 0;
  std::int32_t first_image_no = -2;
  std::uint32_t frame_rate = 1000;
  std::uint32_t real_bpp = 12;
  std::vector<std::vector<std::uint8_t>> images;
  // Time of each image relative to the trigger [s] (written as TIME64 after a trigger at 100 s);
  // empty: no time block (the reader then times image i as (first_image_no + i) / frame_rate).
  std::vector<double> time_s;
};

inline void Put(std::vector<char>& b, std::size_t at, std::uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) b[at + i] = static_cast<char>((value >> (8 * i)) & 0xFF);
}

// TIME64 (32.32 fixed point: u32 fractions of a second, u32 seconds) of `seconds` >= 0.
inline void PutTime64(std::vector<char>& b, std::size_t at, double seconds) {
  const double whole = std::floor(seconds);
  Put(b, at, static_cast<std::uint32_t>(std::llround((seconds - whole) * 4294967296.0)), 4);
  Put(b, at + 4, static_cast<std::uint32_t>(whole), 4);
}

inline std::vector<char> WriteCine(const SyntheticCine& c) {
  constexpr double kTriggerS = 100;
  const std::size_t setup_at = 84, setup_length = 1000;
  const std::size_t time_block = c.time_s.empty() ? 0 : 8 + 8 * c.time_s.size();
  const std::size_t offsets_at = setup_at + setup_length + time_block;
  std::size_t image_at = offsets_at + 8 * c.images.size();
  std::vector<char> b(image_at);
  b[0] = 'C';
  b[1] = 'I';
  Put(b, 2, 44, 2);
  Put(b, 16, static_cast<std::uint32_t>(c.first_image_no), 4);
  Put(b, 20, c.images.size(), 4);
  Put(b, 24, 44, 4);
  Put(b, 28, setup_at, 4);
  Put(b, 32, offsets_at, 4);
  if (!c.time_s.empty()) PutTime64(b, 36, kTriggerS);  // TriggerTime.
  Put(b, 44, 40, 4);
  Put(b, 48, static_cast<std::uint32_t>(c.width), 4);
  Put(b, 52, static_cast<std::uint32_t>(c.bi_height), 4);
  Put(b, 58, c.bit_count, 2);
  Put(b, 60, c.bi_compression, 4);
  Put(b, setup_at + 0, c.frame_rate, 2);
  b[setup_at + 140] = 'S';
  b[setup_at + 141] = 'T';
  Put(b, setup_at + 142, setup_length, 2);
  Put(b, setup_at + 768, c.frame_rate, 4);
  Put(b, setup_at + 896, c.real_bpp, 4);
  if (!c.time_s.empty()) {
    const std::size_t at = setup_at + setup_length;
    Put(b, at, time_block, 4);
    Put(b, at + 4, 1002, 2);
    for (std::size_t i = 0; i < c.time_s.size(); ++i)
      PutTime64(b, at + 8 + 8 * i, kTriggerS + c.time_s[i]);
  }
  for (std::size_t i = 0; i < c.images.size(); ++i) {
    Put(b, offsets_at + 8 * i, image_at, 8);
    std::vector<char> block(8 + c.images[i].size());
    Put(block, 0, 8, 4);
    Put(block, 4, c.images[i].size(), 4);
    std::copy(c.images[i].begin(), c.images[i].end(), block.begin() + 8);
    b.insert(b.end(), block.begin(), block.end());
    image_at += block.size();
  }
  return b;
}

inline void WriteCineFile(const std::string& path, const SyntheticCine& c) {
  const std::vector<char> bytes = WriteCine(c);
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace impactdic::test

#endif  // IMPACTDIC_TESTS_IO_CINE_TEST_WRITER_H_
