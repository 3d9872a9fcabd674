// Checks every input file before it is read, so a folder, a device (/dev/zero), a pipe or a
// runaway file is refused with its name and what was expected, instead of being read for
// minutes and then reported as "empty" or "malformed".
//
//   const std::string text = ReadInputFile(path, "a scene file (YAML)", kMaxTextFileBytes);
#ifndef IMPACTDIC_IO_INPUT_FILE_H_
#define IMPACTDIC_IO_INPUT_FILE_H_

#include <cstdint>
#include <string>
#include <string_view>

namespace impactdic {

// Size limits of the inputs (documented in docs/reliability.md).
// Scene files, calibration YAML, synthetic scene specs: hand-written text of a few kB.
inline constexpr std::uintmax_t kMaxTextFileBytes = std::uintmax_t{64} << 20;  // 64 MiB
// DAQ records and tables: 25 kHz x 8 channels for an hour is ~4 GB of text; a drop test records
// seconds. Larger files are refused rather than read into memory.
inline constexpr std::uintmax_t kMaxCsvFileBytes = std::uintmax_t{2} << 30;  // 2 GiB
// One image file (an uncompressed 16-bit frame at the pixel limit of image_io.h is 512 MiB).
inline constexpr std::uintmax_t kMaxImageFileBytes = std::uintmax_t{1} << 30;  // 1 GiB

// Error naming `path` unless it is an existing regular file (symbolic links followed) of at most
// `max_bytes`: kFileNotFound when it does not exist ("is a dangling symbolic link to X, which
// does not exist" for a link to nowhere), kFileFormat for a folder, device, pipe or socket
// (judged by stat(), so a FIFO is never opened and cannot block) and for a file above the limit.
// `what` says what was expected ("the sensor CSV").
void CheckInputFile(const std::string& path, const std::string& what, std::uintmax_t max_bytes);

// CheckInputFile, then the whole file as bytes; Error kIo naming the file if reading fails.
std::string ReadInputFile(const std::string& path, const std::string& what,
                          std::uintmax_t max_bytes);

// What binary format `head` (the first bytes of a file) starts like: "a PNG image",
// "a TIFF image", "a JPEG image", "a BMP image", "an HDF5 file", "a ZIP archive (e.g. .xlsx)",
// "binary data (NUL bytes)"; "" when it looks like text. For "expected a text file" messages.
std::string BinaryFileKind(std::string_view head);

// Bytes for messages: "512 B", "3.2 MB", "16.8 GB".
std::string FormatBytes(std::uintmax_t bytes);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_INPUT_FILE_H_
