// docs/guide.md run as written on the sample, so the guide and the tool cannot
// drift apart: every ```bash block of the page runs in order from one fresh folder in which the
// guide's names for a user's files are links to the sample's (checkerboard/ -> calibration/,
// recording/ -> sample_frames/frames/, daq.csv -> sample_frames/sensor.csv); a ```yaml block right
// after a line "<!-- edit FILE -->" sets its keys in FILE, line by line, as a user does in an
// editor. Then every results/... and preview/... file the page names must exist, and every --flag
// in any of its code blocks must be in its command's --help.
#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "../core/test_paths.h"
#include "../reliability/fault_util.h"
#include "cli_runner.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

const std::string kGuide = std::string(impactdic::SourceDir()) + "/docs/guide.md";

// A fenced code block of the page: its info string (bash, yaml, sh, text), its text, the file an
// "<!-- edit FILE -->" line just above it names ("" without one) and the line it starts at.
struct CodeBlock {
  std::string info;
  std::string text;
  std::string edit_file;
  int line = 0;
};

std::string Trim(const std::string& s) {
  const std::size_t b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

std::vector<CodeBlock> CodeBlocks(const std::string& doc) {
  static const std::regex kEdit(R"(<!--\s*edit\s+(\S+)\s*-->)");
  std::vector<CodeBlock> blocks;
  std::string previous;  // The last non-blank line outside a block.
  std::optional<CodeBlock> open;
  int number = 0;
  for (const std::string& line : Lines(doc)) {
    ++number;
    if (open) {
      if (line == "```") {
        blocks.push_back(*open);
        open.reset();
      } else {
        open->text += line + "\n";
      }
    } else if (line.rfind("```", 0) == 0) {
      open = CodeBlock{line.substr(3), "", "", number};
      std::smatch m;
      if (std::regex_match(previous, m, kEdit)) open->edit_file = m[1];
    } else if (!Trim(line).empty()) {
      previous = Trim(line);
    }
  }
  EXPECT_FALSE(open) << "docs/guide.md: the block at line " << open->line << " is not closed";
  return blocks;
}

// A YAML mapping line "  key: value" (or, with `commented`, "  # key: value"): its indentation, key
// and value (after the colon, trimmed; may hold a comment).
struct KeyLine {
  std::size_t indent = 0;
  std::string key;
  std::string value;
  bool commented = false;
};

std::optional<KeyLine> ParseKeyLine(const std::string& line) {
  static const std::regex kKey(R"(^( *)(# )?([A-Za-z_][A-Za-z0-9_]*):(?: (.*))?$)");
  std::smatch m;
  if (!std::regex_match(line, m, kKey)) return std::nullopt;
  return KeyLine{static_cast<std::size_t>(m[1].length()), m[3], Trim(m[4]), m[2].matched};
}

// Dotted key path -> line index of every key line of `lines` (commented keys, such as the
// template's "# roi: ...", in `commented`).
void IndexKeys(const std::vector<std::string>& lines, std::map<std::string, std::size_t>* keys,
               std::map<std::string, std::size_t>* commented) {
  std::vector<std::pair<std::size_t, std::string>> parents;  // (indent, key) of open maps.
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::optional<KeyLine> k = ParseKeyLine(lines[i]);
    if (!k) continue;
    while (!parents.empty() && parents.back().first >= k->indent) parents.pop_back();
    std::string path;
    for (const auto& p : parents) path += p.second + ".";
    path += k->key;
    if (k->commented) {
      commented->emplace(path, i);
    } else {
      (*keys)[path] = i;
      parents.emplace_back(k->indent, k->key);
    }
  }
}

// Sets every key of the YAML block `edits` (nested maps of scalars, 2 spaces per level) in the
// YAML text `yaml`: the key's line (or its commented-out line) is replaced; a key the file lacks
// is added below its map (the map too when missing).
std::string ApplyEdits(const std::string& yaml, const std::string& edits,
                       const std::string& where) {
  std::vector<std::string> lines = Lines(yaml);
  std::vector<std::string> path;
  for (const std::string& line : Lines(edits)) {
    if (Trim(line).empty() || Trim(line)[0] == '#') continue;
    const std::optional<KeyLine> k = ParseKeyLine(line);
    if (!k || k->commented || k->indent % 2 != 0) {
      ADD_FAILURE() << where << ": not a 'key: value' line of a nested map: '" << line << "'";
      continue;
    }
    path.resize(k->indent / 2);
    if (k->value.empty() || k->value[0] == '#') {  // A map; its keys follow.
      path.push_back(k->key);
      continue;
    }
    std::map<std::string, std::size_t> keys, commented;
    IndexKeys(lines, &keys, &commented);
    std::string dotted;
    for (const auto& p : path) dotted += p + ".";
    dotted += k->key;
    const std::string text = std::string(2 * path.size(), ' ') + k->key + ": " + k->value;
    if (keys.count(dotted)) {
      lines[keys[dotted]] = text;
    } else if (commented.count(dotted)) {
      lines[commented[dotted]] = text;
    } else {  // Below the deepest map the file has, with the maps it lacks.
      std::size_t depth = path.size();
      std::string prefix;
      while (depth > 0) {
        prefix.clear();
        for (std::size_t d = 0; d < depth; ++d) prefix += (d ? "." : "") + path[d];
        if (keys.count(prefix)) break;
        --depth;
      }
      std::vector<std::string> added;
      for (std::size_t d = depth; d < path.size(); ++d)
        added.push_back(std::string(2 * d, ' ') + path[d] + ":");
      added.push_back(text);
      const std::size_t at = depth > 0 ? keys[prefix] + 1 : lines.size();
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(at), added.begin(), added.end());
    }
  }
  std::string out;
  for (const auto& line : lines) out += line + "\n";
  return out;
}

