#include "impactdic/io/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <system_error>

#include "impactdic/core/error.h"
#include "impactdic/io/input_file.h"

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
  std::random_device rd;
  std::ostringstream name;
  name << "." << final_fs.filename().string() << ".tmp-" << getpid() << "-" << std::hex << rd();
  temp_path_ = (folder / name.str()).string();
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
  return ReadInputFile(path, "a text file", kMaxTextFileBytes);
}

}  // namespace impactdic
