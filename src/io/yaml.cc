#include "impactdic/io/yaml.h"

#include <fmt/format.h>
#include <yaml-cpp/eventhandler.h>

#include <map>
#include <sstream>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/io/input_file.h"

namespace impactdic {
namespace {

// Walks the parser's events (aliases are not expanded, so this is linear in the text) and throws
// at the second occurrence of a key in one map. yaml-cpp's node tree keeps both entries but
// node["key"] returns the first, so without this a repeated key is silently ignored.
class DuplicateKeyFinder : public YAML::EventHandler {
 public:
  explicit DuplicateKeyFinder(std::string path) : path_(std::move(path)) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { Leaf(mark, nullptr); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { Leaf(mark, nullptr); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string& value) override {
    Leaf(mark, &value);
  }
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    Open(/*is_map=*/false);
  }
  void OnSequenceEnd() override { Close(); }
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    Open(/*is_map=*/true);
  }
  void OnMapEnd() override { Close(); }

 private:
  struct Level {
    bool is_map = false;
    bool expect_key = true;            // Maps: the next node is a key (else its value).
    std::string key;                   // Maps: the current key.
    std::size_t index = 0;             // Sequences: the current item.
    std::map<std::string, int> lines;  // Maps: key -> 1-based line of its first occurrence.
  };

  // A node that has no children (scalar, null, alias).
  void Leaf(const YAML::Mark& mark, const std::string* scalar) {
    if (!stack_.empty() && stack_.back().is_map && stack_.back().expect_key)
      Key(scalar ? *scalar : "~", mark.line + 1);
    Completed();
  }
  void Open(bool is_map) {
    if (!stack_.empty() && stack_.back().is_map && stack_.back().expect_key)
      stack_.back().key = "(complex key)";
    stack_.push_back(Level{is_map});
  }
  void Close() {
    stack_.pop_back();
    Completed();
  }
  // A node of the innermost container is complete: a map alternates key and value.
  void Completed() {
    if (stack_.empty()) return;
    Level& level = stack_.back();
    if (level.is_map) {
      level.expect_key = !level.expect_key;
    } else {
      ++level.index;
    }
  }
  void Key(const std::string& key, int line) {
    Level& level = stack_.back();
    level.key = key;
    const auto [it, inserted] = level.lines.emplace(key, line);
    if (inserted) return;
    throw Error(ErrorKind::kFileFormat, KeyPath(),
                fmt::format("the key '{}' a second time at line {} (first at line {})", key, line,
                            it->second),
                "each key at most once in a map (one of the two values would be silently "
                "ignored: delete or merge them)")
        .WithFile(path_, line);
  }
  // "dic.roi", "stages[2]": the keys and indices from the top to the current key.
  std::string KeyPath() const {
    std::string path;
    for (const Level& level : stack_) {
      if (level.is_map) {
        path += (path.empty() ? "" : ".") + level.key;
      } else {
        path += fmt::format("[{}]", level.index);
      }
    }
    return path;
  }

  std::string path_;
  std::vector<Level> stack_;
};

}  // namespace

YAML::Node LoadYaml(const std::string& text, const std::string& path, const std::string& what) {
  const std::string binary = BinaryFileKind(text);
  if (!binary.empty()) throw Error(ErrorKind::kFileFormat, "", binary, what).WithFile(path);
  try {
    std::istringstream in(text);
    YAML::Parser parser(in);
    DuplicateKeyFinder finder(path);
    parser.HandleNextDocument(finder);
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(ErrorKind::kFileFormat, "YAML", e.msg, what)
        .WithFile(path, e.mark.line + 1, e.mark.column + 1);
  }
}

YAML::Node LoadYamlFile(const std::string& path, const std::string& what) {
  return LoadYaml(ReadInputFile(path, what, kMaxTextFileBytes), path, what);
}

}  // namespace impactdic
