// Photron .mraw recordings: raw frames with no header, described by a .cih (text) or .cihx (XML)
// file of the same name beside them.
//
// Layout implemented (from the public descriptions of the format: Photron's PDCLIB SDK sample that
// writes .cih files, and the open readers pyMRAW (ladisk) and the MATLAB "Reader class for Photron
// .mraw-Files" (Lindner); no code of theirs is used):
// - .cih: text lines "Key : Value" (the SDK writes "Key :Value"; the key is what precedes the
//   first ':') up to a line "END"; the first occurrence of a key counts.
// - .cihx: an XML document <cih> ... </cih>, in some versions after a binary preamble; the same
//   values under recordInfo/recordRate, frameInfo/totalFrame, frameInfo/startFrame,
//   imageDataInfo/resolution/width and /height, imageDataInfo/colorInfo/type and /bit,
//   imageDataInfo/effectiveBit/depth and /side, imageFileInfo/fileFormat, and the save step
//   under frameInfo/skipFrame (1 when every recorded frame was saved, as "Save Step" 1: a
//   .cihx of PFV holds <skipFrame>1</skipFrame> beside equal totalFrame and recordedFrame).
// - .mraw: Total Frame frames one after the other, no header and no padding; each frame rows
//   top-down, Image Width pixels each, as one stream of Color Bit bits per pixel: 8-bit one byte a
//   pixel; 16-bit little-endian words; 10 and 12-bit packed most significant bit first (12-bit: 2
//   pixels in 3 bytes, AAAAAAAA AAAABBBB BBBBBBBB; 10-bit: 4 pixels in 5 bytes).
// - With an effective bit depth below the container's (16-bit words holding 12-bit data), the
//   values sit in the lower bits ("EffectiveBit Side : Lower") or the upper ones ("Higher", shifted
//   down here so that values run 0 .. 2^depth - 1).
// - Frame numbers: "Start Frame" is the camera's number of the file's first frame (negative for
//   frames before the trigger); "Save Step" n keeps every n-th recorded frame, so file frame i is
//   camera frame start + i * n, at time (start + i * n) / "Record Rate(fps)"; the file's frames
//   are then "Record Rate(fps)" / n per second apart.
// - Text: ASCII (or UTF-8); a .cih saved as UTF-16 (by a text editor) is decoded when its text is
//   ASCII, and refused by name otherwise.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/range.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/camera_file.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace {

constexpr std::uintmax_t kMaxDescriptionBytes = 64u << 20;  // A .cih/.cihx is a few kB.
constexpr long long kMaxSidePx = 1 << 16;

// A value of the description, by its .cih key and its .cihx element path.
struct Key {
  const char* cih;
  const char* cihx;
};
constexpr Key kRecordRate{"Record Rate(fps)", "recordInfo/recordRate"};
constexpr Key kTotalFrame{"Total Frame", "frameInfo/totalFrame"};
constexpr Key kStartFrame{"Start Frame", "frameInfo/startFrame"};
constexpr Key kSaveStep{"Save Step", "frameInfo/skipFrame"};
constexpr Key kWidth{"Image Width", "imageDataInfo/resolution/width"};
constexpr Key kHeight{"Image Height", "imageDataInfo/resolution/height"};
constexpr Key kColorType{"Color Type", "imageDataInfo/colorInfo/type"};
constexpr Key kColorBit{"Color Bit", "imageDataInfo/colorInfo/bit"};
constexpr Key kEffectiveBit{"EffectiveBit Depth", "imageDataInfo/effectiveBit/depth"};
constexpr Key kEffectiveSide{"EffectiveBit Side", "imageDataInfo/effectiveBit/side"};
constexpr Key kFileFormat{"File Format", "imageFileInfo/fileFormat"};
constexpr std::array<Key, 11> kKeys{kRecordRate,   kTotalFrame,    kStartFrame, kSaveStep,
                                    kWidth,        kHeight,        kColorType,  kColorBit,
                                    kEffectiveBit, kEffectiveSide, kFileFormat};

