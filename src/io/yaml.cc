#include "impactdic/io/yaml.h"

#include <fmt/format.h>
#include <yaml-cpp/eventhandler.h>

#include <algorithm>
#include <cmath>
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

// Records the line where a document starts (its '---', or its first node); reads nothing else.
class DocumentStartFinder : public YAML::EventHandler {
 public:
  int line() const { return line_; }
  void OnDocumentStart(const YAML::Mark& mark) override { line_ = mark.line + 1; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}

 private:
  int line_ = 0;
};

// Optimal-string-alignment distance: insertions, deletions, substitutions and transpositions of
// neighbouring letters each cost 1 (so "tset" is one edit from "test").
std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[a.size()][b.size()];
}

std::string JoinKeys(const std::vector<std::string>& keys) {
  std::string list;
  for (const auto& k : keys) list += (list.empty() ? "" : ", ") + k;
  return list;
}

// " (did you mean 'x'?)" or "".
std::string DidYouMean(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string close = ClosestMatch(word, candidates);
  return close.empty() ? "" : fmt::format(" (did you mean '{}'?)", close);
}

}  // namespace

std::string ClosestMatch(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::string::npos;
  for (const auto& c : candidates) {
    const std::size_t d = EditDistance(word, c);
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  // Close enough: at most a third of the word's letters differ (at least 1, at most 3 edits).
  const std::size_t limit = std::clamp<std::size_t>(word.size() / 3, 1, 3);
  return best_distance <= limit ? best : "";
}

std::string DescribeYaml(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return fmt::format("a list of {}", node.size());
  return "a map";
}

void YamlProblems::Add(const YAML::Node& at, const std::string& key_path, const std::string& text) {
  std::string where = file_;
  if (at.IsDefined() && at.Mark().line >= 0) where += fmt::format(":{}", at.Mark().line + 1);
  lines_.push_back(fmt::format("{}: {}: {}", where, key_path, text));
  key_paths_.insert(key_path);
}

void YamlProblems::ThrowIfAny(const std::string& what, ErrorKind kind) const {
  if (lines_.empty()) return;
  std::string text = fmt::format("{} problem{} in {} {}:", lines_.size(),
                                 lines_.size() == 1 ? "" : "s", what, file_);
  for (const auto& line : lines_) text += "\n  " + line;
  throw Error(kind, text);
}

YamlSection::YamlSection(const YAML::Node& node, std::string prefix, YamlProblems* problems)
    : node_(node), prefix_(std::move(prefix)), problems_(problems) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    problems_->Add(node_, prefix_.empty() ? "(top level)" : prefix_,
                   fmt::format("got {}; expected a map of keys", DescribeYaml(node_)));
    node_ = YAML::Node();
  }
}

std::string YamlSection::PathOf(const std::string& key) const {
  return prefix_.empty() ? key : prefix_ + "." + key;
}

bool DecodeNumber(const YAML::Node& node, const ValueRange& range, double* out) {
  double v = 0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, v) || !range.Contains(v))
    return false;
  *out = v;
  return true;
}

bool DecodeNumber(const YAML::Node& node, const ValueRange& range, int* out) {
  int v = 0;
  if (!node.IsScalar() || !YAML::convert<int>::decode(node, v) || !range.Contains(v)) return false;
  *out = v;
  return true;
}

std::string NumberProblemText(const YAML::Node& node, const std::string& expected) {
  double v = 0;
  if (node.IsScalar() && YAML::convert<double>::decode(node, v) && !std::isfinite(v))
    return fmt::format("got {}; must be a finite number: {}", DescribeYaml(node), expected);
  return fmt::format("got {}; expected {}", DescribeYaml(node), expected);
}

bool YamlSection::Has(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined() && !node_[key].IsNull();
}

YAML::Node YamlSection::Get(const std::string& key) {
  known_.insert(key);
  if (!node_.IsMap()) return YAML::Node();
  return node_[key];
}

YamlSection YamlSection::Sub(const std::string& key) {
  return YamlSection(Get(key), PathOf(key), problems_);
}

