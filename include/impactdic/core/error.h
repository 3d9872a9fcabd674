// Errors for bad input, files and parameters.
//
// Programmer mistakes are assertions; everything a user can cause (a missing file, a malformed
// number, an impossible parameter) throws impactdic::Error, which says what went wrong and where.
// The CLI catches it once in main() and turns it into one message and an exit code.
//
//   throw Error(ErrorKind::kInvalidValue, "dic.subset_size", "even value 24",
//               "an odd integer >= 5").WithFile("scene.yaml");
#ifndef IMPACTDIC_CORE_ERROR_H_
#define IMPACTDIC_CORE_ERROR_H_

#include <stdexcept>
#include <string>

namespace impactdic {

enum class ErrorKind {
  kInvalidValue,  // A parameter or field holds a value outside its allowed range.
  kFileNotFound,  // A named input does not exist.
  kFileFormat,    // A file exists but cannot be parsed (corrupt image, malformed CSV).
  kIo,            // Reading or writing failed (permissions, disk full).
  kNumerical,     // A computation failed in a way the input caused (no convergence, NaN).
};

const char* ToString(ErrorKind kind);

// Process exit code for an error of this kind (1 for every kind: bad input or a failed run).
int ExitCode(ErrorKind kind);

class Error : public std::runtime_error {
 public:
  // `where` names the field, option or key path (e.g. "dic.subset_size", "--subset");
  // `found` what was found; `expected` what is allowed. Any of them may be empty.
  Error(ErrorKind kind, std::string where, std::string found, std::string expected);
  // A free-form message.
  Error(ErrorKind kind, std::string message);

  // Adds the file (and optionally line and column, 1-based; 0 = unknown) the problem is in.
  Error& WithFile(std::string file, int line = 0, int column = 0);

  ErrorKind kind() const { return kind_; }
  const std::string& where() const { return where_; }
  const std::string& found() const { return found_; }
  const std::string& expected() const { return expected_; }
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  int column() const { return column_; }
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  void Compose();

  ErrorKind kind_;
  std::string where_, found_, expected_, free_text_;
  std::string file_;
  int line_ = 0, column_ = 0;
  std::string message_;
};

// Throws Error(kInvalidValue, where, found, expected) unless `condition` holds.
void CheckValue(bool condition, const std::string& where, const std::string& found,
                const std::string& expected);

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_ERROR_H_
