#include "inflate.h"

#include <array>
#include <cstdint>
#include <cstring>

namespace impactdic {
namespace {

// A table entry (uint32): bits 0-5 the code's length in bits (bit 5 always 0; a subtable link:
// 0), so that the entry itself is the shift that drops the code (x86 shifts take the count mod
// 64: one instruction less on the literals' dependency chain), bits 6-8 its kind, bits 9-13 the
// extra bits that follow the code (length, distance) or a subtable's index bits, bits 16-31 the
// value (literal byte, length or distance base, subtable start).
enum Kind : std::uint32_t { kLiteral = 0, kLength = 1, kEnd = 2, kLink = 3, kInvalid = 4 };
constexpr std::uint32_t Entry(std::uint32_t kind, std::uint32_t value, std::uint32_t extra,
                              std::uint32_t length = 0) {
  return value << 16 | extra << 9 | kind << 6 | length;
}
constexpr std::uint32_t KindOf(std::uint32_t e) { return (e >> 6) & 7; }
constexpr std::uint32_t LengthOf(std::uint32_t e) { return e & 63; }
constexpr std::uint32_t ExtraOf(std::uint32_t e) { return (e >> 9) & 31; }
constexpr std::uint32_t ValueOf(std::uint32_t e) { return e >> 16; }

constexpr int kMaxCodeBits = 15;
constexpr int kLitlenBits = 11, kDistanceBits = 8, kCodeLengthBits = 7;
// Main table plus the largest total of subtables (each long code's group of 2^(m - bits) entries,
// m <= 15, at most one group per long code).
constexpr int kLitlenTable = (1 << kLitlenBits) + 288 * (1 << (kMaxCodeBits - kLitlenBits));
constexpr int kDistanceTable = (1 << kDistanceBits) + 32 * (1 << (kMaxCodeBits - kDistanceBits));
constexpr int kCodeLengthTable = 1 << kCodeLengthBits;

constexpr std::array<std::uint16_t, 29> kLengthBase = {3,  4,  5,  6,   7,   8,   9,   10,  11, 13,
                                                       15, 17, 19, 23,  27,  31,  35,  43,  51, 59,
                                                       67, 83, 99, 115, 131, 163, 195, 227, 258};
constexpr std::array<std::uint8_t, 29> kLengthExtra = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                                       2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
constexpr std::array<std::uint16_t, 30> kDistanceBase = {
    1,   2,   3,   4,   5,   7,    9,    13,   17,   25,   33,   49,   65,    97,    129,
    193, 257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
constexpr std::array<std::uint8_t, 30> kDistanceExtra = {0, 0, 0,  0,  1,  1,  2,  2,  3,  3,
                                                         4, 4, 5,  5,  6,  6,  7,  7,  8,  8,
                                                         9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

// What a symbol decodes to, without its code length.
std::uint32_t LitlenSymbol(int s) {
  if (s < 256) return Entry(kLiteral, static_cast<std::uint32_t>(s), 0);
  if (s == 256) return Entry(kEnd, 0, 0);
  if (s < 286) return Entry(kLength, kLengthBase[s - 257], kLengthExtra[s - 257]);
  return Entry(kInvalid, 0, 0);
}
std::uint32_t DistanceSymbol(int s) {
  if (s < 30) return Entry(kLength, kDistanceBase[s], kDistanceExtra[s]);
  return Entry(kInvalid, 0, 0);
}
std::uint32_t CodeLengthSymbol(int s) { return Entry(kLiteral, static_cast<std::uint32_t>(s), 0); }

std::uint32_t Reverse(std::uint32_t code, int bits) {
  std::uint32_t r = 0;
  for (int i = 0; i < bits; ++i, code >>= 1) r = (r << 1) | (code & 1);
  return r;
}

// The decoding table of the canonical Huffman code with `lengths` (RFC 1951, 3.2.2) for n
// symbols: main table of 2^bits entries indexed by the next bits of the stream, codes longer than
// that through a link to a subtable. An over-subscribed code is refused; an incomplete one only
// when `single_allowed` and it is a single code of one bit or no code at all (as zlib allows for
// the literal/length and distance codes; unused entries decode as kInvalid).
bool BuildTable(const std::uint8_t* lengths, int n, std::uint32_t (*symbol)(int), int bits,
                bool single_allowed, std::uint32_t* table, int table_size) {
  int count[kMaxCodeBits + 1] = {};
  for (int s = 0; s < n; ++s) ++count[lengths[s]];
  count[0] = 0;
  int left = 1, max_length = 0;
  for (int len = 1; len <= kMaxCodeBits; ++len) {
    left = (left << 1) - count[len];
    if (left < 0) return false;  // Over-subscribed.
    if (count[len] > 0) max_length = len;
  }
  if (left > 0 && !(single_allowed && max_length <= 1)) return false;  // Incomplete.
  const std::uint32_t invalid = Entry(kInvalid, 0, 0);
  for (int i = 0; i < (1 << bits); ++i) table[i] = invalid;
  // First code of each length, then each symbol's code in symbol order.
  std::uint32_t next[kMaxCodeBits + 2] = {};
  std::uint32_t code = 0;
  for (int len = 1; len <= kMaxCodeBits; ++len) {
    code = (code + static_cast<std::uint32_t>(count[len - 1])) << 1;
    next[len] = code;
  }
  // The longest code behind each main-table prefix (for the subtables' sizes).
  std::uint8_t longest[1 << kLitlenBits] = {};
  std::uint32_t codes[288];
  for (int s = 0; s < n; ++s) {
    const int len = lengths[s];
    if (len == 0) continue;
    codes[s] = Reverse(next[len]++, len);
    if (len > bits) {
      std::uint8_t& m = longest[codes[s] & ((1u << bits) - 1)];
      if (len > m) m = static_cast<std::uint8_t>(len);
    }
  }
  int used = 1 << bits;
  for (int s = 0; s < n; ++s) {
    const int len = lengths[s];
    if (len == 0) continue;
    const std::uint32_t e = symbol(s) | static_cast<std::uint32_t>(len);
    if (len <= bits) {
      for (std::uint32_t i = codes[s]; i < (1u << bits); i += 1u << len) table[i] = e;
      continue;
    }
    const std::uint32_t prefix = codes[s] & ((1u << bits) - 1);
    std::uint32_t& link = table[prefix];
    if (KindOf(link) != kLink) {  // The prefix's subtable: 2^(longest - bits) entries.
      const int sub_bits = longest[prefix] - bits;
      if (used + (1 << sub_bits) > table_size) return false;
      link = Entry(kLink, static_cast<std::uint32_t>(used), static_cast<std::uint32_t>(sub_bits));
      for (int i = 0; i < (1 << sub_bits); ++i) table[used + i] = invalid;
      used += 1 << sub_bits;
    }
    const std::uint32_t start = ValueOf(link), sub_size = 1u << ExtraOf(link);
    for (std::uint32_t i = codes[s] >> bits; i < sub_size; i += 1u << (len - bits))
      table[start + i] = e;
  }
  return true;
}

// The bit stream, least significant bit first, 56 or more bits in the buffer after Refill
// (zeros past the end of the input, counted in `past_end`).
struct Bits {
  const unsigned char* p;
  const unsigned char* end;
  std::uint64_t buffer = 0;
  int count = 0;
  std::size_t past_end = 0;

  void Refill() {
    if (end - p >= 8) {
      std::uint64_t word;
      std::memcpy(&word, p, 8);  // Little-endian hosts (x86-64, AArch64), as is the stream.
      buffer |= word << count;
      p += (63 - count) >> 3;
      count |= 56;
      return;
    }
    while (count <= 56) {
      if (p < end) {
        buffer |= std::uint64_t{*p++} << count;
      } else {
        ++past_end;
      }
      count += 8;
    }
  }
  std::uint32_t Peek(int n) const { return static_cast<std::uint32_t>(buffer & ((1ull << n) - 1)); }
  void Drop(int n) {
    buffer >>= n;
    count -= n;
  }
  // Within the input: no bit consumed came from past its end.
  bool Sound() const { return static_cast<std::size_t>(count) >= 8 * past_end; }
};

// One code from a table built with `bits` (Refill first: at most 15 bits).
inline std::uint32_t Decode(const Bits& in, const std::uint32_t* table, int bits) {
  std::uint32_t e = table[in.Peek(bits)];
  if (KindOf(e) == kLink) e = table[ValueOf(e) + ((in.buffer >> bits) & ((1u << ExtraOf(e)) - 1))];
  return e;
}

struct Tables {
  std::uint32_t litlen[kLitlenTable];
  std::uint32_t distance[kDistanceTable];
};

const Tables& FixedTables() {
  static const Tables tables = [] {
    Tables t{};
    std::uint8_t lengths[288];
    for (int s = 0; s < 288; ++s) lengths[s] = s < 144 ? 8 : s < 256 ? 9 : s < 280 ? 7 : 8;
    BuildTable(lengths, 288, LitlenSymbol, kLitlenBits, false, t.litlen, kLitlenTable);
    std::uint8_t distances[32];
    std::memset(distances, 5, sizeof distances);
    BuildTable(distances, 32, DistanceSymbol, kDistanceBits, false, t.distance, kDistanceTable);
    return t;
  }();
  return tables;
}

// A dynamic block's code lengths (RFC 1951, 3.2.7) into tables.
bool ReadDynamicTables(Bits& in, Tables* t) {
  in.Refill();
  const int nlen = static_cast<int>(in.Peek(5)) + 257;
  in.Drop(5);
  const int ndist = static_cast<int>(in.Peek(5)) + 1;
  in.Drop(5);
  const int ncode = static_cast<int>(in.Peek(4)) + 4;
  in.Drop(4);
  if (nlen > 286 || ndist > 30) return false;
  static constexpr std::uint8_t kOrder[19] = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                              11, 4,  12, 3, 13, 2, 14, 1, 15};
  std::uint8_t code_lengths[19] = {};
  for (int i = 0; i < ncode; ++i) {
    in.Refill();
    code_lengths[kOrder[i]] = static_cast<std::uint8_t>(in.Peek(3));
    in.Drop(3);
  }
  std::uint32_t code_table[kCodeLengthTable];
  if (!BuildTable(code_lengths, 19, CodeLengthSymbol, kCodeLengthBits, false, code_table,
                  kCodeLengthTable))
    return false;
  std::uint8_t lengths[286 + 30] = {};
  for (int i = 0; i < nlen + ndist;) {
    in.Refill();
    const std::uint32_t e = code_table[in.Peek(kCodeLengthBits)];
    if (KindOf(e) != kLiteral) return false;
    in.Drop(static_cast<int>(LengthOf(e)));
    const std::uint32_t s = ValueOf(e);
    if (s < 16) {
      lengths[i++] = static_cast<std::uint8_t>(s);
      continue;
    }
    int repeat = 0;
    std::uint8_t value = 0;
    if (s == 16) {
      if (i == 0) return false;  // Nothing to repeat.
      value = lengths[i - 1];
      repeat = 3 + static_cast<int>(in.Peek(2));
      in.Drop(2);
    } else if (s == 17) {
      repeat = 3 + static_cast<int>(in.Peek(3));
      in.Drop(3);
    } else {
      repeat = 11 + static_cast<int>(in.Peek(7));
      in.Drop(7);
    }
    if (i + repeat > nlen + ndist) return false;
    for (; repeat > 0; --repeat) lengths[i++] = value;
  }
  if (lengths[256] == 0) return false;  // No end-of-block code.
  return BuildTable(lengths, nlen, LitlenSymbol, kLitlenBits, true, t->litlen, kLitlenTable) &&
         BuildTable(lengths + nlen, ndist, DistanceSymbol, kDistanceBits, true, t->distance,
                    kDistanceTable);
}

// A Huffman block's symbols until its end-of-block code.
bool InflateBlock(Bits& in, const Tables& t, unsigned char* begin, unsigned char*& out,
                  unsigned char* end) {
  for (;;) {
    in.Refill();
    std::uint32_t e = Decode(in, t.litlen, kLitlenBits);
    if (KindOf(e) == kLiteral) {
      // Up to three literals per refill (56 bits, 15 at most each).
      if (out == end) return false;
      *out++ = static_cast<unsigned char>(ValueOf(e));
      in.Drop(static_cast<int>(LengthOf(e)));
      e = Decode(in, t.litlen, kLitlenBits);
      if (KindOf(e) == kLiteral) {
        if (out == end) return false;
        *out++ = static_cast<unsigned char>(ValueOf(e));
        in.Drop(static_cast<int>(LengthOf(e)));
        e = Decode(in, t.litlen, kLitlenBits);
        if (KindOf(e) == kLiteral) {
          if (out == end) return false;
          *out++ = static_cast<unsigned char>(ValueOf(e));
          in.Drop(static_cast<int>(LengthOf(e)));
          continue;
        }
      }
      // A length and its distance take up to 48 bits: refill (the bits of e stay where they are).
      in.Refill();
    }
    if (KindOf(e) == kEnd) {
      in.Drop(static_cast<int>(LengthOf(e)));
      return true;
    }
    if (KindOf(e) != kLength) return false;
    int bits = static_cast<int>(LengthOf(e));
    const std::size_t length = ValueOf(e) + ((in.buffer >> bits) & ((1u << ExtraOf(e)) - 1));
    in.Drop(bits + static_cast<int>(ExtraOf(e)));
    const std::uint32_t d = Decode(in, t.distance, kDistanceBits);
    if (KindOf(d) != kLength) return false;
    bits = static_cast<int>(LengthOf(d));
    const std::size_t distance = ValueOf(d) + ((in.buffer >> bits) & ((1u << ExtraOf(d)) - 1));
    in.Drop(bits + static_cast<int>(ExtraOf(d)));
    if (distance > static_cast<std::size_t>(out - begin) ||
        length > static_cast<std::size_t>(end - out))
      return false;
    const unsigned char* from = out - distance;
    if (distance >= 8 && static_cast<std::size_t>(end - out) >= length + 8) {
      // 8 bytes at a time (a source 8 or more bytes back is never overwritten by the same step).
      unsigned char* stop = out + length;
      while (out < stop) {
        std::uint64_t word;
        std::memcpy(&word, from, 8);
        std::memcpy(out, &word, 8);
        out += 8;
        from += 8;
      }
      out = stop;
    } else {
      for (std::size_t k = 0; k < length; ++k) *out++ = *from++;
    }
  }
}

}  // namespace

bool InflateRaw(const unsigned char* in, std::size_t in_size, unsigned char* out,
                std::size_t out_size) {
  Bits bits{in, in + in_size};
  unsigned char* const begin = out;
  unsigned char* const end = out + out_size;
  Tables dynamic;  // ~40 KB on the stack: no allocation per image.
  bool last = false;
  while (!last) {
    bits.Refill();
    last = bits.Peek(1) != 0;
    const std::uint32_t type = (bits.buffer >> 1) & 3;
    bits.Drop(3);
    if (type == 0) {  // Stored: from the next byte boundary, LEN and its complement, LEN bytes.
      bits.Drop(bits.count & 7);
      if (!bits.Sound()) return false;
      // The bytes still in the buffer are the input's from here (zeros past its end excluded).
      const unsigned char* p = bits.p - (bits.count / 8 - static_cast<int>(bits.past_end));
      bits.buffer = 0;
      bits.count = 0;
      bits.past_end = 0;
      if (bits.end - p < 4) return false;
      const std::size_t length = p[0] | std::size_t{p[1]} << 8;
      const std::size_t complement = p[2] | std::size_t{p[3]} << 8;
      p += 4;
      if (length != (~complement & 0xFFFF)) return false;
      if (static_cast<std::size_t>(bits.end - p) < length ||
          static_cast<std::size_t>(end - out) < length)
        return false;
      if (length > 0) std::memcpy(out, p, length);
      out += length;
      bits.p = p + length;
    } else if (type == 1) {
      if (!InflateBlock(bits, FixedTables(), begin, out, end)) return false;
    } else if (type == 2) {
      if (!ReadDynamicTables(bits, &dynamic) || !InflateBlock(bits, dynamic, begin, out, end))
        return false;
    } else {
      return false;
    }
    if (!bits.Sound()) return false;
  }
  return out == end;
}

}  // namespace impactdic