void YamlSection::Problem(const std::string& key, const std::string& text) {
  const YAML::Node at = node_.IsMap() && node_[key].IsDefined() ? node_[key] : node_;
  problems_->Add(at, PathOf(key), text);
}

bool YamlSection::Require(const std::string& key, const std::string& expected) {
  if (Has(key)) return true;
  Problem(key, "missing; expected " + expected);
  return false;
}

bool YamlSection::ReadWith(const std::string& key,
                           const std::function<bool(const YAML::Node&)>& parse,
                           const std::string& expected) {
  const YAML::Node n = Get(key);
  if (!n.IsDefined() || n.IsNull()) return false;
  if (parse(n)) return true;
  problems_->Add(n, PathOf(key), fmt::format("got {}; expected {}", DescribeYaml(n), expected));
  return false;
}

bool YamlSection::ReadNumberWith(const std::string& key,
                                 const std::function<bool(const YAML::Node&)>& parse,
                                 const std::string& expected) {
  const YAML::Node n = Get(key);
  if (!n.IsDefined() || n.IsNull()) return false;
  if (parse(n)) return true;
  problems_->Add(n, PathOf(key), NumberProblemText(n, expected));
  return false;
}

bool YamlSection::Read(const std::string& key, double* out, const ValueRange& range,
                       const std::string& what) {
  return ReadNumberWith(
      key, [&](const YAML::Node& n) { return DecodeNumber(n, range, out); },
      ExpectedText(what, range));
}

bool YamlSection::Read(const std::string& key, int* out, const ValueRange& range,
                       const std::string& what) {
  return ReadNumberWith(
      key, [&](const YAML::Node& n) { return DecodeNumber(n, range, out); },
      ExpectedText("an integer " + what, range));
}

bool YamlSection::Read(const std::string& key, std::uint64_t* out) {
  return ReadWith(
      key,
      [&](const YAML::Node& n) {
        unsigned long long v = 0;
        if (!n.IsScalar() || !YAML::convert<unsigned long long>::decode(n, v)) return false;
        *out = v;
        return true;
      },
      "a non-negative integer");
}

bool YamlSection::Read(const std::string& key, bool* out) {
  return ReadWith(
      key,
      [&](const YAML::Node& n) {
        bool v = false;
        if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) return false;
        *out = v;
        return true;
      },
      "true or false");
}

bool YamlSection::Read(const std::string& key, std::string* out) {
  return ReadWith(
      key,
      [&](const YAML::Node& n) {
        if (!n.IsScalar()) return false;
        *out = n.Scalar();
        return true;
      },
      "a text value");
}

bool YamlSection::ReadChoice(const std::string& key, std::string* out,
                             const std::vector<std::string>& allowed) {
  const YAML::Node n = Get(key);
  if (!n.IsDefined() || n.IsNull()) return false;
  const std::string value = n.IsScalar() ? n.Scalar() : "";
  if (std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
    problems_->Add(n, PathOf(key),
                   fmt::format("got {}; expected one of {}{}", DescribeYaml(n), JoinKeys(allowed),
                               DidYouMean(value, allowed)));
    return false;
  }
  *out = value;
  return true;
}

void YamlSection::Finish() {
  if (!node_.IsMap()) return;
  const std::vector<std::string> known(known_.begin(), known_.end());
  for (const auto& entry : node_) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : "(complex key)";
    if (known_.count(key)) continue;
    problems_->Add(
        entry.first, PathOf(key),
        "unknown key" + DidYouMean(key, known) + "; known keys here: " + JoinKeys(known));
  }
}

namespace {
std::string ValueText(double v) { return fmt::format("{}", v); }
}  // namespace

YamlOptionTable& YamlOptionTable::Add(const std::string& key, double* field,
                                      const ValueRange& range, const std::string& what,
                                      const std::string& doc) {
  return AddNumber(
      key, ExpectedText(what, range), ValueText(*field),
      [field, range](const YAML::Node& n) { return DecodeNumber(n, range, field); }, doc);
}