std::string Trim(std::string_view text) {
  const auto is_space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return std::string(text);
}

// The description's values, by .cih key, and how to name a key in messages.
struct Description {
  std::string path;
  bool xml = false;
  std::map<std::string, std::string> values;  // By Key::cih.

  std::string Name(const Key& key) const { return xml ? key.cihx : key.cih; }
  const std::string* Find(const Key& key) const {
    const auto it = values.find(key.cih);
    return it == values.end() ? nullptr : &it->second;
  }
  const std::string& Require(const Key& key) const {
    const std::string* value = Find(key);
    if (value == nullptr || value->empty()) {
      throw Error(ErrorKind::kFileFormat, Name(key), "nothing",
                  "the key in the camera's description; re-save the recording as .mraw with "
                  "Photron FASTCAM Viewer (PFV) to get a complete .cih/.cihx")
          .WithFile(path);
    }
    return *value;
  }
  long long Integer(const Key& key, long long min, long long max) const {
    const std::string& text = Require(key);
    long long value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size() || value < min || value > max) {
      throw Error(ErrorKind::kFileFormat, Name(key), "'" + text + "'",
                  fmt::format("an integer in [{}, {}]", min, max))
          .WithFile(path);
    }
    return value;
  }
  long long Integer(const Key& key, long long min, long long max, long long fallback) const {
    return Find(key) == nullptr ? fallback : Integer(key, min, max);
  }
};

std::string ReadDescriptionBytes(const std::string& path) {
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw Error(ErrorKind::kIo, path, ec.message(), "a readable file");
  if (size > kMaxDescriptionBytes) {
    throw Error(ErrorKind::kFileFormat, path, fmt::format("{} bytes", size),
                "a .cih/.cihx description of at most 64 MiB");
  }
  std::ifstream in(path, std::ios::binary);
  std::string bytes(static_cast<size_t>(size), '\0');
  if (!in || !in.read(bytes.data(), static_cast<std::streamsize>(size))) {
    throw Error(ErrorKind::kIo, path, "a failed read", "a readable file");
  }
  return bytes;
}

// The text of a .cih: its bytes when they hold no NUL; decoded when it is UTF-16 (a byte-order
// mark, or no BOM and ASCII text, every other byte NUL), characters beyond ASCII read as '?' (the
// keys and the values read are ASCII); else Error naming the file.
std::string CihText(const std::string& bytes, const std::string& path) {
  if (bytes.find('\0') == std::string::npos) return bytes;
  const auto byte = [&](size_t i) {
    return static_cast<unsigned>(static_cast<unsigned char>(bytes[i]));
  };
  size_t begin = 0;
  bool little_endian = true;
  bool utf16 = false;
  if (bytes.size() >= 2 &&
      ((byte(0) == 0xFF && byte(1) == 0xFE) || (byte(0) == 0xFE && byte(1) == 0xFF))) {
    begin = 2;
    little_endian = byte(0) == 0xFF;
    utf16 = true;
  } else if (bytes.size() >= 2) {  // No BOM: ASCII text has its high bytes NUL.
    little_endian = bytes[0] != '\0';
    utf16 = true;
    for (size_t i = little_endian ? 1 : 0; i < std::min<size_t>(bytes.size(), 512); i += 2) {
      utf16 = utf16 && bytes[i] == '\0';
    }
  }
  std::string text;
  for (size_t i = begin; utf16 && i < bytes.size(); i += 2) {
    const unsigned unit = i + 1 >= bytes.size() ? 0
                          : little_endian       ? byte(i) | (byte(i + 1) << 8)
                                                : (byte(i) << 8) | byte(i + 1);
    utf16 = unit != 0;  // A NUL character (or an odd byte count) is no text.
    text.push_back(unit < 0x80 ? static_cast<char>(unit) : '?');
  }
  if (utf16) return text;
  const size_t nul = bytes.find('\0');
  throw Error(
      ErrorKind::kFileFormat, path,
      fmt::format("a NUL byte at byte {}: binary data, not text{}", nul,
                  begin > 0 ? " (UTF-16 by its byte-order mark, with a NUL character)" : ""),
      "a .cih description as ASCII or UTF-8 text (as Photron FASTCAM Viewer writes it; "
      "save it again as such, or use the .cihx)");
}

