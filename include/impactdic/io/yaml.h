// The one way YAML files are loaded: scene files (pipeline/scene.h), calibration files (calib) and
// synthetic scene specs (synth).
//
//   const YAML::Node root = LoadYamlFile("camera.yaml", "a calibration file (YAML)");
//
// Besides YAML syntax errors (Error kFileFormat with file:line:column), it refuses
//  - a key given twice in one map: yaml-cpp would silently keep the first value. The error names
//    the key path and both lines ("test.mass_kg ... at line 9 (first at line 3)");
//  - a file that is not text, e.g. an image given as the calibration: the error names its kind;
//  - a second document (after '---'): yaml-cpp would silently read only the first. The error
//    names the file and the line where the second one starts.
// `what` says what the file should be, for messages ("a scene file (YAML)").
#ifndef IMPACTDIC_IO_YAML_H_
#define IMPACTDIC_IO_YAML_H_

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/range.h"

namespace impactdic {

// Parses `text`, read from `path` (for messages), which must hold one YAML document.
YAML::Node LoadYaml(const std::string& text, const std::string& path, const std::string& what);

// ReadInputFile(path, what, kMaxTextFileBytes) (a regular file of at most 64 MiB), then LoadYaml.
YAML::Node LoadYamlFile(const std::string& path, const std::string& what);

// Closest candidate by edit distance, or "" when none is close (for "did you mean").
std::string ClosestMatch(const std::string& word, const std::vector<std::string>& candidates);

// "nothing", "'abc'", "a list of 3", "a map": what a node holds, for messages.
std::string DescribeYaml(const YAML::Node& node);

// A scalar node holding a number (an integer) in `range`: stored in *out, true; otherwise false
// and *out unchanged. The one number decoder of the YAML readers.
bool DecodeNumber(const YAML::Node& node, const ValueRange& range, double* out);
bool DecodeNumber(const YAML::Node& node, const ValueRange& range, int* out);

// The problem text of a node that should have been a number: "got '.nan'; must be a finite
// number: `expected`" for YAML's .nan, .inf and -.inf, else "got X; expected `expected`".
std::string NumberProblemText(const YAML::Node& node, const std::string& expected);

// Every problem found in one YAML file, so the user sees all of them at once:
//   "file:LINE: key.path: got 'x'; expected ...".
class YamlProblems {
 public:
  explicit YamlProblems(std::string file) : file_(std::move(file)) {}
  // `at` gives the line (an undefined node: none).
  void Add(const YAML::Node& at, const std::string& key_path, const std::string& text);
  bool empty() const { return lines_.empty(); }
  std::size_t size() const { return lines_.size(); }
  const std::vector<std::string>& lines() const { return lines_; }
  // Whether a problem was recorded for `key_path` ("momentum.surface_y_px"): rules across keys
  // skip a key already reported (a bad value is not also "missing").
  bool Has(const std::string& key_path) const { return key_paths_.count(key_path) > 0; }
  // Error(`kind`) "N problem(s) in `what` FILE:" and one line per problem, if any.
  void ThrowIfAny(const std::string& what, ErrorKind kind = ErrorKind::kInvalidValue) const;

 private:
  std::string file_;
  std::vector<std::string> lines_;
  std::set<std::string> key_paths_;
};

// One map of a YAML file, read key by key: every accessor records the key as known, a wrong type
// or value is a problem naming the key path ("dic.subset_size"), and Finish() reports the keys no
// accessor asked for, suggesting the closest known one ("did you mean 'subset_size'?"). The one
// section reader of scene files, calibration files and synthetic scene specs.
//
//   YamlProblems problems(path);
//   YamlSection top(root, "", &problems);
//   YamlSection dic = top.Sub("dic");
//   dic.Read("step", &step, ValueRange{1, 1e6}, "a grid step [px]");
//   dic.Finish();
//   top.Finish();
//   problems.ThrowIfAny("scene file");
//
// The Read functions leave *out unchanged when the key is absent or null, and return whether a
// valid value was stored.
class YamlSection {
 public:
  YamlSection(const YAML::Node& node, std::string prefix, YamlProblems* problems);