YamlOptionTable& YamlOptionTable::Add(const std::string& key, int* field, const ValueRange& range,
                                      const std::string& what, const std::string& doc) {
  return AddNumber(
      key, ExpectedText("an integer " + what, range), std::to_string(*field),
      [field, range](const YAML::Node& n) { return DecodeNumber(n, range, field); }, doc);
}

YamlOptionTable& YamlOptionTable::Add(const std::string& key, bool* field, const std::string& doc) {
  return AddCustom(
      key, "true or false", *field ? "true" : "false",
      [field](const YAML::Node& n) {
        return n.IsScalar() && YAML::convert<bool>::decode(n, *field);
      },
      doc);
}

YamlOptionTable& YamlOptionTable::Add(const std::string& key, std::string* field,
                                      const std::string& doc) {
  return AddCustom(
      key, "a text value", *field,
      [field](const YAML::Node& n) {
        if (!n.IsScalar()) return false;
        *field = n.Scalar();
        return true;
      },
      doc);
}

YamlOptionTable& YamlOptionTable::AddChoice(const std::string& key,
                                            const std::vector<std::string>& names,
                                            const std::string& default_text,
                                            const std::function<void(const std::string&)>& set,
                                            const std::string& doc) {
  AddCustom(
      key, "one of " + JoinKeys(names), default_text,
      [names, set](const YAML::Node& n) {
        if (!n.IsScalar() || std::find(names.begin(), names.end(), n.Scalar()) == names.end())
          return false;
        set(n.Scalar());
        return true;
      },
      doc);
  entries_.back().choices = names;
  return *this;
}

YamlOptionTable& YamlOptionTable::AddCustom(const std::string& key, const std::string& expected,
                                            const std::string& default_text,
                                            std::function<bool(const YAML::Node&)> parse,
                                            const std::string& doc) {
  entries_.push_back(Entry{key, expected, doc, default_text, std::move(parse), {}});
  return *this;
}

YamlOptionTable& YamlOptionTable::AddNumber(const std::string& key, const std::string& expected,
                                            const std::string& default_text,
                                            std::function<bool(const YAML::Node&)> parse,
                                            const std::string& doc) {
  AddCustom(key, expected, default_text, std::move(parse), doc);
  entries_.back().number = true;
  return *this;
}

void YamlOptionTable::Read(YamlSection& section) const {
  for (const Entry& e : entries_) {
    const YAML::Node n = section.Get(e.key);
    const std::string hint = n.IsScalar() ? DidYouMean(n.Scalar(), e.choices) : "";
    if (e.number) {
      section.ReadNumberWith(e.key, e.parse, e.expected);
    } else {
      section.ReadWith(e.key, e.parse, e.expected + hint);
    }
  }
}

std::string YamlOptionTable::Reference() const {
  std::string rows;
  for (const Entry& e : entries_) {
    rows += fmt::format("| `{}.{}` | {} | {} | {} |\n", section_, e.key,
                        e.default_text.empty() ? "(none)" : e.default_text, e.expected, e.doc);
  }
  return rows;
}

YAML::Node LoadYaml(const std::string& text, const std::string& path, const std::string& what) {
  const std::string binary = BinaryFileKind(text);
  if (!binary.empty()) throw Error(ErrorKind::kFileFormat, "", binary, what).WithFile(path);
  try {
    std::istringstream in(text);
    YAML::Parser parser(in);
    DuplicateKeyFinder finder(path);
    parser.HandleNextDocument(finder);
    // yaml-cpp (YAML::Load) reads only the first document: what follows a '---' would be
    // silently ignored.
    DocumentStartFinder second;
    if (parser.HandleNextDocument(second))
      throw Error(ErrorKind::kFileFormat, "YAML",
                  fmt::format("a second document starting at line {}", second.line()),
                  "one document per file: impactdic reads only the first, so everything from "
                  "line " +
                      std::to_string(second.line()) +
                      " on would be silently ignored; merge the two or delete the '---'")
          .WithFile(path, second.line());
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
