#include "impactdic/io/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/io/output_generation.h"

namespace impactdic {
namespace fs = std::filesystem;

AtomicFile::AtomicFile(std::string final_path) : final_path_(std::move(final_path)) {
  fs::path final_fs(final_path_);
  fs::path folder = final_fs.parent_path();
  if (folder.empty()) folder = ".";
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    throw Error(ErrorKind::kIo, final_path_, "output folder " + folder.string() + " does not exist",
                "an existing, writable folder");
  }
  if (access(folder.c_str(), W_OK) != 0) {
    throw Error(ErrorKind::kIo, final_path_,
                "output folder " + folder.string() + " is not writable", "a writable folder");
  }
  RemoveStaleTemporaries(folder.string());
  std::string name = ".";  // (Appended, not "." + ...: GCC 12 warns wrongly on that.)
  name.append(final_fs.filename().string()).append(".tmp-").append(TemporaryTag());
  temp_path_ = (folder / name).string();
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
    throw Error(ErrorKind::kIo, final_path_, "cannot rename temporary file: " + ec.message(),
                "a writable output location");
  }
  committed_ = true;
  interrupt_guard_->Release();
}

void CheckOutputLocation(const std::string& path) { const AtomicFile probe(path); }

void WriteTextFileAtomic(const std::string& path, const std::string& text) {
  AtomicFile file(path);
  {
    std::ofstream out(file.temp_path(), std::ios::binary);
    out << text;
    out.flush();
    if (!out) {
      throw Error(ErrorKind::kIo, path, std::string("write failed: ") + std::strerror(errno), "");
    }
  }
  file.Commit();
}

std::string ReadTextFile(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(ErrorKind::kFileNotFound, path, "", "an existing file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::kIo, path, "cannot open for reading", "a readable file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace impactdic
