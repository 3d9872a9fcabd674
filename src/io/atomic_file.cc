#include "impactdic/io/atomic_file.h"

#include <fcntl.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/input_file.h"
#include "impactdic/io/output_generation.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace {

// The first line of a file (at most 4 KiB, without a UTF-8 byte order mark or the line end).
std::string FirstLine(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string text(4096, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
  text = text.substr(0, text.find('\n'));
  if (!text.empty() && text.back() == '\r') text.pop_back();
  return text;
}

}  // namespace

AtomicFile::AtomicFile(std::string final_path) : final_path_(std::move(final_path)) {
  fs::path final_fs(final_path_);
  fs::path folder = final_fs.parent_path();
  if (folder.empty()) folder = ".";
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    throw Error(ErrorKind::kIo, OutputPathForMessages(final_path_),
                "output folder " + OutputPathForMessages(folder.string()) + " does not exist",
                "an existing, writable folder");
  }
  if (access(folder.c_str(), W_OK) != 0) {
    throw Error(ErrorKind::kIo, OutputPathForMessages(final_path_),
                "output folder " + OutputPathForMessages(folder.string()) + " is not writable",
                "a writable folder");
  }
  RemoveStaleTemporaries(folder.string());
  temp_path_ = (folder / TemporaryName(final_fs.filename().string())).string();
  interrupt_guard_ = std::make_unique<RemoveOnInterrupt>(temp_path_);
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    std::error_code ec;
    fs::remove(temp_path_, ec);
  }
}

void AtomicFile::Commit() {
  std::error_code ec;
  fs::rename(temp_path_, final_path_, ec);
  if (ec) {
    throw Error(ErrorKind::kIo, OutputPathForMessages(final_path_),
                "cannot rename temporary file: " + ec.message(), "a writable output location");
  }
  committed_ = true;
  interrupt_guard_->Release();
}

void CheckOutputLocation(const std::string& path) {
  const AtomicFile probe(path);  // Its constructor checks (and names the file for messages).
}

void CheckNotAnInput(const std::string& output, const std::string& option,
                     const std::vector<std::string>& inputs) {
  std::error_code ec;
  if (!fs::exists(output, ec)) return;  // Every input exists: a new file is none of them.
  for (const std::string& input : inputs) {
    if (!input.empty() && fs::equivalent(output, input, ec)) {
      std::string found = output;
      if (input != output) found += " (the same file as " + input + ")";
      found += ", which is one of the inputs";
      throw Error(ErrorKind::kInvalidValue, option, found,
                  "an output that is not an input (it would be overwritten)");
    }
  }
}

void CheckOutputLocation(const std::string& path, const OutputRules& rules) {
  const std::string ext = ToLower(fs::path(path).extension().string());
  if (!rules.extensions.empty() &&
      std::find(rules.extensions.begin(), rules.extensions.end(), ext) == rules.extensions.end()) {
    std::string allowed;  // ".csv, .h5 or .hdf5"
    for (std::size_t i = 0; i < rules.extensions.size(); ++i)
      allowed += (i == 0                             ? ""
                  : i + 1 == rules.extensions.size() ? " or "
                                                     : ", ") +
                 rules.extensions[i];
    throw Error(ErrorKind::kInvalidValue, rules.option, path, "a file name ending in " + allowed);
  }
  CheckOutputLocation(path);
  std::error_code ec;
  if (!fs::exists(path, ec)) return;  // Every input exists: a new file is none of them.
  if (fs::is_directory(path, ec)) {
    throw Error(ErrorKind::kInvalidValue, rules.option, path + " (a folder)", "a file name");
  }
  CheckNotAnInput(path, rules.option, rules.inputs);
  if (ext == ".h5" || ext == ".hdf5") {
    try {
      const H5Reader existing(path);
    } catch (const Error&) {
      throw Error(ErrorKind::kInvalidValue, rules.option,
                  path + ", an existing file that is not HDF5 (it is kept)",
                  "a new file name, or an HDF5 file to write the command's groups into");
    }
  }
  if (ext == ".csv" || ext == ".json" || ext == ".yaml" || ext == ".yml") {
    const std::string first = FirstLine(path);
    for (const std::string& own : rules.own_first_lines)
      if (!own.empty() && first.rfind(own, 0) == 0) return;
    std::string shown = first.substr(0, 60);
    for (char& c : shown)
      if (static_cast<unsigned char>(c) < 0x20) c = '?';
    throw Error(ErrorKind::kInvalidValue, rules.option,
                path + ", an existing file this command did not write (it is kept; it begins '" +
                    shown + (first.size() > 60 ? "...'" : "'") + ")",
                "a new file name, or one this command wrote (to replace it); move the file away "
                "first if it should go");
  }
}

