// Writes Photron .mraw recordings with their .cih or .cihx description, from the published layout
// (see src/io/mraw_file.cc): frames back to back, 8-bit bytes, 16-bit little-endian words, 10 and
// 12-bit packed most significant bit first. Packing here goes bit by bit, independently of the
// reader's decoders.
#ifndef IMPACTDIC_TESTS_IO_MRAW_TEST_WRITER_H_
#define IMPACTDIC_TESTS_IO_MRAW_TEST_WRITER_H_

#include <cstdint>
#include <fstream>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace impactdic::test {

struct MrawWriteOptions {
  int color_bit = 12;     // Bits per pixel in the .mraw: 8, 10, 12, 16.
  int effective_bit = 0;  // 0: same as color_bit.
  std::string effective_side = "Lower";
  std::string color_type = "Mono";
  double fps = 5000;
  std::string record_rate;  // Written as the rate instead of `fps` when not empty ("1e300").
  long long start_frame = 0;
  int save_step = 0;                   // 0: no "Save Step" line (.cihx: no <skipFrame>).
  bool cihx = false;                   // XML description instead of text.
  bool binary_preamble = true;         // For .cihx: bytes before the XML, as some versions write.
  long long total_frame = -1;          // -1: the number of frames written.
  std::vector<std::string> omit_keys;  // .cih keys left out.
};

// The frame's pixels (CV_8U or CV_16U, values < 2^color_bit) as the .mraw stores them.
inline std::vector<std::uint8_t> PackMrawFrame(const cv::Mat& frame, int color_bit) {
  std::vector<std::uint8_t> out;
  if (color_bit == 16) {
    for (int r = 0; r < frame.rows; ++r) {
      for (int c = 0; c < frame.cols; ++c) {
        const std::uint16_t v = frame.at<std::uint16_t>(r, c);
        out.push_back(static_cast<std::uint8_t>(v & 0xFF));
        out.push_back(static_cast<std::uint8_t>(v >> 8));
      }
    }
    return out;
  }
  std::uint8_t byte = 0;
  int filled = 0;
  for (int r = 0; r < frame.rows; ++r) {
    for (int c = 0; c < frame.cols; ++c) {
      const unsigned v =
          frame.depth() == CV_8U ? frame.at<std::uint8_t>(r, c) : frame.at<std::uint16_t>(r, c);
      for (int b = color_bit - 1; b >= 0; --b) {
        byte = static_cast<std::uint8_t>((byte << 1) | ((v >> b) & 1u));
        if (++filled == 8) {
          out.push_back(byte);
          byte = 0;
          filled = 0;
        }
      }
    }
  }
  if (filled > 0) out.push_back(static_cast<std::uint8_t>(byte << (8 - filled)));
  return out;
}

inline bool Omitted(const MrawWriteOptions& o, const std::string& key) {
  for (const std::string& k : o.omit_keys) {
    if (k == key) return true;
  }
  return false;
}

// Writes `stem`.mraw and `stem`.cih (or .cihx); returns the description's path.
inline std::string WriteMraw(const std::string& stem, const std::vector<cv::Mat>& frames,
                             const MrawWriteOptions& o) {
  {
    std::ofstream mraw(stem + ".mraw", std::ios::binary);
    for (const cv::Mat& f : frames) {
      const std::vector<std::uint8_t> bytes = PackMrawFrame(f, o.color_bit);
      mraw.write(reinterpret_cast<const char*>(bytes.data()),
                 static_cast<std::streamsize>(bytes.size()));
    }
  }
  const int width = frames.empty() ? 0 : frames[0].cols;
  const int height = frames.empty() ? 0 : frames[0].rows;
  const long long total =
      o.total_frame >= 0 ? o.total_frame : static_cast<long long>(frames.size());
  const int effective = o.effective_bit > 0 ? o.effective_bit : o.color_bit;
  const std::string rate =
      o.record_rate.empty() ? std::to_string(static_cast<long long>(o.fps)) : o.record_rate;
  if (!o.cihx) {
    const std::string path = stem + ".cih";
    std::ofstream cih(path);
    const auto line = [&](const std::string& key, const std::string& value) {
      if (!Omitted(o, key)) cih << key << " : " << value << "\r\n";
    };
    cih << "#Camera Information Header\r\n";
    line("Date", "2026/11/27");
    line("Camera Type", "FASTCAM test writer");
    line("Record Rate(fps)", rate);
    line("Shutter Speed(s)", "1/100000");
    line("Trigger Mode", "Center");
    line("Original Total Frame", std::to_string(total));
    line("Total Frame", std::to_string(total));
    line("Start Frame", std::to_string(o.start_frame));
    if (o.save_step > 0) line("Save Step", std::to_string(o.save_step));
    line("Image Width", std::to_string(width));
    line("Image Height", std::to_string(height));
    line("Color Type", o.color_type);
    line("Color Bit", std::to_string(o.color_bit));
    line("File Format", "MRaw");
    line("EffectiveBit Depth", std::to_string(effective));
    line("EffectiveBit Side", o.effective_side);
    line("Device Last Error", "-1:0xffffffff");
    cih << "END\r\n\r\n#Photron Fastcam Viewer Version Information:\r\nTotal Frame : 1\r\n";
    return path;
  }
  const std::string path = stem + ".cihx";
  std::ofstream cihx(path, std::ios::binary);
  if (o.binary_preamble) {
    const char preamble[] = {'\x00', '\x01', '\xff', 'C', 'I', 'H', 'X', '\x00', '\x7f', '\x10'};
    cihx.write(preamble, sizeof(preamble));
  }
  cihx << "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\"?>\n<cih>\n"
       << " <fileInfo><date>2026/11/27</date></fileInfo>\n"
       << " <recordInfo version=\"1\">\n  <recordRate>" << rate
       << "</recordRate>\n  <shutterSpeed>100000</shutterSpeed>\n </recordInfo>\n"
       << " <frameInfo>\n  <totalFrame>" << total << "</totalFrame>\n  <recordedFrame>" << total
       << "</recordedFrame>\n  <startFrame>" << o.start_frame << "</startFrame>\n"
       << (o.save_step > 0 ? "  <skipFrame>" + std::to_string(o.save_step) + "</skipFrame>\n" : "")
       << " </frameInfo>\n"
       << " <imageDataInfo>\n  <resolution><width>" << width << "</width><height>" << height
       << "</height></resolution>\n  <colorInfo><type>" << o.color_type << "</type><bit>"
       << o.color_bit << "</bit></colorInfo>\n  <effectiveBit><depth>" << effective
       << "</depth><side>" << o.effective_side << "</side></effectiveBit>\n </imageDataInfo>\n"
       << " <imageFileInfo><fileFormat>MRaw</fileFormat></imageFileInfo>\n</cih>\n";
  return path;
}

}  // namespace impactdic::test

#endif  // IMPACTDIC_TESTS_IO_MRAW_TEST_WRITER_H_