std::string DescribeBlock(const CodeBlock& b) {
  return "docs/guide.md:" + std::to_string(b.line) + " (```" + b.info + ")";
}

// Every command of the guide, in order, on the sample: each exits 0, and every output the guide
// names exists afterwards.
TEST(GuideDocs, CommandsRunInOrderOnTheSample) {
  const std::vector<CodeBlock> blocks = CodeBlocks(ReadBytes(kGuide));
  TestDir dir;
  const fs::path work = dir.path() / "my_test";
  fs::create_directories(work);
  const fs::path source(impactdic::SourceDir());
  fs::create_directory_symlink(source / "calibration", work / "checkerboard");
  fs::create_directory_symlink(source / "sample_frames" / "frames", work / "recording");
  fs::create_symlink(source / "sample_frames" / "sensor.csv", work / "daq.csv");
  // Each block runs from the work folder with the built impactdic first on the PATH.
  const std::string run_in_work =
      "cd " + work.string() + " && PATH=" + fs::path(impactdic::CliPath()).parent_path().string() +
      ":\"$PATH\" bash -e ";

  int commands = 0, edits = 0;
  for (const CodeBlock& b : blocks) {
    if (b.info == "bash") {
      const std::string script = dir.Write("block_" + std::to_string(b.line) + ".sh", b.text);
      const CliResult r = RunShell(run_in_work + script);
      ASSERT_EQ(r.exit_code, 0) << DescribeBlock(b) << ":\n" << b.text << "\n" << r.output;
      ++commands;
    } else if (!b.edit_file.empty()) {
      ASSERT_EQ(b.info, "yaml") << DescribeBlock(b) << ": an edit block must be ```yaml";
      const fs::path file = work / b.edit_file;
      ASSERT_TRUE(fs::exists(file))
          << DescribeBlock(b) << " edits " << file << ", which no earlier command wrote";
      WriteBytes(file.string(), ApplyEdits(ReadBytes(file.string()), b.text, DescribeBlock(b)));
      ++edits;
    }
  }
  EXPECT_GE(commands, 5) << "the guide's ```bash blocks were not found";
  EXPECT_GE(edits, 3) << "the guide's edit blocks were not found";

  const std::string doc = ReadBytes(kGuide);
  static const std::regex kNamed(R"(`((?:results|preview)/[A-Za-z0-9_.]+\.[a-z0-9]+)`)");
  std::set<std::string> named;
  for (std::sregex_iterator it(doc.begin(), doc.end(), kNamed), end; it != end; ++it)
    named.insert((*it)[1]);
  EXPECT_GE(named.size(), 10u) << "the guide names fewer outputs than expected";
  for (const std::string& name : named)
    EXPECT_TRUE(fs::exists(work / name))
        << "docs/guide.md names " << name << ", which the guide's commands did not write";
}

// Every --flag given to an impactdic command in a code block of the guide (run or shown) is an
// option of that command.
TEST(GuideDocs, EveryFlagIsInItsCommandsHelp) {
  static const std::regex kCommand(R"(\bimpactdic(?: -[qv])* ([a-z][a-z-]*)(.*))");
  static const std::regex kFlag(R"((?:^|\s)(--[a-z][a-z0-9-]*))");
  std::map<std::string, std::string> help;
  int flags = 0;
  for (const CodeBlock& b : CodeBlocks(ReadBytes(kGuide))) {
    for (const std::string& line : Lines(b.text)) {
      std::smatch m;
      if (!std::regex_search(line, m, kCommand)) continue;
      const std::string command = m[1], rest = m[2];
      if (!help.count(command)) {
        const CliResult r = RunCli(command + " --help");
        ASSERT_EQ(r.exit_code, 0) << DescribeBlock(b) << ": impactdic " << command << "\n"
                                  << r.output;
        help[command] = r.output;
      }
      for (std::sregex_iterator it(rest.begin(), rest.end(), kFlag), end; it != end; ++it) {
        const std::string flag = (*it)[1];
        ++flags;
        EXPECT_TRUE(
            std::regex_search(help[command], std::regex("(^|[ ,])" + flag + "(?=[\\s=,]|$)")))
            << DescribeBlock(b) << ": impactdic " << command << " has no option " << flag;
      }
    }
  }
  EXPECT_GE(flags, 5) << "the guide's flags were not found";
}

}  // namespace
}  // namespace impactdic