// "Key : Value" lines up to a line "END" (after which the software appends other sections); the
// first occurrence of a key counts.
void ParseCih(const std::string& text, Description* description) {
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string_view line(text.data() + begin, end - begin);
    begin = end + 1;
    if (Trim(line) == "END") break;
    const size_t colon = line.find(':');
    if (colon == std::string_view::npos) continue;
    description->values.emplace(Trim(line.substr(0, colon)), Trim(line.substr(colon + 1)));
  }
}

// The text of the element at `path` ("a/b/c") inside text[begin, end), or nullopt.
std::optional<std::string> XmlValue(const std::string& text, size_t begin, size_t end,
                                    const std::string& path) {
  size_t start = 0;
  while (start <= path.size()) {
    size_t slash = path.find('/', start);
    if (slash == std::string::npos) slash = path.size();
    const std::string name = path.substr(start, slash - start);
    start = slash + 1;
    // The opening tag "<name>" or "<name ...>" and its closing tag.
    size_t open = begin;
    size_t content = std::string::npos;
    while ((open = text.find("<" + name, open)) != std::string::npos && open < end) {
      const size_t after = open + 1 + name.size();
      if (after < end &&
          (text[after] == '>' || std::isspace(static_cast<unsigned char>(text[after])) != 0)) {
        content = text.find('>', after);
        break;
      }
      open = after;
    }
    if (content == std::string::npos || content >= end) return std::nullopt;
    const size_t close = text.find("</" + name + ">", content);
    if (close == std::string::npos || close > end) return std::nullopt;
    begin = content + 1;
    end = close;
  }
  return Trim(std::string_view(text).substr(begin, end - begin));
}

void ParseCihx(const std::string& bytes, Description* description) {
  const size_t begin = bytes.find("<cih>");
  const size_t end = begin == std::string::npos ? begin : bytes.find("</cih>", begin);
  if (end == std::string::npos) {
    throw Error(ErrorKind::kFileFormat, description->path, "no <cih> ... </cih> element",
                "a Photron .cihx description (XML)");
  }
  for (const Key& key : kKeys) {
    if (*key.cihx == '\0') continue;
    if (auto value = XmlValue(bytes, begin + 5, end, key.cihx)) {
      description->values.emplace(key.cih, std::move(*value));
    }
  }
}

// The file beside `path` with the same stem and one of `extensions` (given in lower case; tried
// in lower and in upper case, as Windows software writes either), or "".
std::string FindPartner(const fs::path& path, std::initializer_list<std::string> extensions) {
  for (const std::string& ext : extensions) {
    std::string upper = ext;
    for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    for (const std::string& spelt : {ext, upper}) {
      fs::path candidate = path;
      candidate.replace_extension(spelt);
      std::error_code ec;
      if (fs::is_regular_file(candidate, ec)) return candidate.string();
    }
  }
  return "";
}

// What the description says of the frames, checked.
struct MrawLayout {
  int width_px = 0, height_px = 0;
  int container_bits = 0;  // Bits per pixel in the .mraw: 8, 10, 12 or 16.
  int data_bits = 0;       // Significant bits.
  int shift = 0;           // Right shift of each value (data in the upper bits).
  long long frame_count = 0, start_frame = 0, save_step = 1;
  double record_rate_fps = 0;
  long long frame_bytes = 0;
};

constexpr const char* kColourUnsupported =
    "colour .mraw files are not supported: export the frames as 16-bit monochrome TIFF from "
    "Photron FASTCAM Viewer, or record in monochrome";

