#include "impactdic/io/input_file.h"

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstring>
#include <fstream>
#include <iterator>

#include "impactdic/core/error.h"
#include "impactdic/core/strings.h"

namespace impactdic {

namespace {

// What a non-regular file is, in words.
std::string FileTypeName(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a pipe (FIFO)";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// Where `path` points when it is a symbolic link whose target does not exist; "" otherwise.
std::string DanglingLinkTarget(const std::string& path) {
  struct stat info {};
  if (lstat(path.c_str(), &info) != 0 || !S_ISLNK(info.st_mode)) return "";
  std::string target(4096, '\0');
  const ssize_t n = readlink(path.c_str(), target.data(), target.size());
  if (n <= 0) return "(unreadable link)";
  target.resize(static_cast<std::size_t>(n));
  return target;
}

}  // namespace

std::string FormatBytes(std::uintmax_t bytes) {
  if (bytes < 1000) return fmt::format("{} B", bytes);
  const char* units[] = {"kB", "MB", "GB", "TB"};
  double value = static_cast<double>(bytes) / 1000;
  int u = 0;
  while (value >= 1000 && u < 3) {
    value /= 1000;
    ++u;
  }
  return fmt::format("{:.1f} {}", value, units[u]);
}

void CheckInputFile(const std::string& path, const std::string& what, std::uintmax_t max_bytes) {
  struct stat info {};
  if (stat(path.c_str(), &info) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) {
      const std::string target = DanglingLinkTarget(path);
      if (!target.empty()) {
        throw Error(ErrorKind::kFileNotFound,
                    fmt::format("is a dangling symbolic link to {}, which does not exist; "
                                "expected {}",
                                target, what))
            .WithFile(path);
      }
      throw Error(ErrorKind::kFileNotFound, "", "", what).WithFile(path);
    }
    throw Error(ErrorKind::kIo, "", std::strerror(errno), what).WithFile(path);
  }
  if (!S_ISREG(info.st_mode)) {
    throw Error(ErrorKind::kFileFormat, fmt::format("is {}, not a regular file; expected {}",
                                                    FileTypeName(info.st_mode), what))
        .WithFile(path);
  }
  const auto size = static_cast<std::uintmax_t>(info.st_size);
  if (size > max_bytes) {
    throw Error(ErrorKind::kFileFormat,
                fmt::format("is {}, more than the {} allowed for {}", FormatBytes(size),
                            FormatBytes(max_bytes), what))
        .WithFile(path);
  }
}

std::string ReadInputFile(const std::string& path, const std::string& what,
                          std::uintmax_t max_bytes) {
  CheckInputFile(path, what, max_bytes);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::kIo, "", "cannot open it for reading", what).WithFile(path);
  // One read of the size the file has now (a byte-wise copy through the stream buffer cost more
  // than decoding a PNG); then whatever it gained meanwhile.
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  std::string bytes(size > 0 ? static_cast<std::size_t>(size) : 0, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  if (in) bytes.append(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) throw Error(ErrorKind::kIo, "", "a read error", what).WithFile(path);
  return bytes;
}

std::string BinaryFileKind(std::string_view head) {
  if (StartsWith(head, "\x89PNG")) return "a PNG image";
  if (StartsWith(head, "II*") || StartsWith(head, std::string_view("MM\0*", 4)))
    return "a TIFF image";
  if (StartsWith(head, "\xFF\xD8\xFF")) return "a JPEG image";
  if (StartsWith(head, "BM") && head.size() > 14 && head.find('\0') < 64) return "a BMP image";
  if (StartsWith(head, "\x89HDF")) return "an HDF5 file";
  if (StartsWith(head, "PK\x03\x04")) return "a ZIP archive (e.g. an .xlsx workbook)";
  if (head.substr(0, 4096).find('\0') != std::string_view::npos) return "binary data (NUL bytes)";
  return "";
}

}  // namespace impactdic