  std::string PathOf(const std::string& key) const;
  bool Has(const std::string& key) const;
  // The node of `key` (undefined when absent); marks the key as known.
  YAML::Node Get(const std::string& key);
  YamlSection Sub(const std::string& key);
  // A problem with `key` (its line when present, else the section's).
  void Problem(const std::string& key, const std::string& text);
  // A problem "missing; expected `expected`" unless `key` is present and not null.
  bool Require(const std::string& key, const std::string& expected);
  YamlProblems* problems() const { return problems_; }

  // A finite number in `range`; `what` names it ("a pounder mass").
  bool Read(const std::string& key, double* out, const ValueRange& range, const std::string& what);
  // An integer in `range`.
  bool Read(const std::string& key, int* out, const ValueRange& range, const std::string& what);
  bool Read(const std::string& key, std::uint64_t* out);
  bool Read(const std::string& key, bool* out);
  bool Read(const std::string& key, std::string* out);
  // One of `allowed` (a near miss gets "did you mean").
  bool ReadChoice(const std::string& key, std::string* out,
                  const std::vector<std::string>& allowed);
  // Any present, non-null node: `parse` stores it and returns false when it is invalid, which is
  // reported as "got ...; expected `expected`".
  bool ReadWith(const std::string& key, const std::function<bool(const YAML::Node&)>& parse,
                const std::string& expected);
  // The same for a number: a non-finite one is reported as such (NumberProblemText).
  bool ReadNumberWith(const std::string& key, const std::function<bool(const YAML::Node&)>& parse,
                      const std::string& expected);

  // Reports keys that no accessor asked for, with a "did you mean" suggestion.
  void Finish();

 private:
  YAML::Node node_;
  std::string prefix_;
  YamlProblems* problems_;
  std::set<std::string> known_;
};

// Keys of one YAML section bound to the fields of option structs (as COLMAP's OptionManager binds
// option names to fields): the table both reads the section into the fields and documents it
// (key, default = the field's value when the table was built, expected values, meaning), so a
// default lives only in the struct that declares the field.
//
//   DicOptions options;
//   YamlOptionTable t("dic");
//   t.Add("step", &options.grid.step, ValueRange{1, 1e6, "px"}, "a grid step", "Grid spacing");
//   t.Read(section);   // section.Finish() is the caller's
class YamlOptionTable {
 public:
  struct Entry {
    std::string key;                               // "step"
    std::string expected;                          // "an integer in [1, 1e+06] px"
    std::string doc;                               // Meaning, unit.
    std::string default_text;                      // The bound field's value when bound.
    std::function<bool(const YAML::Node&)> parse;  // Stores a valid node; false if invalid.
    std::vector<std::string> choices;              // AddChoice: the names ("did you mean").
    bool number = false;  // A number: .nan and .inf are "not a finite number" (AddNumber).
  };

  explicit YamlOptionTable(std::string section) : section_(std::move(section)) {}
  const std::string& section() const { return section_; }
  const std::vector<Entry>& entries() const { return entries_; }

  YamlOptionTable& Add(const std::string& key, double* field, const ValueRange& range,
                       const std::string& what, const std::string& doc);
  YamlOptionTable& Add(const std::string& key, int* field, const ValueRange& range,
                       const std::string& what, const std::string& doc);
  YamlOptionTable& Add(const std::string& key, bool* field, const std::string& doc);
  YamlOptionTable& Add(const std::string& key, std::string* field, const std::string& doc);
  // A name of `names`; `set` stores it (names are checked first).
  YamlOptionTable& AddChoice(const std::string& key, const std::vector<std::string>& names,
                             const std::string& default_text,
                             const std::function<void(const std::string&)>& set,
                             const std::string& doc);
  // Anything else: `parse` validates and stores.
  YamlOptionTable& AddCustom(const std::string& key, const std::string& expected,
                             const std::string& default_text,
                             std::function<bool(const YAML::Node&)> parse, const std::string& doc);
  // AddCustom for a number (ReadNumberWith).
  YamlOptionTable& AddNumber(const std::string& key, const std::string& expected,
                             const std::string& default_text,
                             std::function<bool(const YAML::Node&)> parse, const std::string& doc);

  // Reads every bound key present in `section` (problems go to its YamlProblems).
  void Read(YamlSection& section) const;
  // Markdown table rows "| `dic.step` | 10 | an integer >= 1 | Grid spacing |".
  std::string Reference() const;

 private:
  std::string section_;
  std::vector<Entry> entries_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_IO_YAML_H_