// A colour type other than Mono is refused by that field; colour packing (24, 30, 36 or 48 bits:
// three channels) by Color Bit, saying when Color Type claims Mono that the two contradict.
void CheckMonochrome(const Description& d, long long color_bit) {
  const std::string* type = d.Find(kColorType);
  const bool typed = type != nullptr && !type->empty();
  if (typed && ToLower(*type) != "mono" && ToLower(*type) != "monochrome") {
    throw Error(ErrorKind::kFileFormat, d.Name(kColorType), "'" + *type + "'",
                fmt::format("a monochrome recording ({})", kColourUnsupported))
        .WithFile(d.path);
  }
  if (color_bit == 24 || color_bit == 30 || color_bit == 36 || color_bit == 48) {
    throw Error(ErrorKind::kFileFormat, d.Name(kColorBit),
                fmt::format("{} bits, the packing of colour pixels (three channels of {} bits){}",
                            color_bit, color_bit / 3,
                            typed ? fmt::format(", while {} says '{}': the two fields contradict",
                                                d.Name(kColorType), *type)
                                  : ""),
                fmt::format("a monochrome recording of 8, 10, 12 or 16 bits per pixel ({})",
                            kColourUnsupported))
        .WithFile(d.path);
  }
}

MrawLayout CheckLayout(const Description& d) {
  if (const std::string* format = d.Find(kFileFormat);
      format != nullptr && !format->empty() && ToLower(*format) != "mraw") {
    throw Error(ErrorKind::kFileFormat, d.Name(kFileFormat), "'" + *format + "'",
                "MRaw (the description is of a recording saved in another format: open those "
                "files directly, or re-save as .mraw)")
        .WithFile(d.path);
  }
  MrawLayout layout;
  const long long color_bit = d.Integer(kColorBit, 1, 64);
  CheckMonochrome(d, color_bit);
  if (color_bit != 8 && color_bit != 10 && color_bit != 12 && color_bit != 16) {
    throw Error(ErrorKind::kFileFormat, d.Name(kColorBit), fmt::format("{} bits", color_bit),
                "8, 10, 12 or 16 bits per pixel (re-save the recording as 8 or 16-bit .mraw)")
        .WithFile(d.path);
  }
  layout.container_bits = static_cast<int>(color_bit);
  layout.data_bits = static_cast<int>(d.Integer(kEffectiveBit, 1, color_bit, color_bit));
  if (const std::string* side = d.Find(kEffectiveSide); side != nullptr && !side->empty()) {
    const std::string lower = ToLower(*side);
    if (lower != "lower" && lower != "higher") {
      throw Error(ErrorKind::kFileFormat, d.Name(kEffectiveSide), "'" + *side + "'",
                  "Lower or Higher")
          .WithFile(d.path);
    }
    if (lower == "higher") layout.shift = layout.container_bits - layout.data_bits;
  }
  layout.width_px = static_cast<int>(d.Integer(kWidth, 1, kMaxSidePx));
  layout.height_px = static_cast<int>(d.Integer(kHeight, 1, kMaxSidePx));
  layout.frame_count = d.Integer(kTotalFrame, 1, std::numeric_limits<int>::max());
  layout.start_frame = d.Integer(kStartFrame, -(1LL << 40), 1LL << 40);
  layout.save_step = d.Integer(kSaveStep, 1, 1 << 20, /*fallback=*/1);
  // The camera's rate and the rate of the saved frames, each a camera's (kCameraFpsRange): an
  // absurd rate would make every velocity absurd.
  const std::string& rate_text = d.Require(kRecordRate);
  const std::optional<double> rate = ParseNumber(rate_text);
  if (!rate || !kCameraFpsRange.Contains(*rate)) {
    throw Error(ErrorKind::kFileFormat, d.Name(kRecordRate), "'" + rate_text + "'",
                ExpectedText("a recording frame rate", kCameraFpsRange))
        .WithFile(d.path);
  }
  layout.record_rate_fps = *rate;
  const double saved_fps = *rate / static_cast<double>(layout.save_step);
  if (!kCameraFpsRange.Contains(saved_fps)) {
    throw Error(ErrorKind::kFileFormat, d.Name(kSaveStep),
                fmt::format("{} ({:g} frames/s recorded, one in {} kept: {:g} frames/s)",
                            layout.save_step, *rate, layout.save_step, saved_fps),
                ExpectedText("a rate of the saved frames (" + d.Name(kRecordRate) + " / " +
                                 d.Name(kSaveStep) + ")",
                             kCameraFpsRange))
        .WithFile(d.path);
  }
  const long long frame_bits =
      static_cast<long long>(layout.width_px) * layout.height_px * layout.container_bits;
  if (frame_bits % 8 != 0) {
    throw Error(ErrorKind::kFileFormat, d.Name(kWidth),
                fmt::format("{} x {} pixels of {} bits ({} bits, not whole bytes)", layout.width_px,
                            layout.height_px, layout.container_bits, frame_bits),
                "frames of whole bytes")
        .WithFile(d.path);
  }
  layout.frame_bytes = frame_bits / 8;
  return layout;
}

