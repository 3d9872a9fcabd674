#include "impactdic/core/error.h"

#include <fmt/format.h>

#include <utility>

namespace impactdic {

const char* ToString(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::kInvalidValue: return "invalid value";
    case ErrorKind::kFileNotFound: return "file not found";
    case ErrorKind::kFileFormat: return "bad file format";
    case ErrorKind::kIo: return "I/O error";
    case ErrorKind::kNumerical: return "numerical failure";
  }
  return "error";
}

int ExitCode(ErrorKind /*kind*/) { return 1; }

Error::Error(ErrorKind kind, std::string where, std::string found, std::string expected)
    : std::runtime_error(""),
      kind_(kind),
      where_(std::move(where)),
      found_(std::move(found)),
      expected_(std::move(expected)) {
  Compose();
}

Error::Error(ErrorKind kind, std::string message)
    : std::runtime_error(""), kind_(kind), free_text_(std::move(message)) {
  Compose();
}

Error& Error::WithFile(std::string file, int line, int column) {
  file_ = std::move(file);
  line_ = line;
  column_ = column;
  Compose();
  return *this;
}

void Error::Compose() {
  std::string location;
  if (!file_.empty()) {
    location = file_;
    if (line_ > 0) location += fmt::format(":{}", line_);
    if (column_ > 0) location += fmt::format(":{}", column_);
    location += ": ";
  }
  if (!free_text_.empty()) {
    message_ = location + free_text_;
    return;
  }
  message_ = location;
  if (!where_.empty()) message_ += where_ + ": ";
  message_ += ToString(kind_);
  if (!found_.empty()) message_ += fmt::format(" (got {})", found_);
  if (!expected_.empty()) message_ += fmt::format("; expected {}", expected_);
}

void CheckValue(bool condition, const std::string& where, const std::string& found,
                const std::string& expected) {
  if (!condition) throw Error(ErrorKind::kInvalidValue, where, found, expected);
}

}  // namespace impactdic