Error WriteError(const std::string& written_path, int error_number) {
  const std::string path = OutputPathForMessages(written_path);
  if (error_number == ENOSPC || error_number == EDQUOT) {
    fs::path folder = fs::path(path).parent_path();
    if (folder.empty()) folder = ".";
    return Error(ErrorKind::kIo,
                 std::string("cannot write: ") +
                     (error_number == ENOSPC ? "no space left on device"
                                             : "disk quota exceeded (no space left for you)") +
                     "; free space in " + folder.string() + " or choose another output folder")
        .WithFile(path);
  }
  std::string reason = std::strerror(error_number);
  if (!reason.empty()) reason[0] = static_cast<char>(std::tolower(reason[0]));
  return Error(ErrorKind::kIo, "cannot write: " + reason).WithFile(path);
}

bool DiskFull(const std::string& path) {
  fs::path folder = fs::path(path).parent_path();
  if (folder.empty()) folder = ".";
  struct statvfs info {};
  if (statvfs(folder.c_str(), &info) != 0) return false;
  // root may also write into the blocks reserved for it.
  return (geteuid() == 0 ? info.f_bfree : info.f_bavail) == 0;
}

namespace {

// Writes all of `data` to `fd`, retrying short writes and EINTR; the errno of a failure.
int WriteAll(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return 0;
}

}  // namespace

AtomicStreamWriter::AtomicStreamWriter(const std::string& path) : file_(path) {
  fd_ = open(file_.temp_path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw WriteError(path, errno);
}

AtomicStreamWriter::~AtomicStreamWriter() {
  if (fd_ >= 0) close(fd_);  // Uncommitted: ~AtomicFile removes the temporary file.
}

void AtomicStreamWriter::Write(const void* data, std::size_t size) {
  const char* bytes = static_cast<const char*>(data);
  if (buffer_.size() + size < kBlockBytes) {
    buffer_.append(bytes, size);
    return;
  }
  Flush();
  if (size >= kBlockBytes) {
    if (const int error = WriteAll(fd_, bytes, size); error != 0)
      throw WriteError(file_.final_path(), error);
  } else {
    buffer_.append(bytes, size);
  }
}

void AtomicStreamWriter::Flush() {
  if (const int error = WriteAll(fd_, buffer_.data(), buffer_.size()); error != 0)
    throw WriteError(file_.final_path(), error);
  buffer_.clear();
}

void AtomicStreamWriter::Commit() {
  Flush();
  int error = 0;
  // A file system may only report a full disk when the data reaches it (fsync) or at close.
  if (fsync(fd_) != 0 && errno != EINVAL && errno != EROFS) error = errno;
  if (close(fd_) != 0 && error == 0 && errno != EINTR) error = errno;
  fd_ = -1;
  if (error != 0) throw WriteError(file_.final_path(), error);
  file_.Commit();
}

void WriteFileAtomic(const std::string& path, const void* data, std::size_t size) {
  AtomicStreamWriter out(path);
  out.Write(data, size);
  out.Commit();
}

void WriteTextFileAtomic(const std::string& path, const std::string& text) {
  WriteFileAtomic(path, text.data(), text.size());
}

std::string ReadTextFile(const std::string& path) {
  return ReadInputFile(path, "a text file", kMaxTextFileBytes);
}

}  // namespace impactdic