class MrawReader : public CameraFileReader {
 public:
  MrawReader(CameraFileInfo info, const MrawLayout& layout)
      : info_(std::move(info)), layout_(layout), in_(info_.path, std::ios::binary) {
    if (!in_) throw Error(ErrorKind::kIo, info_.path, "a file that cannot be opened", "readable");
  }
  const CameraFileInfo& info() const override { return info_; }
  cv::Mat ReadFrame(long long index) override;

 private:
  void Decode(cv::Mat* frame) const;

  CameraFileInfo info_;
  MrawLayout layout_;
  std::ifstream in_;
  std::vector<std::uint8_t> bytes_;
};

cv::Mat MrawReader::ReadFrame(long long index) {
  if (index < 0 || index >= info_.frame_count) {
    throw Error(ErrorKind::kInvalidValue, "frame index", std::to_string(index),
                fmt::format("0 .. {}", info_.frame_count - 1))
        .WithFile(info_.path);
  }
  bytes_.resize(static_cast<size_t>(layout_.frame_bytes));
  in_.clear();
  in_.seekg(static_cast<std::streamoff>(index) * layout_.frame_bytes, std::ios::beg);
  in_.read(reinterpret_cast<char*>(bytes_.data()), static_cast<std::streamsize>(bytes_.size()));
  if (in_.gcount() != static_cast<std::streamsize>(bytes_.size())) {
    throw Error(ErrorKind::kFileFormat, fmt::format("frame {}", index),
                fmt::format("the file ending inside it ({} of {} bytes)", in_.gcount(),
                            layout_.frame_bytes),
                "a complete .mraw file (was it truncated while copying?)")
        .WithFile(info_.path);
  }
  cv::Mat frame(layout_.height_px, layout_.width_px,
                layout_.container_bits == 8 ? CV_8UC1 : CV_16UC1);
  Decode(&frame);
  return frame;
}

void MrawReader::Decode(cv::Mat* frame) const {
  const size_t n = static_cast<size_t>(frame->total());
  const std::uint8_t* in = bytes_.data();
  const int shift = layout_.shift;
  if (layout_.container_bits == 8) {
    auto* out = frame->ptr<std::uint8_t>();
    for (size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint8_t>(in[i] >> shift);
    return;
  }
  auto* out = frame->ptr<std::uint16_t>();
  switch (layout_.container_bits) {
    case 16:  // Little-endian words.
      for (size_t i = 0; i < n; ++i) {
        out[i] = static_cast<std::uint16_t>((in[2 * i] | (in[2 * i + 1] << 8)) >> shift);
      }
      return;
    case 12:  // 2 pixels in 3 bytes, most significant bit first (n is even: whole bytes).
      for (size_t i = 0, j = 0; i < n; i += 2, j += 3) {
        out[i] = static_cast<std::uint16_t>(((in[j] << 4) | (in[j + 1] >> 4)) >> shift);
        out[i + 1] = static_cast<std::uint16_t>((((in[j + 1] & 0x0F) << 8) | in[j + 2]) >> shift);
      }
      return;
    default: {  // 10 bits: 4 pixels in 5 bytes, most significant bit first.
      std::uint32_t buffer = 0;
      int buffered_bits = 0;
      size_t j = 0;
      for (size_t i = 0; i < n; ++i) {
        while (buffered_bits < 10) {
          buffer = (buffer << 8) | in[j++];
          buffered_bits += 8;
        }
        buffered_bits -= 10;
        out[i] = static_cast<std::uint16_t>(((buffer >> buffered_bits) & 0x3FF) >> shift);
      }
      return;
    }
  }
}

}  // namespace

