// InflateRaw (src/io/inflate.h) against zlib, the reference: every block kind zlib writes (stored,
// fixed and dynamic Huffman; levels 0-9, the filtered, Huffman-only, run-length and fixed
// strategies; flushes that insert empty stored blocks) on data from random bytes to long runs,
// gives zlib's bytes; a stream that is damaged, cut short, longer or shorter than the buffer is
// refused, never read or written outside its ranges (the asan preset runs this too).
#include "../../src/io/inflate.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace impactdic {
namespace {

using Bytes = std::vector<unsigned char>;

// Raw deflate (no zlib header) of `data` at `level` with `strategy`; `flush_every` > 0 flushes
// (Z_SYNC_FLUSH: an empty stored block) after every so many input bytes.
Bytes Deflate(const Bytes& data, int level, int strategy, std::size_t flush_every = 0) {
  z_stream z{};
  EXPECT_EQ(deflateInit2(&z, level, Z_DEFLATED, -15, 8, strategy), Z_OK);
  Bytes out(deflateBound(&z, data.size()) + 64 + (flush_every ? data.size() / flush_every * 8 : 0));
  z.next_out = out.data();
  z.avail_out = static_cast<uInt>(out.size());
  std::size_t at = 0;
  do {
    const std::size_t piece = flush_every ? std::min(flush_every, data.size() - at) : data.size();
    z.next_in = const_cast<unsigned char*>(data.data() + at);
    z.avail_in = static_cast<uInt>(piece);
    at += piece;
    const int flush = at == data.size() ? Z_FINISH : Z_SYNC_FLUSH;
    const int r = deflate(&z, flush);
    EXPECT_TRUE(r == Z_OK || r == Z_STREAM_END);
  } while (at < data.size());
  out.resize(z.total_out);
  deflateEnd(&z);
  return out;
}

// Inputs of several kinds: random bytes, a skewed distribution (few distinct values: short
// codes), a speckle-like row prediction residual, long runs and repeats (long matches, distance 1
// and distances over 8 bytes apart), and the empty input.
std::vector<Bytes> Inputs() {
  std::mt19937 rng(17);
  std::vector<Bytes> inputs;
  Bytes random(70000);
  for (auto& b : random) b = static_cast<unsigned char>(rng());
  inputs.push_back(random);
  Bytes skewed(50000);
  std::geometric_distribution<int> geometric(0.3);
  for (auto& b : skewed) b = static_cast<unsigned char>(std::min(geometric(rng), 255));
  inputs.push_back(skewed);
  Bytes residual(100000);
  std::normal_distribution<double> normal(0, 9);
  for (auto& b : residual) b = static_cast<unsigned char>(static_cast<int>(normal(rng)) & 0xFF);
  inputs.push_back(residual);
  Bytes runs;
  for (int k = 0; k < 400; ++k) {
    const int length = 1 + static_cast<int>(rng() % 700);
    const auto value = static_cast<unsigned char>(rng() % 4);
    runs.insert(runs.end(), static_cast<std::size_t>(length), value);
    if (k % 3 == 0) {  // A copy of an earlier stretch: matches at many distances.
      const auto from = runs.begin() + static_cast<std::ptrdiff_t>(runs.size() / 2);
      const Bytes stretch(from, from + std::min<std::ptrdiff_t>(300, runs.end() - from));
      runs.insert(runs.end(), stretch.begin(), stretch.end());
    }
  }
  inputs.push_back(runs);
  inputs.push_back(Bytes{});
  inputs.push_back(Bytes{42});
  return inputs;
}

TEST(Inflate, GivesZlibsBytesForEveryBlockKind) {
  const std::vector<Bytes> inputs = Inputs();
  int streams = 0;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const Bytes& data = inputs[k];
    for (int level = 0; level <= 9; ++level) {
      for (int strategy : {Z_DEFAULT_STRATEGY, Z_FILTERED, Z_HUFFMAN_ONLY, Z_RLE, Z_FIXED}) {
        for (std::size_t flush : {std::size_t{0}, std::size_t{9000}}) {
          SCOPED_TRACE("input " + std::to_string(k) + ", level " + std::to_string(level) +
                       ", strategy " + std::to_string(strategy) + ", flush " +
                       std::to_string(flush));
          const Bytes stream = Deflate(data, level, strategy, flush);
          Bytes out(data.size() + 1, 0xAB);  // One more: the sentinel must stay.
          ASSERT_TRUE(InflateRaw(stream.data(), stream.size(), out.data(), data.size()));
          EXPECT_TRUE(std::equal(data.begin(), data.end(), out.begin()));
          EXPECT_EQ(out.back(), 0xAB);
          ++streams;
        }
      }
    }
  }
  EXPECT_EQ(streams, 6 * 10 * 5 * 2);
}