std::vector<std::string> MrawFileParts(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw Error(ErrorKind::kFileNotFound, path, "", "an existing .mraw, .cih or .cihx file");
  }
  const std::string ext = ToLower(fs::path(path).extension().string());
  std::string mraw_path = path;
  std::string description_path = path;
  if (ext == ".mraw") {
    description_path = FindPartner(path, {".cihx", ".cih"});
    if (description_path.empty()) {
      throw Error(ErrorKind::kFileNotFound, path,
                  "no .cih or .cihx file of the same name beside it",
                  "the description Photron FASTCAM Viewer saves with every .mraw: copy it next "
                  "to the .mraw (same name, .cih or .cihx)");
    }
  } else {
    mraw_path = FindPartner(path, {".mraw"});
    if (mraw_path.empty()) {
      throw Error(ErrorKind::kFileNotFound, path, "no .mraw file of the same name beside it",
                  "the recording's frames: copy the .mraw next to its description (same name)");
    }
  }
  return {description_path, mraw_path};
}

std::unique_ptr<CameraFileReader> OpenMrawFile(const std::string& path) {
  const std::vector<std::string> parts = MrawFileParts(path);
  const std::string& description_path = parts[0];
  const std::string& mraw_path = parts[1];
  std::error_code ec;
  Description description;
  description.path = description_path;
  description.xml = ToLower(fs::path(description_path).extension().string()) == ".cihx";
  const std::string bytes = ReadDescriptionBytes(description_path);
  if (description.xml) {
    ParseCihx(bytes, &description);
  } else {
    ParseCih(CihText(bytes, description_path), &description);
  }
  const MrawLayout layout = CheckLayout(description);

  const std::uintmax_t size = fs::file_size(mraw_path, ec);
  if (ec) throw Error(ErrorKind::kIo, mraw_path, ec.message(), "a readable file");
  const long long max_frames = std::numeric_limits<long long>::max() / layout.frame_bytes;
  const bool too_many = layout.frame_count > max_frames;
  if (too_many || static_cast<std::uintmax_t>(layout.frame_count * layout.frame_bytes) != size) {
    // Beyond max_frames the product does not fit in 64 bits: say so instead of computing it.
    const std::string expected = too_many ? std::string("more than 2^63")
                                          : std::to_string(layout.frame_count * layout.frame_bytes);
    throw Error(ErrorKind::kFileFormat, mraw_path, fmt::format("{} bytes", size),
                fmt::format("{} bytes ({} frames of {} x {} pixels at {} bits, as {} says); a "
                            "truncated copy or a description of another recording",
                            expected, layout.frame_count, layout.width_px, layout.height_px,
                            layout.container_bits, description_path));
  }
  CameraFileInfo info;
  info.path = mraw_path;
  info.format = "Photron mraw";
  info.width_px = layout.width_px;
  info.height_px = layout.height_px;
  info.data_bits = layout.data_bits;
  info.frame_count = layout.frame_count;
  info.first_frame_number = layout.start_frame;
  info.frame_step = layout.save_step;
  info.fps = layout.record_rate_fps / static_cast<double>(layout.save_step);
  info.time_s.resize(static_cast<size_t>(layout.frame_count));
  for (long long i = 0; i < layout.frame_count; ++i) {
    info.time_s[static_cast<size_t>(i)] =
        static_cast<double>(info.FrameNumber(i)) / layout.record_rate_fps;
  }
  return std::make_unique<MrawReader>(std::move(info), layout);
}

}  // namespace impactdic