TEST(Inflate, RefusesAWrongSizeACutStreamAndTrailingBytesAreIgnored) {
  const Bytes data = Inputs()[2];
  const Bytes stream = Deflate(data, 6, Z_DEFAULT_STRATEGY);
  Bytes out(data.size() + 16);
  EXPECT_FALSE(InflateRaw(stream.data(), stream.size(), out.data(), data.size() - 1));  // Longer.
  EXPECT_FALSE(InflateRaw(stream.data(), stream.size(), out.data(), data.size() + 1));  // Shorter.
  for (std::size_t cut : {std::size_t{0}, std::size_t{1}, stream.size() / 2, stream.size() - 1})
    EXPECT_FALSE(InflateRaw(stream.data(), cut, out.data(), data.size())) << "cut at " << cut;
  Bytes trailed = stream;
  trailed.insert(trailed.end(), {1, 2, 3, 4});  // A zlib stream's Adler-32, say.
  EXPECT_TRUE(InflateRaw(trailed.data(), trailed.size(), out.data(), data.size()));
  EXPECT_TRUE(std::equal(data.begin(), data.end(), out.begin()));
  // A stored block's length that its complement contradicts; the reserved block type 3.
  const Bytes stored = Deflate(Bytes(100, 7), 0, Z_DEFAULT_STRATEGY);
  Bytes bad = stored;
  bad[3] ^= 0x01;  // LEN's complement NLEN (bytes 3-4 after the 3-bit header's byte).
  EXPECT_FALSE(InflateRaw(bad.data(), bad.size(), out.data(), 100));
  const unsigned char reserved[] = {0x07, 0, 0, 0};
  EXPECT_FALSE(InflateRaw(reserved, sizeof reserved, out.data(), 1));
}

TEST(Inflate, DamagedStreamsNeverOverrun) {
  // Random bit flips and bytes: a false or a true with exactly the buffer filled; the buffers
  // sit in vectors of their exact size, so an access outside them fails under the sanitizers,
  // and the sentinel after the output must stay.
  const Bytes data = Inputs()[2];
  std::mt19937 rng(3);
  int refused = 0;
  for (int strategy : {Z_DEFAULT_STRATEGY, Z_FIXED, Z_HUFFMAN_ONLY}) {
    const Bytes stream = Deflate(Bytes(data.begin(), data.begin() + 20000), 6, strategy);
    for (int trial = 0; trial < 300; ++trial) {
      Bytes damaged = stream;
      const int flips = 1 + static_cast<int>(rng() % 4);
      for (int f = 0; f < flips; ++f) {
        const std::size_t at = rng() % damaged.size();
        if (trial % 2 == 0)
          damaged[at] ^= static_cast<unsigned char>(1u << (rng() % 8));
        else
          damaged[at] = static_cast<unsigned char>(rng());
      }
      Bytes out(20001, 0xCD);
      if (!InflateRaw(damaged.data(), damaged.size(), out.data(), 20000)) ++refused;
      EXPECT_EQ(out.back(), 0xCD);
    }
  }
  EXPECT_GT(refused, 300);  // Most damage is caught (the rest decodes to other bytes).
}

}  // namespace
}  // namespace impactdic
